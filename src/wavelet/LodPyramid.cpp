#include "wavelet/LodPyramid.h"

#include "wavelet/LodKernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

namespace vdbclay::wavelet {

namespace {

using Map = std::map<BlockOrigin, LodBlock>;
constexpr int kDim = kLeafDim;

/// The pyramid's blocks over the volume's leaves and tiles.
class LevelReader final : public LevelSource {
public:
    LevelReader(const HermiteTree& tree, const std::vector<Map>& levels) : tree_(tree), levels_(levels) {}

    BlockView view(int level, const BlockOrigin& origin) const override
    {
        const int scale = 1 << level; // a multiplication: shifting a negative coordinate left is undefined
        const Coord fine(origin[0] * scale, origin[1] * scale, origin[2] * scale);
        BlockView v;
        if (level == 0) {
            v.leaf = tree_.probeConstLeaf(fine);
        } else {
            const Map& map = levels_[std::size_t(level - 1)];
            const auto it = map.find(origin);
            if (it != map.end()) v.block = &it->second;
        }
        // No leaf in the footprint: it lies inside one tile (tiles of different values, or of solid and
        // empty, would meet at edges that carry samples, which live in leaves).
        return v.uniform() ? uniformView(tree_.getValue(fine).id) : v;
    }

private:
    const HermiteTree& tree_;
    const std::vector<Map>& levels_;
};

/// Computes the blocks at `origins` of level `level` (>= 1) in parallel against the current pyramid.
std::vector<std::optional<LodBlock>> computeBlocks(const LevelReader& reader, int level,
                                                   const std::vector<BlockOrigin>& origins)
{
    std::vector<std::optional<LodBlock>> out(origins.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 4), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = lowPassBlock(reader, level, origins[i]);
    });
    return out;
}

std::vector<BlockOrigin> sortedUnique(std::vector<BlockOrigin> v)
{
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

/// The blocks of `origins` and their 26 neighbours, sorted and unique: a block's coarse leaf reads
/// its neighbours' first layer.
std::vector<BlockOrigin> withNeighbours(const std::vector<BlockOrigin>& origins)
{
    std::vector<BlockOrigin> out;
    out.reserve(origins.size() * 27);
    for (const BlockOrigin& o : origins)
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) out.push_back({o[0] + dx * kDim, o[1] + dy * kDim, o[2] + dz * kDim});
    return sortedUnique(std::move(out));
}

} // namespace

LodPyramid::LodPyramid(int levels)
{
    if (levels < 1 || levels > kMaxLodLevels)
        throw std::invalid_argument("a pyramid has 1 to " + std::to_string(kMaxLodLevels) + " levels, not " +
                                    std::to_string(levels));
    levels_.resize(std::size_t(levels));
}

int LodPyramid::levelsFor(const Volume& volume)
{
    const VolumeStats s = volume.stats();
    int extent = 1;
    for (int i = 0; i < 3; ++i) extent = std::max(extent, s.bboxMax[std::size_t(i)] - s.bboxMin[std::size_t(i)] + 1);
    return levelsForExtent(extent);
}

int LodPyramid::levelsForExtent(int extent)
{
    int levels = 1;
    while (levels < kMaxLodLevels && (extent >> levels) > 64) ++levels;
    return levels;
}

const std::map<BlockOrigin, LodBlock>& LodPyramid::blocks(int level) const
{
    if (level < 1 || level > levels()) throw std::out_of_range("no pyramid level " + std::to_string(level));
    return levels_[std::size_t(level - 1)];
}

