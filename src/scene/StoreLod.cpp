#include "scene/StoreLod.h"

#include "scene/DensityBrick.h"
#include "vdb_hermite/NumberText.h"
#include "wavelet/LevelDeviation.h"
#include "wavelet/LodKernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bitset>
#include <list>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>

namespace vdbclay {

namespace {

using wavelet::BlockOrigin;
using wavelet::BlockView;
using wavelet::LodBlock;

/// Set once a pyramid's densities are stored beside its coarse bricks (absent in older stores).
constexpr const char* kLodDensitiesKey = "lod_densities";
/// Set once a pyramid's coarse bricks are resampled at their lattice points (wavelet/LodPyramid.h); an
/// older pyramid's lie up to half a voxel off, and bricks refreshed beside them would not meet them.
constexpr const char* kLodAlignedKey = "lod_aligned";
/// Decoded density bricks kept between bricks of a pass (a brick's 26 neighbours are read again by
/// the bricks after it): more for a whole build, less beside a streaming scene's budget.
constexpr std::size_t kBuildCacheBytes = std::size_t(64) << 20;
constexpr std::size_t kUpdateCacheBytes = std::size_t(16) << 20;
constexpr int kBlockEdge = kLeafDim;

/// Level k's densities are kept under level -k, beside the coarse bricks of level k.
BrickKey densityKey(int level, const IndexCoord& brick) { return {-level, brick}; }

/// Block slots of one brick.
using SlotSet = std::bitset<kBlocksPerBrick>;

IndexCoord parentBrick(const IndexCoord& b) { return {b[0] >> 1, b[1] >> 1, b[2] >> 1}; }

int32_t floorDiv(int32_t v, int32_t d) { return v >= 0 ? v / d : -((-v + d - 1) / d); }

IndexCoord brickOfBlock(const BlockOrigin& o)
{
    return {floorDiv(o[0], kBrickEdge), floorDiv(o[1], kBrickEdge), floorDiv(o[2], kBrickEdge)};
}

int slotOfBlock(const BlockOrigin& o, const IndexCoord& brick)
{
    return DensityBrick::slotOf((o[0] - brick[0] * kBrickEdge) / kBlockEdge, (o[1] - brick[1] * kBrickEdge) / kBlockEdge,
                                (o[2] - brick[2] * kBrickEdge) / kBlockEdge);
}

BlockOrigin blockOfSlot(const IndexCoord& brick, int slot)
{
    const int x = slot / (kBlocksPerBrickSide * kBlocksPerBrickSide), y = (slot / kBlocksPerBrickSide) % kBlocksPerBrickSide,
              z = slot % kBlocksPerBrickSide;
    return {brick[0] * kBrickEdge + x * kBlockEdge, brick[1] * kBrickEdge + y * kBlockEdge, brick[2] * kBrickEdge + z * kBlockEdge};
}

std::string brickName(const SceneStore& scene, const BrickKey& key)
{
    return scene.path() + " brick " + std::to_string(key.level) + "/" + std::to_string(key.brick[0]) + "," +
           std::to_string(key.brick[1]) + "," + std::to_string(key.brick[2]);
}

/// A level's densities as the kernels read them, from the store through a bounded cache. Kernels run
/// in parallel, so they only read: prefetch() loads what a brick's kernels will ask for beforehand.
class DensityCache {
public:
    struct Entry {
        std::shared_ptr<const DensityBrick> brick; // null: no density record, the footprint is uniform
        MaterialId uniform = kEmptyMaterial;
    };

    DensityCache(const SceneStore& scene, std::size_t capacityBytes) : scene_(scene), capacity_(capacityBytes) {}

    void prefetch(int level, const std::vector<IndexCoord>& bricks)
    {
        for (const IndexCoord& b : bricks) {
            const BrickKey key{level, b};
            const auto it = entries_.find(key);
            if (it != entries_.end()) {
                use_.splice(use_.end(), use_, it->second.use);
                continue;
            }
            insert(key, load(level, b));
        }
        trim();
    }

    /// The entry of a prefetched brick.
    const Entry& at(int level, const IndexCoord& brick) const
    {
        const auto it = entries_.find({level, brick});
        if (it == entries_.end()) throw std::logic_error("a density brick was read before it was prefetched");
        return it->second.entry;
    }

