// The editing session, device-free: replays equal the strokes applied by scripts, undo and redo are
// bit-exact (after eviction and with the history spilled too), symmetry equals the written-out strokes,
// autosaved edits survive a SIGKILL, the ray cast meets analytic surfaces, bad session files are refused.
#include "editor/EditingSession.h"
#include "editor/VolumeRayCast.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/Synthesize.h"
#include "sculpt/StrokeScript.h"
#include "support/CliRun.h"
#include "support/TerrainStore.h"
#include "support/TestUtil.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <optional>
#include <random>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// A .vdb holding a sphere of `radius` voxels at the origin (voxel size 1).
std::string makeBall(const TempDir& dir, double radius = 20.0, const std::string& name = "ball.vdb")
{
    Volume v(1.0);
    runStrokeScript(v, parseStrokeScript(nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", radius}}}}}}}.dump()));
    const std::string path = dir.file(name);
    saveVolume(v, path);
    return path;
}

/// A terrain store of 256 voxels with its levels of detail.
std::string makeTerrain(const TempDir& dir, const std::string& name = "t.vdbclay")
{
    return terrainStore(dir, name, 256, 11, 3);
}

Command brushCommand(const std::string& mode, double radius, const nlohmann::json& symmetry = nullptr)
{
    Command c;
    c.kind = Command::Kind::SetBrush;
    c.brush.emplace();
    c.brush->mode = mode;
    c.brush->radius = radius;
    c.brush->strength = 0.7;
    c.brush->distance = 1.5;
    c.brush->symmetry = symmetry;
    return c;
}

Command strokeCommand(Command::Kind kind, const std::array<double, 3>& p = {0, 0, 0}, double pressure = 1.0)
{
    Command c;
    c.kind = kind;
    c.point = p;
    c.pressure = pressure;
    return c;
}

Command simple(Command::Kind kind)
{
    Command c;
    c.kind = kind;
    return c;
}

/// The session's scene as its store holds it after an autosave.
Volume committed(EditingSession& session)
{
    session.autosave();
    return session.scene().storedLevel0();
}

/// Random strokes of every mode on a terrain: each starts where a ray from above meets the surface (the
/// session's own ray cast) and moves a few voxels; pressure varies.
std::vector<Command> randomStrokes(EditingSession& session, int count, uint64_t seed, double from = 40.0, double to = 216.0)
{
    static const char* modes[] = {"add", "remove", "paint", "smooth", "flatten", "inflate", "deflate", "move", "erode"};
    std::mt19937 rng{unsigned(seed)};
    std::uniform_real_distribution<double> xz(from, to), step(-4.0, 4.0), radius(3.0, 6.0), pressure(0.3, 1.0);
    std::vector<Command> out;
    for (int i = 0; i < count; ++i) {
        const std::array<double, 3> top{xz(rng), 200.0, xz(rng)};
        const auto hit = session.pick(top, {0, -1, 0});
        if (!hit) continue;
        out.push_back(brushCommand(modes[i % 9], radius(rng), i % 4 == 3 ? nlohmann::json{{"mirror", {"x"}}, {"center", {128, 0, 128}}} : nlohmann::json()));
        std::array<double, 3> p = hit->point;
        out.push_back(strokeCommand(Command::Kind::StrokeBegin, p, pressure(rng)));
        for (int m = 0; m < 3; ++m) {
            p[0] += step(rng);
            p[2] += step(rng);
            p[1] += 0.3 * step(rng);
            out.push_back(strokeCommand(Command::Kind::StrokeMove, p, pressure(rng)));
        }
        out.push_back(simple(Command::Kind::StrokeEnd));
    }
    return out;
}

SessionOptions quietOptions(uint64_t budgetMB = 256)
{
    SessionOptions o;
    o.memoryBudgetBytes = budgetMB << 20;
    o.autosaveSeconds = 1e9;
    o.idleAutosaveSeconds = 1e9;
    o.message = [](const std::string& m) { std::fprintf(stderr, "session: %s\n", m.c_str()); };
    return o;
}

} // namespace

TEST_CASE("editor: the ray cast meets a sphere at its analytic distance, with its normal", "[editor]")
{
    Volume v(0.5);
    runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 10}, "at": [1.3, -0.7, 0.4]}]})"));
    const std::array<double, 3> c{1.3, -0.7, 0.4};
    std::mt19937 rng{5};
    std::normal_distribution<double> g(0.0, 1.0);
    for (int i = 0; i < 200; ++i) {
        std::array<double, 3> d{g(rng), g(rng), g(rng)};
        const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (double& x : d) x /= n;
        // From 30 units out towards a point near the centre: the ray meets the sphere.
        const std::array<double, 3> o{c[0] - 30 * d[0], c[1] - 30 * d[1], c[2] - 30 * d[2]};
        const auto hit = castRay(v, o, d, 100.0);
        REQUIRE(hit);
        const double r = std::sqrt(std::pow(hit->point[0] - c[0], 2) + std::pow(hit->point[1] - c[1], 2) + std::pow(hit->point[2] - c[2], 2));
        CHECK(std::abs(r - 10.0) < 0.1); // on the surface: quantized crossings, within a fifth of a voxel
        CHECK(std::abs(hit->distance - 20.0) < 0.5 + 1e-9); // the first crossing, within a voxel of the analytic one
        double cosine = 0.0;
        for (std::size_t a = 0; a < 3; ++a) cosine += hit->normal[a] * (hit->point[a] - c[a]) / r;
        CHECK(cosine > std::cos(3.0 * M_PI / 180.0));
    }
    // Pointing away, or too short: no hit. From inside: the next entry after leaving (none for a ball).
    CHECK_FALSE(castRay(v, {30, 0, 0}, {1, 0, 0}, 100.0));
    CHECK_FALSE(castRay(v, {30, 0, 0}, {-1, 0, 0}, 5.0));
    CHECK_FALSE(castRay(v, c, {1, 0, 0}, 100.0));
    CHECK_FALSE(castRay(v, {0, 0, 0}, {0, 0, 0}, 100.0));
}

