#include "scene/StreamingScene.h"

#include "mesher/LodBrickTable.h"
#include "mesher/LodCut.h"
#include "mesher/LodMesh.h"
#include "mesher/VertexMask.h"
#include "mesher/VertexMaterialBlend.h"
#include "mesher/VertexOcclusion.h"
#include "scene/StoreLod.h"
#include "scene/StoreSculpt.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/RegionCodec.h"
#include "vdb_hermite/VolumeRegions.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <mutex>
#include <shared_mutex>
#include <stdexcept>
#include <thread>
#include <utility>

namespace vdbclay {

namespace {

constexpr const char* kEditCountKey = "edit_count";
/// A resident leaf costs about this much (materials, masks, prefix counts, samples, node overhead);
/// used to estimate a brick before it is loaded, from the leaf count the store keeps per brick.
constexpr uint64_t kEstimatedBytesPerLeaf = 2600;
constexpr uint64_t kEstimatedBytesPerBrick = 4 << 10; // its share of the 128^3 nodes above its leaves
/// How far into a neighbour of its level a brick's mesh reads, in voxels: CMS probes one leaf beyond
/// its cells, plus the corners of the cells on its faces; occlusion samples 3.5 voxels out.
constexpr int32_t kMeshReach = kLeafDim + 2;
/// A brick `c` levels coarser than its neighbour also reads one of its own cells (2^c of the
/// neighbour's voxels) into it: the transition cells below its low faces. Classes 0..7 (7: 7 or more).
constexpr int kReachClasses = 8;
int64_t reachOfClass(int c) { return kMeshReach + (c > 0 ? (int64_t(1) << c) : 0); }

int32_t floorDivide(int32_t v, int32_t d) { return v >= 0 ? v / d : -((-v + d - 1) / d); }

/// The 27 directions from a brick to the bricks around it (13: itself), each axis -1, 0 or +1.
int directionIndex(const std::array<int, 3>& d) { return (d[0] + 1) + 3 * (d[1] + 1) + 9 * (d[2] + 1); }

/// The leaf changes StreamingScene remembers for re-meshing only what an edit reached; a brick's mesh
/// older than the oldest one kept is made whole again.
constexpr std::size_t kLeafLogLength = 1 << 16;
/// How far beyond a chunk's cells its vertices' occlusion reads the volume's materials, in whole voxels
/// (samples 3.5 out, rounded to voxels, and a voxel to spare for a vertex on its cell's face).
constexpr int32_t kOcclusionReach = 5;

/// One leaf's part of a level-0 brick's mesh.
struct LeafMesh {
    MeshChunk chunk;
    std::vector<uint8_t> occlusion; // per vertex of the chunk
    std::vector<uint32_t> blend;    // per vertex of the chunk (vertexMaterialBlend)
};

/// A brick's transition cells, meshed apart from its leaves, with the boxes of those cells: a level-0
/// brick's (towards the space outside the cut) stay as they are while no edit reaches their cells.
struct TransitionMesh {
    Mesh mesh; // its own vertices, appended after the welded leaves
    std::vector<uint8_t> occlusion;
    std::vector<uint32_t> blend;
    std::vector<TransitionCellBox> cells;
};

/// Whether level-0 changes reach what some transition cells' vertices read: the cells' points and edges,
/// and the voxels their occlusion and material blend sample around them.
bool reachesAnyCell(const std::vector<BlockChange>& changes, const std::vector<TransitionCellBox>& cells)
{
    const auto reaches = [](const BlockChange& change, const TransitionCellBox& cell) {
        for (std::size_t a = 0; a < 3; ++a) {
            // The changed voxels, and the edges leaving them upwards.
            const int64_t lo = int64_t(change.origin[a]) + change.min[a], hi = int64_t(change.origin[a]) + change.max[a] + 1;
            if (hi < cell.lo[a] - kOcclusionReach || lo > cell.hi[a] + kOcclusionReach) return false;
        }
        return true;
    };
    for (const BlockChange& change : changes)
        for (const TransitionCellBox& cell : cells)
            if (reaches(change, cell)) return true;
    return false;
}

/// What a brick's mesh reads besides the edits the leaf log tells, per direction from the brick
/// (directionIndex): which bricks of the cut touch it on that side, and their loads; at 13, the brick's
/// own loads and the bricks beside it that entered or left the trees. A change on one side leaves the
/// leaves far from that side as they were.
struct MeshReadVersions {
    std::array<uint64_t, 27> sides{};

    bool operator==(const MeshReadVersions& other) const { return sides == other.sides; }
};

/// The leaves of a level-0 brick's pieces (its own, and one layer past its high faces) whose cells or
/// occlusion read as far as `direction` (directionIndex) from the brick: within kMeshReach of its faces
/// on that side.
std::vector<IndexCoord> leavesReadingSide(const IndexCoord& brickMin, int direction)
{
    constexpr int32_t kLeavesAcross = kBrickEdge / kLeafDim + 1;
    std::array<int32_t, 3> first{}, last{};
    for (std::size_t a = 0; a < 3; ++a) {
        const int step = int(direction / (a == 0 ? 1 : a == 1 ? 3 : 9)) % 3 - 1;
        first[a] = 0, last[a] = kLeavesAcross - 1;
        // Leaf i spans [i, i + 1] leaves from the brick's low face.
        if (step < 0) last[a] = (kMeshReach - 1) / kLeafDim;
        if (step > 0) first[a] = (kBrickEdge - kMeshReach) / kLeafDim;
    }
    std::vector<IndexCoord> out;
    for (int32_t i = first[0]; i <= last[0]; ++i)
        for (int32_t j = first[1]; j <= last[1]; ++j)
            for (int32_t k = first[2]; k <= last[2]; ++k)
                out.push_back({brickMin[0] + i * kLeafDim, brickMin[1] + j * kLeafDim, brickMin[2] + k * kLeafDim});
    return out;
}

/// How far a coarse brick's mesh may lie from its cells' surface, voxels of its level (lodShownError).
double coarseTolerance(const MeshOptions& meshing) { return meshing.coarseLevelPlaneTolerance + meshing.coarseLevelSimplifyTolerance; }

/// A set of bricks refilled every frame: its table stays allocated between frames.
class BrickKeySet {
public:
    void insert(const BrickKey& key) { map_.insert(key.level, key.brick); }
    template <class It>
    void insert(It first, It last)
    {
        for (; first != last; ++first) insert(*first);
    }
    bool count(const BrickKey& key) const { return map_.contains(key.level, key.brick); }
    void clear() { map_.clear(); }

private:
    LodBrickMap<char> map_;
};

/// The needed bricks as a tree: each one's children as a range of one list, and an order that visits
/// finer levels first. Made once a frame: the cut is walked up to three times a frame (besides of what
/// the budget holds, with and without the budget, and what is shown) over a few thousand bricks.
struct NeedsTree {
    std::vector<uint32_t> childStart; // children of i: children[childStart[i] .. childStart[i + 1])
    std::vector<uint32_t> children;
    std::vector<uint32_t> finerFirst;
    std::vector<char> selected;

