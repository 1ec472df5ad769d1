// The level-of-detail pyramid of a volume: level k is a field at voxel size 2^k for the whole scene,
// built per leaf and up the tree with the integer Haar low-pass (Haar.h) of the voxels' solid density,
// and the coarse Hermite data derived from it, which the same CMS mesher meshes at every level.
//
// Level k's voxel i stands for the cube of 2^k level-0 voxels starting at 2^k * i, so it sits at the
// cube's centre, 2^k * i + (2^k - 1) / 2 in level-0 index space (levelOffset()). The coarse Hermite data
// resamples the field at level k's lattice points, point i at level-0 point 2^k * i, so that every
// level's lattice lies on the finer ones' and each level's surface lies on the fine one in place (no
// offset to add when meshing it). The field is kept in
// blocks of 8^3 level-k voxels; a block exists where its footprint (8 * 2^k level-0 voxels per side)
// holds a level-0 leaf. Elsewhere the footprint lies inside one tile of the volume, whose value stands
// for every level.
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/BlockChange.h"
#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

namespace vdbclay::wavelet {

using BlockOrigin = std::array<int32_t, 3>;

/// Solid density at full occupancy; a coarse voxel is solid where its density is at least half of it.
constexpr int kFullDensity = 255;
constexpr int kSolidDensity = 128;
constexpr int kMaxLodLevels = 10;

/// The level-(k+1) block whose footprint holds the level-k block at `origin`: floor(origin / 16) * 8.
inline BlockOrigin parentBlock(const BlockOrigin& o)
{
    return {(o[0] >> 4) * kLeafDim, (o[1] >> 4) * kLeafDim, (o[2] >> 4) * kLeafDim};
}

/// 8^3 voxels of one level: the Haar low-pass of the solid density, and the material that holds most
/// of each voxel's solid (0 where none).
struct LodBlock {
    std::array<uint8_t, kLeafDim * kLeafDim * kLeafDim> density{};
    std::array<MaterialId, kLeafDim * kLeafDim * kLeafDim> material{};
    friend bool operator==(const LodBlock& a, const LodBlock& b)
    {
        return a.density == b.density && a.material == b.material;
    }
};

/// What an update changed: per level (index k - 1 for level k), the origins of the blocks recomputed
/// whose content changed, appeared or disappeared, sorted.
struct LodUpdate {
    std::vector<std::vector<BlockOrigin>> changedBlocks;
    std::size_t blocksRecomputed = 0;
};

class LodPyramid {
public:
    /// levels: 1 .. kMaxLodLevels (throws std::invalid_argument otherwise).
    explicit LodPyramid(int levels);

    /// The number of levels that brings a volume's bounds down to about one brick of 64 voxels per side.
    static int levelsFor(const Volume& volume);
    /// The same for bounds of `extent` voxels along their longest side.
    static int levelsForExtent(int extent);

    int levels() const { return int(levels_.size()); }

    /// Computes every level from the volume (parallel over blocks; the same for any thread count).
    void build(const Volume& volume);
    /// Recomputes only the blocks above the blocks an edit changed (EditStats::blockChanges), bottom-up.
    /// `volume` is the edited volume. Afterwards the pyramid equals what build(volume) gives.
    LodUpdate update(const Volume& volume, const std::vector<BlockChange>& changes);

    /// The blocks of level k (1 .. levels()).
    const std::map<BlockOrigin, LodBlock>& blocks(int level) const;

    /// Level k's Hermite data: a volume of voxel size 2^k times the fine one, whose mesh approximates the
    /// fine surface in place. Materials are the fine volume's table.
    Volume coarseVolume(const Volume& fine, int level) const;
    /// Re-derives the coarse leaves around the given level-k blocks (an update's changedBlocks) in a
    /// volume coarseVolume() made, and returns what changed in it for the mesher (MeshChunkSet::update).
    std::vector<BlockChange> updateCoarseVolume(const Volume& fine, int level, const std::vector<BlockOrigin>& blocks,
                                                Volume& coarse) const;

    /// Level-0 index-space position of level k's voxel 0, per axis: (2^k - 1) / 2.
    static double levelOffset(int level) { return (double(1 << level) - 1.0) / 2.0; }

    friend bool operator==(const LodPyramid& a, const LodPyramid& b) { return a.levels_ == b.levels_; }

private:
    std::vector<std::map<BlockOrigin, LodBlock>> levels_; // levels_[k - 1]: level k
};

} // namespace vdbclay::wavelet
