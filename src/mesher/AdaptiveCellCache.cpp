#include "mesher/AdaptiveCellCache.h"

#include "mesher/BlockSets.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <unordered_set>

namespace vdbclay::mesher_detail {

namespace {

/// Subdivides each leaf in parallel and hands its cells to store(i, sizes) on the thread that made them;
/// `keep` (optional) keeps what they read.
template<typename Store>
void subdivideLeaves(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves, const MeshOptions& options,
                     LeafSurroundingsStore* keep, Store&& store)
{
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
            criteria.planeTolerance = options.planeTolerance;
            store(i, subdivideLeaf(read.grid, read.hood, criteria));
        }
    });
}

/// Bit f: the cells along face f (-x, +x, -y, +y, -z, +z) differ between a and b, which is all a face
/// neighbour's meshing reads of a leaf's cells.
unsigned facesDiffering(const LeafCellSizes& a, const LeafCellSizes& b)
{
    constexpr int kLast = LeafCellSizes::kBlocks - 1;
    unsigned faces = 0;
    for (int i = 0; i < LeafCellSizes::kBlocks; ++i)
        for (int j = 0; j < LeafCellSizes::kBlocks; ++j) {
            const auto& x = a.blockLog2Width;
            const auto& y = b.blockLog2Width;
            faces |= unsigned(x[0][i][j] != y[0][i][j]) | unsigned(x[kLast][i][j] != y[kLast][i][j]) << 1 |
                     unsigned(x[i][0][j] != y[i][0][j]) << 2 | unsigned(x[i][kLast][j] != y[i][kLast][j]) << 3 |
                     unsigned(x[i][j][0] != y[i][j][0]) << 4 | unsigned(x[i][j][kLast] != y[i][j][kLast]) << 5;
        }
    return faces;
}

} // namespace

void AdaptiveCellCache::prepare(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                                const MeshOptions& options)
{
    // Every entry is a leaf's (refreshAround drops those of leaves that are gone): as many entries as
    // leaves means every leaf has its cells.
    if (sizes_.size() == tree.leafCount()) return;
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
    std::vector<LeafCellSizes> fresh(missing.size());
    subdivideLeaves(tree, missing, options, nullptr, [&](std::size_t i, const LeafCellSizes& sizes) { fresh[i] = sizes; });
    for (std::size_t i = 0; i < missing.size(); ++i) sizes_.emplace(missing[i]->origin(), fresh[i]);
}

std::vector<BlockOrigin> AdaptiveCellCache::refreshAround(const HermiteTree& tree, const std::vector<BlockChange>& changes,
                                                          const MeshOptions& options, LeafSurroundingsStore* keep)
{
    constexpr unsigned kAllFaces = 0x3f;
    // The leaves across the faces along which a leaf's cells changed, appeared or vanished.
    std::vector<BlockOrigin> splitAnew;
    auto addAcross = [&](const Coord& origin, unsigned faces) {
        for (int f = 0; f < 6; ++f)
            if ((faces >> f) & 1u) {
                const Coord c = faceNeighbour(origin, f);
                splitAnew.push_back({c.x(), c.y(), c.z()});
            }
    };
    std::vector<const HermiteLeaf*> present;
    ConstAccessor acc(tree);
    for (const BlockOrigin& candidate : leavesReaching(changes, kSubdivisionReach)) {
        const Coord origin(candidate[0], candidate[1], candidate[2]);
        if (const HermiteLeaf* leaf = acc.probeConstLeaf(origin)) present.push_back(leaf);
        else if (sizes_.erase(origin)) addAcross(origin, kAllFaces);
    }
    // Each thread compares and replaces the cells of the leaves it subdivided in place (distinct entries
    // of a table nobody resizes meanwhile); new leaves join afterwards.
    std::vector<uint8_t> faces(present.size(), 0);
    std::vector<std::pair<std::size_t, LeafCellSizes>> added;
    std::mutex addedMutex;
    subdivideLeaves(tree, present, options, keep, [&](std::size_t i, const LeafCellSizes& fresh) {
        const auto it = sizes_.find(present[i]->origin());
        if (it == sizes_.end()) {
            faces[i] = kAllFaces;
            const std::lock_guard<std::mutex> lock(addedMutex);
            added.emplace_back(i, fresh);
            return;
        }
        faces[i] = uint8_t(facesDiffering(it->second, fresh));
        it->second = fresh;
    });
    for (const auto& [i, fresh] : added) sizes_.emplace(present[i]->origin(), fresh);
    for (std::size_t i = 0; i < present.size(); ++i) addAcross(present[i]->origin(), faces[i]);
    return splitAnew;
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