    explicit NeedsTree(const ViewNeeds& needs)
    {
        const std::size_t n = needs.bricks.size();
        childStart.assign(n + 1, 0);
        for (std::size_t i = 0; i < n; ++i)
            if (needs.parent[i] != ViewNeeds::kNone) ++childStart[needs.parent[i] + 1];
        for (std::size_t i = 0; i < n; ++i) childStart[i + 1] += childStart[i];
        children.resize(childStart[n]);
        std::vector<uint32_t> next(childStart.begin(), childStart.end() - 1);
        for (uint32_t i = 0; i < n; ++i)
            if (needs.parent[i] != ViewNeeds::kNone) children[next[needs.parent[i]]++] = i;
        finerFirst.resize(n);
        for (uint32_t i = 0; i < n; ++i) finerFirst[i] = i;
        std::stable_sort(finerFirst.begin(), finerFirst.end(), [&](uint32_t a, uint32_t b) { return needs.bricks[a].level < needs.bricks[b].level; });
        selected.assign(n, 0);
        for (uint32_t s : needs.selected) selected[s] = 1;
    }
    const uint32_t* childrenBegin(uint32_t i) const { return children.data() + childStart[i]; }
    const uint32_t* childrenEnd(uint32_t i) const { return children.data() + childStart[i + 1]; }
};

/// The bricks to draw for a selection: see StreamingScene::shownBricks. `unshown` receives the other
/// children of the bricks split into their children (empty ones, or out of view): with the shown ones
/// they make the cut the meshes are made for (LodCut).
std::vector<BrickKey> shownCut(const ViewNeeds& needs, const NeedsTree& tree, const std::vector<char>& isResident, std::vector<BrickKey>& unshown)
{
    unshown.clear();
    const std::size_t n = needs.bricks.size();
    // Whether a node's region can be drawn completely, from itself or its descendants: finer levels first.
    std::vector<char> coverable(n, 0);
    const auto splits = [&](uint32_t i) {
        return tree.childrenBegin(i) != tree.childrenEnd(i) &&
               std::all_of(tree.childrenBegin(i), tree.childrenEnd(i), [&](uint32_t c) { return coverable[c] != 0; });
    };
    for (uint32_t i : tree.finerFirst) coverable[i] = isResident[i] || splits(i);
    std::vector<BrickKey> out;
    std::vector<uint32_t> stack;
    for (uint32_t i = 0; i < n; ++i)
        if (needs.parent[i] == ViewNeeds::kNone) stack.push_back(i);
    while (!stack.empty()) {
        const uint32_t i = stack.back();
        stack.pop_back();
        if (tree.selected[i]) {
            if (isResident[i]) out.push_back(needs.bricks[i]);
            continue;
        }
        if (!splits(i) && isResident[i]) {
            out.push_back(needs.bricks[i]);
            continue;
        }
        stack.insert(stack.end(), tree.childrenBegin(i), tree.childrenEnd(i));
        const BrickKey& parent = needs.bricks[i];
        for (int c = 0; c < 8; ++c) {
            const BrickKey child{parent.level - 1, {2 * parent.brick[0] + (c & 1), 2 * parent.brick[1] + ((c >> 1) & 1),
                                                    2 * parent.brick[2] + ((c >> 2) & 1)}};
            if (std::none_of(tree.childrenBegin(i), tree.childrenEnd(i), [&](uint32_t k) { return needs.bricks[k] == child; }))
                unshown.push_back(child);
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}


} // namespace

struct StreamingScene::BrickMeshPieces {
    std::vector<std::shared_ptr<const LeafMesh>> leaves; // in the order of their origins
    std::shared_ptr<const TransitionMesh> transitions;
    uint64_t leafLogSeq = 0; // the leaf log's last entry when made
    MeshReadVersions inputs; // what the brick's mesh read of the loads around it
    uint64_t bytes = 0;
};

struct StreamingScene::Impl {
    struct Resident {
        uint64_t bytes = 0;
        uint64_t lastUsed = 0;
        uint64_t version = 0; // its content: any change
        // Per reach class (the reader's level above this one's) and direction (directionIndex): the
        // content a brick on that side reads (reachOfClass voxels next to it). Changes farther from
        // that side leave the neighbour's mesh as it was.
        std::array<std::array<uint64_t, 27>, kReachClasses> sides{};
        std::shared_ptr<const BrickMesh> mesh; // the last made, while the brick is shown
        MeshReadVersions meshInputs; // meshReadVersionsLocked(key) when it was made
        uint64_t meshContent = 0;    // `version` when it was made
        uint64_t loadVersion = 0; // the version it was loaded at: changes other than edits
        // A mesh also reads bricks the cut does not show, where they are in the trees: the points of a
        // brick of its own level beside it (its face cells and a leaf beyond), and those of the finer
        // bricks inside it on its faces (its transition cells). Set when such a brick's content enters
        // or leaves its tree (noteContentMoved).
        uint64_t besideMoved = 0; // a brick of its level beside it: its own cells read it
        uint64_t finerMoved = 0;  // a finer brick inside it: its transition cells read it
    };

    StreamingOptions options;
    SceneStore scene;
    int levels = 0;
    BrickPresence present; // per level: stored bricks and the parents of present ones
    std::unordered_map<BrickKey, uint64_t, BrickKeyHash> estimates;
    // The resident bricks of each level share one tree, so the nodes above the leaves cost little per brick.
    // Guarded by `trees`, everything else by `mutex`: meshing and ray casts read the trees for a long
    // while without the lock that the frame's selection needs. A thread needing both takes `trees` first.
    std::vector<Volume> levelVolumes;
    mutable std::shared_mutex trees;
    // Evicted bricks whose content is still in the trees: cleared by the next thread to hold the trees
    // alone (loads, edits), so that evicting needs the lock only.
    std::vector<BrickKey> pendingClears;

    mutable std::mutex mutex;
    // The store's own connection (`scene`: autosaves, the editor's marks, edits' page-ins), taken after
    // `mutex` when both are needed: an autosave writes with this alone, so that frames go on meanwhile.
    mutable std::mutex storeMutex;
    std::condition_variable wake, idle;
    std::unordered_map<BrickKey, Resident, BrickKeyHash> resident;
    std::vector<uint64_t> residentPerLevel;         // of `resident`, per level
    std::set<IndexCoord> dirty;             // the level-0 bricks of `resident` edited since their last save
    std::deque<BrickKey> queue;
    using BrickSet = std::unordered_set<BrickKey, BrickKeyHash>;
    BrickSet inFlight;
    BrickSet staleInFlight; // loads an autosave's LOD update overtook: discarded on arrival
    BrickSet damaged;       // bricks the store could not give: shown by their ancestors, not loaded again
    BrickKeySet wanted;     // the current frame's accepted selection and fallbacks
    BrickSet pinned;        // level-0 bricks an edit is working on outside the lock: never evicted
    // The last edit's volume and bricks, equal to level 0 there (only edits change resident level-0
    // bricks, one at a time; a brick evicted clean loads again as it was): the next edit copies only
    // the bricks it reaches beyond them. The editing thread's alone.
    std::optional<Volume> lastWork;
    std::set<IndexCoord> lastWorkBricks;
    uint64_t residentBytes = 0, inFlightBytes = 0; // resident: bricks and meshes
    uint64_t meshBytes = 0;
    double meshShare = 0.0; // a mesh's bytes over its brick's, lately: estimates what a brick's mesh will take
    uint64_t meshSamples = 0;
    BrickSet meshed;        // resident bricks holding a mesh
    uint64_t frameNumber = 0;
    uint64_t bytesRead = 0, loads = 0, evictions = 0;
    uint64_t edits = 0;
    uint64_t lodBricksWritten = 0;
    uint64_t versions = 0; // the last content version handed out
    // Told of each edit's changed bricks (addEditListener), under their own lock: called outside `mutex`.
    mutable std::mutex listenersMutex;
    mutable std::vector<std::pair<uint64_t, EditListener>> editListeners;
    mutable uint64_t nextListener = 1;
    void tellEditListeners(const std::vector<BrickKey>& changed) const
    {
        if (changed.empty()) return;
        std::lock_guard<std::mutex> lock(listenersMutex);
        for (const auto& [id, listener] : editListeners) listener(changed);
    }
    // Level-0 leaves edits changed (with the bounds of what changed in them), each with a number;
    // numbers up to leafLogFloor are forgotten.
    std::deque<std::pair<uint64_t, BlockChange>> leafLog;
    uint64_t leafLogSeq = 0, leafLogFloor = 0;
    std::vector<BrickKey> shown;
    std::vector<BrickKey> besidesOf, besides; // updateBesides
    std::shared_ptr<const LodCut> cut = std::make_shared<LodCut>(); // the shown bricks and the rest of the split bricks' children
    MaterialTable materials; // the scene's, with what edits defined since the last autosave
    VoxelMask mask;          // as edits left it; maskDirty until autosaved
    bool maskDirty = false;
    // Per brick, the last content version at which the mask changed over it: its mesh's darkening.
    std::unordered_map<BrickKey, uint64_t, BrickKeyHash> maskStamps;
    bool stopping = false;
    bool autosaveWanted = false; // the frame found dirty bricks in the budget's way: a loader saves them
    /// The edit count at which a loader's autosave last failed: the frame asks again only after an edit,
    /// so that a store that refuses writes is not retried on every frame.
    std::optional<uint64_t> loaderAutosaveFailedAt;
    std::vector<std::unique_ptr<BrickStore>> readers; // one per worker
    std::vector<std::thread> workers;

    Impl(const std::string& path, const StreamingOptions& o) : options(o), scene(SceneStore::open(path, o.access))
    {
        levels = scene.lodLevels();
        residentPerLevel.assign(std::size_t(levels) + 1, 0);
        std::vector<std::set<IndexCoord>> stored(std::size_t(levels) + 1);
        uint64_t largest = 0;
        for (int k = 0; k <= levels; ++k) {
            scene.bricks().scan(k, [&](const BrickKey& key, const BrickSummary& s) {
                stored[std::size_t(k)].insert(key.brick);
                const uint64_t estimate = kEstimatedBytesPerBrick + kEstimatedBytesPerLeaf * s.leaves;
                estimates[key] = estimate;
                largest = std::max(largest, estimate);
            });
            if (k > 0)
                for (const IndexCoord& b : stored[std::size_t(k - 1)]) stored[std::size_t(k)].insert(parentBrick(b));
        }
        present = BrickPresence(stored);
        for (int k = 1; k <= levels; ++k) {
            const double voxel = scene.voxelSize() * double(1 << k);
            scene.bricks().scanLodErrors(k, [&](const IndexCoord& b, double error) {
                if (present.contains(k, b)) present.setShownError(k, b, lodShownError(error, voxel, coarseTolerance(options.meshing)));
            });
        }
        if (options.memoryBudgetBytes < largest)
            throw std::invalid_argument("a memory budget of " + std::to_string(options.memoryBudgetBytes >> 20) +
                                        " MB cannot hold one brick of this scene (the largest needs about " +
                                        std::to_string((largest + (1 << 20) - 1) >> 20) + " MB)");
        edits = committedEdits(scene);
        materials = scene.materials();
        mask = scene.mask();
        for (int k = 0; k <= levels; ++k) {
            levelVolumes.emplace_back(scene.voxelSize() * double(1 << k));
            levelVolumes.back().materials() = materials;
        }
        // Each loader reads through a connection of its own: one shared connection serializes the reads.
        for (int i = 0; i < std::max(1, options.loaderThreads); ++i) readers.push_back(scene.bricks().openReader());
        for (std::size_t i = 0; i < readers.size(); ++i) workers.emplace_back([this, i] { work(*readers[i]); });
    }

    ~Impl()
    {
        {
            std::lock_guard<std::mutex> lock(mutex);
            stopping = true;
        }
        wake.notify_all();
        for (std::thread& t : workers) t.join();
    }

    /// fn(other, towards) for each brick of the cut touching a brick (itself included), with the side of
    /// `other` that the brick lies on (directionIndex of `towards`; 13 for the brick itself).
    template <typename Fn>
    void forEachTouchingInCut(const BrickKey& key, const Fn& fn) const
    {
        const int64_t own = int64_t(kLodBrickVoxels) << key.level;
        LodCut::Point lo, hi;
        for (int a = 0; a < 3; ++a) {
            lo[std::size_t(a)] = int64_t(key.brick[std::size_t(a)]) * own;
            hi[std::size_t(a)] = lo[std::size_t(a)] + own;
        }
        cut->forEachTouching(lo, hi, [&](const LodBrick& other) {
            std::array<int, 3> towards{};
            const int64_t otherSize = int64_t(kLodBrickVoxels) << other.level;
            for (int a = 0; a < 3; ++a) {
                const int64_t olo = int64_t(other.brick[std::size_t(a)]) * otherSize, ohi = olo + otherSize;
                towards[std::size_t(a)] = hi[std::size_t(a)] <= olo ? -1 : lo[std::size_t(a)] >= ohi ? 1 : 0;
            }
            fn(other, towards);
        });
    }

    /// Changes when the brick's content, or the bricks its mesh reads (those of the cut touching it,
    /// and their content), change. 0 when it is not resident. Lock held.
    uint64_t meshVersionLocked(const BrickKey& key) const
    {
        const auto it = resident.find(key);
        if (it == resident.end()) return 0;
        // Order-independent sums over the cut's bricks touching this one: which they are, and their content.
        uint64_t v = it->second.version * 0x9E3779B97F4A7C15ull;
        v += it->second.besideMoved * 0xD6E8FEB86659FD93ull;
        v += it->second.finerMoved * 0xA0761D6478BD642Full;
        const auto stamp = maskStamps.find(key);
        if (stamp != maskStamps.end()) v += stamp->second * 0xC2B2AE3D27D4EB4Full;
        const LodBrickHash hash;
        forEachTouchingInCut(key, [&](const LodBrick& other, const std::array<int, 3>& towards) {
            v += hash(other) * 0x100000001B3ull;
            const auto r = resident.find({other.level, other.brick});
            if (r == resident.end()) return;
            // How far into `other` this brick's mesh reads, on the side of it this brick lies on.
            const int reachClass = std::clamp(key.level - other.level, 0, kReachClasses - 1);
            v += r->second.sides[std::size_t(reachClass)][std::size_t(directionIndex(towards))] * 0xC2B2AE3D27D4EB4Full;
        });
        return v;
    }

    /// The bricks beside a view's cut whose points its meshes read (on the shown bricks' faces, a leaf
    /// beyond) where no brick the view may show holds their region: needed too, so that those meshes read
    /// the surface there, not the empty space of a brick not loaded (which capped a level-0 brick under
    /// a level-1 one with a false lid, open at its edges), and do not change with what happens to be
    /// resident beside them. Most needed first; kept while the bricks the view may show stay the same.
    /// Lock held.
    void updateBesides(const ViewNeeds& needs, const NeedsTree& tree, const std::vector<uint32_t>& order, const std::vector<char>& mayShow)
    {
        std::vector<BrickKey> keys;
        for (const uint32_t n : order)
            if (mayShow[n]) keys.push_back(needs.bricks[n]);
        if (keys == besidesOf) return;
        std::vector<BrickKey> notShown;
        const std::vector<BrickKey> cutShown = shownCut(needs, tree, mayShow, notShown); // sorted
        LodBrickMap<char> listed(4 * keys.size());
        for (const BrickKey& key : keys) listed.insert(key.level, key.brick);
        besides.clear();
        for (const BrickKey& key : keys) {
            if (!std::binary_search(cutShown.begin(), cutShown.end(), key)) continue;
            for (uint32_t around = present.neighbours(key.level, key.brick); around != 0; around &= around - 1) {
                const BrickKey beside{key.level, neighbourBrick(key.brick, __builtin_ctz(around))};
                if (listed.insert(beside.level, beside.brick).second) besides.push_back(beside);
            }
        }
        besidesOf = std::move(keys);
    }

    /// How many of a view's needed bricks, in `order`, the budget holds together with the bricks
    /// beside the cut they make (what the cut's meshes read where a coarser brick shows the region
    /// beside them): a brick accepted pays for its neighbours of its level not accepted, until all its
    /// needed children are accepted (it is split then, and no longer read from); a neighbour accepted
    /// later pays only for its mesh. So a budget-limited view refines only as far as its meshes can be
    /// whole. Lock held.
    std::size_t bricksFittingWithBesides(const ViewNeeds& needs, const std::vector<uint32_t>& order) const
    {
        const auto brickBytes = [&](const BrickKey& key) {
            const auto it = resident.find(key);
            return it != resident.end() ? it->second.bytes : estimateOf(key);
        };
        const std::size_t n = needs.bricks.size();
        std::vector<uint32_t> childrenLeft(n, 0);
        for (std::size_t i = 0; i < n; ++i)
            if (needs.parent[i] != ViewNeeds::kNone) ++childrenLeft[needs.parent[i]];
        // Per brick met: whether it is accepted, and how many accepted bricks read it beside them.
        struct Standing {
            bool accepted = false;
            uint32_t readers = 0;
        };
        LodBrickMap<Standing> standing(4 * n);
        const auto standingOf = [&](const BrickKey& key) { return standing.insert(key.level, key.brick).first; };
        uint64_t cost = 0;
        const auto forEachBeside = [&](const BrickKey& key, const auto& fn) {
            for (uint32_t around = present.neighbours(key.level, key.brick); around != 0; around &= around - 1) {
                const BrickKey beside{key.level, neighbourBrick(key.brick, __builtin_ctz(around))};
                Standing* st = standingOf(beside);
                if (!st->accepted) fn(beside, *st);
            }
        };
        std::size_t count = 0;
        for (; count < order.size(); ++count) {
            const uint32_t i = order[count];
            const BrickKey& key = needs.bricks[i];
            const auto it = resident.find(key);
            uint64_t bytes = budgetedBytes(key, it != resident.end() ? &it->second : nullptr);
            Standing* own = standingOf(key);
            if (own->readers > 0) bytes -= brickBytes(key);
            forEachBeside(key, [&](const BrickKey& beside, const Standing& st) {
                if (st.readers == 0) bytes += brickBytes(beside);
            });
            if (cost + bytes > options.memoryBudgetBytes) break;
            cost += bytes;
            own = standingOf(key); // the table may have grown
            own->readers = 0;
            own->accepted = true;
            forEachBeside(key, [&](const BrickKey&, Standing& st) { ++st.readers; });
            // A parent whose needed children are all accepted is split: its besides are read no more.
            const uint32_t parent = needs.parent[i];
            if (parent == ViewNeeds::kNone || --childrenLeft[parent] > 0) continue;
            forEachBeside(needs.bricks[parent], [&](const BrickKey& beside, Standing& st) {
                if (st.readers == 0 || --st.readers > 0) return;
                cost -= brickBytes(beside);
            });
        }
        return count;
    }

    /// What a resident brick's mesh reads of the loads around it, per side (MeshReadVersions). Lock held.
    MeshReadVersions meshReadVersionsLocked(const BrickKey& key) const
    {
        MeshReadVersions out;
        const auto it = resident.find(key);
        if (it == resident.end()) return out;
        // Pieces re-made per leaf are kept only while no brick beside moved (their face cells read it);
        // finer bricks moving inside it change only the transition cells, which are made every time.
        out.sides[13] = it->second.loadVersion * 0x9E3779B97F4A7C15ull + it->second.besideMoved * 0xD6E8FEB86659FD93ull;
        const LodBrickHash hash;
        forEachTouchingInCut(key, [&](const LodBrick& other, const std::array<int, 3>& towards) {
            // The side of this brick that `other` lies on.
            uint64_t& side = out.sides[std::size_t(directionIndex({-towards[0], -towards[1], -towards[2]}))];
            side += hash(other) * 0x100000001B3ull;
            const auto r = resident.find({other.level, other.brick});
            if (r != resident.end()) side += r->second.loadVersion * 0xC2B2AE3D27D4EB4Full;
        });
        return out;
    }

    uint64_t estimateOf(const BrickKey& key) const
    {
        const auto it = estimates.find(key);
        return it == estimates.end() ? kEstimatedBytesPerBrick : it->second;
    }

    /// What a brick takes with its mesh: resident ones as they are (a shown brick's mesh estimated until
    /// it is made), others estimated.
    uint64_t budgetedBytes(const BrickKey& key, const Resident* r) const
    {
        const uint64_t brick = r ? r->bytes : estimateOf(key);
        const uint64_t mesh = r && r->mesh ? r->mesh->bytes : uint64_t(double(brick) * meshShare);
        return brick + mesh;
    }

    void dropMesh(const BrickKey& key, Resident& r)
    {
        if (!r.mesh) return;
        residentBytes -= r.mesh->bytes;
        meshBytes -= r.mesh->bytes;
        r.mesh.reset();
        meshed.erase(key);
    }

    /// Follows what meshes take against their bricks (each mesh made, kept or not: a budget that keeps
    /// none must still learn to leave room for them).
    void learnMeshShare(const Resident& r, const BrickMesh& mesh)
    {
        const double share = r.bytes ? double(mesh.bytes) / double(r.bytes) : 0.0;
        meshShare = meshSamples++ == 0 ? share : 0.9 * meshShare + 0.1 * share;
    }

    /// `inputs`: meshReadVersionsLocked(key) when the mesh was made; `content`: the brick's version then.
    void keepMesh(const BrickKey& key, Resident& r, std::shared_ptr<const BrickMesh> mesh, const MeshReadVersions& inputs, uint64_t content)
    {
        residentBytes += mesh->bytes;
        meshBytes += mesh->bytes;
        r.mesh = std::move(mesh);
        r.meshInputs = inputs;
        r.meshContent = content;
        meshed.insert(key);
    }

    /// What a brick's mesh is made from beside the level trees, taken under the lock so that meshing
    /// runs without it.
    struct MeshInputs {
        BrickKey key;
        std::shared_ptr<const LodCut> cut;
        /// Made and kept in pieces per leaf, re-using those of `old` where no edit since reached them
        /// (above level 0 only the transition cells, which read the finer levels, are made again).
        bool inPieces = false;
        std::shared_ptr<const BrickMeshPieces> old;
        bool reuse = false;               // `old`'s pieces hold where `changed` and `movedSides` do not reach
        std::vector<BlockChange> changed; // level-0 leaves edits changed since `old`, near the brick
        std::vector<int> movedSides;      // a level-0 brick's: directions where the cut or the loads changed
        MeshReadVersions inputs;          // meshReadVersionsLocked(key)
        uint64_t content = 0;             // the brick's version
        uint64_t version = 0;             // meshVersionLocked(key)
        uint64_t leafLogSeq = 0;
        VoxelMask mask;
    };

    /// The inputs of a resident brick's mesh as the scene holds them now. Lock held.
    /// `forEdits`: whether it may be made in pieces, from the kept mesh's where they hold.
    MeshInputs meshInputsLocked(const BrickKey& key, bool forEdits = false) const
    {
        MeshInputs in;
        in.key = key;
        in.cut = cut;
        in.inputs = meshReadVersionsLocked(key);
        const Resident& r = resident.at(key);
        in.content = r.version;
        // A mesh made again for edits is made in pieces, so that the next edits re-mesh only the leaves
        // they reach: the loads around unchanged, or a level-0 brick edited since or already in pieces
        // (the cut moving beside it re-makes the leaves on that side). Others are made whole and take
        // less memory.
        in.inPieces = forEdits && r.mesh && cut->shows({key.level, key.brick}) &&
                      (r.meshInputs == in.inputs || (key.level == 0 && (r.mesh->pieces || r.version != r.meshContent)));
        std::shared_ptr<const BrickMeshPieces> old = in.inPieces ? r.mesh->pieces : nullptr;
        in.version = meshVersionLocked(key);
        in.leafLogSeq = leafLogSeq;
        in.mask = mask;
        if (!in.inPieces) return in;
        // A level-0 brick's pieces hold where the loads and the cut around it did not change: a side that
        // did makes the leaves reading it again (a coarse brick's, all of them).
        if (old && old->leafLogSeq >= leafLogFloor && old->inputs.sides[13] == in.inputs.sides[13]) {
            for (int d = 0; d < 27; ++d)
                if (old->inputs.sides[std::size_t(d)] != in.inputs.sides[std::size_t(d)]) in.movedSides.push_back(d);
            in.reuse = in.movedSides.empty() || key.level == 0;
        }
        in.old = std::move(old);
        if (!in.reuse || key.level != 0) return in;
        // The leaves edits changed since `old`, near enough for this brick's cells or occlusion to read
        // (edits change level 0; the levels above change by loads).
        std::map<IndexCoord, BlockChange> changedAt; // per leaf, the bounds of all its changes
        for (auto it = leafLog.rbegin(); it != leafLog.rend() && it->first > in.old->leafLogSeq; ++it) {
            const BlockChange& c = it->second;
            if (!inPiecesBox(key, c.origin, 2 * kLeafDim)) continue;
            const auto [at, added] = changedAt.emplace(c.origin, c);
            if (!added)
                for (std::size_t a = 0; a < 3; ++a) {
                    at->second.min[a] = std::min(at->second.min[a], c.min[a]);
                    at->second.max[a] = std::max(at->second.max[a], c.max[a]);
                }
        }
        for (const auto& entry : changedAt) in.changed.push_back(entry.second);
        return in;
    }

    /// Whether leaf `c` lies within `grow` voxels of the leaves whose chunks a brick's pieces hold.
    static bool inPiecesBox(const BrickKey& key, const IndexCoord& c, int32_t grow)
    {
        for (std::size_t a = 0; a < 3; ++a) {
            const int32_t lo = key.brick[a] * kBrickEdge, hi = lo + kBrickEdge + kLeafDim;
            if (c[a] < lo - grow || c[a] >= hi + grow) return false;
        }
        return true;
    }

    /// The mesh of a resident brick made from `in` and the level trees (`trees` held, shared or not).
    std::shared_ptr<const BrickMesh> makeMesh(const MeshInputs& in) const
    {
        std::vector<const Volume*> levelsOf;
        for (const Volume& v : levelVolumes) levelsOf.push_back(&v);
        const BrickKey& key = in.key;
        auto out = std::make_shared<BrickMesh>();
        const LodBrick brick{key.level, key.brick};
        const Volume& volume = *levelsOf[std::size_t(key.level)];
        Mesh made;
        if (in.inPieces) {
            out->pieces = remeshPieces(in, levelsOf);
            // Each piece's occlusion (low byte) and blend (the three above) welded along as one value.
            std::vector<const MeshChunk*> chunks;
            std::vector<std::vector<uint32_t>> shading(out->pieces->leaves.size());
            std::vector<const std::vector<uint32_t>*> shadingOf;
            for (std::size_t i = 0; i < out->pieces->leaves.size(); ++i) {
                const LeafMesh& leaf = *out->pieces->leaves[i];
                chunks.push_back(&leaf.chunk);
                shading[i].resize(leaf.occlusion.size());
                for (std::size_t v = 0; v < shading[i].size(); ++v) shading[i][v] = leaf.occlusion[v] | leaf.blend[v] << 8;
                shadingOf.push_back(&shading[i]);
            }
            std::vector<uint32_t> welded;
            made = weldChunks(chunks, shadingOf, &welded);
            out->occlusion.resize(welded.size());
            out->blend.resize(welded.size());
            for (std::size_t v = 0; v < welded.size(); ++v) {
                out->occlusion[v] = uint8_t(welded[v] & 0xffu);
                out->blend[v] = welded[v] >> 8;
            }
            const TransitionMesh& transitions = *out->pieces->transitions;
            appendMesh(made, transitions.mesh);
            out->occlusion.insert(out->occlusion.end(), transitions.occlusion.begin(), transitions.occlusion.end());
            out->blend.insert(out->blend.end(), transitions.blend.begin(), transitions.blend.end());
            std::vector<uint32_t> kept;
            if (simplifyLodBrickMesh(made, key.level, volume.voxelSize(), options.meshing, &kept)) {
                std::vector<uint8_t> occlusion(kept.size());
                std::vector<uint32_t> blend(kept.size());
                for (std::size_t v = 0; v < kept.size(); ++v) {
                    occlusion[v] = out->occlusion[kept[v]];
                    blend[v] = out->blend[kept[v]];
                }
                out->occlusion = std::move(occlusion);
                out->blend = std::move(blend);
            }
        } else {
            // A brick outside the last frame's cut (asked for directly) is meshed alone at its level.
            made = meshLodBrick(levelsOf, in.cut->shows(brick) ? *in.cut : LodCut({brick}), brick, options.meshing);
            simplifyLodBrickMesh(made, key.level, volume.voxelSize(), options.meshing);
            out->occlusion = vertexOcclusion(volume, made);
            out->blend = vertexMaterialBlend(volume, made);
        }
        out->masked = maskedVertices(in.mask, made, scene.voxelSize());
        out->mesh = QuantizedMesh(made, scene.voxelSize() / kMeshLatticePerVoxel);
        out->version = in.version;
        out->content = in.content;
        out->hash = out->mesh.contentHash();
        for (uint8_t o : out->occlusion) out->hash = (out->hash ^ o) * 1099511628211ull;
        for (uint8_t m : out->masked) out->hash = (out->hash ^ m) * 1099511628211ull;
        for (uint32_t b : out->blend) out->hash = (out->hash ^ b) * 1099511628211ull;
        out->bytes = sizeof(BrickMesh) + out->mesh.memoryBytes() + out->occlusion.capacity() + out->masked.capacity() +
                     out->blend.capacity() * sizeof(uint32_t) + (out->pieces ? out->pieces->bytes : 0);
        return out;
    }

    /// The mask changed from `old` to `mask`: the bricks of every level over the leaves that changed (and
    /// those beside them, whose vertices may round into them) get a new stamp, so that their meshes are
    /// darkened anew. Lock held.
    void noteMaskChange(const VoxelMask& old)
    {
        const uint64_t stamp = ++versions;
        if (old.inverted() != mask.inverted()) {
            for (const auto& [key, r] : resident) maskStamps[key] = stamp;
            return;
        }
        std::set<IndexCoord> leaves;
        const auto& a = old.listedLeaves();
        const auto& b = mask.listedLeaves();
        for (const auto& [origin, bits] : a) {
            const auto it = b.find(origin);
            if (it == b.end() || it->second != bits) leaves.insert(origin);
        }
        for (const auto& [origin, bits] : b)
            if (!a.count(origin)) leaves.insert(origin);
        std::set<IndexCoord> bricks;
        for (const IndexCoord& leaf : leaves) {
            IndexCoord lo, hi;
            for (std::size_t i = 0; i < 3; ++i) {
                lo[i] = floorDivide(leaf[i] - 1, kBrickEdge);
                hi[i] = floorDivide(leaf[i] + kLeafDim, kBrickEdge);
            }
            for (int32_t x = lo[0]; x <= hi[0]; ++x)
                for (int32_t y = lo[1]; y <= hi[1]; ++y)
                    for (int32_t z = lo[2]; z <= hi[2]; ++z) bricks.insert({x, y, z});
        }
        for (int k = 0; k <= levels; ++k) {
            std::set<IndexCoord> atLevel;
            for (const IndexCoord& b0 : bricks)
                atLevel.insert({floorDivide(b0[0], 1 << k), floorDivide(b0[1], 1 << k), floorDivide(b0[2], 1 << k)});
            for (const IndexCoord& c : atLevel) maskStamps[{k, c}] = stamp;
        }
    }

    /// The pieces of a brick's mesh of `in`'s cut: those of `in.old` where they still hold (the same
    /// loads around, and no edit logged since reached the leaf), the rest meshed now.
    std::shared_ptr<const BrickMeshPieces> remeshPieces(const MeshInputs& in, const std::vector<const Volume*>& levelsOf) const
    {
        auto next = std::make_shared<BrickMeshPieces>();
        next->inputs = in.inputs;
        next->leafLogSeq = in.leafLogSeq;
        const BrickKey& key = in.key;
        const LodBrick brick{key.level, key.brick};
        const bool reuse = in.reuse;
        const std::vector<BlockChange>& changed = in.changed;
        std::vector<IndexCoord> remesh; // sorted
        if (reuse) {
            for (const IndexCoord& leaf : leavesAffectedBy(changed, options.meshing))
                if (inPiecesBox(key, leaf, 0)) remesh.push_back(leaf);
            for (int side : in.movedSides) {
                const std::vector<IndexCoord> near = leavesReadingSide(brickBox(key.brick).min, side);
                remesh.insert(remesh.end(), near.begin(), near.end());
            }
            std::sort(remesh.begin(), remesh.end());
            remesh.erase(std::unique(remesh.begin(), remesh.end()), remesh.end());
        }
        std::vector<MeshChunk> fresh = meshLodBrickChunks(levelsOf, *in.cut, brick, options.meshing, reuse ? &remesh : nullptr);
        // Occlusion samples reach 3.5 voxels beyond a chunk's cells (which end a voxel past its leaf): the
        // leaves whose reach meets a change.
        std::set<IndexCoord> occludedAgain;
        for (const BlockChange& c : changed)
            for (int d = 0; d < 27; ++d) {
                const IndexCoord leaf{c.origin[0] + (d % 3 - 1) * kLeafDim, c.origin[1] + ((d / 3) % 3 - 1) * kLeafDim,
                                      c.origin[2] + (d / 9 - 1) * kLeafDim};
                bool meets = true;
                for (std::size_t a = 0; a < 3; ++a)
                    meets = meets && c.origin[a] + c.max[a] >= leaf[a] - kOcclusionReach &&
                            c.origin[a] + c.min[a] <= leaf[a] + kLeafDim + kOcclusionReach;
                if (meets) occludedAgain.insert(leaf);
            }
        std::vector<std::shared_ptr<const LeafMesh>> kept;
        if (reuse)
            for (const auto& leaf : in.old->leaves)
                if (!std::binary_search(remesh.begin(), remesh.end(), leaf->chunk.leafOrigin)) {
                    if (!occludedAgain.count(leaf->chunk.leafOrigin)) kept.push_back(leaf);
                    else fresh.push_back(leaf->chunk); // occluded again below
                }
        std::vector<std::shared_ptr<const LeafMesh>> made(fresh.size());
        const Volume& volume = *levelsOf[std::size_t(key.level)];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fresh.size(), 4), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                auto leaf = std::make_shared<LeafMesh>();
                leaf->occlusion = vertexOcclusion(volume, fresh[i].mesh);
                leaf->blend = vertexMaterialBlend(volume, fresh[i].mesh);
                leaf->chunk = std::move(fresh[i]);
                made[i] = std::move(leaf);
            }
        });
        next->leaves = std::move(kept);
        next->leaves.insert(next->leaves.end(), made.begin(), made.end());
        // A coarse brick's transition cells read the finer bricks on its faces, which edits change
        // without a log of it here: made every time.
        const bool transitionsHold =
            reuse && key.level == 0 && in.movedSides.empty() && in.old->transitions && !reachesAnyCell(changed, in.old->transitions->cells);
        if (transitionsHold) {
            next->transitions = in.old->transitions;
        } else {
            auto transitions = std::make_shared<TransitionMesh>();
            appendLodTransitions(levelsOf, *in.cut, brick, transitions->mesh, &transitions->cells);
            transitions->occlusion = vertexOcclusion(volume, transitions->mesh);
            transitions->blend = vertexMaterialBlend(volume, transitions->mesh);
            next->transitions = std::move(transitions);
        }
        std::sort(next->leaves.begin(), next->leaves.end(),
                  [](const auto& a, const auto& b) { return a->chunk.leafOrigin < b->chunk.leafOrigin; });
        next->bytes = sizeof(BrickMeshPieces);
        for (const auto& leaf : next->leaves)
            next->bytes += sizeof(LeafMesh) + leaf->chunk.mesh.memoryBytes() + leaf->chunk.vertexKeys.capacity() * sizeof(uint64_t) +
                           leaf->occlusion.capacity() + leaf->blend.capacity() * sizeof(uint32_t);
        const TransitionMesh& t = *next->transitions;
        next->bytes += sizeof(TransitionMesh) + t.mesh.memoryBytes() + t.occlusion.capacity() + t.blend.capacity() * sizeof(uint32_t) +
                       t.cells.capacity() * sizeof(TransitionCellBox);
        return next;
    }

    /// Remembers level-0 leaves an edit changed. Lock held.
    void logLeafChanges(const std::vector<BlockChange>& leaves)
    {
        for (const BlockChange& leaf : leaves) leafLog.emplace_back(++leafLogSeq, leaf);
        while (leafLog.size() > kLeafLogLength) {
            leafLogFloor = leafLog.front().first;
            leafLog.pop_front();
        }
    }

    /// Removes a resident brick (and its mesh); its content leaves the trees with the next
    /// clearEvicted(). Lock held.
    void evict(std::unordered_map<BrickKey, Resident, BrickKeyHash>::iterator it)
    {
        dropMesh(it->first, it->second);
        residentBytes -= it->second.bytes;
        pendingClears.push_back(it->first);
        --residentPerLevel[std::size_t(it->first.level)];
        resident.erase(it);
    }

    /// Takes the content of evicted bricks out of the trees. `trees` held alone, and the lock.
    void clearEvicted()
    {
        for (const BrickKey& key : pendingClears)
            if (!resident.count(key)) {
                fillRegion(levelVolumes[std::size_t(key.level)], brickBox(key.brick), kEmptyMaterial);
                noteContentMoved(key);
            }
        pendingClears.clear();
    }

    /// A brick's content entered or left its level's tree (a load, or an evicted brick cleared): the
    /// meshes that read it outside the cut get new versions. Those are the resident bricks of its level
    /// beside it, and its ancestors (their transition cells take the finer side's points on their faces).
    /// A brick of the cut needs none: the versions of the bricks beside it count its residency already,
    /// and a cut that gains or loses it changes their versions too. Lock held.
    void noteContentMoved(const BrickKey& key)
    {
        if (cut->shows({key.level, key.brick})) return;
        const uint64_t stamp = ++versions;
        for (int d = 0; d < 27; ++d) {
            if (d == 13) continue;
            const IndexCoord beside = neighbourBrick(key.brick, d);
            const auto it = resident.find({key.level, beside});
            if (it != resident.end()) it->second.besideMoved = stamp;
        }
        for (BrickKey up = key; up.level < levels;) {
            up = {up.level + 1, parentBrick(up.brick)};
            const auto it = resident.find(up);
            if (it != resident.end()) it->second.finerMoved = stamp;
        }
    }

    /// Accounts for a loaded brick and puts it into its level's tree, after the evicted bricks' content
    /// has left. `trees` held alone, and the lock (released while pasting: the frame goes on, and no
    /// reader of the trees sees the brick before it is whole).
    void install(const BrickKey& key, DecodedRegion&& brick, uint64_t bytes, uint64_t bytesReadFromStore, std::unique_lock<std::mutex>& lock)
    {
        const std::vector<BrickKey> clears = std::exchange(pendingClears, {});
        Resident r{bytes, frameNumber, ++versions, {}, nullptr, 0, 0, 0, 0};
        r.loadVersion = r.version;
        for (auto& c : r.sides) c.fill(r.version);
        resident[key] = std::move(r);
        ++residentPerLevel[std::size_t(key.level)];
        residentBytes += bytes;
        bytesRead += bytesReadFromStore;
        ++loads;
        for (const BrickKey& evicted : clears)
            if (!resident.count(evicted)) noteContentMoved(evicted);
        noteContentMoved(key);
        lock.unlock();
        for (const BrickKey& evicted : clears) fillRegion(levelVolumes[std::size_t(evicted.level)], brickBox(evicted.brick), kEmptyMaterial);
        pasteRegion(levelVolumes[std::size_t(key.level)], std::move(brick));
        lock.lock();
    }

    /// Evicts least recently used clean bricks outside `wanted` and `pinned` until `needed` more bytes
    /// fit. Lock held.
    bool makeRoom(uint64_t needed)
    {
        const auto fits = [&] { return residentBytes + inFlightBytes + needed <= options.memoryBudgetBytes; };
        if (fits()) return true;
        // Least recently used first, among the bricks that may go (one pass over the resident bricks,
        // however many go: a budget-limited view evicts several a frame).
        std::vector<std::pair<uint64_t, BrickKey>> candidates;
        for (const auto& [key, r] : resident)
            if (!(key.level == 0 && dirty.count(key.brick)) && !wanted.count(key) && !pinned.count(key)) candidates.emplace_back(r.lastUsed, key);
        std::sort(candidates.begin(), candidates.end());
        for (const auto& [used, key] : candidates) {
            if (fits()) break;
            evict(resident.find(key));
            ++evictions;
        }
        return fits();
    }

    /// Whether dirty bricks take room makeRoom could give once they are saved. Lock held.
    bool dirtyInTheWay() const
    {
        return std::any_of(dirty.begin(), dirty.end(), [&](const IndexCoord& b) { return !wanted.count({0, b}) && !pinned.count({0, b}); });
    }

    /// makeRoom, autosaving first (all the dirty bricks, so the store never holds half an edit) when dirty
    /// bricks stand in the way. `trees` and the lock held, both released while the autosave writes.
    bool makeRoomSaving(uint64_t needed, std::unique_lock<std::shared_mutex>& treesHeld, std::unique_lock<std::mutex>& lock)
    {
        if (makeRoom(needed)) return true;
        if (!dirtyInTheWay()) return false;
        lock.unlock();
        treesHeld.unlock();
        autosave();
        treesHeld.lock();
        lock.lock();
        return makeRoom(needed);
    }

    /// An autosave a loader runs to make room: one that fails leaves the bricks dirty (still resident),
    /// and the editor's own autosave, which reports errors, tries again.
    void autosaveOnLoader()
    {
        try {
            autosave();
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex);
            loaderAutosaveFailedAt = edits;
        }
    }

    void work(const BrickStore& reader)
    {
        std::unique_lock<std::mutex> lock(mutex);
        std::unique_lock<std::shared_mutex> treesHeld(trees, std::defer_lock);
        while (true) {
            wake.wait(lock, [&] { return stopping || autosaveWanted || !queue.empty(); });
            if (stopping) return;
            if (autosaveWanted) {
                autosaveWanted = false;
                lock.unlock();
                autosaveOnLoader();
                lock.lock();
                continue;
            }
            const BrickKey key = queue.front();
            queue.pop_front();
            const uint64_t estimate = estimateOf(key);
            inFlight.insert(key);
            inFlightBytes += estimate;
            // Read under the lock: an autosave on another thread may replace the store's table. The
            // table only grows, and a brick the reader sees was committed with its materials.
            const std::size_t materialCount = materials.size();
            lock.unlock();
            std::optional<DecodedRegion> loaded;
            uint64_t payloadBytes = 0;
            bool unreadable = false;
            try {
                loaded = scene.readBrick(key.level, key.brick, reader, materialCount, &payloadBytes);
            } catch (...) {
                unreadable = true; // a damaged brick shows as missing; sculpting it reports the error
            }
            treesHeld.lock();
            lock.lock();
            inFlight.erase(key);
            inFlightBytes -= estimate;
            if (staleInFlight.erase(key)) loaded.reset(); // the next frame asks for it again
            else if (unreadable) damaged.insert(key);      // and is not asked for again
            if (loaded && !resident.count(key)) {
                const uint64_t bytes = loaded->memoryBytes();
                estimates[key] = bytes; // the next frames budget with what it really takes
                if (wanted.count(key)) {
                    if (makeRoom(bytes)) {
                        install(key, std::move(*loaded), bytes, payloadBytes, lock);
                    } else if (dirtyInTheWay()) {
                        // Saved without the locks, so that frames go on; the brick is read again when the
                        // next frame asks for it (an autosave may have rewritten it).
                        lock.unlock();
                        treesHeld.unlock();
                        autosaveOnLoader();
                        treesHeld.lock();
                        lock.lock();
                    }
                }
            }
            treesHeld.unlock();
            if (inFlight.empty()) idle.notify_all();
        }
    }

    using VoxelRange = std::optional<std::pair<IndexCoord, IndexCoord>>; // level-0 voxels; nullopt: all

    /// Loads the level-0 bricks an edit touches that are not resident: the shown ones stay if the budget
    /// allows, else only the edit's are wanted and the view's make room (the next frame asks for them
    /// again). The bricks are pinned (the caller unpins them). Returns the bricks loaded. `trees` and
    /// the lock held (both released while reading).
    uint64_t pageInForEdit(const std::vector<IndexCoord>& bricks, std::unique_lock<std::shared_mutex>& treesHeld, std::unique_lock<std::mutex>& lock)
    {
        for (const IndexCoord& b : bricks) pinned.insert({0, b});
        wanted.clear();
        wanted.insert(shown.begin(), shown.end());
        for (const IndexCoord& b : bricks) wanted.insert({0, b});
        const auto makeRoomForEdit = [&](uint64_t bytes) {
            if (makeRoomSaving(bytes, treesHeld, lock)) return true;
            // Only the edit's bricks are wanted now. The loads under way finish first (they are then
            // dropped): what they would take must not decide whether the edit fits, or the same session
            // would refuse different edits from run to run. Loads finish with the trees held.
            wanted.clear();
            for (const IndexCoord& b : bricks) wanted.insert({0, b});
            queue.clear();
            while (!inFlight.empty()) {
                treesHeld.unlock();
                idle.wait(lock, [&] { return inFlight.empty(); });
                lock.unlock();
                treesHeld.lock();
                lock.lock();
            }
            return makeRoomSaving(bytes, treesHeld, lock);
        };
        uint64_t pagedIn = 0;
        for (const IndexCoord& b : bricks) {
            const BrickKey key{0, b};
            if (resident.count(key)) continue;
            const std::size_t materialCount = materials.size(); // as a loader does: an autosave may run meanwhile
            lock.unlock();
            treesHeld.unlock();
            uint64_t payloadBytes = 0;
            std::unique_lock<std::mutex> store(storeMutex);
            DecodedRegion brick = scene.readBrick(0, b, scene.bricks(), materialCount, &payloadBytes);
            store.unlock();
            treesHeld.lock();
            lock.lock();
            if (resident.count(key)) continue; // a loader got there first
            const uint64_t bytes = brick.memoryBytes();
            if (!makeRoomForEdit(bytes)) throw std::runtime_error("the edit reaches more bricks than the memory budget holds");
            if (resident.count(key)) continue; // a loader got there while an autosave made room
            install(key, std::move(brick), bytes, payloadBytes, lock);
            ++pagedIn;
        }
        return pagedIn;
    }

    /// Unpins an edit's bricks with the lock held again, whatever happens.
    struct Unpin {
        Impl& s;
        std::unique_lock<std::mutex>& lock;
        const std::vector<IndexCoord>& bricks;
        ~Unpin()
        {
            if (!lock.owns_lock()) lock.lock();
            for (const IndexCoord& b : bricks) s.pinned.erase({0, b});
        }
    };

    /// A volume holding the resident level-0 bricks listed, to edit apart from the loaders' trees: the
    /// last edit's, the bricks it held that this edit does not reach cleared, the others copied from
    /// level 0. `trees` held.
    Volume takeWork(const std::vector<IndexCoord>& bricks, const MaterialTable& materialsNow, const VoxelMask& maskNow)
    {
        Volume work = lastWork ? std::move(*lastWork) : Volume(scene.voxelSize());
        lastWork.reset();
        const std::set<IndexCoord> reached(bricks.begin(), bricks.end());
        for (const IndexCoord& b : lastWorkBricks)
            if (!reached.count(b)) fillRegion(work, brickBox(b), kEmptyMaterial);
        for (const IndexCoord& b : bricks)
            if (!lastWorkBricks.count(b)) pasteRegion(work, levelVolumes[0], brickBox(b));
        lastWorkBricks.clear();
        work.materials() = materialsNow;
        work.mask() = maskNow;
        return work;
    }

    /// Keeps an edit's volume for the next, once level 0 holds what it holds for `bricks`.
    void keepWork(Volume&& work, const std::vector<IndexCoord>& bricks)
    {
        lastWork = std::move(work);
        lastWorkBricks = std::set<IndexCoord>(bricks.begin(), bricks.end());
    }

    /// The leaf boxes of brick `b` where `work` differs from `fine`, with the bounds of what differs;
    /// only boxes some range reaches are compared.
    static std::vector<BlockChange> changedLeaves(const IndexCoord& b, const Volume& fine, const Volume& work, const std::vector<VoxelRange>& reached)
    {
        std::vector<BlockChange> out;
        const LeafAlignedBox box = brickBox(b);
        for (int32_t z = 0; z < box.edge; z += kLeafDim)
            for (int32_t y = 0; y < box.edge; y += kLeafDim)
                for (int32_t x = 0; x < box.edge; x += kLeafDim) {
                    const LeafAlignedBox leaf{{box.min[0] + x, box.min[1] + y, box.min[2] + z}, kLeafDim};
                    const bool inReach = std::any_of(reached.begin(), reached.end(), [&](const VoxelRange& r) {
                        if (!r) return true;
                        for (std::size_t a = 0; a < 3; ++a)
                            if (r->second[a] < leaf.min[a] || r->first[a] > leaf.min[a] + kLeafDim - 1) return false;
                        return true;
                    });
                    if (!inReach) continue;
                    const RegionDifference difference = compareRegion(fine, work, leaf);
                    if (!difference.any()) continue;
                    BlockChange& change = out.emplace_back();
                    change.origin = leaf.min;
                    for (std::size_t a = 0; a < 3; ++a) {
                        change.min[a] = uint8_t(difference.lo[a] - leaf.min[a]);
                        change.max[a] = uint8_t(difference.hi[a] - leaf.min[a]);
                    }
                }
        return out;
    }

    /// The leaves of `fine` and of `work` at the origins given, before and after.
    static void recordLeafChanges(const std::vector<BlockChange>& leaves, const Volume& fine, const Volume& work, std::vector<LeafChange>& out)
    {
        for (const BlockChange& change : leaves) {
            const LeafAlignedBox leaf{change.origin, kLeafDim};
            out.push_back({change.origin, encodeRegion(fine, leaf), encodeRegion(work, leaf)});
        }
    }

    /// Pastes the leaves of brick `b` that changed (`leaves`, changedLeaves) from `work` into level 0 and
    /// returns what the brick now takes. `trees` held alone.
    uint64_t pasteBrick(const IndexCoord& b, const Volume& work, const std::vector<BlockChange>& leaves)
    {
        if (leaves.empty()) return 0;
        for (const BlockChange& leaf : leaves) pasteRegion(levelVolumes[0], work, LeafAlignedBox{leaf.origin, kLeafDim});
        return regionMemoryBytes(levelVolumes[0], brickBox(b));
    }

    /// Accounts for brick `b` pasted where it changed (at `leaves`; pasteBrick gave `bytes`): dirty, a new
    /// version, the leaves logged, and the sides whose neighbours read what changed (those `reached` came
    /// within reach of) bumped. Lock held.
    bool commitBrick(const IndexCoord& b, uint64_t bytes, const std::vector<VoxelRange>& reached, const std::vector<BlockChange>& leaves)
    {
        if (leaves.empty()) return false;
        Resident& r = resident.at({0, b});
        const LeafAlignedBox box = brickBox(b);
        logLeafChanges(leaves);
        // A brick the store did not hold (an edit in empty space) is shown from now on, not from the
        // autosave that stores it: the view walks the bricks present and their ancestors.
        present.add(0, b);
        residentBytes = residentBytes - r.bytes + bytes;
        r.bytes = bytes;
        dirty.insert(b);
        r.version = ++versions;
        for (int c = 0; c < kReachClasses; ++c) {
            std::array<bool, 3> nearLow{}, nearHigh{};
            for (const VoxelRange& range : reached)
                for (int a = 0; a < 3; ++a) {
                    const int64_t lo = box.min[std::size_t(a)], hi = lo + box.edge;
                    nearLow[std::size_t(a)] = nearLow[std::size_t(a)] || !range || range->first[std::size_t(a)] < lo + reachOfClass(c);
                    nearHigh[std::size_t(a)] = nearHigh[std::size_t(a)] || !range || range->second[std::size_t(a)] >= hi - reachOfClass(c);
                }
            for (int d = 0; d < 27; ++d) {
                const std::array<int, 3> dir{d % 3 - 1, (d / 3) % 3 - 1, d / 9 - 1};
                bool reads = true;
                for (int a = 0; a < 3; ++a)
                    reads = reads && (dir[std::size_t(a)] == 0 || (dir[std::size_t(a)] < 0 ? nearLow : nearHigh)[std::size_t(a)]);
                if (reads) r.sides[std::size_t(c)][std::size_t(d)] = r.version;
            }
        }
        return true;
    }

    /// What an autosave writes, taken under the lock: the store is written without it.
    struct SaveBatch {
        std::vector<BrickKey> dirty; // sorted
        MaterialTable materials;
        VoxelMask mask;
        bool maskDirty = false;
        uint64_t edits = 0;
    };

    SaveBatch saveBatchLocked() const
    {
        SaveBatch batch;
        for (const IndexCoord& b : dirty) batch.dirty.push_back({0, b}); // in order: `dirty` is sorted
        batch.materials = materials;
        batch.mask = mask;
        batch.maskDirty = maskDirty;
        batch.edits = edits;
        return batch;
    }

    /// Writes a batch in one transaction, with the LOD pyramid above its bricks brought up to date;
    /// nothing when there is nothing new. `trees` held (read) and `storeMutex`, not the lock.
    LodRefresh writeBatch(const SaveBatch& batch)
    {
        LodRefresh lod;
        // Materials defined since (even ones no voxel uses yet) are saved with the bricks, or alone.
        const bool newMaterials = !(batch.materials == scene.materials());
        if (batch.dirty.empty() && committedEdits(scene) == batch.edits && !newMaterials && !batch.maskDirty) return lod;
        const Volume& fine = levelVolumes[0]; // holds `materials` (edits set both)
        StoreTransaction transaction(scene.bricks());
        for (const BrickKey& key : batch.dirty) {
            if (const std::optional<BrickRecord> record = encodeBrick(fine, key.brick)) scene.bricks().put(key, *record);
            else scene.bricks().erase(key);
        }
        if (newMaterials) scene.setMaterials(batch.materials);
        if (batch.maskDirty) scene.setMask(batch.mask);
        if (!batch.dirty.empty()) {
            scene.forgetBounds();
            std::vector<IndexCoord> bricks;
            for (const BrickKey& key : batch.dirty) bricks.push_back(key.brick);
            if (lodFollowsEdits(scene)) lod = updateStoreLod(scene, bricks);
            else if (levels > 0) scene.setLod(levels, true);
        }
        scene.bricks().putMeta(kEditCountKey, std::to_string(batch.edits));
        transaction.commit();
        return lod;
    }

    /// After writeBatch: its bricks are clean (edits wait for `trees`, held since the batch was taken),
    /// the mask too unless it changed meanwhile, and the coarse bricks it rewrote go. Lock held.
    uint64_t finishSaveLocked(const SaveBatch& batch, const LodRefresh& lod)
    {
        for (const BrickKey& key : batch.dirty) dirty.erase(key.brick);
        if (mask == batch.mask) maskDirty = false;
        lodBricksWritten += lod.bricksWritten();
        forgetCoarseBricks(lod);
        return batch.dirty.size();
    }

    /// Writes the dirty bricks (StreamingScene::autosave), neither `trees` nor the lock held on entry:
    /// level 0 cannot change while the batch is written (edits and loads wait for the trees), and the
    /// lock is held only to take the batch and to mark it saved, so that frames go on meanwhile.
    uint64_t autosave()
    {
        std::shared_lock<std::shared_mutex> treesRead(trees);
        std::unique_lock<std::mutex> lock(mutex);
        const SaveBatch batch = saveBatchLocked();
        lock.unlock();
        LodRefresh lod;
        {
            std::lock_guard<std::mutex> store(storeMutex);
            lod = writeBatch(batch);
        }
        lock.lock();
        return finishSaveLocked(batch, lod);
    }

    /// Coarse bricks an autosave rewrote: resident copies go (the view loads them again), as do loads
    /// in flight, which may have read them half-written. Lock held.
    void forgetCoarseBricks(const LodRefresh& lod)
    {
        for (const auto& [key, error] : lod.errors) {
            present.add(key.level, key.brick);
            present.setShownError(key.level, key.brick, error ? std::optional<double>(lodShownError(*error, scene.voxelSize() * double(1 << key.level), coarseTolerance(options.meshing))) : std::nullopt);
        }
        for (std::size_t i = 0; i < lod.changedBricks.size(); ++i)
            for (const IndexCoord& b : lod.changedBricks[i]) {
                const BrickKey key{int(i) + 1, b};
                present.add(key.level, b);
                estimates.erase(key);
                if (inFlight.count(key)) staleInFlight.insert(key);
                damaged.erase(key);
                const auto it = resident.find(key);
                if (it != resident.end()) evict(it);
            }
    }
};