TEST_CASE("replay: a replayed session equals the session and the strokes in effect applied as a script (undone ones left out)", "[editor][replay]")
{
    TempDir dir;
    const std::string original = makeTerrain(dir);
    std::filesystem::copy_file(original, dir.file("a.vdbclay"));
    std::filesystem::copy_file(original, dir.file("b.vdbclay"));
    SessionRecord record;
    nlohmann::json script;
    Volume live;
    {
        EditingSession session(dir.file("a.vdbclay"), quietOptions());
        session.frame(0.0, {640, 480});
        session.scene().waitForLoads();
        session.frame(0.1, {640, 480});
        const std::vector<Command> strokes = randomStrokes(session, 14, 3);
        REQUIRE(strokes.size() > 50);
        // Some strokes undone (the last of them stays undone), some of those redone.
        int ended = 0;
        for (std::size_t i = 0; i < strokes.size(); ++i) {
            session.apply(strokes[i]);
            if (strokes[i].kind == Command::Kind::StrokeEnd && ++ended % 3 == 0) {
                session.apply(strokeCommand(Command::Kind::Undo));
                if (ended % 2 == 0) session.apply(strokeCommand(Command::Kind::Redo));
            }
            if (i % 3 == 0) session.frame(0.2 + double(i) * 0.01, {640, 480});
        }
        REQUIRE(ended >= 6);
        session.apply(strokeCommand(Command::Kind::Undo));
        CHECK(session.history().redoDepth() == 1);
        CHECK(session.stats().opsRefused == 0);
        CHECK(session.stats().stampsApplied > 40);
        record = session.record();
        script = session.appliedScript();
        live = committed(session);
    }
    // Through its file, as users attach it to reports.
    saveSessionRecord(record, dir.file("s.json"));
    const SessionRecord loaded = loadSessionRecord(dir.file("s.json"));
    REQUIRE(loaded.commands.size() == record.commands.size());
    EditingSession replayed(dir.file("b.vdbclay"), quietOptions());
    replaySession(replayed, loaded);
    CHECK(identical(committed(replayed), live));

    Volume scripted = loadScene(original);
    StrokeScript parsed = parseStrokeScript(script.dump());
    runStrokeScript(scripted, parsed);
    CHECK(identical(scripted, live));
}

