// The leaf-sized blocks of a LeafAlignedBox: how box copies (VolumeRegions) and brick records
// (RegionCodec) number, visit and replace them.
//
// Heavy header (OpenVDB tree types): include it only in those two.
#pragma once

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/VolumeRegions.h"

#include <cstddef>
#include <set>
#include <utility>

namespace vdbclay::region_blocks {

inline std::size_t blocksPerSide(const LeafAlignedBox& box) { return std::size_t(box.edge / kLeafDim); }

inline std::size_t blockCount(const LeafAlignedBox& box)
{
    const std::size_t n = blocksPerSide(box);
    return n * n * n;
}

/// The origin of block `b` of the box, numbered x-major like voxel offsets in a leaf.
inline Coord blockOrigin(const LeafAlignedBox& box, std::size_t b)
{
    const std::size_t n = blocksPerSide(box);
    return Coord(box.min[0] + int32_t(b / (n * n)) * kLeafDim, box.min[1] + int32_t((b / n) % n) * kLeafDim,
                 box.min[2] + int32_t(b % n) * kLeafDim);
}

/// Calls fn(b, origin) for every block in that numbering.
template<typename Fn>
void forEachBlock(const LeafAlignedBox& box, Fn&& fn)
{
    const std::size_t count = blockCount(box);
    for (std::size_t b = 0; b < count; ++b) fn(b, blockOrigin(box, b));
}

/// Replaces every block of the box in `tree` by what content(b, origin) gives, a leaf to adopt or, where
/// that is null, a tile value, then folds the 128^3 nodes that became uniform.
template<typename Content>
void replaceBlocks(HermiteTree& tree, const LeafAlignedBox& box, Content&& content)
{
    std::set<Coord> lowers;
    forEachBlock(box, [&](std::size_t b, const Coord& o) {
        const std::pair<HermiteLeaf*, MaterialValue> block = content(b, o);
        if (block.first) tree.addLeaf(block.first);
        else tree.addTile(1, o, block.second, false);
        lowers.insert(alignDown(o, kLowerDim));
    });
    pruneNodes(tree, lowers);
}

} // namespace vdbclay::region_blocks