StreamingScene::StreamingScene(const std::string& path, const StreamingOptions& options)
    : impl_(std::make_unique<Impl>(path, options))
{
}

StreamingScene::~StreamingScene()
{
    // Closing keeps what was sculpted: the dirty bricks are committed like an autosave.
    if (impl_->options.access == StoreAccess::ReadOnly) return;
    try {
        autosave();
    } catch (...) {
    }
}


FrameReport StreamingScene::frame(const Viewer& viewer, const OccluderDepth* drawn)
{
    Impl& s = *impl_;
    SelectionOptions selection;
    selection.occluders = drawn;
    selection.pixelTolerance = s.options.pixelTolerance;
    selection.voxelSize = s.scene.voxelSize();
    selection.levels = s.levels;
    // Under the lock: edits add to `present`.
    const auto asked = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(s.mutex);
    const double lockWaitMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - asked).count();
    // The levels above edited bricks are rebuilt when they are saved: until then the view shows level 0
    // there.
    std::unordered_set<BrickKey, BrickKeyHash> stale;
    for (const IndexCoord& b : s.dirty)
        for (BrickKey up{0, b}; up.level < s.levels;) {
            up = {up.level + 1, parentBrick(up.brick)};
            if (!stale.insert(up).second) break;
        }
    selection.refineAlways = &stale;
    const std::vector<SelectedBrick> selected = selectBricks(viewer, selection, s.present);
    ++s.frameNumber;
    FrameReport report;
    report.lockWaitMs = lockWaitMs;
    report.requested = selected.size();
    report.hidden = uint64_t(std::count_if(selected.begin(), selected.end(), [](const SelectedBrick& b) { return b.hidden; }));
    // What the view needs, coarse first (ancestors stand in while the selection loads), as far as the
    // budget goes. Each needed brick is looked up once per pass: at 90 Hz this runs under the loaders'
    // lock for a few thousand bricks.
    const ViewNeeds needs = viewNeeds(selected, s.levels);
    const std::vector<BrickKey>& needed = needs.bricks;
    const NeedsTree tree(needs);
    // Where edits are shown at level 0 (the bricks under stale ancestors) first: an edit shows however
    // little of the rest of the view the budget holds.
    std::vector<uint32_t> order = needs.order;
    if (!stale.empty())
        std::stable_partition(order.begin(), order.end(), [&](uint32_t n) {
            const uint32_t parent = needs.parent[n];
            return stale.count(needed[n]) || (parent != ViewNeeds::kNone && stale.count(needed[parent]));
        });
    const uint64_t budget = s.options.memoryBudgetBytes;
    uint64_t cost = 0;
    // Whether the budget still holds a brick (with its mesh where it is to be shown); marks it used.
    const auto admit = [&](const BrickKey& key, bool meshed) {
        const auto it = s.resident.find(key);
        const Impl::Resident* r = it != s.resident.end() ? &it->second : nullptr;
        const uint64_t bytes = meshed ? s.budgetedBytes(key, r) : r ? r->bytes : s.estimateOf(key);
        if (cost + bytes > budget) return false;
        cost += bytes;
        if (it != s.resident.end()) it->second.lastUsed = s.frameNumber;
        return true;
    };
    // The bricks the view may show: those it accepted, and edited bricks (they stay until saved). A brick
    // left resident from an earlier view is not drawn: its besides may be missing.
    std::size_t accepted = 0, besidesAccepted = 0;
    std::vector<char> mayShow(needed.size(), 0);
    // Returns false, without finding the besides, where `orLess` and the budget did not hold `count`.
    const auto acceptFirst = [&](std::size_t count, bool orLess) {
        cost = 0;
        accepted = 0;
        while (accepted < count && admit(needed[order[accepted]], true)) ++accepted;
        if (accepted < count && !orLess) return false;
        std::fill(mayShow.begin(), mayShow.end(), 0);
        for (std::size_t i = 0; i < accepted; ++i) mayShow[order[i]] = 1;
        for (std::size_t i = 0; i < needed.size(); ++i)
            if (needed[i].level == 0 && s.dirty.count(needed[i].brick)) mayShow[i] = 1;
        s.updateBesides(needs, tree, order, mayShow);
        besidesAccepted = 0; // read, never shown: no mesh to budget
        while (besidesAccepted < s.besides.size() && admit(s.besides[besidesAccepted], false)) ++besidesAccepted;
        return besidesAccepted == s.besides.size();
    };
    report.budgetLimited = !acceptFirst(order.size(), false);
    if (report.budgetLimited) acceptFirst(s.bricksFittingWithBesides(needs, order), true);
    s.wanted.clear();
    for (std::size_t i = 0; i < accepted; ++i) s.wanted.insert(needed[order[i]]);
    s.wanted.insert(s.besides.begin(), s.besides.begin() + std::ptrdiff_t(besidesAccepted));
    // The frame never autosaves (it would wait for the store): dirty bricks in the budget's way are saved by
    // a loader, and go at a later frame.
    if (!s.makeRoom(0) && s.dirtyInTheWay() && s.loaderAutosaveFailedAt != s.edits) s.autosaveWanted = true;
    // Looked up after makeRoom: an autosave it ran may have dropped rewritten coarse bricks.
    std::vector<char> isResident(needed.size());
    for (std::size_t i = 0; i < needed.size(); ++i) isResident[i] = s.resident.count(needed[i]) > 0;
    std::vector<char> showable(needed.size());
    for (std::size_t i = 0; i < needed.size(); ++i) showable[i] = isResident[i] && mayShow[i];
    s.queue.clear();
    for (std::size_t i = 0; i < accepted; ++i) {
        const BrickKey& key = needed[order[i]];
        if (!isResident[order[i]] && !s.inFlight.count(key) && !s.damaged.count(key)) s.queue.push_back(key);
    }
    bool besidesResident = true;
    for (std::size_t i = 0; i < besidesAccepted; ++i) {
        const BrickKey& key = s.besides[i];
        if (s.resident.count(key)) continue;
        besidesResident = false;
        if (!s.inFlight.count(key) && !s.damaged.count(key)) s.queue.push_back(key);
    }
    s.wake.notify_all();

    // What the view shows now: each selected brick at its own level if it may be shown, else its
    // finest ancestor that may.
    report.coarseComplete = true;
    report.complete = true;
    for (std::size_t i = 0; i < selected.size(); ++i) {
        const SelectedBrick& b = selected[i];
        report.targetError = std::max(report.targetError, b.screenError);
        int shown = -1;
        for (uint32_t n = needs.selected[i]; n != ViewNeeds::kNone; n = needs.parent[n])
            if (showable[n]) {
                shown = needed[n].level;
                break;
            }
        if (shown < 0) {
            report.coarseComplete = false;
            report.complete = false;
            continue;
        }
        if (shown == b.key.level) ++report.hits;
        else report.complete = false;
        report.screenError = std::max(report.screenError, b.screenError * double(1 << (shown - b.key.level)));
    }
    std::vector<BrickKey> unshown;
    s.shown = shownCut(needs, tree, showable, unshown);
    // What is shown stays until the next frame: making room for a mesh must not punch holes in the view.
    s.wanted.insert(s.shown.begin(), s.shown.end());
    std::vector<LodBrick> cut;
    for (const BrickKey& k : s.shown) cut.push_back({k.level, k.brick});
    for (const BrickKey& k : unshown) cut.push_back({k.level, k.brick});
    if (cut != s.cut->bricks()) s.cut = std::make_shared<const LodCut>(cut); // its lookup set is rebuilt only when it changes
    // Meshes are kept for the shown bricks only: a brick that left the view is meshed again if it returns.
    for (auto it = s.meshed.begin(); it != s.meshed.end();) {
        const BrickKey key = *it++;
        if (!std::binary_search(s.shown.begin(), s.shown.end(), key)) s.dropMesh(key, s.resident.at(key));
    }
    report.settled = besidesResident &&
                     std::all_of(order.begin(), order.begin() + std::ptrdiff_t(accepted), [&](uint32_t n) { return isResident[n] != 0; });
    report.residentPerLevel = s.residentPerLevel;
    report.residentBytes = s.residentBytes;
    report.meshBytes = s.meshBytes;
    report.bytesRead = std::exchange(s.bytesRead, 0);
    report.loads = std::exchange(s.loads, 0);
    report.evictions = std::exchange(s.evictions, 0);
    report.pending = s.queue.size() + s.inFlight.size();
    report.damagedBricks = s.damaged.size();
    return report;
}

