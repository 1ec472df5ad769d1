#include "mesher/BlockSets.h"

#include <algorithm>

namespace vdbclay::mesher_detail {

namespace {

/// A box of blocks, in units of blocks (inclusive).
struct BlockBox {
    std::array<int64_t, 3> lo, hi;
};

int64_t inBlocks(int64_t voxel) { return voxel >> kLeafLog2Dim; } // rounds down

/// The blocks in any of the boxes, sorted and unique. Compact sets (one edit's blocks) are marked in a
/// grid of flags over their bounds, which gives them in order without sorting; scattered ones are sorted.
std::vector<BlockOrigin> blocksIn(const std::vector<BlockBox>& boxes)
{
    std::vector<BlockOrigin> out;
    if (boxes.empty()) return out;
    auto origin = [](int64_t x, int64_t y, int64_t z) {
        return BlockOrigin{int32_t(x * kLeafDim), int32_t(y * kLeafDim), int32_t(z * kLeafDim)};
    };
    std::array<int64_t, 3> lo = boxes.front().lo, hi = boxes.front().hi;
    int64_t marks = 0;
    for (const BlockBox& box : boxes) {
        int64_t cells = 1;
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], box.lo[a]);
            hi[a] = std::max(hi[a], box.hi[a]);
            cells *= box.hi[a] - box.lo[a] + 1;
        }
        marks += cells;
    }
    // The grid costs a pass over its cells: keep that within a small multiple of the marking work.
    const int64_t maxCells = marks * 16 + 4096;
    int64_t dim[3], cells = 1;
    bool compact = true;
    for (int a = 0; a < 3 && compact; ++a) {
        dim[a] = hi[a] - lo[a] + 1;
        compact = dim[a] <= maxCells / cells;
        cells *= dim[a];
    }
    if (!compact) {
        out.reserve(std::size_t(marks));
        for (const BlockBox& box : boxes)
            for (int64_t x = box.lo[0]; x <= box.hi[0]; ++x)
                for (int64_t y = box.lo[1]; y <= box.hi[1]; ++y)
                    for (int64_t z = box.lo[2]; z <= box.hi[2]; ++z) out.push_back(origin(x, y, z));
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        return out;
    }
    std::vector<uint8_t> marked(std::size_t(cells), 0);
    for (const BlockBox& box : boxes)
        for (int64_t x = box.lo[0]; x <= box.hi[0]; ++x)
            for (int64_t y = box.lo[1]; y <= box.hi[1]; ++y) {
                uint8_t* row = marked.data() + ((x - lo[0]) * dim[1] + (y - lo[1])) * dim[2];
                std::fill(row + (box.lo[2] - lo[2]), row + (box.hi[2] - lo[2]) + 1, uint8_t(1));
            }
    std::size_t i = 0;
    for (int64_t x = 0; x < dim[0]; ++x)
        for (int64_t y = 0; y < dim[1]; ++y)
            for (int64_t z = 0; z < dim[2]; ++z, ++i)
                if (marked[i]) out.push_back(origin(lo[0] + x, lo[1] + y, lo[2] + z));
    return out;
}

} // namespace

std::vector<BlockOrigin> blocksAround(const std::vector<BlockOrigin>& blocks, const std::vector<BlockOrigin>& offsets)
{
    std::vector<BlockBox> boxes;
    boxes.reserve(blocks.size() * offsets.size());
    for (const BlockOrigin& b : blocks)
        for (const BlockOrigin& d : offsets) {
            BlockBox box;
            for (int a = 0; a < 3; ++a) box.lo[a] = box.hi[a] = inBlocks(int64_t(b[a]) + d[a]);
            boxes.push_back(box);
        }
    return blocksIn(boxes);
}

std::vector<BlockOrigin> leavesReaching(const std::vector<BlockChange>& changes, const LeafReach& reach,
                                        const std::vector<BlockOrigin>& alsoBlocks)
{
    // A leaf at L reads L + low .. L + high: it meets the changed voxels B + min .. B + max where
    // L lies in B + min - high .. B + max - low.
    std::vector<BlockBox> boxes;
    boxes.reserve(changes.size() + alsoBlocks.size());
    for (const BlockChange& c : changes) {
        BlockBox& box = boxes.emplace_back();
        for (int a = 0; a < 3; ++a) {
            box.lo[a] = inBlocks(int64_t(c.origin[a]) + c.min[a] - reach.high + kLeafDim - 1);
            box.hi[a] = inBlocks(int64_t(c.origin[a]) + c.max[a] - reach.low);
        }
    }
    for (const BlockOrigin& b : alsoBlocks) {
        BlockBox& box = boxes.emplace_back();
        for (int a = 0; a < 3; ++a) box.lo[a] = box.hi[a] = inBlocks(b[a]);
    }
    return blocksIn(boxes);
}

} // namespace vdbclay::mesher_detail
