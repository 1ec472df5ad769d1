// The editing session sculpts as a sculptor expects (issue 37): strokes follow the surface as the stroke
// found it, add and remove change it by at most strength x radius, grab keeps the grabbed point under the
// pointer, and the record holds each stroke point's ray beside the point it placed.
#include "editor/EditingSession.h"
#include "editor/CameraControl.h"
#include "editor/VolumeRayCast.h"
#include "sculpt/StrokeScript.h"
#include "support/QuietSession.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

constexpr double kBall = 20.0;

std::string makeBall(const TempDir& dir, const std::string& name = "ball.vdb")
{
    Volume v(1.0);
    runStrokeScript(v, parseStrokeScript(nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", kBall}}}}}}}.dump()));
    const std::string path = dir.file(name);
    saveVolume(v, path);
    return path;
}


double length(const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

std::array<double, 3> minus(const std::array<double, 3>& a, const std::array<double, 3>& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

const std::array<double, 3> kEye{0.0, 0.0, 80.0};

/// The ray from the eye on +z through `aim`.
Ray rayTowards(const std::array<double, 3>& aim)
{
    std::array<double, 3> d = minus(aim, kEye);
    const double n = length(d);
    for (double& x : d) x /= n;
    return {kEye, d};
}

/// Looks at the ball from the eye and streams it in (a ray meets only what is resident).
void useCamera(EditingSession& session)
{
    Command c;
    c.kind = Command::Kind::SetCamera;
    c.camera.eye = kEye;
    c.camera.target = {0, 0, 0};
    session.apply(c);
    for (int i = 0; i < 3; ++i) {
        session.frame(0.0, {640, 480});
        session.scene().waitForLoads();
    }
}

void useBrush(EditingSession& session, const std::string& mode, double radius, double strength, bool accumulate = false,
              double distance = 2.0)
{
    Command c;
    c.kind = Command::Kind::SetBrush;
    c.brush.emplace();
    c.brush->mode = mode;
    c.brush->radius = radius;
    c.brush->strength = strength;
    c.brush->accumulate = accumulate;
    c.brush->distance = distance;
    session.apply(c);
}

void stroke(EditingSession& session, Command::Kind kind, const Ray& ray)
{
    Command c;
    c.kind = kind;
    c.ray = ray;
    session.apply(c);
}

void endStroke(EditingSession& session)
{
    Command c;
    c.kind = Command::Kind::StrokeEnd;
    session.apply(c);
}

/// A sideways drag across the front of the ball, 25 pointer moves from x = -12 to 12.
void sidewaysDrag(EditingSession& session, double y = 0.0)
{
    for (int i = 0; i <= 24; ++i) stroke(session, i == 0 ? Command::Kind::StrokeBegin : Command::Kind::StrokeMove, rayTowards({-12.0 + i, y, 0.0}));
    endStroke(session);
}

/// How far the surface lies from the ball's centre along the direction to `aim` (a ray from outside).
double surfaceRadius(const EditingSession& session, const std::array<double, 3>& direction)
{
    const double n = length(direction);
    const std::array<double, 3> d{direction[0] / n, direction[1] / n, direction[2] / n};
    const std::array<double, 3> from{d[0] * 60.0, d[1] * 60.0, d[2] * 60.0};
    const auto hit = session.pick(from, {-d[0], -d[1], -d[2]});
    REQUIRE(hit);
    return length(hit->point);
}

} // namespace

TEST_CASE("editor: a sideways add stroke follows the surface as it began and raises it by at most strength x radius", "[editor][sculpt]")
{
    TempDir dir;
    const double radius = 4.0, strength = 0.5;
    for (const std::string mode : {"add", "remove"}) {
        EditingSession session(makeBall(dir, mode + ".vdb"), quietSession());
        useCamera(session);
        useBrush(session, mode, radius, strength);
        sidewaysDrag(session);
        // Every stroke point lies on the ball as it was (a crossing is within a voxel of the sphere), and
        // the record holds the ray beside it.
        std::vector<std::array<double, 3>> points;
        for (const RecordedCommand& rc : session.record().commands) {
            const Command& c = rc.command;
            if (c.kind != Command::Kind::StrokeBegin && c.kind != Command::Kind::StrokeMove) continue;
            REQUIRE(c.ray);
            REQUIRE(c.point);
            REQUIRE(c.normal);
            CHECK(std::fabs(length(*c.point) - kBall) < 1.0);
            points.push_back(*c.point);
        }
        CHECK(points.size() == 25);
        // The surface under the stroke moved by strength x radius (a voxel of tolerance for the lattice).
        double highest = 0.0, lowest = 1e9;
        for (const auto& p : points) {
            const double r = surfaceRadius(session, p);
            highest = std::max(highest, r);
            lowest = std::min(lowest, r);
        }
        INFO(mode << ": surface radius under the stroke from " << lowest << " to " << highest);
        if (mode == "add") {
            CHECK(highest <= kBall + strength * radius + 1.0);
            CHECK(lowest >= kBall + strength * radius - 1.0);
        } else {
            CHECK(lowest >= kBall - strength * radius - 1.0);
            CHECK(highest <= kBall - strength * radius + 1.0);
        }
    }
}

TEST_CASE("editor: inflate and deflate move the surface by at most strength x distance per stroke, unless they accumulate", "[editor][sculpt]")
{
    TempDir dir;
    const double radius = 6.0, strength = 0.8, distance = 2.5, cap = strength * distance;
    for (const std::string mode : {"inflate", "deflate"})
        for (const bool accumulate : {false, true}) {
            EditingSession session(makeBall(dir, mode + (accumulate ? "-acc.vdb" : ".vdb")), quietSession());
            useCamera(session);
            useBrush(session, mode, radius, strength, accumulate, distance);
            sidewaysDrag(session); // stamps 1.5 voxels apart: each point under the stroke is stamped about 8 times
            CHECK(session.stats().opsRefused == 0);
            // How far the surface moved along the stroke's line, from the ball's radius.
            double farthest = 0.0, nearest = 1e9;
            for (int x = -9; x <= 9; ++x) {
                const double moved = std::fabs(surfaceRadius(session, {double(x), 0.0, std::sqrt(kBall * kBall - x * x)}) - kBall);
                farthest = std::max(farthest, moved);
                nearest = std::min(nearest, moved);
            }
            INFO(mode << (accumulate ? " accumulating" : "") << ": moved from " << nearest << " to " << farthest);
            if (accumulate) {
                CHECK(farthest > cap + 2.0);
            } else {
                CHECK(farthest <= cap + 1.0);
                CHECK(nearest >= cap - 1.0);
            }
        }
}

TEST_CASE("script: inflate and deflate that continue a stroke move the surface from where it began, at most distance x strength", "[sculpt][field]")
{
    const auto ball = [] {
        Volume v(1.0);
        runStrokeScript(v, parseStrokeScript(nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", kBall}}}}}}}.dump()));
        return v;
    };
    // The surface's height above the ball's centre at (x, 0).
    const auto heightAt = [](const Volume& v, double x) {
        const auto hit = castRay(v, {x, 0.0, 60.0}, {0.0, 0.0, -1.0}, 100.0);
        REQUIRE(hit);
        return hit->point[2];
    };
    for (const std::string mode : {"inflate", "deflate"}) {
        const double sign = mode == "inflate" ? 1.0 : -1.0, distance = 2.0, strength = 0.75;
        // Five stamps on one spot, then a row along x, once as one stroke and once as separate ones.
        nlohmann::json stroke = nlohmann::json::array(), separate = nlohmann::json::array();
        for (int i = 0; i < 9; ++i) {
            const double x = i < 5 ? 0.0 : double(i - 4) * 1.5;
            nlohmann::json op = {{"mode", mode}, {"brush", {{"shape", "sphere"}, {"radius", 6.0}}}, {"at", {x, 0.0, kBall}},
                                 {"strength", strength}, {"distance", distance}, {"falloff", "constant"}};
            separate.push_back(op);
            if (i > 0) op["stroke"] = "continue";
            stroke.push_back(op);
        }
        Volume capped = ball(), summed = ball();
        runStrokeScript(capped, parseStrokeScript(nlohmann::json{{"ops", stroke}}.dump()));
        runStrokeScript(summed, parseStrokeScript(nlohmann::json{{"ops", separate}}.dump()));
        for (const double x : {0.0, 1.5, 3.0, 4.5}) {
            INFO(mode << " at x = " << x);
            CHECK(std::fabs(sign * (heightAt(capped, x) - std::sqrt(kBall * kBall - x * x)) - strength * distance) < 0.6);
            CHECK(sign * (heightAt(summed, x) - std::sqrt(kBall * kBall - x * x)) > 3.0 * strength * distance);
        }
        // A stroke held by the caller across scripts (the editor's way) does what one script does.
        Volume carried = ball();
        StrokeStart start(1.0);
        for (const nlohmann::json& op : stroke)
            runStrokeScript(carried, parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump()), {}, &start);
        CHECK(identical(carried, capped));
    }
}

TEST_CASE("script: 'stroke' is refused outside inflate and deflate strokes", "[sculpt][field]")
{
    const auto refusal = [](const nlohmann::json& ops) {
        try {
            parseStrokeScript(nlohmann::json{{"ops", ops}}.dump());
        } catch (const ScriptError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const nlohmann::json inflate = {{"mode", "inflate"}, {"brush", {{"shape", "sphere"}, {"radius", 3.0}}}, {"distance", 1.0}};
    const nlohmann::json add = {{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 3.0}}}};
    nlohmann::json goesOn = inflate, addGoesOn = add, badValue = inflate;
    goesOn["stroke"] = "continue";
    addGoesOn["stroke"] = "continue";
    badValue["stroke"] = "begin";
    CHECK(refusal({inflate, goesOn}) == "accepted");
    CHECK(refusal(nlohmann::json::array({goesOn})) == "accepted"); // nothing before it to continue: it begins the stroke
    CHECK(refusal({add, addGoesOn}).find("ops[1].stroke: belongs to inflate and deflate") != std::string::npos);
    CHECK(refusal({add, goesOn}).find("ops[1].stroke: continues a stroke only after an inflate or deflate op") != std::string::npos);
    CHECK(refusal({inflate, badValue}).find("ops[1].stroke: must be \"continue\"") != std::string::npos);
}

TEST_CASE("editor: with accumulate on, a stroke builds on itself and climbs towards the camera", "[editor][sculpt]")
{
    TempDir dir;
    const std::string path = makeBall(dir);
    EditingSession session(path, quietSession());
    useCamera(session);
    useBrush(session, "add", 4.0, 1.0, true);
    // The pointer stays put: each stamp lands on the previous one.
    stroke(session, Command::Kind::StrokeBegin, rayTowards({0, 0, 0}));
    for (int i = 0; i < 6; ++i) stroke(session, Command::Kind::StrokeMove, rayTowards({0.5 * (i % 2), 0, 0}));
    endStroke(session);
    const Command& last = session.record().commands[session.record().commands.size() - 2].command;
    REQUIRE(last.point);
    CHECK((*last.point)[2] > kBall + 3.0);

    // Off, the same pointer path stays on the ball as it began.
    EditingSession fresh(makeBall(dir, "again.vdb"), quietSession());
    useCamera(fresh);
    useBrush(fresh, "add", 4.0, 1.0, false);
    stroke(fresh, Command::Kind::StrokeBegin, rayTowards({0, 0, 0}));
    for (int i = 0; i < 6; ++i) stroke(fresh, Command::Kind::StrokeMove, rayTowards({0.5 * (i % 2), 0, 0}));
    endStroke(fresh);
    for (const RecordedCommand& rc : fresh.record().commands)
        if (rc.command.point) CHECK(std::fabs(length(*rc.command.point) - kBall) < 1.0);
}

TEST_CASE("editor: grab keeps the grabbed point under the pointer for a drag of three radii", "[editor][sculpt]")
{
    TempDir dir;
    const std::string path = makeBall(dir);
    EditingSession session(path, quietSession());
    useCamera(session);
    const double radius = 6.0;
    useBrush(session, "move", radius, 1.0);
    stroke(session, Command::Kind::StrokeBegin, rayTowards({0, 0, 0}));
    REQUIRE(session.strokeActive());
    const std::array<double, 3> grabbed = session.strokePoint();
    CHECK(std::fabs(grabbed[2] - kBall) < 1.0);
    // The pointer crosses the view: the grabbed point follows it on the plane facing the camera.
    const int steps = 18;
    std::array<double, 3> aim{};
    for (int i = 1; i <= steps; ++i) {
        aim = {3.0 * radius * i / steps, 0.0, grabbed[2]};
        stroke(session, Command::Kind::StrokeMove, rayTowards(aim));
    }
    endStroke(session);
    // The surface under the pointer is where the grabbed point went (half a voxel).
    const Ray last = rayTowards(aim);
    const auto hit = session.pick(last.origin, last.direction);
    REQUIRE(hit);
    INFO("the pointer's ray meets the surface at " << hit->point[0] << ", " << hit->point[1] << ", " << hit->point[2]);
    CHECK(length(minus(hit->point, aim)) <= 0.5);
    // One stroke, one undo step; undone, the ball is whole again.
    CHECK(session.history().undoDepth() == 1);
    Command undo;
    undo.kind = Command::Kind::Undo;
    session.apply(undo);
    CHECK_FALSE(session.pick(last.origin, last.direction)); // the pointer's ray passes beside the ball
    const auto back = session.pick({aim[0], 0.0, 60.0}, {0, 0, -1});
    REQUIRE(back);
    CHECK(std::fabs(length(back->point) - kBall) < 1.0);
}

TEST_CASE("replay: a session of rays replays to the same scene and every recorded point is placed again", "[editor][replay][sculpt]")
{
    TempDir dir;
    SessionRecord record;
    {
        EditingSession session(makeBall(dir, "a.vdb"), quietSession());
        useCamera(session);
        useBrush(session, "add", 3.0, 0.6);
        sidewaysDrag(session, 4.0);
        session.frame(0.1, {640, 480});
        useBrush(session, "move", 5.0, 1.0);
        stroke(session, Command::Kind::StrokeBegin, rayTowards({0, -6, 0}));
        for (int i = 1; i <= 6; ++i) stroke(session, Command::Kind::StrokeMove, rayTowards({0, -6.0 - i, 19.0}));
        endStroke(session);
        session.frame(0.2, {640, 480});
        useBrush(session, "inflate", 4.0, 0.8);
        sidewaysDrag(session, -3.0);
        session.frame(0.3, {640, 480});
        session.autosave();
        record = session.record();
    }
    // Through the file, as a bug report would carry it.
    saveSessionRecord(record, dir.file("s.json"));
    const SessionRecord loaded = loadSessionRecord(dir.file("s.json"));
    EditingSession replayed(makeBall(dir, "b.vdb"), quietSession());
    replaySession(replayed, loaded);
    CHECK(replayed.stats().placementsDiffering == 0);
    replayed.autosave();
    EditingSession original(dir.file("a.vdb"), quietSession());
    CHECK(identical(original.scene().storedLevel0(), replayed.scene().storedLevel0()));
}

TEST_CASE("editor: orbit about a pivot keeps the pivot where it is on the screen, axis views look along the axes", "[editor][camera]")
{
    render::Camera c;
    c.eye = {30, 20, 80};
    c.target = {0, 0, 0};
    const std::array<double, 3> pivot{10, 5, 12};
    const std::array<int, 2> viewport{800, 600};
    // Where the pivot lies on the screen: the angles of its direction from the view's axis.
    const auto screenAngles = [&](const render::Camera& cam) {
        const Ray centre = pointerRay(cam, viewport, 400, 300);
        std::array<double, 3> d = minus(pivot, cam.eye);
        const double n = length(d);
        for (double& x : d) x /= n;
        return std::acos(std::clamp(d[0] * centre.direction[0] + d[1] * centre.direction[1] + d[2] * centre.direction[2], -1.0, 1.0));
    };
    const render::Camera turned = orbitAbout(c, pivot, 25.0, -10.0);
    CHECK(std::fabs(screenAngles(turned) - screenAngles(c)) < 1e-9);
    CHECK(std::fabs(length(minus(turned.eye, pivot)) - length(minus(c.eye, pivot))) < 1e-9);
    CHECK(length(minus(turned.eye, c.eye)) > 1.0);
    // The view turns as orbit() turns it about the target.
    const render::Camera plain = orbit(c, 25.0, -10.0);
    const auto direction = [](const render::Camera& cam) {
        std::array<double, 3> d = minus(cam.target, cam.eye);
        const double n = length(d);
        for (double& x : d) x /= n;
        return d;
    };
    CHECK(length(minus(direction(turned), direction(plain))) < 1e-9);

    const double distance = length(minus(c.eye, c.target));
    const std::pair<AxisView, std::array<double, 3>> views[] = {{AxisView::Front, {0, 0, 1}}, {AxisView::Back, {0, 0, -1}}, {AxisView::Right, {1, 0, 0}},
                                                                {AxisView::Left, {-1, 0, 0}}, {AxisView::Top, {0, 1, 0}}, {AxisView::Bottom, {0, -1, 0}}};
    for (const auto& [view, back] : views) {
        const render::Camera v = axisView(c, view);
        CHECK(v.target == c.target);
        for (std::size_t a = 0; a < 3; ++a) CHECK(v.eye[a] == Approx(c.target[a] + back[a] * distance));
        const Ray r = pointerRay(v, viewport, 400, 300); // a usable view, even straight down
        for (double x : r.direction) CHECK(std::isfinite(x));
    }
    const render::Camera centred = frameOn(c, pivot, 7.0);
    CHECK(centred.target == pivot);
    CHECK(length(minus(centred.eye, pivot)) == Approx(7.0));
    CHECK(length(minus(direction(centred), direction(c))) < 1e-12);
}

TEST_CASE("sculpt: a blended add is the smooth union of the surface and the brush, and never less than the exact add", "[sculpt][field]")
{
    // A ball of radius 20 and a sphere of radius 6 pressed into its side, on and off the lattice.
    for (const std::array<double, 3>& c : {std::array<double, 3>{22.0, 0.0, 0.0}, std::array<double, 3>{15.3, 12.7, -4.1}}) {
        const double width = 4.0;
        Volume exact(1.0), blended(1.0);
        const std::string ball = R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 20}}]})";
        runStrokeScript(exact, parseStrokeScript(ball));
        runStrokeScript(blended, parseStrokeScript(ball));
        nlohmann::json stamp = {{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 6}}}, {"at", c}};
        runStrokeScript(exact, parseStrokeScript(nlohmann::json{{"ops", {stamp}}}.dump()));
        stamp["blend"] = width;
        runStrokeScript(blended, parseStrokeScript(nlohmann::json{{"ops", {stamp}}}.dump()));
        int filled = 0, checked = 0;
        for (int x = 0; x <= 34; ++x)
            for (int y = -20; y <= 24; ++y)
                for (int z = -20; z <= 16; ++z) {
                    const std::array<int32_t, 3> v{x, y, z};
                    const bool e = exact.materialAt(v) != kEmptyMaterial, b = blended.materialAt(v) != kEmptyMaterial;
                    if (e) CHECK(b); // the blend only adds
                    const double a = std::sqrt(double(x * x + y * y + z * z)) - 20.0;
                    const double s = std::sqrt((x - c[0]) * (x - c[0]) + (y - c[1]) * (y - c[1]) + (z - c[2]) * (z - c[2])) - 6.0;
                    const double t = std::max(width - std::fabs(a - s), 0.0) / width;
                    const double smooth = std::min(a, s) - 0.25 * width * t * t;
                    // Away from the smooth union's surface (a voxel and a half: the lattice's resampling),
                    // the blended solid is the analytic one.
                    if (std::fabs(smooth) > 1.5) {
                        ++checked;
                        INFO("voxel " << x << " " << y << " " << z << ": smooth union " << smooth);
                        CHECK(b == (smooth < 0.0));
                    }
                    filled += b && !e;
                }
        INFO("stamp at " << c[0] << " " << c[1] << " " << c[2]);
        CHECK(filled > 20); // the crease is filled
        CHECK(checked > 40000);
    }
}