void StreamingScene::waitForLoads() const
{
    Impl& s = *impl_;
    std::unique_lock<std::mutex> lock(s.mutex);
    s.idle.wait(lock, [&] { return s.queue.empty() && s.inFlight.empty(); });
}

StreamingScene::EditReport StreamingScene::sculpt(const StrokeScript& script, std::vector<LeafChange>* changes, StrokeStart* stroke)
{
    Impl& s = *impl_;
    if (s.options.access == StoreAccess::ReadOnly) throw std::logic_error("sculpting a scene opened read-only");
    const auto start = std::chrono::steady_clock::now();
    // An op the limits refuse is refused before anything it reaches is paged in (a brush mirrored about a
    // far centre reaches a long row of bricks).
    const double surfaceVoxels = checkStrokeScript(script, s.scene.voxelSize(), materials());
    // So is one whose leaves alone would pass the budget, whatever is resident: decided from the op.
    if (surfaceVoxels * kBytesPerSurfaceVoxel > double(s.options.memoryBudgetBytes))
        throw std::runtime_error("the edit would make about " + std::to_string(uint64_t(surfaceVoxels * kBytesPerSurfaceVoxel) >> 20) +
                                 " MB of leaves, more than the memory budget of " + std::to_string(s.options.memoryBudgetBytes >> 20) +
                                 " MB holds (use a smaller brush, or a larger --memory-budget)");
    const std::vector<IndexCoord> bricks = bricksReachedBy(script, s.scene.voxelSize(), [&] {
        std::lock_guard<std::mutex> lock(s.mutex);
        return s.present.bricks(0);
    });
    EditReport report;
    // The script runs outside the locks, so that selection, loads, meshing and picks go on meanwhile: its
    // bricks stay resident (pinned), and only this thread changes level 0 where they are (edits are
    // applied one at a time, from one thread).
    std::unique_lock<std::shared_mutex> trees(s.trees);
    std::unique_lock<std::mutex> lock(s.mutex);
    const Impl::Unpin unpin{s, lock, bricks};
    report.bricksPagedIn = s.pageInForEdit(bricks, trees, lock);
    report.pageInSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const MaterialTable materialsNow = s.materials;
    const VoxelMask maskNow = s.mask;
    lock.unlock();
    Volume work = s.takeWork(bricks, materialsNow, maskNow);
    trees.unlock();
    report.ops = runStrokeScript(work, script, {}, stroke);
    std::vector<Impl::VoxelRange> reached;
    for (const ScriptOp& op : script.ops) reached.push_back(voxelsReachedBy(op, s.scene.voxelSize()));
    // Level 0 still holds these bricks as they were (only this thread changes them): compared with the
    // trees shared, which leaves meshing and picks going.
    std::vector<std::vector<BlockChange>> leaves(bricks.size());
    {
        std::shared_lock<std::shared_mutex> before(s.trees);
        for (std::size_t i = 0; i < bricks.size(); ++i) {
            leaves[i] = Impl::changedLeaves(bricks[i], s.levelVolumes[0], work, reached);
            if (changes) Impl::recordLeafChanges(leaves[i], s.levelVolumes[0], work, *changes);
        }
    }
    trees.lock();
    s.levelVolumes[0].materials() = work.materials();
    std::vector<uint64_t> bytes(bricks.size());
    for (std::size_t i = 0; i < bricks.size(); ++i) bytes[i] = s.pasteBrick(bricks[i], work, leaves[i]);
    lock.lock();
    s.clearEvicted();
    std::vector<BrickKey> changed;
    for (std::size_t i = 0; i < bricks.size(); ++i)
        if (s.commitBrick(bricks[i], bytes[i], reached, leaves[i])) changed.push_back({0, bricks[i]});
    report.bricksChanged += changed.size();
    s.materials = work.materials();
    if (work.mask() != s.mask) {
        const VoxelMask old = std::move(s.mask);
        s.mask = work.mask();
        s.maskDirty = true;
        s.noteMaskChange(old);
    }
    s.edits += script.ops.size();
    s.keepWork(std::move(work), bricks);
    lock.unlock();
    trees.unlock();
    s.tellEditListeners(changed);
    return report;
}