    /// What was just computed for a brick (it replaces what the cache held).
    void replace(int level, const IndexCoord& brick, Entry entry)
    {
        const auto it = entries_.find({level, brick});
        if (it != entries_.end()) {
            bytes_ -= bytesOf(it->second.entry);
            use_.erase(it->second.use);
            entries_.erase(it);
        }
        insert({level, brick}, std::move(entry));
        trim();
    }

private:
    struct Slot {
        Entry entry;
        std::list<BrickKey>::iterator use;
    };

    static std::size_t bytesOf(const Entry& e) { return e.brick ? e.brick->memoryBytes() : 0; }

    Entry load(int level, const IndexCoord& b) const
    {
        Entry e;
        if (level > 0) {
            if (const std::optional<BrickRecord> record = scene_.bricks().get(densityKey(level, b))) {
                const std::string name = brickName(scene_, densityKey(level, b));
                e.brick = std::make_shared<DensityBrick>(decodeDensityBrick(record->payload, scene_.materials().size(), name));
                return e;
            }
        }
        // No density: the brick's footprint holds no leaf, so it lies in one tile of level 0, and the
        // level-0 brick at its corner says which.
        const int32_t scale = int32_t(1) << level;
        const BrickKey corner{0, {b[0] * scale, b[1] * scale, b[2] * scale}};
        if (const std::optional<BrickRecord> record = scene_.bricks().get(corner)) {
            if (!record->uniform)
                throw StoreError("'" + scene_.path() + "': its LOD pyramid does not match level 0 at " +
                                 brickName(scene_, corner) + "; run 'vdbclay lod build'");
            e.uniform = *record->uniform;
        }
        return e;
    }

    void insert(const BrickKey& key, Entry entry)
    {
        bytes_ += bytesOf(entry);
        use_.push_back(key);
        entries_.emplace(key, Slot{std::move(entry), std::prev(use_.end())});
    }

    void trim()
    {
        while (bytes_ > capacity_ && use_.size() > 27) {
            const auto it = entries_.find(use_.front());
            bytes_ -= bytesOf(it->second.entry);
            entries_.erase(it);
            use_.pop_front();
        }
    }

    const SceneStore& scene_;
    const std::size_t capacity_;
    std::map<BrickKey, Slot> entries_;
    std::list<BrickKey> use_; // least recently used first
    std::size_t bytes_ = 0;
};

/// Blocks of level 0 from a volume holding the bricks a pass loaded, of higher levels from the cache.
class StoreLevelSource final : public wavelet::LevelSource {
public:
    StoreLevelSource(const DensityCache& cache, const Volume* levelZero) : cache_(cache), levelZero_(levelZero) {}

    BlockView view(int level, const BlockOrigin& origin) const override
    {
        if (level == 0) {
            const HermiteTree& tree = levelZero_->impl().grid->constTree();
            const Coord c(origin[0], origin[1], origin[2]);
            BlockView v;
            v.leaf = tree.probeConstLeaf(c);
            return v.leaf ? v : wavelet::uniformView(tree.getValue(c).id);
        }
        const IndexCoord brick = brickOfBlock(origin);
        const DensityCache::Entry& e = cache_.at(level, brick);
        if (!e.brick) return wavelet::uniformView(e.uniform);
        const int slot = slotOfBlock(origin, brick);
        BlockView v;
        v.block = e.brick->block(slot);
        return v.block ? v : wavelet::uniformView(e.brick->uniform[std::size_t(slot)]);
    }

private:
    const DensityCache& cache_;
    const Volume* levelZero_;
};

std::vector<IndexCoord> childBricks(const IndexCoord& b)
{
    std::vector<IndexCoord> out;
    for (int c = 0; c < 8; ++c) out.push_back({2 * b[0] + (c & 1), 2 * b[1] + ((c >> 1) & 1), 2 * b[2] + ((c >> 2) & 1)});
    return out;
}

std::vector<IndexCoord> neighbourBricks(const IndexCoord& b)
{
    std::vector<IndexCoord> out;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) out.push_back({b[0] + dx, b[1] + dy, b[2] + dz});
    return out;
}

/// One pass up the pyramid from changed level-0 bricks. `rebuilt`: the coarse levels were erased
/// before, so nothing stored above level 0 needs reading.
class LodPass {
public:
    LodPass(SceneStore& scene, int levels, bool rebuilt, const Progress& progress)
        : scene_(scene), levels_(levels), rebuilt_(rebuilt), progress_(progress),
          cache_(scene, rebuilt ? kBuildCacheBytes : kUpdateCacheBytes)
    {
        result_.changedBricks.resize(std::size_t(levels));
    }

