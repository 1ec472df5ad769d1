// The edit worker (issue 38): the frame thread submits and never waits; commands apply in the order
// submitted, so a session gives the same scene through the worker, with any number of threads and any
// timing, as applied directly, and as `sculpt` of its exported script.
#include "editor/SessionWorker.h"
#include "sculpt/StrokeScript.h"
#include "support/QuietSession.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"
#include "vdb_hermite/VolumeRegions.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <random>
#include <thread>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

constexpr double kBall = 20.0;
const std::array<int, 2> kViewport{640, 480};

std::string makeBall(const TempDir& dir, const std::string& name)
{
    Volume v(1.0);
    runStrokeScript(v, parseStrokeScript(nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", kBall}}}}}}}.dump()));
    const std::string path = dir.file(name);
    saveVolume(v, path);
    return path;
}

Volume committed(EditingSession& session)
{
    session.autosave();
    return session.scene().storedLevel0();
}

/// Holds the edit worker before its next task while closed (SessionWorkerOptions::beforeTask).
class Gate {
public:
    explicit Gate(bool closed) : closed_(closed) {}
    void set(bool closed)
    {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            closed_ = closed;
        }
        changed_.notify_all();
    }
    /// Options whose worker waits at the gate before each task.
    SessionWorkerOptions options()
    {
        SessionWorkerOptions o;
        o.beforeTask = [this] {
            std::unique_lock<std::mutex> lock(mutex_);
            changed_.wait(lock, [&] { return !closed_; });
        };
        return o;
    }

private:
    std::mutex mutex_;
    std::condition_variable changed_;
    bool closed_;
};

Command brushCommand(const std::string& mode, double radius, double strength)
{
    Command c;
    c.kind = Command::Kind::SetBrush;
    c.brush.emplace();
    c.brush->mode = mode;
    c.brush->radius = radius;
    c.brush->strength = strength;
    if (mode == "paint") c.brush->material = "default";
    return c;
}

Command kind(Command::Kind k)
{
    Command c;
    c.kind = k;
    return c;
}

/// A ray from the eye on +z towards a point of the ball's front.
Command strokeTowards(Command::Kind k, double x, double y)
{
    const std::array<double, 3> eye{0.0, 0.0, 80.0};
    std::array<double, 3> d{x - eye[0], y - eye[1], -eye[2]};
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double& v : d) v /= n;
    Command c;
    c.kind = k;
    c.ray = Ray{eye, d};
    return c;
}

/// Strokes of every mode across the ball's front (seeded), with undo and redo between them and an undo
/// in the middle of a stroke, each frame's commands followed by its frame.
void sculptSession(EditingSession& session, unsigned seed)
{
    Command camera;
    camera.kind = Command::Kind::SetCamera;
    camera.camera.eye = {0.0, 0.0, 80.0};
    camera.camera.target = {0.0, 0.0, 0.0};
    session.apply(camera);
    double time = 0.0;
    const auto frame = [&] { session.frame(time += 1.0 / 90.0, kViewport); };
    for (int i = 0; i < 3; ++i) {
        frame();
        session.scene().waitForLoads();
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-9.0, 9.0);
    const char* modes[] = {"add", "smooth", "inflate", "remove", "paint", "deflate", "flatten", "move", "mask", "add"};
    for (int s = 0; s < 10; ++s) {
        session.apply(brushCommand(modes[s], 3.0 + (s % 3), 0.5 + 0.05 * s));
        double x = u(rng), y = u(rng);
        session.apply(strokeTowards(Command::Kind::StrokeBegin, x, y));
        frame();
        for (int m = 0; m < 5; ++m) {
            x += 1.5;
            session.apply(strokeTowards(Command::Kind::StrokeMove, x, y + 0.3 * m));
            if (s == 6 && m == 2) session.apply(kind(Command::Kind::Undo)); // ends the stroke, then undoes it
            frame();
        }
        session.apply(kind(Command::Kind::StrokeEnd));
        if (s == 3) session.apply(kind(Command::Kind::Undo));
        if (s == 4) session.apply(kind(Command::Kind::Redo));
        frame();
    }
    session.apply(kind(Command::Kind::Undo));
    frame();
}

