// The editing session on a store: bricks stream in by view under a memory budget (coarse first, then
// refined, on worker threads), the least recently used ones are evicted, edits page in what they touch,
// and autosave commits the dirty bricks in one transaction. The figures per frame (FrameReport) are the
// API the editor and `vdbclay lod inspect` show.
#pragma once

#include "scene/SceneStore.h"
#include "scene/ViewSelection.h"
#include "mesher/Mesher.h"
#include "mesher/QuantizedMesh.h"
#include "sculpt/StrokeScript.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

/// One 8^3 box of level 0 (a leaf, uniform material or nothing) as encodeRegion writes it, before and
/// after an edit: what the editor's undo history keeps per changed leaf.
struct LeafChange {
    IndexCoord origin{0, 0, 0};
    std::string before, after;
};
/// One 8^3 box's content to put back (LeafChange::before to undo, after to redo).
struct LeafImage {
    IndexCoord origin{0, 0, 0};
    std::string bytes;
};

struct StreamingOptions {
    uint64_t memoryBudgetBytes = 512ull << 20; // resident bricks (volume data) and their meshes
    double pixelTolerance = 1.0;
    int loaderThreads = 2;
    StoreAccess access = StoreAccess::ReadOnly; // ReadWrite to edit and autosave
    /// How meshBrick() meshes the shown bricks: adaptive CMS whose cells also stay whole where their
    /// crossings lie within a quarter voxel of a plane (what cells split at 15 degrees already cut off a
    /// curved surface: no coarser, and far fewer triangles on a terrain), half a voxel on coarse levels.
    MeshOptions meshing = [] {
        MeshOptions o;
        o.kind = MesherKind::CubicalMarchingSquares;
        o.planeTolerance = 0.25;
        return o;
    }();
};

struct FrameReport {
    std::vector<uint64_t> residentPerLevel; // bricks resident, per level
    uint64_t residentBytes = 0; // bricks and their meshes
    uint64_t meshBytes = 0;     // of which meshes (the shown bricks' made so far)
    uint64_t bytesRead = 0;    // payload bytes read from the store since the last frame
    uint64_t loads = 0;        // bricks loaded since the last frame
    uint64_t evictions = 0;    // since the last frame
    uint64_t requested = 0;    // bricks the view asked for this frame
    uint64_t hits = 0;         // of those, resident already
    uint64_t hidden = 0;       // of those, left coarse behind the last frame's depth (OccluderDepth)
    double hitRate() const { return requested ? double(hits) / double(requested) : 1.0; }
    double screenError = 0.0;  // pixels: the largest error among the bricks shown (resident or fallback)
    double targetError = 0.0;  // pixels: the largest error of the selection the view asked for
    bool coarseComplete = false; // every region in view shows some level
    bool complete = false;       // every region in view shows the level it asked for
    bool budgetLimited = false;  // the selection was cut to fit the budget: the view refines less
    bool settled = false;        // every brick the budget admitted is resident: refined as far as it goes
    uint64_t pending = 0;        // loads still queued or running
    uint64_t damagedBricks = 0;  // bricks the store could not give (damaged records), so far
    double lockWaitMs = 0.0;     // what the frame waited for the scene's lock (loaders, edits and saves hold it)
};

class StreamingScene {
public:
    /// Opens the store. Throws std::invalid_argument when the budget cannot hold the largest stored
    /// brick, StoreError when the store cannot be opened.
    StreamingScene(const std::string& path, const StreamingOptions& options);
    /// Commits the dirty bricks (a scene opened for writing), as autosave() does.
    ~StreamingScene();
    StreamingScene(const StreamingScene&) = delete;
    StreamingScene& operator=(const StreamingScene&) = delete;

    /// One frame: selects the bricks the view needs, queues the missing ones (coarse first), evicts
    /// the least recently used bricks the view does not need when over budget, and reports. `drawn`
    /// (optional): the last frame's depth; bricks it hides are not refined (SelectionOptions::occluders).
    FrameReport frame(const Viewer& viewer, const OccluderDepth* drawn = nullptr);
    /// Waits until every queued load has finished (tests, and callers that want a complete view).
    void waitForLoads() const;