TEST_CASE("sculpt: smooth at strength 1 removes a one-voxel bump in one pass and rounds a seam between CSG stamps", "[sculpt][field]")
{
    const auto solidAbove = [](const Volume& v, int top) {
        int count = 0;
        for (int x = -6; x <= 6; ++x)
            for (int z = -6; z <= 6; ++z)
                for (int y = top + 1; y <= top + 4; ++y) count += v.materialAt({x, y, z}) != kEmptyMaterial;
        return count;
    };
    // A slab whose top voxels are y = 0, with one voxel more on top at the origin (box sizes are half extents).
    Volume v(1.0);
    runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "box", "size": [20, 10, 20]}, "at": [0, -9.5, 0]},
                                                     {"mode": "add", "brush": {"shape": "box", "size": [0.5, 0.5, 0.5]}, "at": [0, 1, 0]}]})"));
    REQUIRE(solidAbove(v, 0) == 1);
    runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "smooth", "brush": {"shape": "sphere", "radius": 5}, "at": [0, 0.5, 0], "strength": 1}]})"));
    CHECK(solidAbove(v, 0) == 0);
    CHECK(v.materialAt({0, 0, 0}) != kEmptyMaterial); // the slab stays

    // Two boxes stamped on a slab meet at a right-angled crease; a smooth pass along it fills the crease and
    // takes the edge off: voxels change on both sides.
    Volume seam(1.0);
    const std::string boxes = R"({"ops": [{"mode": "add", "brush": {"shape": "box", "size": [20, 10, 20]}, "at": [0, -9.5, 0]},
                                          {"mode": "add", "brush": {"shape": "box", "size": [5, 5, 20]}, "at": [0, 5.5, 0]}]})";
    runStrokeScript(seam, parseStrokeScript(boxes));
    Volume before = seam.clone();
    runStrokeScript(seam, parseStrokeScript(R"({"ops": [{"mode": "smooth", "brush": {"shape": "sphere", "radius": 6}, "path": [[5, 0.5, -10], [5, 0.5, 10]], "strength": 1}]})"));
    int filled = 0, cut = 0;
    for (int x = -2; x <= 12; ++x)
        for (int y = -3; y <= 12; ++y)
            for (int z = -4; z <= 4; ++z) {
                const bool was = before.materialAt({x, y, z}) != kEmptyMaterial, now = seam.materialAt({x, y, z}) != kEmptyMaterial;
                filled += now && !was;
                cut += was && !now;
            }
    INFO("filled " << filled << ", cut " << cut);
    CHECK(filled >= 9 * 2); // at least two voxels deep into the crease along the 9 rows checked
    CHECK(cut >= 9);        // and the box's lower corner rounds
}