TEST_CASE("editor: undo of random strokes restores the scene bit-exactly after eviction and spills, redo restores the edits", "[editor]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    const Volume before = loadScene(path);
    SessionOptions options = quietOptions(4); // a few bricks: the strokes' bricks leave when the view moves on
    options.history.memoryBytes = 64 << 10;    // most of the history goes to the spill file
    EditingSession session(path, options);
    Command near;
    near.kind = Command::Kind::SetCamera;
    near.camera.eye = {40, 90, -60};
    near.camera.target = {60, 30, 60};
    session.apply(near);
    session.frame(0.0, {640, 480});
    session.scene().waitForLoads();
    const std::vector<Command> strokes = randomStrokes(session, 12, 9, 8.0, 110.0);
    uint64_t strokeCount = 0;
    for (const Command& c : strokes) {
        session.apply(c);
        strokeCount += c.kind == Command::Kind::StrokeEnd;
        if (c.kind == Command::Kind::StrokeEnd) session.frame(1.0, {640, 480});
    }
    CHECK(session.stats().opsRefused == 0);
    REQUIRE(session.history().undoDepth() >= strokeCount / 2); // a stroke may change nothing (paint on one material)
    CHECK(session.history().spilledBytes() > 0);
    const Volume after = committed(session);
    CHECK_FALSE(identical(after, before));

    // Look at the far side from station to station: loading what each shows pushes the bricks the
    // strokes touched out of the budget (least recently used first).
    const std::array<std::array<double, 2>, 4> stations{{{250, 250}, {250, 150}, {150, 250}, {200, 200}}};
    uint64_t strokesEvicted = 0;
    for (int i = 0; i < 40 && strokesEvicted == 0; ++i) {
        const auto& at = stations[std::size_t(i / 10) % stations.size()];
        Command away;
        away.kind = Command::Kind::SetCamera;
        away.camera.eye = {at[0], 50, at[1]};
        away.camera.target = {at[0] - 40, 25, at[1] - 40};
        session.apply(away);
        session.frame(2.0 + i, {640, 480});
        session.scene().waitForLoads();
        const Volume resident = session.scene().residentLevel0();
        for (const Command& c : strokes)
            if (c.kind == Command::Kind::StrokeBegin) {
                const IndexCoord below{int32_t(std::floor((*c.point)[0])), int32_t(std::floor((*c.point)[1])) - 2, int32_t(std::floor((*c.point)[2]))};
                strokesEvicted += resident.materialAt(below) == kEmptyMaterial && after.materialAt(below) != kEmptyMaterial;
            }
    }
    CHECK(strokesEvicted > 0);

    const std::size_t depth = session.history().undoDepth();
    for (std::size_t i = 0; i < depth; ++i) session.apply(simple(Command::Kind::Undo));
    CHECK(session.history().undoDepth() == 0);
    CHECK(identical(committed(session), before));
    for (std::size_t i = 0; i < depth; ++i) session.apply(simple(Command::Kind::Redo));
    CHECK(identical(committed(session), after));
    // A new stroke that changes the scene after an undo forgets what could be redone (one that changes
    // nothing keeps it).
    session.apply(simple(Command::Kind::Undo));
    REQUIRE(session.history().redoDepth() == 1);
    session.apply(near);
    session.apply(brushCommand("remove", 6.0));
    session.apply(strokes[1]);
    session.apply(simple(Command::Kind::StrokeEnd));
    CHECK(session.history().redoDepth() == 0);
}

