#include "mesher/BlockSets.h"

#include "vdb_hermite/Volume.h"

#include <algorithm>
#include <optional>

namespace vdbclay::mesher_detail {

namespace {

/// blocksAround by marking, or nullopt where the blocks are not leaf-aligned or their bounds hold many
/// more cells than there are marks to make.
std::optional<std::vector<BlockOrigin>> markAround(const std::vector<BlockOrigin>& blocks, const std::vector<BlockOrigin>& offsets)
{
    if (blocks.empty() || offsets.empty()) return std::vector<BlockOrigin>{};
    // In units of blocks; origins are multiples of the leaf size, so shifting divides exactly.
    auto inBlocks = [](const BlockOrigin& b) {
        return std::array<int64_t, 3>{int64_t(b[0]) >> kLeafLog2Dim, int64_t(b[1]) >> kLeafLog2Dim, int64_t(b[2]) >> kLeafLog2Dim};
    };
    constexpr int32_t kMask = kLeafDim - 1;
    for (const auto* set : {&blocks, &offsets})
        for (const BlockOrigin& b : *set)
            if ((b[0] | b[1] | b[2]) & kMask) return std::nullopt;
    std::vector<std::array<int64_t, 3>> steps;
    steps.reserve(offsets.size());
    for (const BlockOrigin& d : offsets) steps.push_back(inBlocks(d));
    std::array<int64_t, 3> lo = inBlocks(blocks.front()), hi = lo;
    for (const BlockOrigin& b : blocks) {
        const auto c = inBlocks(b);
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
    }
    // The grid costs a pass over its cells: keep that within a small multiple of the marking work.
    const int64_t maxCells = int64_t(blocks.size() * offsets.size()) * 16 + 4096;
    int64_t dim[3], cells = 1;
    for (int a = 0; a < 3; ++a) {
        const auto [least, most] = std::minmax_element(steps.begin(), steps.end(),
                                                       [a](const auto& p, const auto& q) { return p[a] < q[a]; });
        lo[a] += (*least)[a];
        hi[a] += (*most)[a];
        dim[a] = hi[a] - lo[a] + 1;
        if (dim[a] > maxCells / cells) return std::nullopt;
        cells *= dim[a];
    }
    std::vector<uint8_t> marked(std::size_t(cells), 0);
    std::vector<int64_t> stepIndex;
    stepIndex.reserve(steps.size());
    for (const auto& d : steps) stepIndex.push_back((d[0] * dim[1] + d[1]) * dim[2] + d[2]);
    for (const BlockOrigin& b : blocks) {
        const auto c = inBlocks(b);
        const int64_t at = ((c[0] - lo[0]) * dim[1] + (c[1] - lo[1])) * dim[2] + (c[2] - lo[2]);
        for (const int64_t step : stepIndex) marked[std::size_t(at + step)] = 1;
    }
    std::vector<BlockOrigin> out;
    std::size_t i = 0;
    for (int64_t x = 0; x < dim[0]; ++x)
        for (int64_t y = 0; y < dim[1]; ++y)
            for (int64_t z = 0; z < dim[2]; ++z, ++i)
                if (marked[i])
                    out.push_back({int32_t((lo[0] + x) * kLeafDim), int32_t((lo[1] + y) * kLeafDim), int32_t((lo[2] + z) * kLeafDim)});
    return out;
}

} // namespace

std::vector<BlockOrigin> blocksAround(const std::vector<BlockOrigin>& blocks, const std::vector<BlockOrigin>& offsets)
{
    if (auto marked = markAround(blocks, offsets)) return std::move(*marked);
    std::vector<BlockOrigin> out;
    out.reserve(blocks.size() * offsets.size());
    for (const BlockOrigin& b : blocks)
        for (const BlockOrigin& d : offsets) out.push_back({b[0] + d[0], b[1] + d[1], b[2] + d[2]});
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

} // namespace vdbclay::mesher_detail