TEST_CASE("sculpt: paint honours strength and falloff, its edge a gradient of coverage, not a one-voxel step", "[sculpt][paint]")
{
    // A slab whose top voxels are y = 0, painted from above with a sphere of radius 10 centred on the top.
    const auto painted = [](const std::string& extra) {
        Volume v(1.0);
        runStrokeScript(v, parseStrokeScript(R"({"materials": [{"name": "red", "color": [1, 0, 0]}],
            "ops": [{"mode": "add", "brush": {"shape": "box", "size": [20, 4, 20]}, "at": [0, -3.5, 0]},
                    {"mode": "paint", "material": "red", "brush": {"shape": "sphere", "radius": 10}, "at": [0.3, 0, -0.2])" + extra + "}]}"));
        return v;
    };
    // The share of the top layer's voxels painted, in rings one voxel wide about the centre.
    const auto coverage = [](const Volume& v) {
        std::vector<int> red(12, 0), all(12, 0);
        const MaterialId id = *v.materials().find("red");
        for (int x = -12; x <= 12; ++x)
            for (int z = -12; z <= 12; ++z) {
                const int ring = int(std::hypot(x - 0.3, z + 0.2));
                if (ring >= 12) continue;
                ++all[std::size_t(ring)];
                red[std::size_t(ring)] += v.materialAt({x, 0, z}) == id;
            }
        std::vector<double> share;
        for (std::size_t r = 0; r < all.size(); ++r) share.push_back(double(red[r]) / double(all[r]));
        return share;
    };
    // Hard paint (as before, and as scripts without a falloff still paint): all inside, none outside.
    const std::vector<double> hard = coverage(painted(""));
    for (int r = 0; r < 9; ++r) CHECK(hard[std::size_t(r)] == 1.0);
    for (int r = 11; r < 12; ++r) CHECK(hard[std::size_t(r)] == 0.0);
    // A smooth falloff: full at the centre, none outside, and rings in between partly painted, fewer
    // towards the rim: the edge spreads over several voxels.
    const std::vector<double> soft = coverage(painted(R"(, "falloff": "smooth")"));
    std::string shares;
    for (double s : soft) shares += std::to_string(s).substr(0, 4) + " ";
    INFO("painted share per ring: " << shares);
    CHECK(soft[0] == 1.0);
    CHECK(soft[11] == 0.0);
    int partial = 0;
    for (double s : soft) partial += s > 0.1 && s < 0.9;
    CHECK(partial >= 3);
    for (std::size_t r = 0; r + 2 < soft.size(); ++r) CHECK(soft[r + 2] <= soft[r] + 0.05); // falling outwards
    // Strength scales the coverage: half strength paints about half of what full strength does.
    const std::vector<double> half = coverage(painted(R"(, "falloff": "constant", "strength": 0.5)"));
    double inner = 0.0;
    for (int r = 0; r < 8; ++r) inner += half[std::size_t(r)] / 8.0;
    CHECK(inner > 0.25);
    CHECK(inner < 0.75);
}