TEST_CASE("editor: a mirrored stroke equals the stroke and its mirror image applied one by one", "[editor]")
{
    TempDir dir;
    const std::string ball = makeBall(dir);
    std::filesystem::copy_file(ball, dir.file("b.vdb"));
    // x >= 12: the copies' regions (brush, reach, blur) stay apart, so their order does not matter.
    const std::vector<std::array<double, 3>> path{{12, 15, 5}, {13, 14, 6}, {14, 13, 6}, {15, 12, 6}};
    const auto stroke = [&](EditingSession& s, double sign) {
        s.apply(strokeCommand(Command::Kind::StrokeBegin, {sign * path[0][0], path[0][1], path[0][2]}));
        for (std::size_t i = 1; i < path.size(); ++i) s.apply(strokeCommand(Command::Kind::StrokeMove, {sign * path[i][0], path[i][1], path[i][2]}));
        s.apply(simple(Command::Kind::StrokeEnd));
    };
    for (const char* mode : {"add", "remove", "inflate", "smooth"}) {
        DYNAMIC_SECTION(mode)
        {
            EditingSession mirrored(ball, quietOptions());
            mirrored.apply(brushCommand(mode, 3.0, {{"mirror", {"x"}}}));
            stroke(mirrored, 1.0);
            EditingSession written(dir.file("b.vdb"), quietOptions());
            written.apply(brushCommand(mode, 3.0));
            stroke(written, 1.0);
            stroke(written, -1.0);
            CHECK(identical(committed(mirrored), committed(written)));
        }
    }
}

TEST_CASE("editor: a session killed after an autosave reopens with its edits, the .vdb stays as it was", "[editor]")
{
    TempDir dir;
    const std::string ball = makeBall(dir);
    const std::vector<char> original = readBytes(ball);
    std::vector<Command> commands{brushCommand("add", 4.0), strokeCommand(Command::Kind::StrokeBegin, {0, 20, 0}),
                                  strokeCommand(Command::Kind::StrokeMove, {8, 18, 0}), simple(Command::Kind::StrokeEnd),
                                  brushCommand("remove", 3.0), strokeCommand(Command::Kind::StrokeBegin, {0, 0, 20}),
                                  simple(Command::Kind::StrokeEnd)};
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
        try {
            EditingSession session(ball, quietOptions());
            for (const Command& c : commands) session.apply(c);
            session.autosave();
            std::raise(SIGKILL); // no destructor, no save
        } catch (...) {
        }
        ::_exit(3);
    }
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    REQUIRE(WIFSIGNALED(status));
    CHECK(readBytes(ball) == original);

    // What those strokes make, in a session that finishes normally on a copy.
    std::filesystem::copy_file(ball, dir.file("copy.vdb"));
    Volume expected;
    uint64_t edits = 0;
    {
        EditingSession session(dir.file("copy.vdb"), quietOptions());
        for (const Command& c : commands) session.apply(c);
        expected = committed(session);
        edits = session.scene().edits();
    }
    REQUIRE(edits > 0);
    {
        EditingSession reopened(ball, quietOptions());
        CHECK(reopened.recoveredEdits() == edits);
        CHECK(identical(committed(reopened), expected));
        reopened.apply(simple(Command::Kind::Save)); // the .vdb now holds them
    }
    CHECK(identical(loadVolume(ball), expected));
    {
        EditingSession again(ball, quietOptions());
        CHECK(again.recoveredEdits() == 0);
    }
    // Dropping a recovery gives the saved file back.
    SessionOptions discard = quietOptions();
    {
        EditingSession session(ball, quietOptions());
        for (const Command& c : commands) session.apply(c);
    } // autosaved at the end, not saved
    discard.discardRecovery = true;
    EditingSession fresh(ball, discard);
    CHECK(fresh.recoveredEdits() == 0);
    CHECK(identical(committed(fresh), expected));
}