    LodRefresh run(const std::vector<IndexCoord>& changedLevelZero)
    {
        std::set<IndexCoord> changed(changedLevelZero.begin(), changedLevelZero.end());
        // Bricks of the level below whose surface or error changed: their parents' errors follow them,
        // whether or not the parents' densities changed.
        std::set<IndexCoord> moved = changed;
        for (int k = 1; k <= levels_ && (!changed.empty() || !moved.empty()); ++k) {
            std::set<IndexCoord> targets;
            for (const IndexCoord& b : changed) targets.insert(parentBrick(b));
            std::map<IndexCoord, SlotSet> coarseSlots; // level-k blocks whose coarse data must be redone
            changed.clear();
            uint64_t done = 0;
            for (const IndexCoord& t : targets) {
                if (densityPass(k, t, coarseSlots)) changed.insert(t);
                report(k, ++done, targets.size());
            }
            std::set<IndexCoord> movedHere;
            done = 0;
            for (const auto& [brick, slots] : coarseSlots) {
                if (coarsePass(k, brick, slots)) movedHere.insert(brick);
                report(k, ++done, coarseSlots.size());
            }
            for (const IndexCoord& b : moved) {
                const IndexCoord parent = parentBrick(b);
                if (coarseSlots.count(parent) || movedHere.count(parent)) continue;
                if (refreshError(k, parent)) movedHere.insert(parent);
            }
            moved = std::move(movedHere);
        }
        return std::move(result_);
    }

private:
    void report(int level, uint64_t done, uint64_t total) const
    {
        // Two passes per level, each shown as half of the level's share.
        if (progress_) progress_(uint64_t(level - 1) * 1000 + 500 * done / std::max<uint64_t>(total, 1), uint64_t(levels_) * 1000);
    }

    /// Recomputes level k's densities of brick t from the level below; returns whether they changed
    /// and adds the blocks whose coarse data they reach to coarseSlots.
    bool densityPass(int k, const IndexCoord& t, std::map<IndexCoord, SlotSet>& coarseSlots)
    {
        ++result_.densityBricksComputed;
        std::optional<Volume> levelZero;
        if (k == 1) {
            levelZero.emplace(scene_.voxelSize());
            levelZero->materials() = scene_.materials();
            scene_.loadBricks(0, childBricks(t), *levelZero);
        } else {
            cache_.prefetch(k - 1, childBricks(t));
        }
        // What was stored before, read directly: a brick without a record would be looked up in level 0,
        // which the edit has already changed.
        std::optional<DensityBrick> before;
        if (!rebuilt_)
            if (const std::optional<BrickRecord> record = scene_.bricks().get(densityKey(k, t)))
                before = decodeDensityBrick(record->payload, scene_.materials().size(), brickName(scene_, densityKey(k, t)));
        const StoreLevelSource source(cache_, levelZero ? &*levelZero : nullptr);
        std::array<std::optional<LodBlock>, kBlocksPerBrick> blocks;
        std::array<MaterialId, kBlocksPerBrick> uniform{};
        tbb::parallel_for(tbb::blocked_range<int>(0, kBlocksPerBrick, 16), [&](const auto& range) {
            for (int s = range.begin(); s != range.end(); ++s) {
                const BlockOrigin o = blockOfSlot(t, s);
                blocks[std::size_t(s)] = wavelet::lowPassBlock(source, k, o);
                if (!blocks[std::size_t(s)]) uniform[std::size_t(s)] = source.view(k - 1, {2 * o[0], 2 * o[1], 2 * o[2]}).material;
            }
        });
        DensityCache::Entry after;
        auto brick = std::make_shared<DensityBrick>();
        for (int s = 0; s < kBlocksPerBrick; ++s) {
            if (blocks[std::size_t(s)]) {
                brick->slot[std::size_t(s)] = int16_t(brick->blocks.size());
                brick->blocks.push_back(std::move(*blocks[std::size_t(s)]));
            } else {
                brick->uniform[std::size_t(s)] = uniform[std::size_t(s)];
            }
        }
        if (brick->blocks.empty()) after.uniform = uniform[0];
        else after.brick = std::move(brick);

        // Where either side has no record, every block counts as changed: a uniform footprint may have
        // changed its material, and that is cheap to redo.
        std::vector<int> changedSlots;
        for (int s = 0; s < kBlocksPerBrick; ++s)
            if (!before || !after.brick || !before->sameSlot(*after.brick, s)) changedSlots.push_back(s);
        if (changedSlots.empty()) return false;
        if (after.brick)
            scene_.bricks().put(densityKey(k, t), {std::nullopt, encodeDensityBrick(*after.brick), uint32_t(after.brick->blocks.size())});
        else if (before)
            scene_.bricks().erase(densityKey(k, t));
        cache_.replace(k, t, std::move(after));
        for (int s : changedSlots) {
            const BlockOrigin o = blockOfSlot(t, s);
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const BlockOrigin n{o[0] + dx * kBlockEdge, o[1] + dy * kBlockEdge, o[2] + dz * kBlockEdge};
                        const IndexCoord b = brickOfBlock(n);
                        coarseSlots[b].set(std::size_t(slotOfBlock(n, b)));
                    }
        }
        return true;
    }