TEST_CASE("sculpt: a falloff curve weights the brush as drawn: two points equal linear, flat equals constant, bad curves are refused", "[sculpt][field]")
{
    CHECK(falloffWeight(Falloff::Curve, 5.0, 10.0, {0.0, 1.0}) == Approx(0.5));
    CHECK(falloffWeight(Falloff::Curve, 2.5, 10.0, {0.0, 0.2, 1.0}) == Approx(0.1));
    CHECK(falloffWeight(Falloff::Curve, 10.0, 10.0, {0.3, 0.6}) == Approx(0.6));
    CHECK(falloffWeight(Falloff::Curve, -1.0, 10.0, {1.0, 1.0}) == 0.0);
    // The same edit two ways gives the same volume, bit for bit.
    const auto edited = [](const std::string& falloff) {
        Volume v(1.0);
        runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 12}},
            {"mode": "inflate", "distance": 3, "brush": {"shape": "sphere", "radius": 8}, "at": [0, 12, 0], "falloff": )" + falloff + "}]}"));
        return v;
    };
    CHECK(identical(edited("[0, 1]"), edited(R"("linear")")));
    CHECK(identical(edited("[1, 1, 1]"), edited(R"("constant")")));
    CHECK_FALSE(identical(edited("[0, 0.2, 1]"), edited(R"("linear")")));
    for (const std::string bad : {"[]", "[0.5]", "[0, 2]", R"(["a", 1])", "[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,1]", R"("curve")"}) {
        INFO(bad);
        CHECK_THROWS_AS(parseStrokeScript(R"({"ops": [{"mode": "smooth", "brush": {"shape": "sphere"}, "falloff": )" + bad + "}]}"), ScriptError);
    }
    // The brush keeps its curve through a session file; paint takes it too.
    BrushSettings b;
    b.mode = "paint";
    b.falloff = "curve";
    b.falloffCurve = {0.0, 0.9, 1.0};
    const BrushSettings back = parseBrushSettings(brushSettingsJson(b));
    CHECK(back.falloff == "curve");
    CHECK(back.falloffCurve == b.falloffCurve);
    const nlohmann::json op = strokeOpJson(b, {{0, 0, 0}}, 1.0);
    CHECK(op.at("falloff") == nlohmann::json::array({0.0, 0.9, 1.0}));
    CHECK_NOTHROW(parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump()));
    CHECK_THROWS_AS(parseBrushSettings(nlohmann::json{{"falloff", "curve"}}), std::invalid_argument);
}

