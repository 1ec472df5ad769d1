// The editing session: a scene streaming under a memory budget, the current brush, the camera, the
// undo history, autosave and the session record. Device-free: every user action is a Command applied
// here, so the desktop window, the headset and replays drive the same code.
#pragma once

#include "editor/EditedScene.h"
#include "editor/History.h"
#include "editor/SessionCommand.h"
#include "editor/VolumeRayCast.h"
#include "scene/StreamingScene.h"
#include "sculpt/StrokeScript.h"

#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <map>
#include <set>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

struct SessionOptions {
    uint64_t memoryBudgetBytes = 1ull << 30; // resident bricks and meshes
    HistoryLimits history;
    double autosaveSeconds = 5.0;  // dirty bricks are committed this often while sculpting,
    double idleAutosaveSeconds = 1.0; // and once no command came for this long
    int loaderThreads = 2;
    bool discardRecovery = false;  // a .vdb's working store: drop unsaved edits instead of recovering them
    bool refuseUnsaved = false;    // a .vdb's working store with unsaved edits is refused (a replay starts from the saved scene)
    std::string recordPath;        // written at every autosave and by saveRecord(): the session so far
    std::function<void(const std::string&)> message; // one-line notices (autosaves, refused strokes)
};

struct SessionStats {
    uint64_t stampsApplied = 0;
    uint64_t opsRefused = 0;   // stroke stretches a brush could not apply (reported through `message`)
    uint64_t autosaves = 0;
    uint64_t placementsDiffering = 0; // replayed stroke points the recorded ray no longer places (the recorded point is used)
    uint64_t bricksChangedLastFrame = 0;
    double editMsLastFrame = 0.0; // sculpting (page-in included) in the last frame's commands
};

class EditingSession {
public:
    /// Opens `scenePath` (a .vdb or a store) for editing; see prepareScene for recovery.
    EditingSession(const std::string& scenePath, const SessionOptions& options);
    /// Autosaves and writes the record (when recording).
    ~EditingSession();
    EditingSession(const EditingSession&) = delete;
    EditingSession& operator=(const EditingSession&) = delete;

    /// Edits autosaved after the last save that this session found and kept (a session that crashed).
    uint64_t recoveredEdits() const { return prepared_.recoveredEdits; }
    /// Whether the scene changed since it was opened or last saved into its own file (recovered edits
    /// count): what the window's title marks with a '*'.
    bool unsaved() const { return unsaved_; }

    /// Everything a user can do. Recorded with the current frame and time. A stroke stretch the brush
    /// cannot apply (too large, unknown material) is skipped with a message, never thrown; a save that
    /// fails throws (the scene stays as it was).
    void apply(const Command& command);

    /// One frame at `time` seconds since the session began: streams for the camera's view at this
    /// viewport and autosaves when due. Commands applied next belong to the next frame. The two halves,
    /// streamView then advanceFrame.
    FrameReport frame(double time, const std::array<int, 2>& viewport);
    /// Streams for a view: the loaders' selection for `camera` at `viewport`, leaving coarse what `drawn`
    /// (the renderer's last drawn depth, optional) hides. Touches the scene alone, so a frame thread may
    /// call it while a SessionWorker applies commands.
    FrameReport streamView(const render::Camera& camera, const std::array<int, 2>& viewport, const OccluderDepth* drawn = nullptr);
    /// The session's side of a frame: its clock, the last frame's figures, an autosave when due, the
    /// record's frame count.
    void advanceFrame(double time, const std::array<int, 2>& viewport);

    /// The surface under a ray, from the resident data of any level (no loading).
    std::optional<SurfaceHit> pick(const std::array<double, 3>& origin, const std::array<double, 3>& direction,
                                   double maxDistance = 1e30) const;

    /// The same, unless a load or an edit holds the data now: then false at once (a frame asks again next
    /// frame instead of waiting).
    bool tryPick(const std::array<double, 3>& origin, const std::array<double, 3>& direction, double maxDistance,
                 std::optional<SurfaceHit>* hit) const;

    const BrushSettings& brush() const { return brush_; }
    const render::Camera& camera() const { return camera_; }
    /// The scene's bounds in world units (the far side of the last voxel included; a box of 64 voxels
    /// about the origin for an empty scene): what framing and the near plane hold.
    std::pair<std::array<double, 3>, std::array<double, 3>> sceneBox() const;
    /// The box of the bricks the view shows now (a voxel of their level around them), what the near
    /// plane must keep in front of it each frame; sceneBox() while nothing is shown.
    std::pair<std::array<double, 3>, std::array<double, 3>> shownBox() const;
    bool strokeActive() const { return stroke_.active; }
    /// Where the active stroke's brush is (for the overlay and a move brush's drag plane).
    std::array<double, 3> strokePoint() const { return stroke_.lastPoint.point; }
    const History& history() const { return history_; }
    const SessionStats& stats() const { return stats_; }
    const SessionRecord& record() const { return record_; }
    /// The ops in effect, as a stroke script (what `vdbclay sculpt` applies to the scene as it was opened
    /// to make it as it is): those of undone strokes and of strokes that changed nothing are left out.
    nlohmann::json appliedScript() const;
    uint64_t frameNumber() const { return frameNumber_; }
    /// The scene, to look at (views, picks, meshes, figures): every change goes through apply(), so that
    /// history, autosave and replays see it.
    const StreamingScene& scene() const { return *scene_; }
    const std::string& scenePath() const { return scenePath_; }