std::optional<std::pair<IndexCoord, IndexCoord>> StreamingScene::storeBounds() const
{
    std::lock_guard<std::mutex> store(impl_->storeMutex);
    return impl_->scene.bounds();
}

VoxelMask StreamingScene::mask() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->mask;
}

void StreamingScene::setMask(const VoxelMask& mask)
{
    Impl& s = *impl_;
    if (s.options.access == StoreAccess::ReadOnly) throw std::logic_error("editing a scene opened read-only");
    std::lock_guard<std::mutex> lock(s.mutex);
    if (mask == s.mask) return;
    const VoxelMask old = std::move(s.mask);
    s.mask = mask;
    s.maskDirty = true;
    s.noteMaskChange(old);
    ++s.edits;
}

StreamingScene::EditReport StreamingScene::restoreLeaves(const std::vector<LeafImage>& leaves)
{
    Impl& s = *impl_;
    if (s.options.access == StoreAccess::ReadOnly) throw std::logic_error("editing a scene opened read-only");
    const auto start = std::chrono::steady_clock::now();
    std::set<IndexCoord> brickSet;
    std::vector<Impl::VoxelRange> reached;
    for (const LeafImage& leaf : leaves) {
        IndexCoord brick, last;
        for (int a = 0; a < 3; ++a) {
            const int32_t o = leaf.origin[std::size_t(a)];
            if (o % kLeafDim != 0) throw std::invalid_argument("a leaf image off the leaf lattice");
            brick[std::size_t(a)] = o >= 0 ? o / kBrickEdge : -((-o + kBrickEdge - 1) / kBrickEdge);
            last[std::size_t(a)] = o + kLeafDim - 1;
        }
        brickSet.insert(brick);
        reached.push_back(std::make_pair(leaf.origin, last));
    }
    const std::vector<IndexCoord> bricks(brickSet.begin(), brickSet.end());
    EditReport report;
    std::unique_lock<std::shared_mutex> trees(s.trees);
    std::unique_lock<std::mutex> lock(s.mutex);
    const Impl::Unpin unpin{s, lock, bricks};
    report.bricksPagedIn = s.pageInForEdit(bricks, trees, lock);
    report.pageInSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    s.clearEvicted();
    const MaterialTable materialsNow = s.materials;
    const VoxelMask maskNow = s.mask;
    lock.unlock(); // the images are decoded, compared and pasted with the trees alone: frames go on
    Volume work = s.takeWork(bricks, materialsNow, maskNow);
    for (const LeafImage& leaf : leaves)
        pasteRegion(work, decodeRegion(leaf.bytes, {leaf.origin, kLeafDim}, s.scene.voxelSize(), materialsNow.size(), "the edit history"));
    std::vector<std::vector<BlockChange>> changed(bricks.size());
    std::vector<uint64_t> bytes(bricks.size());
    for (std::size_t i = 0; i < bricks.size(); ++i) {
        changed[i] = Impl::changedLeaves(bricks[i], s.levelVolumes[0], work, reached);
        bytes[i] = s.pasteBrick(bricks[i], work, changed[i]);
    }
    lock.lock();
    std::vector<BrickKey> changedBricks;
    for (std::size_t i = 0; i < bricks.size(); ++i)
        if (s.commitBrick(bricks[i], bytes[i], reached, changed[i])) changedBricks.push_back({0, bricks[i]});
    report.bricksChanged += changedBricks.size();
    ++s.edits;
    s.keepWork(std::move(work), bricks);
    lock.unlock();
    trees.unlock();
    s.tellEditListeners(changedBricks);
    return report;
}