TEST_CASE("editor: a parallel view draws the target's plane at the same scale with rays within a third of a degree, and toggles back", "[editor][camera]")
{
    render::Camera c;
    c.eye = {30, 20, 80};
    c.target = {2, -1, 3};
    c.fovYDegrees = 45.0;
    const std::array<int, 2> viewport{800, 600};
    // Where a pixel's ray meets the plane through the target facing the view.
    const auto onTargetPlane = [&](const render::Camera& cam, double x, double y) {
        const Ray r = pointerRay(cam, viewport, x, y);
        const std::array<double, 3> n = [&] {
            std::array<double, 3> d = minus(cam.target, cam.eye);
            const double l = length(d);
            for (double& v : d) v /= l;
            return d;
        }();
        const double t = ((cam.target[0] - r.origin[0]) * n[0] + (cam.target[1] - r.origin[1]) * n[1] + (cam.target[2] - r.origin[2]) * n[2]) /
                         (r.direction[0] * n[0] + r.direction[1] * n[1] + r.direction[2] * n[2]);
        return std::array<double, 3>{r.origin[0] + r.direction[0] * t, r.origin[1] + r.direction[1] * t, r.origin[2] + r.direction[2] * t};
    };
    const render::Camera parallel = parallelView(c);
    for (const auto& [x, y] : {std::pair<double, double>{0, 0}, {800, 600}, {123, 456}})
        CHECK(length(minus(onTargetPlane(parallel, x, y), onTargetPlane(c, x, y))) < 1e-6 * length(minus(c.eye, c.target)));
    const Ray a = pointerRay(parallel, viewport, 0, 0), b = pointerRay(parallel, viewport, 800, 600);
    const double angle = std::acos(a.direction[0] * b.direction[0] + a.direction[1] * b.direction[1] + a.direction[2] * b.direction[2]) * 180.0 / M_PI;
    CHECK(angle < 1.0 / 3.0);
    const render::Camera back = perspectiveView(parallel, 45.0);
    for (std::size_t i = 0; i < 3; ++i) CHECK(back.eye[i] == Approx(c.eye[i]).margin(1e-9 * 80.0));
    CHECK(back.fovYDegrees == Approx(45.0));
    // Zooming a parallel view by 2 halves what it shows and keeps the point under the cursor there.
    const std::array<double, 3> under = onTargetPlane(parallel, 600, 200);
    const render::Camera zoomed = zoomByFieldOfView(parallel, 2.0, under);
    CHECK(length(minus(onTargetPlane(zoomed, 600, 200), under)) < 1e-6 * length(minus(c.eye, c.target)));
    CHECK(length(minus(onTargetPlane(zoomed, 0, 0), onTargetPlane(zoomed, 800, 0))) ==
          Approx(0.5 * length(minus(onTargetPlane(parallel, 0, 0), onTargetPlane(parallel, 800, 0)))).epsilon(1e-6));
}
