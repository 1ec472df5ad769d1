#include "editor/SessionWorker.h"

#include "editor/BrushSettings.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace vdbclay {

namespace {

/// The session as the frame may show it; read on the worker between commands.
SessionSnapshot snapshotOf(const EditingSession& session)
{
    SessionSnapshot s;
    s.strokeActive = session.strokeActive();
    s.strokePoint = session.strokePoint();
    s.stats = session.stats();
    s.undoDepth = session.history().undoDepth();
    s.redoDepth = session.history().redoDepth();
    s.unsaved = session.unsaved();
    s.historyBytes = session.history().memoryBytes();
    s.historySpilledBytes = session.history().spilledBytes();
    return s;
}

/// Where a save command writes.
std::string savedPath(const Command& save, const EditingSession& session) { return save.path.empty() ? session.scenePath() : save.path; }

} // namespace

SessionWorker::SessionWorker(EditingSession& session, SessionWorkerOptions options)
    : session_(session), options_(std::move(options)), camera_(session.camera()), brush_(session.brush())
{
    snapshot_ = snapshotOf(session_);
    thread_ = std::thread([this] { run(); });
}

SessionWorker::~SessionWorker()
{
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    thread_.join();
}

void SessionWorker::submit(const Command& command)
{
    if (command.kind == Command::Kind::SetBrush) {
        if (!command.brush) throw std::invalid_argument("a brush command carries no brush settings");
        checkBrushSettings(*command.brush);
        brush_ = *command.brush;
    }
    if (command.kind == Command::Kind::SetCamera) camera_ = command.camera;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        Task task;
        task.command = command;
        queue_.push_back(std::move(task));
    }
    wake_.notify_one();
}

FrameReport SessionWorker::frame(double time, const std::array<int, 2>& viewport, const OccluderDepth* drawn)
{
    return frame(time, viewport, camera_, drawn);
}

FrameReport SessionWorker::frame(double time, const std::array<int, 2>& viewport, const render::Camera& view, const OccluderDepth* drawn)
{
    const FrameReport report = session_.streamView(view, viewport, drawn);
    {
        std::lock_guard<std::mutex> lock(mutex_);
        Task task;
        task.frame = true;
        task.time = time;
        task.viewport = viewport;
        queue_.push_back(std::move(task));
    }
    wake_.notify_one();
    return report;
}

void SessionWorker::setMergeStrokePoints(bool merge)
{
    std::lock_guard<std::mutex> lock(mutex_);
    options_.mergeStrokePoints = merge;
}

std::size_t SessionWorker::pending() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.size() + (running_ ? 1 : 0);
}

void SessionWorker::waitIdle() const
{
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [&] { return queue_.empty() && !running_; });
}

SessionSnapshot SessionWorker::snapshot() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return snapshot_;
}

std::vector<std::string> SessionWorker::takeFailures()
{
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> out;
    out.swap(failures_);
    return out;
}

void SessionWorker::run()
{
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
        if (queue_.empty()) return; // stopping, and everything submitted is done
        Task task = std::move(queue_.front());
        queue_.pop_front();
        running_ = true;
        // A stroke point with the stroke's next point already waiting behind it (frames aside) goes with
        // it, as one op: a brush slower than the pointer keeps up instead of falling further behind.
        if (!task.frame && task.command.kind == Command::Kind::StrokeMove) {
            const auto next = std::find_if(queue_.begin(), queue_.end(), [](const Task& t) { return !t.frame; });
            const bool merge = options_.mergeStrokePoints && next != queue_.end() && next->command.kind == Command::Kind::StrokeMove &&
                               mergedRun_ < kMaxMergedPoints;
            task.command.mergedWithNext = merge;
            mergedRun_ = merge ? mergedRun_ + 1 : 0;
        }
        // A save is the one command slow enough (a whole scene written) that the frame says so meanwhile.
        if (!task.frame && task.command.kind == Command::Kind::Save)
            snapshot_.busy = "saving " + savedPath(task.command, session_);
        lock.unlock();
        if (options_.beforeTask) options_.beforeTask();
        std::string failure;
        const auto started = std::chrono::steady_clock::now();
        try {
            if (task.frame) session_.advanceFrame(task.time, task.viewport);
            else session_.apply(task.command);
        } catch (const std::exception& e) {
            failure = std::string(task.frame ? "the autosave" : commandName(task.command.kind)) + " failed: " + e.what();
        } catch (...) {
            failure = std::string(task.frame ? "the autosave" : commandName(task.command.kind)) + " failed";
        }
        if (options_.afterTask)
            options_.afterTask(task.frame ? nullptr : &task.command,
                               std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count());
        SessionSnapshot published = snapshotOf(session_);
        lock.lock();
        published.commandsApplied = snapshot_.commandsApplied + (task.frame ? 0 : 1);
        const bool saved = !task.frame && task.command.kind == Command::Kind::Save && failure.empty();
        published.saves = snapshot_.saves + (saved ? 1 : 0);
        published.lastSavedPath = saved ? savedPath(task.command, session_) : snapshot_.lastSavedPath;
        snapshot_ = std::move(published);
        if (!failure.empty()) failures_.push_back(std::move(failure));
        running_ = false;
        if (queue_.empty()) idle_.notify_all();
    }
}

std::size_t submitRecordedFrame(SessionWorker& worker, const SessionRecord& record, std::size_t next, uint64_t frame, double* time)
{
    return forRecordedFrame(record, next, frame, time, [&](const Command& c) { worker.submit(c); });
}

} // namespace vdbclay