    struct EditReport {
        std::vector<ScriptOpReport> ops;
        uint64_t bricksPagedIn = 0;
        uint64_t bricksChanged = 0;
        double pageInSeconds = 0.0;
    };
    /// Applies a script at level 0: the bricks its brushes reach are paged in first (loaded now if not
    /// resident), the changed ones stay resident and dirty until autosave. `changes`, when given, receives
    /// every level-0 leaf box the script changed, before and after (in brick order, then box order).
    /// `stroke` carries an inflate or deflate stroke across calls (runStrokeScript).
    EditReport sculpt(const StrokeScript& script, std::vector<LeafChange>* changes = nullptr, StrokeStart* stroke = nullptr);
    /// Puts leaf boxes back as the images hold them (undo, redo), paging their bricks in first; counts as
    /// one edit. Throws VolumeIOError for damaged images.
    EditReport restoreLeaves(const std::vector<LeafImage>& leaves);
    /// The mask brushes respect (VoxelMask.h), as edits left it; autosave stores it.
    VoxelMask mask() const;
    /// Replaces the mask (undo, redo of a mask edit); counts as one edit.
    void setMask(const VoxelMask& mask);
    /// The scene's materials, with those edits defined since the last autosave.
    MaterialTable materials() const;
    /// Edits applied since the store was made, including those not yet autosaved.
    uint64_t edits() const;
    /// Calls `visit` with each level's resident data (index = level), the loaders held off meanwhile, and
    /// whether the level-0 brick holding a world point is resident (coarser levels stand in elsewhere; where
    /// it is, they may lag its edits until the next autosave).
    using FinestResidentAt = std::function<bool(const std::array<double, 3>& world)>;
    void visitResidentLevels(const std::function<void(const std::vector<const Volume*>&, const FinestResidentAt&)>& visit) const;
    /// The same unless a load or an edit holds the data now: then false at once, `visit` not called (a
    /// frame thread's question that can wait for the next frame).
    bool tryVisitResidentLevels(const std::function<void(const std::vector<const Volume*>&, const FinestResidentAt&)>& visit) const;
    /// A value the store keeps beside the bricks (the editor's save marks), and writing one at once, in a
    /// transaction of its own.
    std::optional<std::string> meta(const std::string& key) const;
    void commitMeta(const std::string& key, const std::string& value);
    /// Writes every dirty brick, and the count of edits applied, in one transaction, with the LOD pyramid
    /// above them brought up to date (resident coarse bricks it changed are loaded again). Returns the
    /// level-0 bricks written.
    uint64_t autosave();
    uint64_t dirtyBricks() const;
    /// Coarse bricks the autosaves so far rewrote to keep the pyramid current.
    uint64_t lodBricksWritten() const;
    /// Edits (script ops) applied since the store was made, as of the last autosave.
    static uint64_t committedEdits(const SceneStore& scene);

    /// Resident bricks and their meshes: what the memory budget bounds.
    uint64_t residentBytes() const;
    uint64_t residentMeshBytes() const;
    /// Active voxels of the resident bricks summed over every level, each on its own lattice: the
    /// surface (in voxel^2 of its level) that residentBytes() holds.
    uint64_t residentActiveVoxels() const;
    /// What stays as the store was opened: its lattice and file. The store itself is not handed out:
    /// its connection is the loaders' and autosave's, under the scene's locks (storeBounds,
    /// storedLevel0, storedBricks, materials read it safely).
    double voxelSize() const;
    const std::string& storePath() const;
    /// Edits (script ops) the store holds as committed by the last autosave.
    uint64_t committedEditsStored() const;
    /// The store's bounds (SceneStore::bounds), read under the scene's lock: safe beside an autosave on
    /// another thread.
    std::optional<std::pair<IndexCoord, IndexCoord>> storeBounds() const;
    /// The resident level-0 bricks, for checks: a volume holding them (dirty content included).
    Volume residentLevel0() const;
    /// Level 0 as the store holds it (as of the last autosave), read through the store's connection under
    /// its lock: safe beside an autosave a load or an edit runs on another thread.
    Volume storedLevel0() const;
    /// Level-0 bricks as the store holds them, the same way.
    Volume storedBricks(const std::vector<IndexCoord>& bricks) const;

