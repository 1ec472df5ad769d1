#include "wavelet/LodKernels.h"

#include "wavelet/Haar.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace vdbclay::wavelet {

namespace {

constexpr int kDim = kLeafDim;
constexpr int kHalf = kDim / 2;

inline int offsetOf(int x, int y, int z) { return (x << (2 * kLeafLog2Dim)) | (y << kLeafLog2Dim) | z; }

/// The densities and materials of a level-k block and two layers of voxels around it (12^3): a point's
/// resampled density reads the voxel below it, and the gradient at a crossing's far end one point beyond.
struct Surroundings {
    static constexpr int kRing = 2;
    static constexpr int kEdge = kDim + 2 * kRing;
    std::array<uint8_t, kEdge * kEdge * kEdge> density{};
    std::array<MaterialId, kEdge * kEdge * kEdge> material{};
    static int at(int x, int y, int z) { return ((x + kRing) * kEdge + (y + kRing)) * kEdge + (z + kRing); }
};

Surroundings gather(const LevelSource& source, int level, const BlockOrigin& origin)
{
    Surroundings s;
    constexpr int kRing = Surroundings::kRing;
    for (int bx = -1; bx <= 1; ++bx)
        for (int by = -1; by <= 1; ++by)
            for (int bz = -1; bz <= 1; ++bz) {
                const BlockView v =
                    source.view(level, {origin[0] + bx * kDim, origin[1] + by * kDim, origin[2] + bz * kDim});
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

/// Level k's densities resampled at its lattice points. A level-k voxel's density stands for the cube of
/// 2^k level-0 points it averages, centred (2^k - 1) / 2 level-0 voxels past its lattice point, while the
/// cut shows level k's point i at level-0 point 2^k i (every level's lattice on the finer ones'). So a
/// point takes the trilinear density at its own place: per axis, t = 1/2 + 2^-(k+1) of the voxel at it
/// and the rest of the one below. Without it a coarse surface lies up to half its voxel off the fine one.
/// Holds the block's points and one ring around them (the gradient's reach): -1 .. 9 per axis.
struct AlignedField {
    static constexpr int kRing = 1;
    static constexpr int kEdge = kDim + 2 + 2 * kRing; // points -1 .. kDim + 1
    std::array<double, kEdge * kEdge * kEdge> density{};
    std::array<MaterialId, kEdge * kEdge * kEdge> material{}; // kEmptyMaterial where not solid
    static int at(int x, int y, int z) { return ((x + kRing) * kEdge + (y + kRing)) * kEdge + (z + kRing); }
    double densityAt(int x, int y, int z) const { return density[std::size_t(at(x, y, z))]; }
    MaterialId solidMaterial(int x, int y, int z) const { return material[std::size_t(at(x, y, z))]; }
    /// The density gradient at a point: central differences smoothed over the 3x3 cross-section
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

AlignedField alignedField(const Surroundings& s, int level)
{
    // Weights per axis of the voxel at the point (t) and the one below (1 - t).
    const double t = 0.5 + std::ldexp(1.0, -(level + 1));
    const double weightOf[2] = {1.0 - t, t};
    AlignedField out;
    for (int x = -AlignedField::kRing; x <= kDim + 1; ++x)
        for (int y = -AlignedField::kRing; y <= kDim + 1; ++y)
            for (int z = -AlignedField::kRing; z <= kDim + 1; ++z) {
                double density = 0.0;
                MaterialId materials[8];
                double solid[8];
                for (int c = 0; c < 8; ++c) {
                    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
                    const int i = Surroundings::at(x - 1 + dx, y - 1 + dy, z - 1 + dz);
                    solid[c] = weightOf[dx] * weightOf[dy] * weightOf[dz] * double(s.density[std::size_t(i)]);
                    materials[c] = s.material[std::size_t(i)];
                    density += solid[c];
                }
                const int at = AlignedField::at(x, y, z);
                out.density[std::size_t(at)] = density;
                if (density < kSolidDensity) continue; // material stays empty
                // The material holding most of the point's solid (ties: the lower id), as the low-pass picks.
                MaterialId best = kEmptyMaterial;
                double bestWeight = 0.0;
                for (int c = 0; c < 8; ++c) {
                    if (materials[c] == kEmptyMaterial || solid[c] <= 0.0) continue;
                    double weight = 0.0;
                    for (int d = 0; d < 8; ++d)
                        if (materials[d] == materials[c]) weight += solid[d];
                    if (weight > bestWeight || (weight == bestWeight && materials[c] < best)) best = materials[c], bestWeight = weight;
                }
                out.material[std::size_t(at)] = best;
            }
    return out;
}

HermiteLeafData coarseLeaf(const AlignedField& s)
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
                    const double dv = s.densityAt(x, y, z);
                    const double du = s.densityAt(ux, uy, uz);
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

} // namespace

std::optional<LodBlock> lowPassBlock(const LevelSource& source, int level, const BlockOrigin& origin)
{
    const int childLevel = level - 1;
    BlockView children[8];
    bool any = false;
    for (int c = 0; c < 8; ++c) {
        const BlockOrigin o{2 * origin[0] + (c & 1) * kDim, 2 * origin[1] + ((c >> 1) & 1) * kDim,
                            2 * origin[2] + ((c >> 2) & 1) * kDim};
        children[c] = source.view(childLevel, o);
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

HermiteLeafData coarseBlockData(const LevelSource& source, int level, const BlockOrigin& origin)
{
    // Most blocks of a brick lie in empty space or deep inside: when the block and its 26 neighbours
    // are all one tile, so is its coarse data (no edge changes material).
    bool uniform = true;
    MaterialId material = kEmptyMaterial;
    for (int i = 0; i < 27 && uniform; ++i) {
        const BlockView v = source.view(level, {origin[0] + (i % 3 - 1) * kDim, origin[1] + (i / 3 % 3 - 1) * kDim,
                                                origin[2] + (i / 9 - 1) * kDim});
        uniform = v.uniform() && (i == 0 || v.material == material);
        material = v.material;
    }
    if (!uniform) return coarseLeaf(alignedField(gather(source, level, origin), level));
    HermiteLeafData data;
    data.material.fill(MaterialValue{material});
    return data;
}

std::vector<BlockChange> writeCoarseBlocks(const LevelSource& source, int level, const std::vector<BlockOrigin>& origins,
                                           Volume& coarse)
{
    std::vector<HermiteLeafData> data(origins.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 8), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) data[i] = coarseBlockData(source, level, origins[i]);
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
