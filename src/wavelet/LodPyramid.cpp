#include "wavelet/LodPyramid.h"

#include "vdb_hermite/HermiteGrid.h"
#include "wavelet/Haar.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

namespace vdbclay::wavelet {

namespace {

using Map = std::map<BlockOrigin, LodBlock>;
constexpr int kDim = kLeafDim;
constexpr int kHalf = kDim / 2;

inline int offsetOf(int x, int y, int z) { return (x << (2 * kLeafLog2Dim)) | (y << kLeafLog2Dim) | z; }
inline BlockOrigin parentOf(const BlockOrigin& o)
{
    // floor(o / 16) * 8: the level-(k+1) block whose footprint holds the level-k block at o.
    return {(o[0] >> 4) * kDim, (o[1] >> 4) * kDim, (o[2] >> 4) * kDim};
}

/// One 8^3 block of level k read for the level above or for coarse Hermite data: a block of the
/// pyramid (or a leaf at level 0), or the uniform value of the volume's tile its footprint lies in.
struct BlockView {
    const LodBlock* block = nullptr;
    const HermiteLeaf* leaf = nullptr;
    uint8_t density = 0;
    MaterialId material = kEmptyMaterial;

    bool uniform() const { return !block && !leaf; }
    uint8_t densityAt(int offset) const
    {
        if (block) return block->density[std::size_t(offset)];
        if (leaf) return leaf->getValue(Index(offset)).solid() ? uint8_t(kFullDensity) : uint8_t(0);
        return density;
    }
    MaterialId materialAt(int offset) const
    {
        if (block) return block->material[std::size_t(offset)];
        if (leaf) return leaf->getValue(Index(offset)).id;
        return material;
    }
};

class LevelReader {
public:
    LevelReader(const HermiteTree& tree, const std::vector<Map>& levels) : tree_(tree), levels_(levels) {}

    /// The level-k block at `origin` (level-k index space, a multiple of 8).
    BlockView view(int level, const BlockOrigin& origin) const
    {
        BlockView v;
        const int scale = 1 << level; // a multiplication: shifting a negative coordinate left is undefined
        const Coord fine(origin[0] * scale, origin[1] * scale, origin[2] * scale);
        if (level == 0) {
            v.leaf = tree_.probeConstLeaf(fine);
        } else {
            const Map& map = levels_[std::size_t(level - 1)];
            const auto it = map.find(origin);
            if (it != map.end()) v.block = &it->second;
        }
        if (v.uniform()) {
            // No leaf in the footprint: it lies inside one tile (tiles of different values, or of solid
            // and empty, would meet at edges that carry samples, which live in leaves).
            const MaterialValue value = tree_.getValue(fine);
            v.material = value.id;
            v.density = value.solid() ? uint8_t(kFullDensity) : uint8_t(0);
        }
        return v;
    }

private:
    const HermiteTree& tree_;
    const std::vector<Map>& levels_;
};

/// The level-(k+1) block at `origin` from its eight level-k children, or nullopt when none of them is a
/// block (its footprint holds no leaf). Density: the integer Haar low-pass (x, then y, then z, as
/// liftingDecompose3D); material: the one with the largest density among the eight (ties: lower id).
std::optional<LodBlock> computeBlock(const LevelReader& reader, int childLevel, const BlockOrigin& origin)
{
    BlockView children[8];
    bool any = false;
    for (int c = 0; c < 8; ++c) {
        const BlockOrigin o{2 * origin[0] + (c & 1) * kDim, 2 * origin[1] + ((c >> 1) & 1) * kDim,
                            2 * origin[2] + ((c >> 2) & 1) * kDim};
        children[c] = reader.view(childLevel, o);
        any = any || !children[c].uniform();
    }
    if (!any) return std::nullopt;
    LodBlock out;
    for (int c = 0; c < 8; ++c) {
        const BlockView& child = children[c];
        const int bx = (c & 1) * kHalf, by = ((c >> 1) & 1) * kHalf, bz = ((c >> 2) & 1) * kHalf;
        for (int x = 0; x < kHalf; ++x)
            for (int y = 0; y < kHalf; ++y)
                for (int z = 0; z < kHalf; ++z) {
                    int32_t d[2][2][2];
                    MaterialId m[8];
                    int32_t w[8];
                    for (int i = 0; i < 8; ++i) {
                        const int dx = i & 1, dy = (i >> 1) & 1, dz = (i >> 2) & 1;
                        const int at = offsetOf(2 * x + dx, 2 * y + dy, 2 * z + dz);
                        d[dx][dy][dz] = child.densityAt(at);
                        m[i] = child.materialAt(at);
                        w[i] = d[dx][dy][dz];
                    }
                    int32_t lx[2][2], lxy[2], low, detail;
                    for (int j = 0; j < 2; ++j)
                        for (int k = 0; k < 2; ++k) liftingForward(d[0][j][k], d[1][j][k], lx[j][k], detail);
                    for (int k = 0; k < 2; ++k) liftingForward(lx[0][k], lx[1][k], lxy[k], detail);
                    liftingForward(lxy[0], lxy[1], low, detail);
                    MaterialId best = kEmptyMaterial;
                    int32_t bestWeight = 0;
                    for (int i = 0; i < 8; ++i) {
                        if (m[i] == kEmptyMaterial || w[i] == 0) continue;
                        int32_t weight = 0;
                        for (int j = 0; j < 8; ++j)
                            if (m[j] == m[i]) weight += w[j];
                        if (weight > bestWeight || (weight == bestWeight && m[i] < best)) best = m[i], bestWeight = weight;
                    }
                    const int at = offsetOf(bx + x, by + y, bz + z);
                    out.density[std::size_t(at)] = uint8_t(low);
                    out.material[std::size_t(at)] = low > 0 ? best : kEmptyMaterial;
                }
    }
    return out;
}

/// Computes the blocks at `origins` of level `level` (>= 1) in parallel against the current pyramid.
std::vector<std::optional<LodBlock>> computeBlocks(const LevelReader& reader, int level,
                                                   const std::vector<BlockOrigin>& origins)
{
    std::vector<std::optional<LodBlock>> out(origins.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 4), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = computeBlock(reader, level - 1, origins[i]);
    });
    return out;
}