/// Replays a record through a worker, the frame thread submitting each frame's commands and never
/// waiting; the worker sleeps a random while before each task.
Volume replayThroughWorker(const std::string& scene, const SessionRecord& record, int threads, unsigned delaySeed)
{
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    EditingSession session(scene, quietSession());
    {
        std::mt19937 rng(delaySeed);
        std::mutex rngMutex;
        SessionWorkerOptions options;
        options.mergeStrokePoints = false; // a replay: the record says which points went together
        options.beforeTask = [&] {
            int micros = 0;
            {
                std::lock_guard<std::mutex> lock(rngMutex);
                micros = std::uniform_int_distribution<int>(0, 1500)(rng);
            }
            std::this_thread::sleep_for(std::chrono::microseconds(micros));
        };
        SessionWorker worker(session, options);
        std::size_t next = 0;
        double time = 0.0;
        for (uint64_t f = 0; f < record.frames; ++f) {
            next = submitRecordedFrame(worker, record, next, f, &time);
            worker.frame(time, record.viewport);
        }
        worker.waitIdle();
        CHECK(worker.takeFailures().empty());
        CHECK(worker.snapshot().stats.placementsDiffering == 0);
    }
    return committed(session);
}

} // namespace

TEST_CASE("editor: a session through the edit worker with 1, 2 and 4 threads and random delays makes the scene of the session applied directly and of its script", "[editor][replay][worker]")
{
    TempDir dir;
    const std::string original = makeBall(dir, "a.vdb");
    std::filesystem::copy_file(original, dir.file("b.vdb"));
    SessionRecord record;
    nlohmann::json script;
    Volume direct;
    {
        EditingSession session(original, quietSession());
        sculptSession(session, 7);
        CHECK(session.stats().opsRefused == 0);
        CHECK(session.stats().stampsApplied > 30);
        record = session.record();
        script = session.appliedScript();
        direct = committed(session);
    }
    int run = 0;
    for (const int threads : {1, 2, 4}) {
        const std::string copy = dir.file("worker" + std::to_string(threads) + ".vdb");
        std::filesystem::copy_file(dir.file("b.vdb"), copy);
        INFO(threads << " threads");
        CHECK(identical(replayThroughWorker(copy, record, threads, unsigned(++run)), direct));
    }
    Volume scripted = loadVolume(dir.file("b.vdb"));
    runStrokeScript(scripted, parseStrokeScript(script.dump()));
    CHECK(identical(scripted, direct));
}

