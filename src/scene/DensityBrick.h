// The LOD pyramid's low-pass kept in the store, one record per brick of a level: the 8^3 blocks of
// density and materials (wavelet::LodBlock) that hold part of the surface, and the uniform material
// of every other block. Coarse levels are built from these brick by brick (StoreLod.h): level k+1 from
// level k's densities, never from the whole of level 0.
#pragma once

#include "wavelet/LodPyramid.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

/// Blocks per brick side (a brick is 8 leaves = 8 blocks of 8 voxels per side, at every level).
constexpr int kBlocksPerBrickSide = 8;
constexpr int kBlocksPerBrick = kBlocksPerBrickSide * kBlocksPerBrickSide * kBlocksPerBrickSide;

struct DensityBrick {
    /// Per block slot (x-major, like voxel offsets in a leaf): its index in `blocks`, or -1 where the
    /// block is uniform and `uniform` holds its material (full density where solid).
    std::array<int16_t, kBlocksPerBrick> slot;
    std::array<MaterialId, kBlocksPerBrick> uniform{};
    std::vector<wavelet::LodBlock> blocks;

    DensityBrick() { slot.fill(-1); }
    static int slotOf(int x, int y, int z) { return (x * kBlocksPerBrickSide + y) * kBlocksPerBrickSide + z; }
    const wavelet::LodBlock* block(int s) const { return slot[std::size_t(s)] < 0 ? nullptr : &blocks[std::size_t(slot[std::size_t(s)])]; }
    /// Whether block slot s holds the same content in both.
    bool sameSlot(const DensityBrick& other, int s) const;
    std::size_t memoryBytes() const { return sizeof(DensityBrick) + blocks.size() * sizeof(wavelet::LodBlock); }
};

/// The record's bytes: a small header, then the slots and blocks Blosc-compressed. The same content
/// always gives the same bytes.
std::string encodeDensityBrick(const DensityBrick& brick);
/// Reads encodeDensityBrick's bytes back; throws StoreError naming `what` when they are damaged or
/// name a material beyond `materialCount`.
DensityBrick decodeDensityBrick(const std::string& bytes, std::size_t materialCount, const std::string& what);

} // namespace vdbclay