TEST_CASE("editor: malformed session files are refused naming the place", "[editor][replay]")
{
    TempDir dir;
    const auto refused = [&](const std::string& text, const std::string& expected) {
        writeText(dir.file("s.json"), text);
        try {
            loadSessionRecord(dir.file("s.json"));
            FAIL("accepted: " << text);
        } catch (const SessionError& e) {
            INFO(e.what());
            CHECK(std::string(e.what()).find(expected) != std::string::npos);
        }
    };
    refused("{", "not valid JSON");
    refused(R"({"ops": []})", "not a VDBClay session file");
    refused(R"({"vdbclay_session": 2, "commands": []})", "version 1");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "fly"}]})", "commands[0].command");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "stroke_begin", "point": [0, 1]}]})", "commands[0].point");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "stroke_move", "point": [0, 1, 2], "pressure": 2}]})", "pressure");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 3, "command": "undo"}, {"frame": 2, "command": "undo"}]})", "commands[1].frame");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "brush", "brush": {"mode": "melt"}}]})", "brush.mode");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "camera", "eye": [0, 0, 0], "target": [0, 0, 0]}]})", "differ");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "undo", "extra": 1}]})", "commands[0].extra");
    refused(R"({"vdbclay_session": 1, "viewport": [0, 10], "commands": []})", "viewport");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "stroke_move", "point": [0, 1, 2], "merged": 1}]})", "commands[0].merged");
    refused(R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "stroke_begin", "point": [0, 1, 2], "merged": true}]})", "belongs to stroke moves");
    // Keys of control characters in a material or an op are quoted printable (found by fuzz_session_file: DEL).
    for (const std::string command : {"\"material\", \"material\": {\"name\": \"clay\", \"c\x7flor\": [1, 0, 0]}",
                                      "\"op\", \"op\": {\"mo\xc2\x9b" "2Jde\": \"add\", \"brush\": {\"shape\": \"sphere\"}}",
                                      "\"op\", \"op\": {\"mode\": \"add\", \"material\": \"\xc2\x9b" "2J\", \"brush\": {\"shape\": \"sphere\", \"\x7f\": 1}}",
                                      "\"op\", \"op\": {\"mode\": \"rem\x7fve\", \"brush\": {\"shape\": \"sph\x7fre\"}, \"falloff\": \"s\x7f\"}"}) {
        const std::string text = "{\"vdbclay_session\": 1, \"commands\": [{\"frame\": 0, \"command\": " + command + "}]}";
        try {
            parseSessionRecord(text, "s.json");
            FAIL("accepted: " << text);
        } catch (const SessionError& e) {
            CHECK(std::string(e.what()).find("commands[0]") != std::string::npos);
            CHECK(isPrintableName(e.what(), std::string::npos));
        }
    }
}

TEST_CASE("replay: vdbclay edit --headless replays, saves, exports the script, and refuses what it cannot do", "[editor][replay][cli]")
{
    TempDir dir;
    makeBall(dir);
    SessionRecord record;
    record.viewport = {320, 240};
    record.commands = {{0, 0.0, brushCommand("add", 4.0, {{"radial", {{"axis", "y"}, {"count", 3}}}})},
                       {1, 0.1, strokeCommand(Command::Kind::StrokeBegin, {0, 20, 0})},
                       {2, 0.2, strokeCommand(Command::Kind::StrokeMove, {10, 17, 0}, 0.6)},
                       {3, 0.3, simple(Command::Kind::StrokeEnd)},
                       {4, 0.4, brushCommand("smooth", 5.0)},
                       {4, 0.4, strokeCommand(Command::Kind::StrokeBegin, {0, 0, 20})},
                       {5, 0.5, simple(Command::Kind::StrokeEnd)},
                       {6, 0.6, simple(Command::Kind::Undo)},
                       {7, 0.7, simple(Command::Kind::Redo)}};
    record.frames = 8;
    saveSessionRecord(record, dir.file("s.json"));
    const CommandResult r = runCli(dir, "edit ball.vdb --replay s.json --headless -o out.vdb --export-script applied.json --json");
    const nlohmann::json j = parseJsonOutput(r);
    CHECK(j.at("frames") == 8);
    CHECK(j.at("undo_depth") == 2);
    CHECK(j.at("refused") == 0);
    const CommandResult sculpted = runCli(dir, "sculpt ball.vdb applied.json -o ref.vdb");
    REQUIRE(sculpted.exitCode == 0);
    CHECK(identical(loadVolume(dir.file("out.vdb")), loadVolume(dir.file("ref.vdb"))));
    // --frames 4: only the first stroke.
    const nlohmann::json part = parseJsonOutput(runCli(dir, "edit ball.vdb --replay s.json --headless --frames 4 --discard-recovery --json"));
    CHECK(part.at("frames") == 4);
    CHECK(part.at("undo_depth") == 1);

    writeText(dir.file("bad.json"), R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "stroke_begin"}]})");
    checkCleanFailure(runCli(dir, "edit ball.vdb --replay bad.json --headless"));
    checkCleanFailure(runCli(dir, "edit ball.vdb --replay missing.json --headless"));
    checkCleanFailure(runCli(dir, "edit ball.vdb -o out2.vdb"));
    checkCleanFailure(runCli(dir, "edit ball.vdb --headless -o out.png"));
    if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) { // with a display, the window would open
        const CommandResult noDisplay = runCli(dir, "edit ball.vdb");
        checkCleanFailure(noDisplay);
        CHECK(noDisplay.err.find("no display") != std::string::npos);
        CHECK(noDisplay.err.find("--headless") != std::string::npos);
    }
}