    /// What the last frame showed, without overlaps: each selected brick where it is resident; where a
    /// selected brick is not, the finest resident ancestor that stands for all of its selected
    /// descendants (a brick is shown split into its children only once all of them can be shown).
    std::vector<BrickKey> shownBricks() const;
    /// The level the last frame showed at a world point (that of the shown brick holding it), or
    /// nothing where no shown brick holds it.
    std::optional<int> shownLevelAt(const std::array<double, 3>& world) const;
    /// A number that changes whenever what a resident brick's mesh is made from changes: its content
    /// (loaded again, sculpted), the bricks of the view's cut that touch it, or theirs; 0 when the brick
    /// is not resident.
    uint64_t brickVersion(const BrickKey& key) const;
    /// Called on the editing thread after each edit (sculpt, restoreLeaves) with the level-0 bricks whose
    /// content it changed, outside the scene's locks: meshers start on them before a frame asks. Returns
    /// an id for removeEditListener. (Registering observes the scene; it does not change it.)
    using EditListener = std::function<void(const std::vector<BrickKey>&)>;
    uint64_t addEditListener(EditListener listener) const;
    void removeEditListener(uint64_t id) const;
    /// The content version of a resident brick's own data: it only grows, with each edit or load of it;
    /// nullopt when the brick is not resident. A mesh made at content c holds every edit up to c.
    std::optional<uint64_t> brickContent(const BrickKey& key) const;
    /// brickVersion of each brick, under one lock.
    std::vector<uint64_t> brickVersions(const std::vector<BrickKey>& keys) const;
    /// The mesh of a resident brick on its own level's lattice (meshLodBrick with the scene's
    /// StreamingOptions::meshing: vertex-aligned, with transition cells where the last frame's cut shows
    /// a finer brick beside it), in world units, with the version (brickVersion) it was made at; nullptr
    /// when the brick is not resident. The scene keeps it beside the brick, counted in the memory
    /// budget, until the brick's version changes, the brick leaves the view or is evicted: asking again
    /// costs nothing. To keep it, bricks the view no longer wants may be evicted (clean ones only: this
    /// never writes the store); a mesh the budget cannot hold even so is not kept. Const as a cache is:
    /// what the scene holds changes, not what it shows.
    struct BrickMeshPieces;
    /// Kept meshes' positions lie on a lattice of this many steps per level-0 voxel, the same for every
    /// brick and level (a position two bricks compute alike decodes alike in both): within 1/128 voxel
    /// of what the mesher made.
    static constexpr int kMeshLatticePerVoxel = 64;
    struct BrickMesh {
        QuantizedMesh mesh; // positions on the kMeshLatticePerVoxel lattice
        std::vector<uint8_t> occlusion; // per vertex (vertexOcclusion)
        std::vector<uint8_t> masked;    // per vertex, 1 where the mask keeps its voxel; empty: none masked
        std::vector<uint32_t> blend;    // per vertex (vertexMaterialBlend): the material beside its own, and its share
        uint64_t version = 0;
        uint64_t content = 0; // brickContent when it was made
        uint64_t hash = 0;  // of the mesh and its per-vertex shading: equal meshes need no new upload
        uint64_t bytes = 0; // what it takes in memory, its pieces included
        /// Once edits re-mesh the brick (its own or, for a coarse brick, finer ones beside it): the
        /// mesh per leaf, which the next re-mesh re-uses where no edit reached.
        std::shared_ptr<const BrickMeshPieces> pieces;
    };
    std::shared_ptr<const BrickMesh> meshBrick(const BrickKey& key) const;
    /// The same mesh made now from the resident data and the last cut, neither taken from the scene's
    /// meshes nor kept (checks that a kept mesh is still what its brick makes).
    std::shared_ptr<const BrickMesh> meshBrickAfresh(const BrickKey& key) const;
    int levels() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace vdbclay