TEST_CASE("editor: the frame thread submits strokes, undo and frames while the edit worker is held, and the scene comes out as its record replays", "[editor][worker]")
{
    TempDir dir;
    const std::string a = makeBall(dir, "a.vdb");
    std::filesystem::copy_file(a, dir.file("b.vdb"));
    // The commands of a stroke, an undo while it is under way, and another stroke.
    std::vector<Command> commands{brushCommand("add", 4.0, 0.6), strokeTowards(Command::Kind::StrokeBegin, -6.0, 2.0)};
    for (int m = 1; m <= 6; ++m) commands.push_back(strokeTowards(Command::Kind::StrokeMove, -6.0 + 1.5 * m, 2.0));
    commands.push_back(kind(Command::Kind::Undo));
    commands.push_back(brushCommand("smooth", 5.0, 1.0));
    commands.push_back(strokeTowards(Command::Kind::StrokeBegin, 3.0, -3.0));
    for (int m = 1; m <= 4; ++m) commands.push_back(strokeTowards(Command::Kind::StrokeMove, 3.0 + m, -3.0));
    commands.push_back(kind(Command::Kind::StrokeEnd));

    Command camera;
    camera.kind = Command::Kind::SetCamera;
    camera.camera.eye = {0.0, 0.0, 80.0};
    camera.camera.target = {0.0, 0.0, 0.0};
    const auto stream = [&](EditingSession& session) {
        for (int i = 0; i < 3; ++i) {
            session.frame(0.0, kViewport);
            session.scene().waitForLoads();
        }
    };

    Volume direct;
    uint64_t stampsDirect = 0;
    {
        EditingSession session(a, quietSession());
        session.apply(camera);
        stream(session);
        for (const Command& c : commands) session.apply(c);
        session.frame(1.0, kViewport);
        CHECK(session.history().undoDepth() == 1);
        CHECK(session.history().redoDepth() == 0); // the smooth stroke after the undo dropped the redo
        stampsDirect = session.stats().stampsApplied;
        direct = committed(session);
    }

    std::filesystem::copy_file(a, dir.file("c.vdb"));
    EditingSession session(dir.file("b.vdb"), quietSession());
    session.apply(camera);
    stream(session);
    Gate gate(true);
    {
        SessionWorker worker(session, gate.options());
        // Everything goes in while the worker is held: none of it waits on an edit.
        for (const Command& c : commands) worker.submit(c);
        worker.frame(1.0, kViewport);
        CHECK(worker.pending() == commands.size() + 1);
        CHECK(worker.brush().mode == "smooth"); // the panels show the brush at once
        CHECK(worker.snapshot().commandsApplied == 0);
        CHECK(session.pick({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0})); // the frame's picks go on meanwhile
        gate.set(false);
        worker.waitIdle();
        CHECK(worker.pending() == 0);
        const SessionSnapshot done = worker.snapshot();
        CHECK(done.commandsApplied == commands.size());
        CHECK(done.undoDepth == 1);
        CHECK(done.redoDepth == 0);
        CHECK_FALSE(done.strokeActive);
        CHECK(done.unsaved);
    }
    // The points of each stroke waited together, so each stroke went in merged: fewer ops than points.
    const SessionRecord record = session.record();
    const auto merged = std::count_if(record.commands.begin(), record.commands.end(), [](const RecordedCommand& rc) { return rc.command.mergedWithNext; });
    CHECK(merged >= 8);
    CHECK(session.stats().stampsApplied < stampsDirect);
    // Its record replays to the same scene (the merges are in it), and so does its exported script.
    const Volume live = committed(session);
    {
        EditingSession replayed(dir.file("c.vdb"), quietSession());
        replaySession(replayed, record);
        CHECK(identical(committed(replayed), live));
    }
    Volume scripted = loadVolume(a);
    runStrokeScript(scripted, parseStrokeScript(session.appliedScript().dump()));
    CHECK(identical(scripted, live));
    // Merged or not, the strokes changed the scene alike: it differs from the stroke applied point by
    // point only where the merged op's surface meets itself.
    CHECK_FALSE(identical(live, loadVolume(a)));
    CHECK(compareRegion(live, direct, {{-32, -32, -32}, 64}).occupancy < 200);
}

TEST_CASE("editor: a save through the edit worker that cannot be written is reported, and the session goes on", "[editor][worker]")
{
    TempDir dir;
    EditingSession session(makeBall(dir, "a.vdb"), quietSession());
    {
        SessionWorker worker(session);
        Command save = kind(Command::Kind::Save);
        save.path = dir.file("no-such-folder/b.vdb");
        worker.submit(save);
        worker.submit(brushCommand("smooth", 4.0, 1.0));
        CHECK_THROWS_AS(worker.submit(brushCommand("no-such-mode", 4.0, 1.0)), std::invalid_argument);
        worker.waitIdle();
        const std::vector<std::string> failures = worker.takeFailures();
        REQUIRE(failures.size() == 1);
        CHECK(failures[0].find("failed") != std::string::npos);
        CHECK(worker.takeFailures().empty());
        CHECK(worker.snapshot().busy.empty());
        CHECK(worker.snapshot().commandsApplied == 2);
    }
    CHECK(session.brush().mode == "smooth");
}