MaterialTable StreamingScene::materials() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->materials;
}

uint64_t StreamingScene::edits() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->edits;
}

namespace {

template <typename Impl, typename Visit>
void visitLevelsLocked(const Impl& s, const Visit& visit)
{
    std::vector<const Volume*> levels;
    for (const Volume& v : s.levelVolumes) levels.push_back(&v);
    const double h = s.scene.voxelSize();
    visit(levels, [&](const std::array<double, 3>& world) {
        BrickKey key;
        for (std::size_t a = 0; a < 3; ++a) key.brick[a] = int32_t(std::floor(world[a] / (h * kBrickEdge)));
        return s.resident.count(key) > 0;
    });
}

} // namespace

void StreamingScene::visitResidentLevels(const std::function<void(const std::vector<const Volume*>&, const FinestResidentAt&)>& visit) const
{
    const Impl& s = *impl_;
    std::shared_lock<std::shared_mutex> trees(s.trees);
    std::lock_guard<std::mutex> lock(s.mutex);
    visitLevelsLocked(s, visit);
}

bool StreamingScene::tryVisitResidentLevels(const std::function<void(const std::vector<const Volume*>&, const FinestResidentAt&)>& visit) const
{
    const Impl& s = *impl_;
    std::shared_lock<std::shared_mutex> trees(s.trees, std::try_to_lock);
    if (!trees.owns_lock()) return false;
    std::unique_lock<std::mutex> lock(s.mutex, std::try_to_lock);
    if (!lock.owns_lock()) return false;
    visitLevelsLocked(s, visit);
    return true;
}

