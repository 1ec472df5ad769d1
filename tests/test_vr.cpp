// The VR front end: its device-free parts (the world's placement, what the controllers mean) directly,
// and whole sessions through the fake OpenXR runtime (tests/fakexr) with Khronos' core validation layer
// and the Vulkan validation layer on: test names with "xr:" (the sanitizer build, which has no Vulkan
// driver, leaves them out).
#include "support/CliRun.h"
#include "support/TestUtil.h"
#include "vr/VrComfort.h"
#include "vr/VrControls.h"
#include "vr/VrMenus.h"
#include "vr/WorldPlacement.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace vdbclay;
using namespace vdbclay::vr;
using namespace vdbclay::test;
using nlohmann::json;

namespace {

// --- device-free ---------------------------------------------------------------------------------

HandInput handAt(double x, double y, double z)
{
    HandInput h;
    h.tracked = true;
    h.grip.position = glm::dvec3(x, y, z);
    h.aim = h.grip;
    return h;
}

} // namespace

TEST_CASE("vr placement: a framed scene stands whole in front of the viewer, 1.5 m across", "[vr]")
{
    Pose head;
    head.position = glm::dvec3(0.3, 1.7, 0.2);
    head.orientation = glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 1, 0)); // looking along -X
    const WorldTransform w = frameScene({-10, 0, -40}, {30, 20, 40}, head);
    CHECK(w.scale == Approx(kFramedWidthMetres / 80.0));
    const glm::dvec3 centre = w.toStage(glm::dvec3(10, 10, 0));
    CHECK(centre.x < head.position.x - 0.6); // in front, along -X
    CHECK(std::fabs(centre.z - head.position.z) < 1e-9);
    CHECK(centre.y > 0.0);
    // The scene's -Z faces the viewer's forward: its +Z (toward a desktop's default viewer) points back at them.
    const glm::dvec3 toward = glm::normalize(w.toStage(glm::dvec3(10, 10, 1)) - centre);
    CHECK(toward.x == Approx(1.0).margin(1e-9));
    // Round trips.
    const glm::dvec3 p(3, -4, 5);
    CHECK(glm::length(w.toScene(w.toStage(p)) - p) < 1e-9);
}

TEST_CASE("vr placement: a two-hand grab keeps what lies under the hands under them, turns about the vertical and clamps its scale", "[vr]")
{
    WorldTransform start;
    start.scale = 0.01;
    start.translation = glm::dvec3(0, 1, -1);
    WorldGrab grab;
    grab.setScaleLimits(0.001, 0.05);
    const glm::dvec3 a0(-0.2, 1.2, -0.4), b0(0.2, 1.2, -0.4);
    REQUIRE(grab.update(a0, b0, start).scale == start.scale); // the grab begins: nothing moves
    const glm::dvec3 sceneA = start.toScene(a0), sceneB = start.toScene(b0);
    // Hands apart to twice the spread, turned 90 degrees about +Y, moved up.
    const glm::dvec3 a1(0.1, 1.5, 0.0), b1(0.1, 1.5, -0.8);
    const WorldTransform w = grab.update(a1, b1, start);
    CHECK(w.scale == Approx(0.02));
    CHECK(glm::length(w.toStage(sceneA) - a1) < 1e-9);
    CHECK(glm::length(w.toStage(sceneB) - b1) < 1e-9);
    // Beyond the limit the scale stops, the midpoint still follows.
    const WorldTransform far = grab.update(glm::dvec3(-5, 1, -0.4), glm::dvec3(5, 1, -0.4), start);
    CHECK(far.scale == Approx(0.05));
    CHECK(glm::length(far.toStage(0.5 * (sceneA + sceneB)) - glm::dvec3(0, 1, -0.4)) < 1e-9);
    // One hand left: the grab starts again from where the world is (nothing jumps), then moves with it.
    const WorldTransform one = grab.update(std::nullopt, b1, w);
    CHECK(glm::length(one.translation - w.translation) < 1e-12);
    const WorldTransform moved = grab.update(std::nullopt, b1 + glm::dvec3(0, 0.1, 0), w);
    CHECK(glm::length(moved.translation - (w.translation + glm::dvec3(0, 0.1, 0))) < 1e-12);
    CHECK(moved.scale == w.scale);
}