TEST_CASE("editor: a material defined and not used yet survives an autosave, a crash and a save", "[editor]")
{
    TempDir dir;
    const std::string ball = makeBall(dir);
    Command define;
    define.kind = Command::Kind::DefineMaterial;
    define.material = {{"name", "jade"}, {"color", {0.2, 0.7, 0.5, 1.0}}, {"toughness", 0.8}};
    {
        EditingSession session(ball, quietOptions());
        session.apply(define);
        session.autosave(); // then the session ends without a save: what a crash leaves
    }
    {
        EditingSession reopened(ball, quietOptions());
        CHECK(reopened.scene().materials().find("jade"));
        Command save;
        save.kind = Command::Kind::Save;
        reopened.apply(save);
    }
    CHECK(loadVolume(ball).materials().find("jade"));
}

namespace {

/// A session of two add strokes on the ball and a smoothing one, as the window records it.
SessionRecord ballStrokes()
{
    SessionRecord record;
    record.viewport = {320, 240};
    record.commands = {{0, 0.0, brushCommand("add", 4.0)},
                       {1, 0.1, strokeCommand(Command::Kind::StrokeBegin, {0, 20, 0})},
                       {2, 0.2, strokeCommand(Command::Kind::StrokeMove, {8, 18, 0})},
                       {3, 0.3, simple(Command::Kind::StrokeEnd)},
                       {4, 0.4, brushCommand("smooth", 5.0)},
                       {5, 0.5, strokeCommand(Command::Kind::StrokeBegin, {0, 0, 20})},
                       {6, 0.6, simple(Command::Kind::StrokeEnd)}};
    record.frames = 7;
    return record;
}

/// The edits a .vdb's working store holds beyond the last save (0 when it has none, or no working store).
uint64_t unsavedEditsOf(const std::string& vdb)
{
    SessionOptions o = quietOptions();
    EditingSession session(vdb, o);
    return session.recoveredEdits();
}

} // namespace

