#include "wavelet/MixedLevels.h"

#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace vdbclay::wavelet {

namespace {

using ConstAccessor = openvdb::tree::ValueAccessor<const HermiteTree>;
constexpr int kDim = kLeafDim;
constexpr double kThreshold = kSolidDensity - 0.5;

BlockOrigin blockOf(const Coord& p) { return {p.x() & ~(kDim - 1), p.y() & ~(kDim - 1), p.z() & ~(kDim - 1)}; }

/// The field a block shows, point by point: level 0's materials, or level k's low-pass reconstructed
/// piecewise-linearly between the centres of its voxels (level k's voxel i sits at 2^k i + (2^k - 1) / 2).
class MixedField {
public:
    MixedField(const Volume& fine, const LodPyramid& pyramid, const LevelOfBlock& levelOf)
        : tree_(fine.impl().grid->constTree()), acc_(tree_), pyramid_(pyramid), levelOf_(levelOf)
    {
    }

    struct Point {
        MaterialId material = kEmptyMaterial;
        double density = 0.0;
        int level = 0;
    };

    Point at(const Coord& p)
    {
        const BlockOrigin block = blockOf(p);
        if (block != lastBlock_) lastBlock_ = block, lastLevel_ = std::clamp(levelOf_(block), 0, pyramid_.levels());
        Point out;
        out.level = lastLevel_;
        if (lastLevel_ == 0) {
            out.material = acc_.getValue(p).id;
            out.density = out.material != kEmptyMaterial ? kFullDensity : 0.0;
            return out;
        }
        const int k = lastLevel_;
        const double scale = double(1 << k), shift = (scale - 1.0) / 2.0;
        double x[3] = {(p.x() - shift) / scale, (p.y() - shift) / scale, (p.z() - shift) / scale};
        int base[3];
        double f[3];
        for (int a = 0; a < 3; ++a) base[a] = int(std::floor(x[a])), f[a] = x[a] - base[a];
        double best = -1.0;
        for (int c = 0; c < 8; ++c) {
            const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
            const double w = (dx ? f[0] : 1.0 - f[0]) * (dy ? f[1] : 1.0 - f[1]) * (dz ? f[2] : 1.0 - f[2]);
            const auto [density, material] = sample(k, Coord(base[0] + dx, base[1] + dy, base[2] + dz));
            out.density += w * density;
            // The material of the solid that weighs most at this point.
            if (material != kEmptyMaterial && w * density > best) best = w * density, out.material = material;
        }
        if (out.density < kThreshold) out.material = kEmptyMaterial;
        return out;
    }

    /// The density gradient at a point shown at a coarse level, per level-0 voxel: level k's central
    /// differences at its voxels, interpolated like the density, so normals turn smoothly across its
    /// voxels (and its adaptive cells can stay wide).
    std::array<double, 3> coarseGradient(const Coord& p, int k)
    {
        const double scale = double(1 << k), shift = (scale - 1.0) / 2.0;
        double x[3] = {(p.x() - shift) / scale, (p.y() - shift) / scale, (p.z() - shift) / scale};
        int base[3];
        double f[3];
        for (int a = 0; a < 3; ++a) base[a] = int(std::floor(x[a])), f[a] = x[a] - base[a];
        std::array<double, 3> g{0.0, 0.0, 0.0};
        for (int c = 0; c < 8; ++c) {
            const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
            const double w = (dx ? f[0] : 1.0 - f[0]) * (dy ? f[1] : 1.0 - f[1]) * (dz ? f[2] : 1.0 - f[2]);
            const Coord q(base[0] + dx, base[1] + dy, base[2] + dz);
            for (int a = 0; a < 3; ++a) {
                const Coord step(a == 0, a == 1, a == 2);
                g[std::size_t(a)] += w * (sample(k, q + step).first - sample(k, q - step).first) / (2.0 * scale);
            }
        }
        return g;
    }

private:
    std::pair<double, MaterialId> sample(int level, const Coord& c)
    {
        const BlockOrigin origin = blockOf(c);
        if (level != cachedLevel_ || origin != cachedOrigin_) {
            cachedLevel_ = level;
            cachedOrigin_ = origin;
            const auto& blocks = pyramid_.blocks(level);
            const auto it = blocks.find(origin);
            cached_ = it == blocks.end() ? nullptr : &it->second;
            if (!cached_) {
                // No block: its footprint lies inside one tile of the fine volume.
                cachedTile_ = acc_.getValue(Coord(c.x() * (1 << level), c.y() * (1 << level), c.z() * (1 << level))).id;
            }
        }
        if (!cached_) return {cachedTile_ != kEmptyMaterial ? double(kFullDensity) : 0.0, cachedTile_};
        const int offset = ((c.x() & (kDim - 1)) << 6) | ((c.y() & (kDim - 1)) << 3) | (c.z() & (kDim - 1));
        return {double(cached_->density[std::size_t(offset)]), cached_->material[std::size_t(offset)]};
    }

