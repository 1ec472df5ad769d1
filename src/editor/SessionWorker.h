// The editing session's edit worker: the frame thread submits commands and reads what the last finished
// command published, and never waits for an edit, an undo, an autosave or a save (docs/DESIGN.md, the
// flow of a frame). Commands apply strictly in the order submitted, on one thread, so a session record
// replays to the same scene whatever the timing; the frame's own side (the camera it draws with, the
// brush its panels show, streaming for the view) stays on the frame thread.
#pragma once

#include "editor/EditingSession.h"

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vdbclay {

/// What the worker last published: the session as of the last command it finished.
struct SessionSnapshot {
    bool strokeActive = false;
    std::array<double, 3> strokePoint{0, 0, 0};
    SessionStats stats;
    std::size_t undoDepth = 0, redoDepth = 0;
    bool unsaved = false;
    uint64_t historyBytes = 0, historySpilledBytes = 0;
    uint64_t commandsApplied = 0;
    uint64_t saves = 0;          // saves that succeeded, the last one into
    std::string lastSavedPath;
    std::string busy; // what a slow command under way is doing ("saving ..."), else empty
};

/// The most stroke points the worker merges into one op (Command::mergedWithNext).
constexpr int kMaxMergedPoints = 32;

struct SessionWorkerOptions {
    /// Runs on the worker before each command and frame it takes on (tests inject delays here).
    std::function<void()> beforeTask;
    /// Runs on the worker after each: the command (null for a frame) and the milliseconds it took
    /// (benchmarks). The session may be read there: it is the worker's.
    std::function<void(const Command* command, double milliseconds)> afterTask;
    /// Whether a stroke point goes with the next one already waiting (Command::mergedWithNext): a live
    /// session keeps up with the pointer so; a replay, whose record says which points went together,
    /// must not merge others (what waits depends on timing).
    bool mergeStrokePoints = true;
};

class SessionWorker {
public:
    /// Starts the worker on `session`, which it then owns the use of: the session's commands, frames,
    /// history and record go through the worker; its scene, pick() and scene path stay safe from any
    /// thread. The session must outlive the worker.
    explicit SessionWorker(EditingSession& session, SessionWorkerOptions options = {});
    /// Finishes every command submitted (a user's strokes are never dropped), then stops.
    ~SessionWorker();
    SessionWorker(const SessionWorker&) = delete;
    SessionWorker& operator=(const SessionWorker&) = delete;

    /// Queues a command and returns. A camera or brush takes effect on the frame's side at once (a brush
    /// the session would refuse throws std::invalid_argument here, changing nothing).
    void submit(const Command& command);
    /// The frame thread's frame: streams for the camera submitted last (leaving coarse what `drawn`, the
    /// renderer's last drawn depth, hides), then queues the session's side of the frame (its clock,
    /// autosave when due), ordered with the commands.
    FrameReport frame(double time, const std::array<int, 2>& viewport, const OccluderDepth* drawn = nullptr);
    /// The same, streaming for `view` instead (a headset's eyes move every frame: they are not commands).
    FrameReport frame(double time, const std::array<int, 2>& viewport, const render::Camera& view, const OccluderDepth* drawn = nullptr);

    /// Turns merging of waiting stroke points on or off from now on (a window starting a replay).
    void setMergeStrokePoints(bool merge);
    /// Commands and frames queued or under way.
    std::size_t pending() const;
    /// Waits until the worker has done everything submitted (tests, closing a scene).
    void waitIdle() const;
    SessionSnapshot snapshot() const;
    /// What failed since the last call (a save that could not be written), one line each.
    std::vector<std::string> takeFailures();

    /// The camera and brush as submitted last: what the frame draws and the panels show.
    const render::Camera& camera() const { return camera_; }
    const BrushSettings& brush() const { return brush_; }
    // What is safe from any thread.
    const StreamingScene& scene() const { return session_.scene(); }
    const std::string& scenePath() const { return session_.scenePath(); }
    uint64_t recoveredEdits() const { return session_.recoveredEdits(); }
    /// The session: for pick() from any thread, and, once waitIdle() returned, for anything.
    EditingSession& session() { return session_; }
    const EditingSession& session() const { return session_; }

private:
    struct Task {
        bool frame = false;
        Command command;
        double time = 0.0;
        std::array<int, 2> viewport{0, 0};
    };
    void run();

    EditingSession& session_;
    SessionWorkerOptions options_;
    render::Camera camera_;
    BrushSettings brush_;

    mutable std::mutex mutex_;
    mutable std::condition_variable wake_, idle_;
    std::deque<Task> queue_;
    bool running_ = false; // a task taken off the queue and not finished
    int mergedRun_ = 0;    // stroke points merged in a row so far
    bool stopping_ = false;
    SessionSnapshot snapshot_;
    std::vector<std::string> failures_;
    std::thread thread_;
};

/// Submits the recorded commands from index `next` on that belong before frame `frame` (save commands
/// skipped, as applyRecordedFrame does); returns the next index and, in `time`, the clock of the last one.
std::size_t submitRecordedFrame(SessionWorker& worker, const SessionRecord& record, std::size_t next, uint64_t frame, double* time = nullptr);

} // namespace vdbclay