TEST_CASE("vr controls: the trigger strokes with pressure, with hysteresis, and a lost focus ends the stroke", "[vr]")
{
    VrControls controls(1);
    BrushSettings brush;
    WorldTransform world;
    world.scale = 0.01;
    ControllerFrame f;
    f.seconds = 1.0 / 90.0;
    f.hands[1] = handAt(0.1, 1.0, -0.5);
    f.hands[1].trigger = 0.15; // below the start
    CHECK(controls.update(f, brush, world).commands.empty());
    f.hands[1].trigger = 0.6;
    auto out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].kind == Command::Kind::StrokeBegin);
    CHECK(out.commands[0].pressure == Approx(0.6));
    const glm::dvec3 expected = world.toScene(glm::dvec3(0.1, 1.0, -0.5 - kBrushReachMetres));
    CHECK((*out.commands[0].point)[0] == Approx(expected.x));
    CHECK((*out.commands[0].point)[2] == Approx(expected.z));
    f.hands[1].grip.position.x += 0.01;
    f.hands[1].trigger = 0.15; // between end and start: the stroke goes on
    out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].kind == Command::Kind::StrokeMove);
    CHECK(out.commands[0].pressure == Approx(0.15));
    f.focused = false;
    out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].kind == Command::Kind::StrokeEnd);
    CHECK_FALSE(out.strokeActive);
}

TEST_CASE("vr controls: the thumbstick resizes the brush with one command when let go and flicks through the modes", "[vr]")
{
    VrControls controls(1);
    BrushSettings brush;
    brush.radius = 8.0;
    WorldTransform world;
    ControllerFrame f;
    f.seconds = 0.5;
    f.hands[1] = handAt(0, 1, -0.5);
    f.hands[1].thumbstick = glm::dvec2(0, 1);
    auto out = controls.update(f, brush, world);
    CHECK(out.commands.empty());
    CHECK(out.brushRadius == Approx(8.0 * std::sqrt(2.0)));
    out = controls.update(f, brush, world);
    CHECK(out.brushRadius == Approx(16.0));
    f.hands[1].thumbstick = glm::dvec2(0, 0);
    out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].kind == Command::Kind::SetBrush);
    CHECK(out.commands[0].brush->radius == Approx(16.0));
    // A flick right: the next mode, once until the stick comes back.
    f.hands[1].thumbstick = glm::dvec2(0.9, 0);
    out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].brush->mode == vrBrushModes()[1]);
    CHECK(controls.update(f, brush, world).commands.empty());
    f.hands[1].thumbstick = glm::dvec2(0, 0);
    controls.update(f, brush, world);
    f.hands[1].thumbstick = glm::dvec2(-0.9, 0);
    out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].brush->mode == vrBrushModes().back());
}

TEST_CASE("vr controls: undo and redo on the brush hand's buttons, once per press, never mid-stroke", "[vr]")
{
    VrControls controls(1);
    BrushSettings brush;
    WorldTransform world;
    ControllerFrame f;
    f.hands[1] = handAt(0, 1, -0.5);
    f.hands[1].primary = true;
    auto out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].kind == Command::Kind::Undo);
    CHECK(controls.update(f, brush, world).commands.empty()); // held: once
    f.hands[1].primary = false;
    f.hands[1].secondary = true;
    out = controls.update(f, brush, world);
    REQUIRE(out.commands.size() == 1);
    CHECK(out.commands[0].kind == Command::Kind::Redo);
    f.hands[1].secondary = false;
    f.hands[1].trigger = 1.0;
    controls.update(f, brush, world);
    f.hands[1].primary = true;
    out = controls.update(f, brush, world);
    for (const Command& c : out.commands) CHECK(c.kind != Command::Kind::Undo);
}

TEST_CASE("vr menus: the menu stands above the off hand, and a ray meets it at the picture's pixel it points at", "[vr]")
{
    ControllerFrame f;
    f.hands[0] = handAt(-0.1, 1.1, -0.35);
    f.hands[1] = handAt(0.2, 1.0, -0.2);
    MenuLayout layout = layoutMenus(f, 1, true, true);
    REQUIRE(layout.menu);
    CHECK(layout.menu->centre.y > f.hands[0].grip.position.y + 0.5 * MenuLayout::kMenuHeight);
    CHECK(layout.hints.size() == 2);
    CHECK(layout.hints[0].centre.x < f.hands[0].grip.position.x); // on each hand's outer side
    CHECK(layout.hints[1].centre.x > f.hands[1].grip.position.x);
    // A ray from the right hand to a point a quarter across and a third down the menu.
    const auto& m = *layout.menu;
    const glm::dvec3 target = m.centre + m.right * (-0.25 * m.width) + m.up * ((0.5 - 1.0 / 3.0) * m.height);
    Pose ray;
    ray.position = f.hands[1].grip.position;
    const glm::dvec3 d = glm::normalize(target - ray.position);
    ray.orientation = glm::dquat(glm::dvec3(0, 0, -1), d);
    const auto hit = layout.pointAt(ray, 1024, 1024);
    REQUIRE(hit);
    CHECK(hit->x == Approx(0.25 * m.uv[2] * 1024).margin(1e-6));
    CHECK(hit->y == Approx((1.0 / 3.0) * m.uv[3] * 1024).margin(1e-6));
    // Pointing away misses; no menu, nothing to meet.
    ray.orientation = glm::dquat(glm::dvec3(0, 0, -1), -d);
    CHECK_FALSE(layout.pointAt(ray, 1024, 1024));
    CHECK_FALSE(layoutMenus(f, 1, false, true).menu);
    CHECK(layoutMenus(f, 1, false, false).hints.empty());
}