    const HermiteTree& tree_;
    ConstAccessor acc_;
    const LodPyramid& pyramid_;
    const LevelOfBlock& levelOf_;
    BlockOrigin lastBlock_{INT32_MIN, 0, 0};
    int lastLevel_ = 0;
    int cachedLevel_ = -1;
    BlockOrigin cachedOrigin_{INT32_MIN, 0, 0};
    const LodBlock* cached_ = nullptr;
    MaterialId cachedTile_ = kEmptyMaterial;
};

/// One block of the mixed volume. Edges between two level-0 points keep level 0's sample; every other
/// edge whose materials differ gets the crossing of the linearly interpolated density and the normal
/// of its gradient.
HermiteLeafData mixedBlock(MixedField& field, const HermiteTree& fine, const BlockOrigin& o)
{
    constexpr int kEdge = kDim + 3; // -1 .. 9
    std::vector<MixedField::Point> points(std::size_t(kEdge) * kEdge * kEdge);
    const auto at = [&](int x, int y, int z) -> MixedField::Point& {
        return points[(std::size_t(x + 1) * kEdge + std::size_t(y + 1)) * kEdge + std::size_t(z + 1)];
    };
    for (int x = -1; x <= kDim + 1; ++x)
        for (int y = -1; y <= kDim + 1; ++y)
            for (int z = -1; z <= kDim + 1; ++z) at(x, y, z) = field.at(Coord(o[0] + x, o[1] + y, o[2] + z));
    const auto gradient = [&](int x, int y, int z) {
        const auto d = [&](int i, int j, int k) {
            return at(std::clamp(i, -1, kDim + 1), std::clamp(j, -1, kDim + 1), std::clamp(k, -1, kDim + 1)).density;
        };
        return std::array<double, 3>{d(x + 1, y, z) - d(x - 1, y, z), d(x, y + 1, z) - d(x, y - 1, z), d(x, y, z + 1) - d(x, y, z - 1)};
    };
    const HermiteLeaf* fineLeaf = fine.probeConstLeaf(Coord(o[0], o[1], o[2]));
    HermiteLeafData data;
    for (int x = 0; x < kDim; ++x)
        for (int y = 0; y < kDim; ++y)
            for (int z = 0; z < kDim; ++z) {
                const Index offset = Index((x << 6) | (y << 3) | z);
                const MixedField::Point& v = at(x, y, z);
                data.material[offset].id = v.material;
                for (int axis = 0; axis < 3; ++axis) {
                    const int ux = x + (axis == 0), uy = y + (axis == 1), uz = z + (axis == 2);
                    const MixedField::Point& u = at(ux, uy, uz);
                    if (u.material == v.material) continue;
                    const int bit = HermiteLeaf::edgeBit(offset, axis);
                    data.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                    const PackedSample* kept = v.level == 0 && u.level == 0 && fineLeaf ? fineLeaf->sample(offset, axis) : nullptr;
                    if (kept) {
                        data.samples.push_back(*kept);
                        continue;
                    }
                    const bool occupancy = (v.material == kEmptyMaterial) != (u.material == kEmptyMaterial);
                    const double t = occupancy && u.density != v.density
                                         ? std::clamp((kThreshold - v.density) / (u.density - v.density), 0.0, 1.0)
                                         : 0.5;
                    const auto gradientOf = [&](const MixedField::Point& point, int i, int j, int k) {
                        return point.level > 0 ? field.coarseGradient(Coord(o[0] + i, o[1] + j, o[2] + k), point.level)
                                               : gradient(i, j, k);
                    };
                    const auto gv = gradientOf(v, x, y, z), gu = gradientOf(u, ux, uy, uz);
                    std::array<double, 3> n{};
                    double length = 0.0;
                    for (int i = 0; i < 3; ++i) {
                        n[std::size_t(i)] = -((1.0 - t) * gv[std::size_t(i)] + t * gu[std::size_t(i)]);
                        length += n[std::size_t(i)] * n[std::size_t(i)];
                    }
                    if (length > 0.0) {
                        for (double& c : n) c /= std::sqrt(length);
                    } else {
                        n = {0.0, 0.0, 0.0};
                        n[std::size_t(axis)] = v.material == kEmptyMaterial ? -1.0 : 1.0;
                    }
                    data.samples.push_back(packSample(t, n));
                }
            }
    return data;
}

} // namespace

