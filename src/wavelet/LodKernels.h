// The per-block kernels of the LOD pyramid, over any source of level-k blocks: the Haar low-pass that
// makes a level-(k+1) block from its eight children, and the coarse Hermite data of a level-k block
// from its densities and those of its neighbours. LodPyramid runs them over a whole volume in memory;
// the scene store (scene/StoreLod.h) runs them brick by brick.
//
// Heavy header (OpenVDB leaf types): include it only where the kernels run.
#pragma once

#include "vdb_hermite/HermiteGrid.h"
#include "wavelet/LodPyramid.h"

#include <optional>
#include <vector>

namespace vdbclay::wavelet {

/// One 8^3 block of level k as the kernels read it: a block of the pyramid, a leaf at level 0, or the
/// uniform value of the tile its footprint lies in.
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

/// Where the kernels read level-k blocks (level 0: the sculpted volume's leaves and tiles).
class LevelSource {
public:
    virtual ~LevelSource() = default;
    /// The level-k block at `origin` (level-k index space, a multiple of 8). The views stay valid while
    /// the kernel that asked runs.
    virtual BlockView view(int level, const BlockOrigin& origin) const = 0;
};

/// A view of a block with a uniform value (a tile's material; solid means full density).
inline BlockView uniformView(MaterialId material)
{
    BlockView v;
    v.material = material;
    v.density = material == kEmptyMaterial ? uint8_t(0) : uint8_t(kFullDensity);
    return v;
}

/// The level-`level` block at `origin` from its eight level-(level - 1) children, or nullopt when none
/// of them is a block (its footprint holds no leaf; it then has the uniform value of its children).
/// Density: the integer Haar low-pass (x, then y, then z, as liftingDecompose3D); material: the one
/// with the largest density among the eight (ties: lower id).
std::optional<LodBlock> lowPassBlock(const LevelSource& source, int level, const BlockOrigin& origin);

/// Level k's Hermite data for one block: materials where the density reaches half, a crossing on every
/// edge whose end materials differ, placed where the linearly interpolated density crosses half, with
/// the normal of the density's gradient there. Reads two voxels into the 26 neighbouring blocks.
HermiteLeafData coarseBlockData(const LevelSource& source, int level, const BlockOrigin& origin);

/// Writes the coarse Hermite data of exactly the given level-k blocks into `coarse` (in parallel): a
/// leaf, or a tile where a block is uniform without samples. Returns what changed, for the mesher.
std::vector<BlockChange> writeCoarseBlocks(const LevelSource& source, int level, const std::vector<BlockOrigin>& origins,
                                           Volume& coarse);

} // namespace vdbclay::wavelet