std::vector<BlockOrigin> sortedUnique(std::vector<BlockOrigin> v)
{
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

// --- coarse Hermite data --------------------------------------------------------------------------

/// The densities and materials of a level-k block and two layers of voxels around it (12^3): the
/// gradient at a crossing's far end reads one voxel beyond it.
struct Surroundings {
    static constexpr int kRing = 2;
    static constexpr int kEdge = kDim + 2 * kRing;
    std::array<uint8_t, kEdge * kEdge * kEdge> density{};
    std::array<MaterialId, kEdge * kEdge * kEdge> material{};
    static int at(int x, int y, int z) { return ((x + kRing) * kEdge + (y + kRing)) * kEdge + (z + kRing); }
    double densityAt(int x, int y, int z) const { return double(density[std::size_t(at(x, y, z))]); }
    MaterialId solidMaterial(int x, int y, int z) const
    {
        const int i = at(x, y, z);
        return density[std::size_t(i)] >= kSolidDensity ? material[std::size_t(i)] : kEmptyMaterial;
    }
    /// The density gradient at a voxel: central differences smoothed over the 3x3 cross-section
    /// (Sobel weights), as the box-filtered occupancy is noisy at coarse levels.
    std::array<double, 3> gradient(int x, int y, int z) const
    {
        std::array<double, 3> g{0.0, 0.0, 0.0};
        for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j) {
                const double w = double((2 - std::abs(i)) * (2 - std::abs(j)));
                g[0] += w * (densityAt(x + 1, y + i, z + j) - densityAt(x - 1, y + i, z + j));
                g[1] += w * (densityAt(x + i, y + 1, z + j) - densityAt(x + i, y - 1, z + j));
                g[2] += w * (densityAt(x + i, y + j, z + 1) - densityAt(x + i, y + j, z - 1));
            }
        return g;
    }
};

Surroundings gather(const LevelReader& reader, int level, const BlockOrigin& origin)
{
    Surroundings s;
    constexpr int kRing = Surroundings::kRing;
    for (int bx = -1; bx <= 1; ++bx)
        for (int by = -1; by <= 1; ++by)
            for (int bz = -1; bz <= 1; ++bz) {
                const BlockView v =
                    reader.view(level, {origin[0] + bx * kDim, origin[1] + by * kDim, origin[2] + bz * kDim});
                const auto range = [=](int b) {
                    return b < 0 ? std::pair{kDim - kRing, kDim} : b > 0 ? std::pair{0, kRing} : std::pair{0, kDim};
                };
                const auto [x0, x1] = range(bx);
                const auto [y0, y1] = range(by);
                const auto [z0, z1] = range(bz);
                for (int x = x0; x < x1; ++x)
                    for (int y = y0; y < y1; ++y)
                        for (int z = z0; z < z1; ++z) {
                            const int i = Surroundings::at(x + bx * kDim, y + by * kDim, z + bz * kDim);
                            s.density[std::size_t(i)] = v.densityAt(offsetOf(x, y, z));
                            s.material[std::size_t(i)] = v.materialAt(offsetOf(x, y, z));
                        }
            }
    return s;
}