Volume mixedLevelVolume(const Volume& fine, const LodPyramid& pyramid, const LevelOfBlock& levelOf)
{
    const HermiteTree& tree = fine.impl().grid->constTree();
    // Blocks where a surface of some level can lie: around the fine leaves, as far as the coarsest
    // level's surface can reach (its density averages the fine voxels up to 1.5 of its voxels away).
    const int reach = 1 + (3 * (1 << pyramid.levels()) + 2 * kDim - 1) / (2 * kDim);
    std::set<BlockOrigin> candidates;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const Coord o = leaf->origin();
        for (int dx = -reach; dx <= reach; ++dx)
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dz = -reach; dz <= reach; ++dz)
                    candidates.insert({o.x() + dx * kDim, o.y() + dy * kDim, o.z() + dz * kDim});
    }
    const std::vector<BlockOrigin> blocks(candidates.begin(), candidates.end());
    std::vector<HermiteLeafData> data(blocks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 16), [&](const auto& range) {
        MixedField field(fine, pyramid, levelOf);
        for (std::size_t i = range.begin(); i != range.end(); ++i) data[i] = mixedBlock(field, tree, blocks[i]);
    });

    Volume out(fine.voxelSize());
    out.materials() = fine.materials();
    HermiteTree& dst = out.impl().grid->tree();
    // Interiors from the fine volume's tiles; the blocks near a surface replace what they cover.
    forEachTile(tree, [&](const CoordBBox& tile, MaterialValue value) {
        if (!value.solid()) return;
        const int level = tile.dim().x() >= kUpperDim ? 3 : tile.dim().x() >= kLowerDim ? 2 : 1;
        dst.addTile(level, tile.min(), value, false);
    });
    std::set<Coord> lowers;
    for (std::size_t i = 0; i < blocks.size(); ++i) {
        const Coord o(blocks[i][0], blocks[i][1], blocks[i][2]);
        lowers.insert(alignDown(o, kLowerDim));
        const MaterialValue first = data[i].material[0];
        const bool uniform = data[i].samples.empty() &&
                             std::all_of(data[i].material.begin(), data[i].material.end(), [&](MaterialValue m) { return m == first; });
        if (uniform) dst.addTile(1, o, first, false);
        else dst.touchLeaf(o)->assign(std::move(data[i]));
    }
    pruneNodes(dst, lowers);
    return out;
}

} // namespace vdbclay::wavelet
