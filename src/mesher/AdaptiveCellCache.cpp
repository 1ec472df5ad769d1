#include "mesher/AdaptiveCellCache.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace vdbclay::mesher_detail {

void AdaptiveCellCache::prepare(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                                const MeshOptions& options)
{
    std::vector<const HermiteLeaf*> missing;
    std::unordered_set<Coord> queued;
    auto add = [&](const HermiteLeaf* leaf) {
        if (leaf && !sizes_.count(leaf->origin()) && queued.insert(leaf->origin()).second) missing.push_back(leaf);
    };
    for (const HermiteLeaf* leaf : leaves) {
        add(leaf);
        for (int f = 0; f < 6; ++f) add(tree.probeConstLeaf(faceNeighbour(leaf->origin(), f)));
    }
    std::vector<LeafCellSizes> fresh(missing.size());
    const double cosHalfSpread = std::cos(0.5 * options.subdivisionAngleDegrees * M_PI / 180.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, missing.size(), 8), [&](const auto& range) {
        ConstAccessor acc(tree);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const HermiteLeaf& leaf = *missing[i];
            const Neighbourhood hood(leaf, acc);
            SubdivisionCriteria criteria;
            criteria.maxCellSize = options.maxCellWidth;
            if (options.leafMaxCellWidth) {
                const Coord o = leaf.origin();
                criteria.maxCellSize = std::min(criteria.maxCellSize, options.leafMaxCellWidth({o.x(), o.y(), o.z()}));
            }
            criteria.cosHalfSpread = cosHalfSpread;
            fresh[i] = subdivideLeaf(CornerGrid(leaf, hood), hood, criteria);
        }
    });
    for (std::size_t i = 0; i < missing.size(); ++i) sizes_.emplace(missing[i]->origin(), fresh[i]);
}

CellWidthField AdaptiveCellCache::around(const HermiteLeaf& leaf) const
{
    const LeafCellSizes* blocks[7] = {find(leaf.origin())};
    for (int f = 0; f < 6; ++f) blocks[1 + f] = find(faceNeighbour(leaf.origin(), f));
    return CellWidthField(leaf.origin(), blocks);
}

void AdaptiveCellCache::forgetAround(const std::vector<std::array<int32_t, 3>>& dirtyBlocks)
{
    if (sizes_.empty()) return;
    for (const auto& b : dirtyBlocks)
        forEachLeafSubdividingWith(Coord(b[0], b[1], b[2]), [&](const Coord& leaf) { sizes_.erase(leaf); });
}

const LeafCellSizes* AdaptiveCellCache::find(const Coord& origin) const
{
    const auto it = sizes_.find(origin);
    return it == sizes_.end() ? nullptr : &it->second;
}

} // namespace vdbclay::mesher_detail
