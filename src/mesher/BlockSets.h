// Internal to the mesher: sets of leaf-sized blocks around other blocks (the leaves an edit's blocks
// reach), sorted and unique. Light: no OpenVDB templates.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay::mesher_detail {

using BlockOrigin = std::array<int32_t, 3>;

/// The blocks at each of `offsets` (in voxels, multiples of the leaf size) from each of `blocks`
/// (leaf-aligned origins), sorted and unique. Compact sets (one edit's blocks) are marked in a grid of
/// flags over their bounds, which gives them in order without sorting; scattered ones are sorted.
std::vector<BlockOrigin> blocksAround(const std::vector<BlockOrigin>& blocks, const std::vector<BlockOrigin>& offsets);

} // namespace vdbclay::mesher_detail