TEST_CASE("replay: the same session replayed twice gives the same scene, and unsaved edits are refused, not replayed over", "[editor][replay][cli]")
{
    TempDir dir;
    const std::string ball = makeBall(dir);
    const std::vector<char> original = readBytes(ball);
    saveSessionRecord(ballStrokes(), dir.file("s.json"));
    for (const char* out : {"a.vdb", "b.vdb"}) {
        const nlohmann::json j = parseJsonOutput(runCli(dir, std::string("edit ball.vdb --replay s.json --headless --json -o ") + out));
        CHECK(j.at("recovered_edits") == 0);
        CHECK(j.at("stamps") == 3);
    }
    CHECK(runCli(dir, "diff a.vdb b.vdb").exitCode == 0);
    CHECK(readBytes(ball) == original);
    CHECK(unsavedEditsOf(ball) == 0); // the replay's edits left with it

    // Edits autosaved and never saved (a crash): a replay says so and changes nothing.
    {
        EditingSession session(ball, quietOptions());
        for (const RecordedCommand& rc : ballStrokes().commands) session.apply(rc.command);
    }
    const uint64_t unsaved = unsavedEditsOf(ball);
    REQUIRE(unsaved > 0);
    const CommandResult refused = runCli(dir, "edit ball.vdb --replay s.json --headless -o c.vdb");
    checkCleanFailure(refused);
    CHECK(refused.err.find("a replay starts from the scene as saved") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("c.vdb")));
    CHECK(unsavedEditsOf(ball) == unsaved);
    // Dropping them, the replay starts from the saved scene again.
    REQUIRE(runCli(dir, "edit ball.vdb --replay s.json --headless --discard-recovery -o c.vdb").exitCode == 0);
    CHECK(runCli(dir, "diff a.vdb c.vdb").exitCode == 0);
    CHECK(readBytes(ball) == original);
}

TEST_CASE("editor: a working store knows its .vdb by content: touch changes nothing, a same-size change with its time kept is seen", "[editor]")
{
    TempDir dir;
    const std::string ball = makeBall(dir);
    {
        EditingSession session(ball, quietOptions());
        for (const RecordedCommand& rc : ballStrokes().commands) session.apply(rc.command);
    }
    const uint64_t unsaved = unsavedEditsOf(ball);
    REQUIRE(unsaved > 0);
    std::filesystem::last_write_time(ball, std::filesystem::file_time_type::clock::now() + std::chrono::hours(1));
    CHECK(unsavedEditsOf(ball) == unsaved); // the same bytes: the same scene

    // One byte changed in place, the size and the time as they were.
    const auto time = std::filesystem::last_write_time(ball);
    std::vector<char> bytes = readBytes(ball);
    bytes[bytes.size() / 2] = char(bytes[bytes.size() / 2] ^ 0x5A);
    writeText(ball, std::string(bytes.begin(), bytes.end()));
    std::filesystem::last_write_time(ball, time);
    try {
        EditingSession session(ball, quietOptions());
        FAIL("the changed .vdb was hidden by the old working store");
    } catch (const std::runtime_error& e) {
        CHECK(std::string(e.what()).find("which was changed since") != std::string::npos);
    }
}