/// Level k's Hermite data for one block: materials where the density reaches half, a crossing on every
/// edge whose end materials differ, placed where the linearly interpolated density crosses half, with
/// the normal of the density's gradient there (pointing out of the solid).
HermiteLeafData coarseLeaf(const Surroundings& s)
{
    HermiteLeafData data;
    std::array<double, 3> gradient[2];
    for (int x = 0; x < kDim; ++x)
        for (int y = 0; y < kDim; ++y)
            for (int z = 0; z < kDim; ++z) {
                const int offset = offsetOf(x, y, z);
                const MaterialId from = s.solidMaterial(x, y, z);
                data.material[std::size_t(offset)].id = from;
                for (int axis = 0; axis < 3; ++axis) {
                    const int ux = x + (axis == 0), uy = y + (axis == 1), uz = z + (axis == 2);
                    const MaterialId to = s.solidMaterial(ux, uy, uz);
                    if (to == from) continue;
                    const double dv = s.density[std::size_t(Surroundings::at(x, y, z))];
                    const double du = s.density[std::size_t(Surroundings::at(ux, uy, uz))];
                    const bool occupancyChanges = (from == kEmptyMaterial) != (to == kEmptyMaterial);
                    const double threshold = kSolidDensity - 0.5;
                    const double t = occupancyChanges && du != dv ? std::clamp((threshold - dv) / (du - dv), 0.0, 1.0) : 0.5;
                    gradient[0] = s.gradient(x, y, z);
                    gradient[1] = s.gradient(ux, uy, uz);
                    std::array<double, 3> n{};
                    double length = 0.0;
                    for (int i = 0; i < 3; ++i) {
                        n[i] = -((1.0 - t) * gradient[0][i] + t * gradient[1][i]);
                        length += n[i] * n[i];
                    }
                    if (length > 0.0) {
                        for (double& c : n) c /= std::sqrt(length);
                    } else {
                        n = {0.0, 0.0, 0.0};
                        n[std::size_t(axis)] = from == kEmptyMaterial ? -1.0 : 1.0;
                    }
                    const int bit = HermiteLeaf::edgeBit(Index(offset), axis);
                    data.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                    data.samples.push_back(packSample(t, n));
                }
            }
    return data;
}

bool uniformWithoutSamples(const HermiteLeafData& data, MaterialValue& value)
{
    if (!data.samples.empty()) return false;
    value = data.material[0];
    return std::all_of(data.material.begin(), data.material.end(), [&](MaterialValue m) { return m == value; });
}

/// The blocks of `origins` and their 26 neighbours, sorted and unique: a block's coarse leaf reads
/// its neighbours' first layer.
std::vector<BlockOrigin> withNeighbours(const std::vector<BlockOrigin>& origins)
{
    std::vector<BlockOrigin> out;
    out.reserve(origins.size() * 27);
    for (const BlockOrigin& o : origins)
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) out.push_back({o[0] + dx * kDim, o[1] + dy * kDim, o[2] + dz * kDim});
    return sortedUnique(std::move(out));
}

} // namespace

LodPyramid::LodPyramid(int levels)
{
    if (levels < 1 || levels > kMaxLodLevels)
        throw std::invalid_argument("a pyramid has 1 to " + std::to_string(kMaxLodLevels) + " levels, not " +
                                    std::to_string(levels));
    levels_.resize(std::size_t(levels));
}

int LodPyramid::levelsFor(const Volume& volume)
{
    const VolumeStats s = volume.stats();
    int extent = 1;
    for (int i = 0; i < 3; ++i) extent = std::max(extent, s.bboxMax[std::size_t(i)] - s.bboxMin[std::size_t(i)] + 1);
    int levels = 1;
    while (levels < kMaxLodLevels && (extent >> levels) > 64) ++levels;
    return levels;
}

const std::map<BlockOrigin, LodBlock>& LodPyramid::blocks(int level) const
{
    if (level < 1 || level > levels()) throw std::out_of_range("no pyramid level " + std::to_string(level));
    return levels_[std::size_t(level - 1)];
}

void LodPyramid::build(const Volume& volume)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    for (auto& level : levels_) level.clear();
    const LevelReader reader(tree, levels_);
    std::vector<BlockOrigin> origins;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const Coord o = leaf->origin();
        origins.push_back(parentOf({o.x(), o.y(), o.z()}));
    }
    for (int k = 1; k <= levels(); ++k) {
        origins = sortedUnique(std::move(origins));
        std::vector<std::optional<LodBlock>> blocks = computeBlocks(reader, k, origins);
        Map& map = levels_[std::size_t(k - 1)];
        std::vector<BlockOrigin> parents;
        for (std::size_t i = 0; i < origins.size(); ++i) {
            if (!blocks[i]) continue;
            map.emplace_hint(map.end(), origins[i], std::move(*blocks[i]));
            parents.push_back(parentOf(origins[i]));
        }
        origins = std::move(parents);
    }
}