TEST_CASE("editor: a session killed while the edit worker holds pending strokes reopens with exactly what its last autosave saved", "[editor][worker]")
{
    TempDir dir;
    const std::string ball = makeBall(dir, "a.vdb");
    std::filesystem::copy_file(ball, dir.file("copy.vdb"));
    const std::string recordPath = dir.file("record.json");
    const auto at = [](Command::Kind k, const std::array<double, 3>& p) {
        Command c;
        c.kind = k;
        c.point = p;
        return c;
    };
    const std::vector<Command> applied{brushCommand("add", 4.0, 0.7), at(Command::Kind::StrokeBegin, {0, 20, 0}),
                                       at(Command::Kind::StrokeMove, {6, 19, 0}), kind(Command::Kind::StrokeEnd)};
    const std::vector<Command> pending{brushCommand("remove", 5.0, 1.0), at(Command::Kind::StrokeBegin, {0, 0, 20}),
                                       at(Command::Kind::StrokeMove, {5, 0, 19}), kind(Command::Kind::StrokeEnd)};
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
        try {
            SessionOptions options = quietSession();
            options.recordPath = recordPath;
            options.idleAutosaveSeconds = 0.5; // the frame at 10 s finds the session idle: it autosaves
            EditingSession session(ball, options);
            Gate gate(false);
            SessionWorker worker(session, gate.options());
            for (const Command& c : applied) worker.submit(c);
            worker.frame(10.0, kViewport);
            worker.waitIdle();
            gate.set(true); // what comes next stays pending
            for (const Command& c : pending) worker.submit(c);
            worker.frame(11.0, kViewport);
            std::raise(SIGKILL); // strokes pending, no destructor, no save
        } catch (...) {
        }
        ::_exit(3);
    }
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    REQUIRE(WIFSIGNALED(status));

    // What the autosave said it saved: the record written with it, replayed on the scene as it was.
    const SessionRecord record = loadSessionRecord(recordPath);
    CHECK(record.commands.size() == applied.size());
    Volume expected;
    uint64_t edits = 0;
    {
        EditingSession replayed(dir.file("copy.vdb"), quietSession());
        replaySession(replayed, record);
        expected = committed(replayed);
        edits = replayed.scene().edits();
    }
    REQUIRE(edits > 0);
    EditingSession reopened(ball, quietSession());
    CHECK(reopened.recoveredEdits() == edits);
    CHECK(identical(committed(reopened), expected));
}

TEST_CASE("editor: a grab's drag steps waiting together apply as its last one, exactly as applied step by step", "[editor][worker]")
{
    TempDir dir;
    const std::string a = makeBall(dir, "a.vdb");
    std::filesystem::copy_file(a, dir.file("b.vdb"));
    Command camera;
    camera.kind = Command::Kind::SetCamera;
    camera.camera.eye = {0.0, 0.0, 80.0};
    camera.camera.target = {0.0, 0.0, 0.0};
    // The drag starts with a move (a move with no stroke begins one, and goes in at once).
    std::vector<Command> drag{brushCommand("move", 5.0, 1.0), strokeTowards(Command::Kind::StrokeMove, 0.0, 0.0)};
    for (int m = 1; m <= 6; ++m) drag.push_back(strokeTowards(Command::Kind::StrokeMove, 1.5 * m, 0.5 * m));
    drag.push_back(kind(Command::Kind::StrokeEnd));
    const auto open = [&](const std::string& path) {
        auto session = std::make_unique<EditingSession>(path, quietSession());
        session->apply(camera);
        for (int i = 0; i < 3; ++i) {
            session->frame(0.0, kViewport);
            session->scene().waitForLoads();
        }
        return session;
    };
    auto direct = open(a);
    for (const Command& c : drag) direct->apply(c);
    auto merged = open(dir.file("b.vdb"));
    {
        Gate gate(true);
        SessionWorker worker(*merged, gate.options());
        for (const Command& c : drag) worker.submit(c);
        gate.set(false);
        worker.waitIdle();
    }
    const auto& commands = merged->record().commands;
    CHECK(std::count_if(commands.begin(), commands.end(), [](const RecordedCommand& rc) { return rc.command.mergedWithNext; }) == 5);
    CHECK(merged->stats().stampsApplied < direct->stats().stampsApplied);
    CHECK(identical(committed(*merged), committed(*direct)));
    // The record, merges included, goes through its file and replays to the same scene.
    saveSessionRecord(merged->record(), dir.file("s.json"));
    const SessionRecord loaded = loadSessionRecord(dir.file("s.json"));
    REQUIRE(loaded.commands.size() == commands.size());
    for (std::size_t i = 0; i < commands.size(); ++i) CHECK(loaded.commands[i].command.mergedWithNext == commands[i].command.mergedWithNext);
    std::filesystem::copy_file(a, dir.file("c.vdb"));
    EditingSession replayed(dir.file("c.vdb"), quietSession());
    replaySession(replayed, loaded);
    CHECK(identical(committed(replayed), committed(*direct)));
}
