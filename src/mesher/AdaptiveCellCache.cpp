#include "mesher/AdaptiveCellCache.h"

#include "mesher/BlockSets.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_set>

namespace vdbclay::mesher_detail {

namespace {

/// The cells of each leaf, subdivided in parallel; `keep` (optional) keeps what they read.
std::vector<LeafCellSizes> subdivideLeaves(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                                           const MeshOptions& options, LeafSurroundingsStore* keep = nullptr)
{
    std::vector<LeafCellSizes> sizes(leaves.size());
    if (keep) {
        keep->resize(leaves.size());
        for (std::size_t i = 0; i < leaves.size(); ++i) keep->origins[i] = leaves[i]->origin();
    }
    const double cosHalfSpread = std::cos(0.5 * options.subdivisionAngleDegrees * M_PI / 180.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 2), [&](const auto& range) {
        ConstAccessor acc(tree);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const HermiteLeaf& leaf = *leaves[i];
            LeafSurroundings unkept;
            LeafSurroundings& read = keep ? keep->leaves[i] : unkept;
            read.hood = Neighbourhood(leaf, acc);
            read.grid.fill(leaf, read.hood);
            SubdivisionCriteria criteria;
            criteria.maxCellSize = options.maxCellWidth;
            if (options.leafMaxCellWidth) {
                const Coord o = leaf.origin();
                criteria.maxCellSize = std::min(criteria.maxCellSize, options.leafMaxCellWidth({o.x(), o.y(), o.z()}));
            }
            criteria.cosHalfSpread = cosHalfSpread;
            sizes[i] = subdivideLeaf(read.grid, read.hood, criteria);
        }
    });
    return sizes;
}

} // namespace

void AdaptiveCellCache::prepare(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                                const MeshOptions& options)
{
    std::vector<const HermiteLeaf*> missing;
    std::unordered_set<Coord> queued;
    ConstAccessor acc(tree);
    auto add = [&](const HermiteLeaf* leaf) {
        if (leaf && !sizes_.count(leaf->origin()) && queued.insert(leaf->origin()).second) missing.push_back(leaf);
    };
    for (const HermiteLeaf* leaf : leaves) {
        add(leaf);
        for (int f = 0; f < 6; ++f) add(acc.probeConstLeaf(faceNeighbour(leaf->origin(), f)));
    }
    std::vector<LeafCellSizes> fresh = subdivideLeaves(tree, missing, options);
    for (std::size_t i = 0; i < missing.size(); ++i) sizes_.emplace(missing[i]->origin(), fresh[i]);
}

std::vector<std::array<int32_t, 3>> AdaptiveCellCache::refreshAround(const HermiteTree& tree,
                                                                     const std::vector<std::array<int32_t, 3>>& dirtyBlocks,
                                                                     const MeshOptions& options, LeafSurroundingsStore* keep)
{
    std::vector<BlockOrigin> readers;
    forEachLeafSubdividingWith(Coord(0), [&](const Coord& leaf) { readers.push_back({leaf.x(), leaf.y(), leaf.z()}); });

    std::vector<std::array<int32_t, 3>> changed;
    std::vector<const HermiteLeaf*> present;
    ConstAccessor acc(tree);
    for (const BlockOrigin& candidate : blocksAround(dirtyBlocks, readers)) {
        const Coord origin(candidate[0], candidate[1], candidate[2]);
        if (const HermiteLeaf* leaf = acc.probeConstLeaf(origin)) present.push_back(leaf);
        else if (sizes_.erase(origin)) changed.push_back({origin.x(), origin.y(), origin.z()});
    }
    const std::vector<LeafCellSizes> fresh = subdivideLeaves(tree, present, options, keep);
    for (std::size_t i = 0; i < present.size(); ++i) {
        const Coord origin = present[i]->origin();
        const auto [it, added] = sizes_.try_emplace(origin, fresh[i]);
        if (!added && std::memcmp(&it->second, &fresh[i], sizeof(LeafCellSizes)) == 0) continue;
        it->second = fresh[i];
        changed.push_back({origin.x(), origin.y(), origin.z()});
    }
    return changed;
}

CellWidthField AdaptiveCellCache::around(const HermiteLeaf& leaf) const
{
    const LeafCellSizes* blocks[7] = {find(leaf.origin())};
    for (int f = 0; f < 6; ++f) blocks[1 + f] = find(faceNeighbour(leaf.origin(), f));
    return CellWidthField(leaf.origin(), blocks);
}

const LeafCellSizes* AdaptiveCellCache::find(const Coord& origin) const
{
    const auto it = sizes_.find(origin);
    return it == sizes_.end() ? nullptr : &it->second;
}

} // namespace vdbclay::mesher_detail