LodUpdate LodPyramid::update(const Volume& volume, const std::vector<BlockChange>& changes)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    const LevelReader reader(tree, levels_);
    LodUpdate result;
    result.changedBlocks.resize(levels_.size());
    std::vector<BlockOrigin> origins;
    for (const BlockChange& c : changes) origins.push_back(parentOf(c.origin));
    for (int k = 1; k <= levels(); ++k) {
        origins = sortedUnique(std::move(origins));
        std::vector<std::optional<LodBlock>> blocks = computeBlocks(reader, k, origins);
        result.blocksRecomputed += origins.size();
        Map& map = levels_[std::size_t(k - 1)];
        std::vector<BlockOrigin>& changed = result.changedBlocks[std::size_t(k - 1)];
        for (std::size_t i = 0; i < origins.size(); ++i) {
            const auto it = map.find(origins[i]);
            if (!blocks[i]) {
                if (it == map.end()) continue;
                map.erase(it);
            } else if (it == map.end()) {
                map.emplace(origins[i], std::move(*blocks[i]));
            } else if (it->second == *blocks[i]) {
                continue;
            } else {
                it->second = std::move(*blocks[i]);
            }
            changed.push_back(origins[i]);
        }
        origins.clear();
        for (const BlockOrigin& o : changed) origins.push_back(parentOf(o));
    }
    return result;
}

Volume LodPyramid::coarseVolume(const Volume& fine, int level) const
{
    Volume coarse(fine.voxelSize() * double(1 << level));
    coarse.materials() = fine.materials();
    // Solid interiors first: each solid tile of the fine volume shrinks to its image at this level (a
    // block that holds part of an image and no leaf's footprint is uniform: one tile fills it all).
    // The blocks near the surface then replace what they cover.
    HermiteTree& out = coarse.impl().grid->tree();
    std::set<Coord> lowers;
    forEachTile(fine.impl().grid->constTree(), [&](const CoordBBox& tile, MaterialValue value) {
        if (!value.solid()) return;
        const int size = tile.dim().x() >> level;
        const Coord o(tile.min().x() >> level, tile.min().y() >> level, tile.min().z() >> level);
        if (size >= kUpperDim) out.addTile(3, o, value, false);
        else if (size >= kLowerDim) out.addTile(2, o, value, false);
        else if (size < kDim) out.addTile(1, alignDown(o, kDim), value, false), lowers.insert(alignDown(o, kLowerDim));
        else
            for (int x = 0; x < size; x += kDim)
                for (int y = 0; y < size; y += kDim)
                    for (int z = 0; z < size; z += kDim) out.addTile(1, o.offsetBy(x, y, z), value, false);
        lowers.insert(alignDown(o, kLowerDim));
    });
    pruneNodes(out, lowers);
    std::vector<BlockOrigin> origins;
    for (const auto& [origin, block] : blocks(level)) origins.push_back(origin);
    updateCoarseVolume(fine, level, origins, coarse);
    return coarse;
}

std::vector<BlockChange> LodPyramid::updateCoarseVolume(const Volume& fine, int level,
                                                        const std::vector<BlockOrigin>& blocks, Volume& coarse) const
{
    if (level < 1 || level > levels()) throw std::out_of_range("no pyramid level " + std::to_string(level));
    const HermiteTree& tree = fine.impl().grid->constTree();
    const LevelReader reader(tree, levels_);
    const std::vector<BlockOrigin> origins = withNeighbours(blocks);
    std::vector<HermiteLeafData> data(origins.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 8), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) data[i] = coarseLeaf(gather(reader, level, origins[i]));
    });
    HermiteTree& out = coarse.impl().grid->tree();
    std::vector<BlockChange> changes;
    std::set<Coord> lowers;
    for (std::size_t i = 0; i < origins.size(); ++i) {
        const Coord o(origins[i][0], origins[i][1], origins[i][2]);
        MaterialValue uniform;
        const bool isUniform = uniformWithoutSamples(data[i], uniform);
        const HermiteLeaf* leaf = out.probeConstLeaf(o);
        BlockChange whole;
        whole.origin = origins[i];
        if (isUniform) {
            if (!leaf && out.getValue(o) == uniform) continue;
            out.addTile(1, o, uniform, false);
            lowers.insert(alignDown(o, kLowerDim));
            changes.push_back(whole);
        } else if (leaf) {
            if (const std::optional<BlockChange> change = leaf->changeTo(data[i])) {
                out.touchLeaf(o)->assign(std::move(data[i]));
                changes.push_back(*change);
            }
        } else {
            out.touchLeaf(o)->assign(std::move(data[i]));
            changes.push_back(whole);
        }
    }
    pruneNodes(out, lowers);
    return changes;
}

} // namespace vdbclay::wavelet