TEST_CASE("replay: a session is checked whole before its first command, and refusals are decided by the op", "[editor][replay][cli]")
{
    TempDir dir;
    const std::string ball = makeBall(dir);
    // A bad material or op at the end: refused naming the file and the command, nothing applied.
    nlohmann::json session = sessionRecordJson(ballStrokes());
    session["commands"].push_back({{"frame", 7}, {"command", "material"}, {"material", {{"name", "red"}, {"color", {2, 0, 0}}}}});
    writeText(dir.file("bad-material.json"), session.dump());
    session["commands"].back() = {{"frame", 7}, {"command", "op"}, {"op", {{"mode", "melt"}}}};
    writeText(dir.file("bad-op.json"), session.dump());
    for (const auto& [file, place] : {std::pair{"bad-material.json", "'bad-material.json'.commands[7].material.color"},
                                      std::pair{"bad-op.json", "'bad-op.json'.commands[7].op"}}) {
        const CommandResult r = runCli(dir, std::string("edit ball.vdb --headless --replay ") + file);
        checkCleanFailure(r);
        CHECK(r.err.find(place) != std::string::npos);
        CHECK(unsavedEditsOf(ball) == 0);
    }

    // A stamp whose leaves alone would pass the budget, and one mirrored about a far centre, are refused
    // before anything is paged in, by the op and not by what happens to be resident.
    SessionRecord huge;
    huge.commands = {{0, 0.0, brushCommand("add", 1000.0)},
                     {1, 0.1, strokeCommand(Command::Kind::StrokeBegin, {0, 20, 0})},
                     {2, 0.2, simple(Command::Kind::StrokeEnd)},
                     {3, 0.3, brushCommand("add", 4.0, {{"mirror", {"x"}}, {"center", {1e6, 0, 0}}})},
                     {4, 0.4, strokeCommand(Command::Kind::StrokeBegin, {0, 20, 0})},
                     {5, 0.5, simple(Command::Kind::StrokeEnd)}};
    saveSessionRecord(huge, dir.file("huge.json"));
    const CommandResult r = runCli(dir, "edit ball.vdb --headless --replay huge.json --json");
    const nlohmann::json j = parseJsonOutput(r);
    CHECK(j.at("refused") == 2);
    CHECK(j.at("stamps") == 0);
    CHECK(r.err.find("more than the memory budget of 1024 MB holds") != std::string::npos);
    CHECK(r.err.find("the brush reaches 2e+06 voxels from the origin") != std::string::npos);

    // A budget that holds the strokes only if the view's bricks make way: the same refusals every run.
    const std::string terrain = makeTerrain(dir);
    SessionRecord strokes;
    strokes.viewport = {640, 480};
    strokes.commands.push_back({0, 0.0, brushCommand("add", 6.0)});
    for (int i = 0; i < 6; ++i) {
        strokes.commands.push_back({uint64_t(2 * i + 1), 0.0, strokeCommand(Command::Kind::StrokeBegin, {30.0 + 35.0 * i, 40, 60.0 + 25.0 * i})});
        strokes.commands.push_back({uint64_t(2 * i + 2), 0.0, simple(Command::Kind::StrokeEnd)});
    }
    strokes.frames = 14;
    saveSessionRecord(strokes, dir.file("strokes.json"));
    std::optional<nlohmann::json> first;
    for (int run = 0; run < 3; ++run) {
        std::filesystem::copy_file(terrain, dir.file("run.vdbclay"), std::filesystem::copy_options::overwrite_existing);
        const nlohmann::json report = parseJsonOutput(runCli(dir, "edit run.vdbclay --headless --replay strokes.json --memory-budget 1 --json"));
        if (!first) first = report;
        CHECK(report.at("refused") == first->at("refused"));
        CHECK(report.at("stamps") == first->at("stamps"));
        CHECK(report.at("edits") == first->at("edits"));
    }
}

TEST_CASE("editor: hostile session files are refused before any work, and a move without a stroke is recorded as its beginning", "[editor][replay]")
{
    TempDir dir;
    const auto refusedWith = [&](const std::string& path, const std::string& expected) {
        try {
            loadSessionRecord(path);
            FAIL("accepted: " << path);
        } catch (const SessionError& e) {
            CHECK_THAT(e.what(), Catch::Contains(expected));
        }
    };
    refusedWith("/dev/zero", "not a regular file");
    REQUIRE(::mkfifo(dir.file("pipe.json").c_str(), 0644) == 0);
    refusedWith(dir.file("pipe.json"), "not a regular file");
    writeText(dir.file("wide.json"), R"({"vdbclay_session": 1, "viewport": [16384, 16384], "commands": []})");
    refusedWith(dir.file("wide.json"), "1 to 8192");
    writeText(dir.file("up.json"), R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "camera", "eye": [0, 9, 0], "target": [0, 0, 0], "up": [0, 0, 0]}]})");
    refusedWith(dir.file("up.json"), "commands[0].up: must not be [0, 0, 0]");

    const std::string ball = makeBall(dir);
    EditingSession session(ball, quietOptions());
    session.apply(strokeCommand(Command::Kind::StrokeMove, {0, 20, 0}));
    session.apply(strokeCommand(Command::Kind::StrokeMove, {4, 19, 0}));
    session.apply(simple(Command::Kind::StrokeEnd));
    REQUIRE(session.record().commands.size() == 3);
    CHECK(session.record().commands[0].command.kind == Command::Kind::StrokeBegin);
    CHECK(session.record().commands[1].command.kind == Command::Kind::StrokeMove);
}