TEST_CASE("vr comfort: late frames lower the detail to its floor, frames in time bring it back, frames near the deadline hold it", "[vr]")
{
    VrComfort comfort;
    const double period = 1000.0 / 90.0;
    comfort.frameTook(7.0, period); // between half and 0.8 of the period: held
    CHECK(comfort.detail() == 1.0);
    comfort.frameTook(10.0, period);
    CHECK(comfort.detail() == Approx(0.8));
    for (int i = 0; i < 20; ++i) comfort.frameTook(30.0, period);
    CHECK(comfort.detail() == VrComfort::kLeastDetail);
    comfort.frameTook(7.0, period);
    CHECK(comfort.detail() == VrComfort::kLeastDetail);
    for (int i = 0; i < 200; ++i) comfort.frameTook(3.0, period);
    CHECK(comfort.detail() == 1.0);
}

// --- sessions through the fake runtime -------------------------------------------------------------

namespace {

struct Ppm {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
    const uint8_t* at(int x, int y) const { return &rgb[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3]; }
};

Ppm readPpm(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in);
    std::string magic;
    int maxValue = 0;
    Ppm p;
    in >> magic >> p.width >> p.height >> maxValue;
    in.get();
    REQUIRE(magic == "P6");
    p.rgb.resize(std::size_t(p.width) * std::size_t(p.height) * 3);
    in.read(reinterpret_cast<char*>(p.rgb.data()), std::streamsize(p.rgb.size()));
    REQUIRE(in);
    return p;
}

/// Pixels unlike the background (the corner's colour): their count and mean x.
struct Silhouette {
    double pixels = 0, meanX = 0;
};
Silhouette silhouette(const Ppm& p)
{
    const uint8_t* bg = p.at(0, 0);
    Silhouette s;
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) {
            const uint8_t* c = p.at(x, y);
            if (std::abs(int(c[0]) - bg[0]) + std::abs(int(c[1]) - bg[1]) + std::abs(int(c[2]) - bg[2]) > 24) {
                s.pixels += 1;
                s.meanX += x + 0.5;
            }
        }
    if (s.pixels > 0) s.meanX /= s.pixels;
    return s;
}