std::optional<std::string> StreamingScene::meta(const std::string& key) const
{
    std::lock_guard<std::mutex> store(impl_->storeMutex);
    return impl_->scene.bricks().meta(key);
}

void StreamingScene::commitMeta(const std::string& key, const std::string& value)
{
    std::lock_guard<std::mutex> store(impl_->storeMutex);
    StoreTransaction transaction(impl_->scene.bricks());
    impl_->scene.bricks().putMeta(key, value);
    transaction.commit();
}

uint64_t StreamingScene::autosave() { return impl_->autosave(); }

uint64_t StreamingScene::lodBricksWritten() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->lodBricksWritten;
}

uint64_t StreamingScene::dirtyBricks() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->dirty.size();
}

uint64_t StreamingScene::committedEdits(const SceneStore& scene)
{
    const std::optional<std::string> text = scene.bricks().meta(kEditCountKey);
    if (!text) return 0;
    if (text->empty() || text->size() > 19 || text->find_first_not_of("0123456789") != std::string::npos)
        throw StoreError("'" + scene.path() + "' is damaged: its edit count is not a number");
    return std::stoull(*text);
}

uint64_t StreamingScene::residentBytes() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->residentBytes;
}

uint64_t StreamingScene::residentMeshBytes() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->meshBytes;
}

