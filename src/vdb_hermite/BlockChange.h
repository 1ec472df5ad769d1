// What an edit changed in one leaf-sized block: handed from the sculpting kernels to whatever redoes
// work where a volume changed (the mesher's incremental update). Light: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay {

/// A leaf-sized block whose content changed, with the leaf-local bounds (inclusive, 0 .. 7 per axis) of
/// the voxels whose material or edge samples changed; a voxel's samples are those of its positive edges.
/// A block that turned from a leaf into a tile or back, or a tile that changed, changed throughout.
struct BlockChange {
    std::array<int32_t, 3> origin{0, 0, 0};
    std::array<uint8_t, 3> min{0, 0, 0};
    std::array<uint8_t, 3> max{kLeafDim - 1, kLeafDim - 1, kLeafDim - 1};
};

/// Changes throughout each of the given blocks: all that a list of changed blocks tells.
inline std::vector<BlockChange> wholeBlockChanges(const std::vector<std::array<int32_t, 3>>& origins)
{
    std::vector<BlockChange> changes(origins.size());
    for (std::size_t i = 0; i < origins.size(); ++i) changes[i].origin = origins[i];
    return changes;
}

} // namespace vdbclay