std::string readText(const std::string& path)
{
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// The environment of a session through the fake runtime, both validation layers on, its findings in `dir`.
std::string xrEnvironment(const TempDir& dir)
{
    return "XR_RUNTIME_JSON=" + quote(VDBCLAY_FAKEXR_JSON) + " FAKEXR_SCRIPT=" + quote(dir.file("headset.json")) +
           " FAKEXR_ERRORS=" + quote(dir.file("fakexr-errors.txt")) + " FAKEXR_CAPTURE=" + quote(dir.path().string()) +
           " FAKEXR_LOG=" + quote(dir.file("frames.jsonl")) + " XR_ENABLE_API_LAYERS=XR_APILAYER_LUNARG_core_validation" +
           " XR_CORE_VALIDATION_EXPORT_TYPE=text XR_CORE_VALIDATION_FILE_NAME=" + quote(dir.file("xr-validation.txt")) +
           " VDBCLAY_VULKAN_VALIDATION=1";
}

/// Neither the fake runtime nor the core validation layer found anything.
void checkNoXrFindings(const TempDir& dir)
{
    INFO("fake runtime: " << readText(dir.file("fakexr-errors.txt")));
    INFO("core validation: " << readText(dir.file("xr-validation.txt")));
    CHECK_FALSE(std::filesystem::exists(dir.file("fakexr-errors.txt")));
    CHECK_FALSE(std::filesystem::exists(dir.file("xr-validation.txt")));
}

/// `vdbclay edit SCENE --vr --json ARGS` through the fake headset scripted by `script`.
CommandResult runVr(const TempDir& dir, const json& script, const std::string& args)
{
    std::ofstream(dir.file("headset.json")) << script.dump(1);
    return runCli(dir, "edit " + args + " --vr --json", xrEnvironment(dir));
}

/// The report's JSON on stdout.
json vrReport(const CommandResult& r)
{
    INFO("stdout: " << r.out);
    INFO("stderr: " << r.err);
    const std::size_t start = r.out.find('{');
    REQUIRE(start != std::string::npos);
    json j;
    REQUIRE_NOTHROW(j = json::parse(r.out.substr(start)));
    CHECK(j.at("validation_messages") == 0);
    return j;
}

/// A ball of radius 32 voxels (64 wide: framed 1.5 m across, 1.35 m in front of the default head).
void makeBall(const TempDir& dir, const std::string& name = "ball.vdb")
{
    REQUIRE(runCli(dir, "new " + name + " --shape sphere --size 32").exitCode == 0);
}

/// The scene a VR session left in the working store of `scene`, saved into `out`.
void exportScene(const TempDir& dir, const std::string& scene, const std::string& out)
{
    const CommandResult r = runCli(dir, "edit " + scene + " --headless -o " + out);
    INFO(r.err);
    REQUIRE(r.exitCode == 0);
}

json diffScenes(const TempDir& dir, const std::string& a, const std::string& b)
{
    const CommandResult r = runCli(dir, "diff " + a + " " + b + " --json");
    const std::size_t start = r.out.find('{');
    REQUIRE(start != std::string::npos);
    return json::parse(r.out.substr(start));
}

json handKey(uint64_t frame, double x, double y, double z, double trigger = 0.0, double squeeze = 0.0)
{
    return {{"frame", frame}, {"position", {x, y, z}}, {"trigger", trigger}, {"squeeze", squeeze}};
}

/// The right hand carving left to right across the ball's near side at `pressure` after switching to
/// remove (a thumbstick flick: add -> remove); the left hand away below.
json grooveScript(double pressure)
{
    json right = json::array();
    right.push_back(handKey(0, -0.2, 1.25, -0.5));
    right.push_back({{"frame", 5}, {"thumbstick", {1.0, 0.0}}});
    right.push_back({{"frame", 8}, {"thumbstick", {0.0, 0.0}}});
    right.push_back(handKey(20, -0.2, 1.25, -0.5, pressure));
    right.push_back(handKey(60, 0.2, 1.25, -0.5, pressure));
    right.push_back(handKey(64, 0.2, 1.25, -0.5, 0.0));
    return {{"left", json::array({handKey(0, -0.3, 0.3, 0.2)})}, {"right", right}};
}

} // namespace

TEST_CASE("xr: Khronos' hello_xr runs 300 frames through the fake runtime, the core validation layer silent", "[vr]")
{
    TempDir dir;
    std::ofstream(dir.file("headset.json")) << json{{"stop_after_frames", 300}}.dump();
    // hello_xr ends on a key press: its input stays open (and empty) until it exits.
    const CommandResult r = runCli(dir, "-c " + quote("/usr/bin/hello_xr -g Vulkan2 < <(sleep 60)"), xrEnvironment(dir), "/bin/bash");
    INFO(r.err.substr(r.err.size() > 4000 ? r.err.size() - 4000 : 0));
    REQUIRE(r.exitCode == 0);
    checkNoXrFindings(dir);
    std::istringstream frames(readText(dir.file("frames.jsonl")));
    std::string line;
    int count = 0;
    while (std::getline(frames, line)) ++count;
    CHECK(count >= 300);
}

TEST_CASE("xr: a VR session through the fake runtime goes from instance to exit through every state and draws the scene", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    const json report = vrReport(runVr(dir, {{"capture", {30}}}, "ball.vdb --frames 45"));
    checkNoXrFindings(dir);
    CHECK(report.at("frames") == 45);
    CHECK(report.at("frames_drawn").get<int>() >= 40);
    CHECK(report.at("lost") == false);
    CHECK(report.at("states") == json({"IDLE", "READY", "SYNCHRONIZED", "VISIBLE", "FOCUSED", "VISIBLE", "SYNCHRONIZED", "STOPPING", "IDLE", "EXITING"}));
    // Both eyes saw the ball: a large disc in the middle of each picture.
    for (int eye = 0; eye < 2; ++eye) {
        const Ppm image = readPpm(dir.file("frame-00030-view-" + std::to_string(eye) + ".ppm"));
        const Silhouette s = silhouette(image);
        CHECK(s.pixels > 0.15 * image.width * image.height);
        CHECK(s.meanX == Approx(0.5 * image.width).margin(0.1 * image.width));
    }
}

TEST_CASE("xr: the runtime asking the session to stop ends it cleanly", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    const json report = vrReport(runVr(dir, {{"stop_after_frames", 30}}, "ball.vdb"));
    checkNoXrFindings(dir);
    CHECK(report.at("frames") == 30);
    CHECK(report.at("states").back() == "EXITING");
}