uint64_t StreamingScene::residentActiveVoxels() const
{
    std::shared_lock<std::shared_mutex> trees(impl_->trees);
    uint64_t total = 0;
    for (const Volume& level : impl_->levelVolumes) total += level.stats().activeVoxels;
    return total;
}

double StreamingScene::voxelSize() const { return impl_->scene.voxelSize(); }
const std::string& StreamingScene::storePath() const { return impl_->scene.path(); }

uint64_t StreamingScene::committedEditsStored() const
{
    std::lock_guard<std::mutex> store(impl_->storeMutex);
    return committedEdits(impl_->scene);
}

int StreamingScene::levels() const { return impl_->levels; }

std::vector<BrickKey> StreamingScene::shownBricks() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->shown;
}

std::optional<int> StreamingScene::shownLevelAt(const std::array<double, 3>& world) const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (const BrickKey& key : impl_->shown) {
        const double edge = double(int64_t(kBrickEdge) << key.level) * impl_->scene.voxelSize();
        bool inside = true;
        for (std::size_t a = 0; a < 3; ++a) inside = inside && world[a] >= key.brick[a] * edge && world[a] < (key.brick[a] + 1) * edge;
        if (inside) return key.level;
    }
    return std::nullopt;
}

uint64_t StreamingScene::brickVersion(const BrickKey& key) const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->meshVersionLocked(key);
}

uint64_t StreamingScene::addEditListener(EditListener listener) const
{
    std::lock_guard<std::mutex> lock(impl_->listenersMutex);
    const uint64_t id = impl_->nextListener++;
    impl_->editListeners.emplace_back(id, std::move(listener));
    return id;
}

void StreamingScene::removeEditListener(uint64_t id) const
{
    std::lock_guard<std::mutex> lock(impl_->listenersMutex);
    auto& all = impl_->editListeners;
    all.erase(std::remove_if(all.begin(), all.end(), [&](const auto& entry) { return entry.first == id; }), all.end());
}

std::optional<uint64_t> StreamingScene::brickContent(const BrickKey& key) const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    const auto it = impl_->resident.find(key);
    if (it == impl_->resident.end()) return std::nullopt;
    return it->second.version;
}

std::vector<uint64_t> StreamingScene::brickVersions(const std::vector<BrickKey>& keys) const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    std::vector<uint64_t> out;
    out.reserve(keys.size());
    for (const BrickKey& key : keys) out.push_back(impl_->meshVersionLocked(key));
    return out;
}

std::shared_ptr<const StreamingScene::BrickMesh> StreamingScene::meshBrick(const BrickKey& key) const
{
    Impl& s = *impl_;
    // The trees shared for the whole time (loads and edits paste into them), the lock only while the
    // inputs are taken and the mesh is kept: selection goes on meanwhile.
    std::shared_lock<std::shared_mutex> trees(s.trees);
    std::unique_lock<std::mutex> lock(s.mutex);
    auto it = s.resident.find(key);
    if (it == s.resident.end()) return nullptr;
    if (it->second.mesh && it->second.mesh->version == s.meshVersionLocked(key)) return it->second.mesh;
    const Impl::MeshInputs in = s.meshInputsLocked(key, true);
    lock.unlock();
    std::shared_ptr<const BrickMesh> out = s.makeMesh(in);
    lock.lock();
    it = s.resident.find(key);
    if (it == s.resident.end()) return out; // evicted meanwhile (its content is still in the trees)
    s.learnMeshShare(it->second, *out);
    // Kept if the budget holds it (other bricks may make room); else made again when asked for.
    s.dropMesh(key, it->second);
    if (s.makeRoom(out->bytes)) {
        const auto kept = s.resident.find(key); // makeRoom may have evicted it, if it was not wanted
        if (kept != s.resident.end()) s.keepMesh(key, kept->second, out, in.inputs, in.content);
    }
    return out;
}

std::shared_ptr<const StreamingScene::BrickMesh> StreamingScene::meshBrickAfresh(const BrickKey& key) const
{
    const Impl& s = *impl_;
    std::shared_lock<std::shared_mutex> trees(s.trees);
    std::unique_lock<std::mutex> lock(s.mutex);
    if (!s.resident.count(key)) return nullptr;
    const Impl::MeshInputs in = s.meshInputsLocked(key);
    lock.unlock();
    return s.makeMesh(in);
}

Volume StreamingScene::storedLevel0() const
{
    std::lock_guard<std::mutex> store(impl_->storeMutex);
    return impl_->scene.loadLevel(0);
}

Volume StreamingScene::storedBricks(const std::vector<IndexCoord>& bricks) const
{
    std::lock_guard<std::mutex> store(impl_->storeMutex);
    Volume out(impl_->scene.voxelSize());
    out.materials() = impl_->scene.materials();
    impl_->scene.loadBricks(0, bricks, out);
    return out;
}

Volume StreamingScene::residentLevel0() const
{
    std::shared_lock<std::shared_mutex> trees(impl_->trees);
    std::lock_guard<std::mutex> lock(impl_->mutex);
    Volume out = impl_->levelVolumes[0].clone();
    out.materials() = impl_->materials;
    out.mask() = impl_->mask;
    return out;
}

} // namespace vdbclay