    /// Re-derives the coarse Hermite data of the given blocks of level-k brick `brick` and stores it, with
    /// its error. Returns whether either changed.
    bool coarsePass(int k, const IndexCoord& brick, const SlotSet& slots)
    {
        ++result_.hermiteBricksComputed;
        cache_.prefetch(k, neighbourBricks(brick));
        Volume coarse(scene_.voxelSize() * double(1 << k));
        coarse.materials() = scene_.materials();
        std::vector<std::optional<BrickRecord>> before(1);
        if (!rebuilt_) scene_.loadBricks(k, {brick}, coarse, {}, &before);
        std::vector<BlockOrigin> origins;
        for (int s = 0; s < kBlocksPerBrick; ++s)
            if (slots.test(std::size_t(s))) origins.push_back(blockOfSlot(brick, s));
        wavelet::writeCoarseBlocks(StoreLevelSource(cache_, nullptr), k, origins, coarse);
        const std::optional<BrickRecord> after = encodeBrick(coarse, brick);
        const bool errorChanged = storeError(k, brick, after ? std::optional<double>(dataError(k, brick, coarse)) : std::nullopt);
        if (sameBrick(before[0], after)) return errorChanged;
        if (after) scene_.bricks().put({k, brick}, *after);
        else scene_.bricks().erase({k, brick});
        result_.changedBricks[std::size_t(k - 1)].push_back(brick);
        return true;
    }

    /// Recomputes the error of a level-k brick whose record stays (the levels below it changed); returns
    /// whether it changed.
    bool refreshError(int k, const IndexCoord& brick)
    {
        Volume coarse(scene_.voxelSize() * double(1 << k));
        coarse.materials() = scene_.materials();
        std::vector<std::optional<BrickRecord>> record(1);
        scene_.loadBricks(k, {brick}, coarse, {}, &record);
        return storeError(k, brick, record[0] ? std::optional<double>(dataError(k, brick, coarse)) : std::nullopt);
    }

    /// Keeps a brick's error (nullopt: none); returns whether it differs from what was kept.
    bool storeError(int k, const IndexCoord& brick, std::optional<double> error)
    {
        const std::optional<double> before = rebuilt_ ? std::nullopt : scene_.bricks().lodError({k, brick});
        if (before == error) return false;
        if (error) scene_.bricks().putLodError({k, brick}, *error);
        else scene_.bricks().eraseLodError({k, brick});
        result_.errors.emplace_back(BrickKey{k, brick}, error);
        return true;
    }