TEST_CASE("xr: without a runtime, --vr says so in one line and exits 1", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    const CommandResult r = runCli(dir, "edit ball.vdb --vr --frames 5", "XR_RUNTIME_JSON=" + quote(dir.file("none.json")));
    checkCleanFailure(r);
    CHECK(r.exitCode == 1);
    CHECK(r.err.find("OpenXR runtime") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("xr: a groove carved with the trigger equals the same stroke applied by sculpt, and replays headless to the same scene", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    makeBall(dir, "original.vdb");
    const json report = vrReport(runVr(dir, grooveScript(1.0), "ball.vdb --frames 80 --record session.json"));
    checkNoXrFindings(dir);
    CHECK(report.at("commands").get<int>() > 10);
    CHECK(report.at("haptic_pulses").get<int>() >= 1); // the brush reached the ball
    exportScene(dir, "ball.vdb", "carved.vdb");
    const json carved = diffScenes(dir, "original.vdb", "carved.vdb");
    CHECK(carved.at("identical") == false);
    CHECK(carved.at("difference_volume").get<double>() > 100.0);
    // The session's ops as a script, applied by sculpt to the ball as it was: the same scene, bit for bit.
    REQUIRE(runCli(dir, "edit original.vdb --replay session.json --headless --export-script ops.json -o replayed.vdb").exitCode == 0);
    REQUIRE(runCli(dir, "sculpt original.vdb ops.json -o sculpted.vdb").exitCode == 0);
    CHECK(diffScenes(dir, "carved.vdb", "sculpted.vdb").at("identical") == true);
    CHECK(diffScenes(dir, "carved.vdb", "replayed.vdb").at("identical") == true);
    // It is a groove: the ops remove, across the ball's near side.
    const json ops = json::parse(readText(dir.file("ops.json")));
    REQUIRE(ops.at("ops").size() > 0);
    for (const json& op : ops.at("ops")) CHECK(op.at("mode") == "remove");
}

TEST_CASE("xr: pressure changes the groove's width as the brush says", "[vr]")
{
    double removed[2] = {0, 0};
    const double pressures[2] = {0.4, 1.0};
    for (int i = 0; i < 2; ++i) {
        TempDir dir;
        makeBall(dir);
        makeBall(dir, "original.vdb");
        vrReport(runVr(dir, grooveScript(pressures[i]), "ball.vdb --frames 80"));
        checkNoXrFindings(dir);
        exportScene(dir, "ball.vdb", "carved.vdb");
        removed[i] = diffScenes(dir, "original.vdb", "carved.vdb").at("difference_volume").get<double>();
    }
    INFO("removed at pressure 0.4: " << removed[0] << ", at 1: " << removed[1]);
    CHECK(removed[0] > 0.0);
    CHECK(removed[1] > 2.0 * removed[0]); // the brush's size follows pressure (the default)
}

TEST_CASE("xr: a two-hand grab changes the view, not the scene", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    makeBall(dir, "original.vdb");
    // Both hands squeeze at frame 30 and move apart to twice their spread: the ball grows about them.
    const json script = {{"capture", {20, 75}},
                         {"left", json::array({handKey(0, -0.1, 1.0, -0.3), handKey(30, -0.1, 1.0, -0.3, 0.0, 1.0), handKey(60, -0.2, 1.0, -0.3, 0.0, 1.0),
                                               handKey(65, -0.2, 1.0, -0.3, 0.0, 0.0)})},
                         {"right", json::array({handKey(0, 0.1, 1.0, -0.3), handKey(30, 0.1, 1.0, -0.3, 0.0, 1.0), handKey(60, 0.2, 1.0, -0.3, 0.0, 1.0),
                                                handKey(65, 0.2, 1.0, -0.3, 0.0, 0.0)})}};
    const json report = vrReport(runVr(dir, script, "ball.vdb --frames 80"));
    checkNoXrFindings(dir);
    CHECK(report.at("commands") == 0);
    const Silhouette before = silhouette(readPpm(dir.file("frame-00020-view-0.ppm")));
    const Silhouette after = silhouette(readPpm(dir.file("frame-00075-view-0.ppm")));
    INFO("ball pixels before " << before.pixels << ", after " << after.pixels);
    CHECK(after.pixels > 1.2 * before.pixels);
    exportScene(dir, "ball.vdb", "after.vdb");
    CHECK(diffScenes(dir, "original.vdb", "after.vdb").at("identical") == true);
}

TEST_CASE("xr: the eyes see the scene from two poses an interpupillary distance apart", "[vr]")
{
    // The ball's image in the left eye lies right of its image in the right eye by its disparity, which
    // grows linearly with the distance between the eyes (f ipd / depth, times the widening of a large
    // sphere's silhouette, 1 / (1 - (radius / depth)^2), the same for every ipd).
    auto disparity = [](double ipd) {
        TempDir dir;
        makeBall(dir);
        // Hands behind the head: no brush in view.
        const json script = {{"capture", {20}}, {"ipd", ipd},
                             {"left", json::array({handKey(0, -0.2, 1.0, 0.5)})}, {"right", json::array({handKey(0, 0.2, 1.0, 0.5)})}};
        vrReport(runVr(dir, script, "ball.vdb --frames 30"));
        checkNoXrFindings(dir);
        const Ppm left = readPpm(dir.file("frame-00020-view-0.ppm")), right = readPpm(dir.file("frame-00020-view-1.ppm"));
        return silhouette(left).meanX - silhouette(right).meanX;
    };
    const double none = disparity(0.0), normal = disparity(0.064), wide = disparity(0.128);
    INFO("disparity at ipd 0: " << none << " px, 64 mm: " << normal << " px, 128 mm: " << wide << " px");
    CHECK(std::fabs(none) < 0.05);
    CHECK(wide == Approx(2.0 * normal).epsilon(0.05));
    // The ball's centre stands 1.35 m in front of the eyes (frameScene); f = width / (tan(right) - tan(left))
    // for the fake's +-0.8 rad views; the silhouette widens by less than 1.6 for a ball 1.5 m across.
    const double f = 256.0 / (2.0 * std::tan(0.8));
    CHECK(normal > f * 0.064 / 1.35);
    CHECK(normal < 1.6 * f * 0.064 / 1.35);
}

TEST_CASE("xr: focus lost mid-stroke ends the stroke cleanly", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    json script = grooveScript(1.0);
    script["focus_lost_at"] = 40;
    script["focus_back_at"] = 50;
    const json report = vrReport(runVr(dir, script, "ball.vdb --frames 80 --record session.json"));
    checkNoXrFindings(dir);
    const std::vector<std::string> states = report.at("states");
    CHECK(std::count(states.begin(), states.end(), "FOCUSED") == 2);
    // Every stroke the record holds ends before the next begins, the one cut short included.
    const json record = json::parse(readText(dir.file("session.json")));
    int open = 0, strokes = 0;
    for (const json& c : record.at("commands")) {
        const std::string kind = c.at("command");
        if (kind == "stroke_begin") {
            CHECK(open == 0);
            open = 1;
            ++strokes;
        } else if (kind == "stroke_end") {
            CHECK(open == 1);
            open = 0;
        } else if (kind == "stroke_move") {
            CHECK(open == 1);
        }
    }
    CHECK(open == 0);
    CHECK(strokes == 2); // cut by the focus lost, begun again once it came back with the trigger still held
}

TEST_CASE("xr: a session the runtime loses keeps every edit", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    makeBall(dir, "original.vdb");
    json script = grooveScript(1.0);
    script["loss_pending_at"] = 70;
    const CommandResult r = runVr(dir, script, "ball.vdb --frames 200 --record session.json");
    const json report = vrReport(r);
    checkNoXrFindings(dir);
    CHECK(r.exitCode == 1);
    CHECK(report.at("lost") == true);
    CHECK(report.at("states").back() == "LOSS_PENDING");
    CHECK(r.err.find("autosaved") != std::string::npos);
    // What autosave kept is the whole stroke: the record replayed on the original gives the same scene.
    exportScene(dir, "ball.vdb", "kept.vdb");
    REQUIRE(runCli(dir, "edit original.vdb --replay session.json --headless -o replayed.vdb").exitCode == 0);
    CHECK(diffScenes(dir, "original.vdb", "kept.vdb").at("identical") == false);
    CHECK(diffScenes(dir, "kept.vdb", "replayed.vdb").at("identical") == true);
}

TEST_CASE("xr: a runtime without depth, with sRGB formats only and one view drives the editor", "[vr]")
{
    TempDir dir;
    makeBall(dir);
    const json script = {{"depth_extension", false}, {"stereo", false}, {"formats", {43 /* B8G8R8A8_SRGB */}}, {"width", 200}, {"height", 150},
                         {"capture", {20}}};
    const json report = vrReport(runVr(dir, script, "ball.vdb --frames 30"));
    checkNoXrFindings(dir);
    const std::string headset = report.at("headset");
    CHECK(headset.find("1 view of 200 x 150") != std::string::npos);
    CHECK(headset.find("sRGB viewed as UNORM") != std::string::npos);
    CHECK(headset.find("depth kept") != std::string::npos);
    const Ppm image = readPpm(dir.file("frame-00020-view-0.ppm"));
    CHECK(image.width == 200);
    CHECK(silhouette(image).pixels > 0.1 * image.width * image.height);
}

TEST_CASE("xr: the menu stands where the off hand holds it, and a choice made by pointing and pulling the trigger changes the next stroke", "[vr]")
{
    // The left hand holds the menu up (Y at frame 5); the right hand stays low and away.
    const glm::dvec3 offHand(-0.1, 1.1, -0.35);
    json left = json::array({handKey(0, offHand.x, offHand.y, offHand.z), {{"frame", 5}, {"buttons", {{"y", true}}}}, {{"frame", 7}, {"buttons", {{"y", false}}}}});
    ControllerFrame held;
    held.hands[0] = handAt(offHand.x, offHand.y, offHand.z);
    const MenuLayout layout = layoutMenus(held, 1, true, true);
    REQUIRE(layout.menu);
    const MenuLayout::Panel& menu = *layout.menu;

    TempDir dir;
    makeBall(dir);
    makeBall(dir, "original.vdb");
    const json first = vrReport(runVr(dir, {{"capture", {3, 20}}, {"left", left}, {"right", json::array({handKey(0, 0.3, 0.6, -0.1)})}}, "ball.vdb --frames 21"));
    checkNoXrFindings(dir);
    // The menu is drawn where the hand holds it: around its centre the left eye's picture changes once it
    // is shown (the panel covers what was there).
    {
        const glm::dvec3 eye(-0.032, 1.6, 0.0); // the fake's head and ipd
        const glm::dvec3 p = menu.centre - eye;
        const double f = 128.0 / std::tan(0.8);
        const int px = int(128.0 + f * p.x / -p.z), py = int(128.0 - f * p.y / -p.z);
        const Ppm before = readPpm(dir.file("frame-00003-view-0.ppm")), after = readPpm(dir.file("frame-00020-view-0.ppm"));
        INFO("menu centre at pixel " << px << ", " << py);
        REQUIRE(px >= 0);
        REQUIRE(px < 256);
        REQUIRE(py >= 0);
        REQUIRE(py < 256);
        int changed = 0, total = 0;
        for (int y = py - 7; y <= py + 7; ++y)
            for (int x = px - 7; x <= px + 7; ++x) {
                if (x < 0 || y < 0 || x >= 256 || y >= 256) continue;
                const uint8_t* b = before.at(x, y);
                const uint8_t* a = after.at(x, y);
                changed += std::abs(int(a[0]) - b[0]) + std::abs(int(a[1]) - b[1]) + std::abs(int(a[2]) - b[2]) > 24 ? 1 : 0;
                ++total;
            }
        CHECK(changed > total / 2);
        // Far from it (the upper right of the view), nothing changed.
        const uint8_t* b = before.at(250, 5);
        const uint8_t* a = after.at(250, 5);
        CHECK(std::abs(int(a[0]) - b[0]) + std::abs(int(a[1]) - b[1]) + std::abs(int(a[2]) - b[2]) <= 3);
    }
    REQUIRE(first.at("menu_widgets").contains("mirror x"));
    const std::array<float, 4> rect = first.at("menu_widgets").at("mirror x");

    // The same menu; the right hand points at "mirror x" and pulls the trigger, then goes to the ball
    // and adds a stroke: mirrored now.
    const double u = (0.5 * (rect[0] + rect[2]) / 1024.0 - menu.uv[0]) / (menu.uv[2] - menu.uv[0]);
    const double v = (0.5 * (rect[1] + rect[3]) / 1024.0 - menu.uv[1]) / (menu.uv[3] - menu.uv[1]);
    const glm::dvec3 target = menu.centre + menu.right * ((u - 0.5) * menu.width) + menu.up * ((0.5 - v) * menu.height);
    const glm::dvec3 from(0.15, 1.0, -0.2);
    const glm::dquat aim = glm::dquat(glm::dvec3(0, 0, -1), glm::normalize(target - from));
    auto pose = [](uint64_t frame, const glm::dvec3& p, const glm::dquat& q, double trigger) {
        return json{{"frame", frame}, {"position", {p.x, p.y, p.z}}, {"orientation", {q.x, q.y, q.z, q.w}}, {"trigger", trigger}};
    };
    const glm::dquat ahead(1, 0, 0, 0);
    json right = json::array({pose(0, from, aim, 0.0), pose(25, from, aim, 0.0), pose(26, from, aim, 1.0), pose(29, from, aim, 1.0),
                              pose(30, from, aim, 0.0), pose(40, glm::dvec3(0.1, 1.25, -0.5), ahead, 0.0),
                              pose(45, glm::dvec3(0.1, 1.25, -0.5), ahead, 1.0), pose(60, glm::dvec3(0.2, 1.3, -0.5), ahead, 1.0),
                              pose(64, glm::dvec3(0.2, 1.3, -0.5), ahead, 0.0)});
    TempDir second;
    makeBall(second);
    makeBall(second, "original.vdb");
    vrReport(runVr(second, {{"left", left}, {"right", right}}, "ball.vdb --frames 75 --record session.json"));
    checkNoXrFindings(second);
    REQUIRE(runCli(second, "edit original.vdb --replay session.json --headless --export-script ops.json").exitCode == 0);
    const json ops = json::parse(readText(second.file("ops.json"))).at("ops");
    REQUIRE(ops.size() > 0);
    for (const json& op : ops) {
        CHECK(op.at("mode") == "add");
        REQUIRE(op.contains("symmetry"));
        CHECK(op.at("symmetry").at("mirror") == json({"x"}));
    }
}

TEST_CASE("xr: the suggested bindings drive the brush on every controller profile", "[vr]")
{
    // Each profile as the fake emulates it: the trigger strokes; where there is a thumbstick (a trackpad
    // on the Vive), its flick turns add into remove.
    struct Profile {
        const char* path;
        bool stick;
    };
    for (const Profile& profile : {Profile{"/interaction_profiles/oculus/touch_controller", true}, Profile{"/interaction_profiles/valve/index_controller", true},
                                   Profile{"/interaction_profiles/htc/vive_controller", true}, Profile{"/interaction_profiles/khr/simple_controller", false}}) {
        INFO(profile.path);
        TempDir dir;
        makeBall(dir);
        makeBall(dir, "original.vdb");
        json script = grooveScript(1.0);
        script["profile"] = profile.path;
        vrReport(runVr(dir, script, "ball.vdb --frames 80 --record session.json"));
        checkNoXrFindings(dir);
        REQUIRE(runCli(dir, "edit original.vdb --replay session.json --headless --export-script ops.json").exitCode == 0);
        const json ops = json::parse(readText(dir.file("ops.json"))).at("ops");
        REQUIRE(ops.size() > 0);
        CHECK(ops.front().at("mode") == (profile.stick ? "remove" : "add"));
    }
}

TEST_CASE("xr: the controller hints stand beside the hands until the menu button turns them off", "[vr]")
{
    // The left hand low in front, its menu button pressed at frame 20: the hint beside it (on its outer,
    // left side) is drawn at frame 15 and gone at frame 35.
    const glm::dvec3 hand(-0.05, 1.35, -0.3);
    const json left = json::array({handKey(0, hand.x, hand.y, hand.z), {{"frame", 20}, {"buttons", {{"menu", true}}}}, {{"frame", 22}, {"buttons", {{"menu", false}}}}});
    TempDir dir;
    makeBall(dir);
    vrReport(runVr(dir, {{"capture", {15, 35}}, {"left", left}, {"right", json::array({handKey(0, 0.3, 0.4, 0.3)})}}, "ball.vdb --frames 40"));
    checkNoXrFindings(dir);
    ControllerFrame f;
    f.hands[0] = handAt(hand.x, hand.y, hand.z);
    const MenuLayout layout = layoutMenus(f, 1, false, true);
    REQUIRE(layout.hints.size() == 1);
    const glm::dvec3 p = layout.hints[0].centre - glm::dvec3(-0.032, 1.6, 0.0); // from the left eye
    const double fx = 128.0 / std::tan(0.8);
    const int px = int(128.0 + fx * p.x / -p.z), py = int(128.0 - fx * p.y / -p.z);
    REQUIRE(px >= 7);
    REQUIRE(px < 249);
    REQUIRE(py >= 7);
    REQUIRE(py < 249);
    const Ppm shown = readPpm(dir.file("frame-00015-view-0.ppm")), hidden = readPpm(dir.file("frame-00035-view-0.ppm"));
    int changed = 0, total = 0;
    for (int y = py - 3; y <= py + 3; ++y)
        for (int x = px - 7; x <= px + 7; ++x) {
            const uint8_t* a = shown.at(x, y);
            const uint8_t* b = hidden.at(x, y);
            changed += std::abs(int(a[0]) - b[0]) + std::abs(int(a[1]) - b[1]) + std::abs(int(a[2]) - b[2]) > 24 ? 1 : 0;
            ++total;
        }
    INFO("hint centre at pixel " << px << ", " << py << ": " << changed << " of " << total << " pixels changed");
    CHECK(changed > total / 2);
}