void LodPyramid::build(const Volume& volume)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    for (auto& level : levels_) level.clear();
    const LevelReader reader(tree, levels_);
    std::vector<BlockOrigin> origins;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const Coord o = leaf->origin();
        origins.push_back(parentBlock({o.x(), o.y(), o.z()}));
    }
    for (int k = 1; k <= levels(); ++k) {
        origins = sortedUnique(std::move(origins));
        std::vector<std::optional<LodBlock>> blocks = computeBlocks(reader, k, origins);
        Map& map = levels_[std::size_t(k - 1)];
        std::vector<BlockOrigin> parents;
        for (std::size_t i = 0; i < origins.size(); ++i) {
            if (!blocks[i]) continue;
            map.emplace_hint(map.end(), origins[i], std::move(*blocks[i]));
            parents.push_back(parentBlock(origins[i]));
        }
        origins = std::move(parents);
    }
}

LodUpdate LodPyramid::update(const Volume& volume, const std::vector<BlockChange>& changes)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    const LevelReader reader(tree, levels_);
    LodUpdate result;
    result.changedBlocks.resize(levels_.size());
    std::vector<BlockOrigin> origins;
    for (const BlockChange& c : changes) origins.push_back(parentBlock(c.origin));
    for (int k = 1; k <= levels(); ++k) {
        origins = sortedUnique(std::move(origins));
        std::vector<std::optional<LodBlock>> blocks = computeBlocks(reader, k, origins);
        result.blocksRecomputed += origins.size();
        Map& map = levels_[std::size_t(k - 1)];
        std::vector<BlockOrigin>& changed = result.changedBlocks[std::size_t(k - 1)];
        for (std::size_t i = 0; i < origins.size(); ++i) {
            const auto it = map.find(origins[i]);
            if (!blocks[i]) {
                if (it == map.end()) continue;
                map.erase(it);
            } else if (it == map.end()) {
                map.emplace(origins[i], std::move(*blocks[i]));
            } else if (it->second == *blocks[i]) {
                continue;
            } else {
                it->second = std::move(*blocks[i]);
            }
            changed.push_back(origins[i]);
        }
        origins.clear();
        for (const BlockOrigin& o : changed) origins.push_back(parentBlock(o));
    }
    return result;
}

Volume LodPyramid::coarseVolume(const Volume& fine, int level) const
{
    Volume coarse(fine.voxelSize() * double(1 << level));
    coarse.materials() = fine.materials();
    // Solid interiors first: each solid tile of the fine volume shrinks to its image at this level (a
    // block that holds part of an image and no leaf's footprint is uniform: one tile fills it all).
    // The blocks near the surface then replace what they cover.
    HermiteTree& out = coarse.impl().grid->tree();
    std::set<Coord> lowers;
    forEachTile(fine.impl().grid->constTree(), [&](const CoordBBox& tile, MaterialValue value) {
        if (!value.solid()) return;
        const int size = tile.dim().x() >> level;
        const Coord o(tile.min().x() >> level, tile.min().y() >> level, tile.min().z() >> level);
        if (size >= kUpperDim) out.addTile(3, o, value, false);
        else if (size >= kLowerDim) out.addTile(2, o, value, false);
        else if (size < kDim) out.addTile(1, alignDown(o, kDim), value, false), lowers.insert(alignDown(o, kLowerDim));
        else
            for (int x = 0; x < size; x += kDim)
                for (int y = 0; y < size; y += kDim)
                    for (int z = 0; z < size; z += kDim) out.addTile(1, o.offsetBy(x, y, z), value, false);
        lowers.insert(alignDown(o, kLowerDim));
    });
    pruneNodes(out, lowers);
    std::vector<BlockOrigin> origins;
    for (const auto& [origin, block] : blocks(level)) origins.push_back(origin);
    updateCoarseVolume(fine, level, origins, coarse);
    return coarse;
}

std::vector<BlockChange> LodPyramid::updateCoarseVolume(const Volume& fine, int level,
                                                        const std::vector<BlockOrigin>& blocks, Volume& coarse) const
{
    if (level < 1 || level > levels()) throw std::out_of_range("no pyramid level " + std::to_string(level));
    const LevelReader reader(fine.impl().grid->constTree(), levels_);
    return writeCoarseBlocks(reader, level, withNeighbours(blocks), coarse);
}

} // namespace vdbclay::wavelet