    /// How far level k's surface in `brick` may lie from level 0's (StoreLod.h): its children's errors,
    /// the largest (a child without one: its voxel), plus how far it lies from level k - 1's there.
    double dataError(int k, const IndexCoord& brick, const Volume& coarse) const
    {
        const std::vector<IndexCoord> children = childBricks(brick);
        Volume fine(scene_.voxelSize() * double(1 << (k - 1)));
        fine.materials() = scene_.materials();
        scene_.loadBricks(k - 1, children, fine);
        double below = 0.0;
        if (k > 1)
            for (const IndexCoord& child : children)
                below = std::max(below, scene_.bricks().lodError({k - 1, child}).value_or(fine.voxelSize()));
        const double edge = double(kBrickEdge) * coarse.voxelSize();
        const std::array<double, 3> lo{brick[0] * edge, brick[1] * edge, brick[2] * edge};
        const std::array<double, 3> hi{lo[0] + edge, lo[1] + edge, lo[2] + edge};
        // A feature one level lost or made counts a whole coarse voxel: the view then treats the brick
        // as it treats one without an error (lodShownError caps there).
        return below + wavelet::levelDeviation(coarse, fine, lo, hi, coarse.voxelSize());
    }

    SceneStore& scene_;
    const int levels_;
    const bool rebuilt_;
    const Progress& progress_;
    DensityCache cache_;
    LodRefresh result_;
};

} // namespace

int lodLevelsFor(const SceneStore& scene)
{
    const std::vector<IndexCoord> bricks = scene.brickCoords(0);
    if (bricks.empty()) return 1;
    IndexCoord lo = bricks.front(), hi = bricks.front();
    for (const IndexCoord& b : bricks)
        for (std::size_t i = 0; i < 3; ++i) lo[i] = std::min(lo[i], b[i]), hi[i] = std::max(hi[i], b[i]);
    int extent = 1;
    for (std::size_t i = 0; i < 3; ++i) extent = std::max(extent, (hi[i] - lo[i] + 1) * kBrickEdge);
    return wavelet::LodPyramid::levelsForExtent(extent);
}

int buildStoreLod(SceneStore& scene, int levels, const Progress& progress)
{
    if (levels == 0) levels = lodLevelsFor(scene);
    if (levels < 1 || levels > wavelet::kMaxLodLevels)
        throw std::invalid_argument("a pyramid has 1 to " + std::to_string(wavelet::kMaxLodLevels) + " levels, not " +
                                    std::to_string(levels));
    if (scene.voxelSize() * double(1 << levels) > kMaxVoxelSize)
        throw std::invalid_argument("a voxel size of " + formatNumber(scene.voxelSize()) + " leaves room for fewer than " +
                                    std::to_string(levels) + " levels");
    StoreTransaction transaction(scene.bricks());
    for (int k = 1; k <= std::max(levels, scene.lodLevels()); ++k) {
        for (const int level : {k, -k})
            for (const IndexCoord& b : scene.brickCoords(level)) scene.bricks().erase({level, b});
        std::vector<IndexCoord> errors;
        scene.bricks().scanLodErrors(k, [&](const IndexCoord& b, double) { errors.push_back(b); });
        for (const IndexCoord& b : errors) scene.bricks().eraseLodError({k, b});
    }
    LodPass(scene, levels, true, progress).run(scene.brickCoords(0));
    scene.setLod(levels, false);
    scene.bricks().putMeta(kLodDensitiesKey, "1");
    scene.bricks().putMeta(kLodAlignedKey, "1");
    scene.storeBounds(); // a writer's pass over the store: the bounds of level 0 kept for readers
    transaction.commit();
    return levels;
}

bool lodFollowsEdits(const SceneStore& scene)
{
    return scene.lodLevels() > 0 && !scene.lodStale() && metaFlag(scene.bricks(), kLodDensitiesKey) &&
           metaFlag(scene.bricks(), kLodAlignedKey);
}

LodRefresh updateStoreLod(SceneStore& scene, const std::vector<IndexCoord>& changedBricks)
{
    if (!lodFollowsEdits(scene)) throw std::logic_error("updateStoreLod: the store's pyramid does not follow edits");
    return LodPass(scene, scene.lodLevels(), false, {}).run(changedBricks);
}

} // namespace vdbclay
