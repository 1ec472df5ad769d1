// Internal to the mesher: sets of leaf-sized blocks around other blocks (the leaves an edit's blocks
// reach), sorted and unique. Light: no OpenVDB templates.
#pragma once

#include "vdb_hermite/BlockChange.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay::mesher_detail {

using BlockOrigin = std::array<int32_t, 3>;

/// The voxels a leaf's work reads, per axis in leaf-local coordinates (inclusive): an edit that changes
/// none of them leaves that work's result as it was.
struct LeafReach {
    int low = 0;
    int high = kLeafDim - 1;
};

/// The blocks at each of `offsets` (in voxels, multiples of the leaf size) from each of `blocks`
/// (leaf-aligned origins), sorted and unique.
std::vector<BlockOrigin> blocksAround(const std::vector<BlockOrigin>& blocks, const std::vector<BlockOrigin>& offsets);

/// The leaves whose `reach` holds a changed voxel of one of `changes`, and the blocks in `alsoBlocks`
/// (leaf-aligned origins, in any order), sorted and unique (whether or not a leaf is there).
std::vector<BlockOrigin> leavesReaching(const std::vector<BlockChange>& changes, const LeafReach& reach,
                                        const std::vector<BlockOrigin>& alsoBlocks = {});

} // namespace vdbclay::mesher_detail