    /// Commits dirty bricks now (Ctrl+S saves; this only protects against a crash).
    void autosave();
    /// Writes the record to options.recordPath (nothing when not recording).
    void saveRecord() const;

private:
    /// Where a stroke's stamp goes: the surface point and its outward normal (none: the stamp sits on the
    /// point, as in sessions recorded before rays were).
    struct Placement {
        std::array<double, 3> point{0, 0, 0};
        std::optional<std::array<double, 3>> normal;
    };
    struct Stroke {
        bool active = false;
        Placement lastStamp;                      // where the last stamp went
        Placement lastPoint;                      // where the pointer was last
        std::array<double, 3> grab{0, 0, 0};      // a move brush: the surface point grabbed
        double travelled = 0.0;                   // along the pointer's path since the last stamp
        std::vector<LeafChange> changes;          // merged per leaf: first before, last after
        std::map<IndexCoord, std::size_t> changeIndex;
        nlohmann::json ops = nlohmann::json::array(); // applied
        // The stroke's starting state where it changed the scene: the changes' before images, decoded
        // on demand (what the pointer's ray is cast against, so that stamps never climb on their own).
        std::unique_ptr<Volume> before;
        std::set<IndexCoord> replaced;
        std::size_t decoded = 0;
        std::optional<std::string> maskBefore; // the mask as the stroke found it (VoxelMask::encode())
        std::unique_ptr<StrokeStart> start;    // inflate and deflate: the stroke's start where they reached
        // Merged points not applied yet: a stretch's stamps (its pressure), or a grab's last drag.
        std::vector<std::array<double, 3>> pendingPath;
        std::optional<std::array<double, 3>> pendingDrag;
        double pendingPressure = 1.0;
    };
    /// Fills in the point (and normal) of a stroke command from its ray; false when the ray meets no
    /// surface (the command then changes nothing).
    bool placeStroke(Command& command);
    std::optional<SurfaceHit> castAtStrokeStart(const Ray& ray);
    std::array<double, 3> stampCentre(const Placement& at, double pressure) const;
    void beginStroke(const Placement& at, double pressure);
    /// `merged`: the stamps wait for the next point's (Command::mergedWithNext).
    void moveStroke(const Placement& at, double pressure, bool merged);
    void dragStroke(const std::array<double, 3>& point, double pressure, bool merged);
    /// Applies what merged stroke points left waiting.
    void flushMerged();
    /// Whether the brush changes the surface by at most distance x strength per stroke, measured against
    /// the stroke's start (inflate and deflate that do not accumulate).
    bool capsPerStroke() const;
    void endStroke();
    void applyOp(const nlohmann::json& op);
    void putBack(const HistoryStep& step);
    void undo();
    void redo();
    void defineMaterial(const nlohmann::json& material);
    void notify(const std::string& text) const;

    std::string scenePath_;
    SessionOptions options_;
    PreparedScene prepared_;
    std::unique_ptr<StreamingScene> scene_;
    History history_;
    BrushSettings brush_;
    render::Camera camera_;
    Stroke stroke_;
    SessionStats stats_;
    SessionRecord record_;
    nlohmann::json materialsDefined_ = nlohmann::json::array();
    ToolCache tools_; // grid tools stamped so far, built once (a tool file is not expected to change under a session)
    uint64_t frameNumber_ = 0;
    double time_ = 0.0, lastAutosave_ = 0.0, lastCommand_ = 0.0;
    bool editedSinceAutosave_ = false;
    bool unsaved_ = false;
    double editMs_ = 0.0;
    uint64_t bricksChanged_ = 0;
};

/// Applies the recorded commands from index `next` on that belong before frame `frame` (save commands
/// skipped: a replay never writes the files the recorded session saved to); returns the next index and,
/// in `time`, the clock of the last one applied. What replaySession and the window's replay do each frame.
std::size_t applyRecordedFrame(EditingSession& session, const SessionRecord& record, std::size_t next, uint64_t frame, double* time = nullptr);

/// Replays a recorded session on `session` (frame by frame, each frame's commands first, the record's
/// viewport) up to `frames` frames (all when absent); `onFrame` runs after each frame. Save commands are
/// skipped: a replay never writes the files the recorded session saved to.
void replaySession(EditingSession& session, const SessionRecord& record, std::optional<uint64_t> frames = std::nullopt,
                   const std::function<void(uint64_t frame, const FrameReport&)>& onFrame = {});

} // namespace vdbclay
