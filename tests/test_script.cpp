// Stroke scripts: parsing the issue's example, rejecting malformed scripts with a message that names
// the place, and running scripts (unknown materials leave the volume untouched).
#include "scene/CameraPath.h"
#include "scene/SceneDiff.h"
#include "sculpt/StrokePath.h"
#include "sculpt/StrokeScript.h"
#include "support/CliRun.h"
#include "support/HermiteProbe.h"
#include "support/ExampleScript.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <limits>
#include <string>
#include <sys/stat.h>

using namespace vdbclay;
using namespace vdbclay::test;
using nlohmann::json;

namespace {

/// The message of the ScriptError that parsing `text` throws ("" when it parses, which fails the caller).
std::string parseError(const std::string& text)
{
    try {
        (void)parseStrokeScript(text);
    } catch (const ScriptError& e) {
        return e.what();
    }
    return "";
}

/// The example with one change applied to its JSON.
template<typename Edit>
std::string editedExample(Edit edit)
{
    json j = json::parse(kExampleScript);
    edit(j);
    return j.dump();
}

void checkRejected(const std::string& text, std::initializer_list<const char*> mustContain)
{
    const std::string message = parseError(text);
    INFO("script: " << text.substr(0, 300));
    INFO("message: " << message);
    REQUIRE_FALSE(message.empty());
    for (const char* part : mustContain) CHECK(message.find(part) != std::string::npos);
}

} // namespace

TEST_CASE("the issue's example script parses", "[script]")
{
    const StrokeScript s = parseStrokeScript(kExampleScript);
    REQUIRE(s.materials.size() == 1);
    CHECK(s.materials[0].name == "stone");
    CHECK(s.materials[0].toughness == Approx(0.9f));
    CHECK(s.materials[0].color == std::array<float, 4>{0.6f, 0.6f, 0.6f, 1.0f});
    REQUIRE(s.ops.size() == 5);

    CHECK(s.ops[0].mode == CsgMode::Add);
    CHECK(s.ops[0].material == "stone");
    CHECK(s.ops[0].path.empty());
    CHECK(s.ops[0].brush.distance(Vec3d(0.0)) == Approx(-20.0));
    CHECK(s.ops[0].brush.distance(Vec3d(25.0, 0.0, 0.0)) == Approx(5.0));

    // Box with half-extents 8,8,30 (rounding 1) at (10,0,0), turned 30 degrees about z.
    CHECK(s.ops[1].mode == CsgMode::Remove);
    CHECK(s.ops[1].material.empty());
    CHECK(s.ops[1].brush.distance(Vec3d(10.0, 0.0, 0.0)) == Approx(-8.0));
    CHECK(s.ops[1].brush.distance(Vec3d(10.0, 0.0, 29.5)) < 0.0);
    CHECK(s.ops[1].brush.distance(Vec3d(10.0, 0.0, 31.0)) > 0.0);
    // The +x face normal turned by +30 degrees about z points to (cos 30, sin 30, 0).
    const Vec3d faceDir(std::cos(kPi / 6.0), std::sin(kPi / 6.0), 0.0);
    CHECK(s.ops[1].brush.distance(Vec3d(10.0, 0.0, 0.0) + faceDir * 9.0) == Approx(1.0).margin(1e-9));

    CHECK(s.ops[2].mode == CsgMode::Paint);
    CHECK(s.ops[2].material == "default");
    REQUIRE(s.ops[2].path.size() == 2);
    CHECK(s.ops[2].path[1] == Vec3d(15.0, 0.0, 15.0));
    CHECK(s.ops[2].brush.distance(Vec3d(0.0, 0.0, 20.0)) == Approx(-6.0)); // placed at the first point

    CHECK(s.ops[3].mode == CsgMode::Erode);
    CHECK(s.ops[3].strength == 1.0);
    CHECK_FALSE(s.ops[3].depth.has_value());
    CHECK(s.ops[3].brush.innerRadius() == Approx(4.0));
    CHECK(s.ops[3].brush.distance(Vec3d(0.0, 18.0 + 5.0 + 4.0 - 0.5, 0.0)) < 0.0); // capsule along local Y

    CHECK(s.ops[4].mode == CsgMode::Add);
    CHECK(s.ops[4].brush.distance(Vec3d(0.0, -25.0, 0.0)) < 0.0);
    CHECK(s.ops[4].brush.distance(Vec3d(0.0, -25.0 + 9.0, 0.0)) < 0.0); // scaled by 2 along y
    CHECK(s.ops[4].brush.distance(Vec3d(0.0, -25.0 + 11.0, 0.0)) > 0.0);
    CHECK(s.ops[4].brush.distance(Vec3d(4.0, -25.0, 0.0)) > 0.0); // the removed box
}

TEST_CASE("defaults: strength 1, toughness 0.5, position at the origin", "[script]")
{
    const StrokeScript s = parseStrokeScript(
        R"({"materials": [{"name": "wax"}], "ops": [{"mode": "erode", "brush": {"shape": "sphere", "radius": 2}, "depth": 1.5}]})");
    REQUIRE(s.materials.size() == 1);
    CHECK(s.materials[0].toughness == Approx(0.5f));
    REQUIRE(s.ops.size() == 1);
    CHECK(s.ops[0].strength == 1.0);
    REQUIRE(s.ops[0].depth.has_value());
    CHECK(*s.ops[0].depth == 1.5);
    CHECK(s.ops[0].brush.distance(Vec3d(0.0)) == Approx(-2.0));
    CHECK(parseStrokeScript(R"({"ops": []})").ops.empty());
}

TEST_CASE("malformed scripts are rejected with the place named", "[script]")
{
    SECTION("bad JSON")
    {
        checkRejected(R"({"ops": [ {"mode": "add", )", {"JSON"});
        checkRejected("", {"JSON"});
    }
    SECTION("unknown mode")
    {
        checkRejected(editedExample([](json& j) { j["ops"][1]["mode"] = "smash"; }), {"ops[1]", "mode", "smash"});
    }
    SECTION("unknown shape")
    {
        checkRejected(editedExample([](json& j) { j["ops"][1]["brush"]["shape"] = "pyramid"; }),
                      {"ops[1].brush", "pyramid"});
        checkRejected(editedExample([](json& j) { j["ops"][4]["brush"]["parts"][1]["shape"] = "blob"; }),
                      {"ops[4].brush.parts[1]", "blob"});
    }
    SECTION("unknown key")
    {
        checkRejected(editedExample([](json& j) { j["ops"][1]["colour"] = "red"; }), {"ops[1]", "colour"});
        checkRejected(editedExample([](json& j) { j["ops"][0]["brush"]["radiuss"] = 3; }), {"ops[0].brush", "radiuss"});
        checkRejected(editedExample([](json& j) { j["materials"][0]["hardness"] = 1; }), {"materials[0]", "hardness"});
        checkRejected(editedExample([](json& j) { j["version"] = 2; }), {"version"});
    }
    SECTION("negative or missing sizes")
    {
        checkRejected(editedExample([](json& j) { j["ops"][1]["brush"] = {{"shape", "sphere"}, {"radius", -3}}; }),
                      {"ops[1].brush", "radius"});
        checkRejected(editedExample([](json& j) { j["ops"][0]["brush"]["radius"] = 0; }), {"ops[0].brush", "radius"});
        checkRejected(editedExample([](json& j) { j["ops"][3]["brush"].erase("length"); }), {"ops[3].brush", "length"});
        checkRejected(editedExample([](json& j) { j["ops"][1]["brush"]["rounding"] = 9; }), {"ops[1].brush", "rounding"});
        checkRejected(editedExample([](json& j) { j["ops"][0]["brush"]["radius"] = "big"; }), {"ops[0].brush.radius"});
    }
    SECTION("missing brush")
    {
        checkRejected(editedExample([](json& j) { j["ops"][1].erase("brush"); }), {"ops[1]", "brush"});
    }
    SECTION("paint without material")
    {
        checkRejected(editedExample([](json& j) { j["ops"][2].erase("material"); }), {"ops[2]", "material"});
    }
    SECTION("other bad values")
    {
        checkRejected(editedExample([](json& j) { j["ops"][3]["strength"] = 1.5; }), {"ops[3].strength"});
        checkRejected(editedExample([](json& j) { j["ops"][0]["at"] = {1, 2}; }), {"ops[0].at"});
        checkRejected(editedExample([](json& j) { j["ops"][2]["at"] = {0, 0, 0}; }), {"ops[2]", "path"});
        checkRejected(editedExample([](json& j) { j["ops"][0]["scale"] = {1, -1, 1}; }), {"ops[0].scale"});
        checkRejected(editedExample([](json& j) { j["materials"][0]["toughness"] = 2; }), {"materials[0].toughness"});
        checkRejected(editedExample([](json& j) { j["materials"].push_back(j["materials"][0]); }),
                      {"materials[1].name", "duplicate"});
        checkRejected(editedExample([](json& j) { j["ops"][0]["brush"] = {{"shape", "half-space"}}; }), {"ops[0]"});
        checkRejected(editedExample([](json& j) { j["ops"][4]["brush"]["parts"][0]["op"] = "remove"; }),
                      {"ops[4].brush.parts[0].op"});
        checkRejected(editedExample([](json& j) { j.erase("ops"); }), {"ops"});
        checkRejected("[1, 2, 3]", {"script"});
    }
}

TEST_CASE("loadStrokeScript reports unreadable files as ScriptError", "[script]")
{
    TempDir dir;
    CHECK_THROWS_AS(loadStrokeScript(dir.file("missing.json")), ScriptError);
    writeText(dir.file("example.json"), kExampleScript);
    CHECK(loadStrokeScript(dir.file("example.json")).ops.size() == 5);
    writeText(dir.file("bad.json"), "{ \"ops\": [ { \"mode\": ");
    CHECK_THROWS_AS(loadStrokeScript(dir.file("bad.json")), ScriptError);
}

TEST_CASE("running the example script sculpts the volume", "[script]")
{
    Volume v(1.0);
    std::vector<std::size_t> seen;
    const auto reports =
        runStrokeScript(v, parseStrokeScript(kExampleScript), [&](const ScriptOpReport& r) { seen.push_back(r.index); });
    REQUIRE(reports.size() == 5);
    CHECK(seen == std::vector<std::size_t>{0, 1, 2, 3, 4});
    const auto stone = v.materials().find("stone");
    REQUIRE(stone.has_value());
    CHECK(*stone == 2);
    CHECK(v.materialAt({0, 0, 0}) == *stone);  // inside the sphere
    CHECK(v.materialAt({10, 0, 0}) == kEmptyMaterial); // the box removed it
    CHECK(v.materialAt({-2, 0, 18}) == 1);     // painted "default" near the first path point
    CHECK(v.materialAt({0, 18, 0}) == kEmptyMaterial); // eroded (stone: bites 0.1 * 4 deep at the centre)
    CHECK(v.materialAt({0, -25, 0}) == 1);     // the blend brush adds the volume's first material
    CHECK(v.materialAt({0, -33, 0}) == 1);     // ... stretched along y
}

TEST_CASE("runStrokeScript rejects unknown materials before touching the volume", "[script]")
{
    Volume v(1.0);
    defineMaterial(v, "clay", 0.2f);
    apply(v, CsgMode::Add, sphere(8.0), at({0.2, 0.1, 0.0}), 2);
    const Volume before = v.clone();

    SECTION("a material that is neither in the volume nor in the script")
    {
        const StrokeScript s = parseStrokeScript(editedExample([](json& j) { j["ops"][1]["material"] = "unobtainium"; }));
        try {
            runStrokeScript(v, s);
            FAIL("runStrokeScript accepted an unknown material");
        } catch (const ScriptError& e) {
            const std::string message = e.what();
            INFO(message);
            CHECK(message.find("ops[1]") != std::string::npos);
            CHECK(message.find("unobtainium") != std::string::npos);
        }
        // Neither the ops before it nor the script's own materials were applied.
        CHECK(identical(before, v));
        CHECK_FALSE(v.materials().find("stone").has_value());
    }
    SECTION("a material the volume already has")
    {
        const StrokeScript s = parseStrokeScript(
            R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 3}, "at": [12, 0, 0], "material": "clay"}]})");
        runStrokeScript(v, s);
        CHECK(v.materialAt({12, 0, 0}) == 2);
        CHECK(v.materials().size() == 2);
    }
    SECTION("a script material updates the one with the same name")
    {
        const StrokeScript s = parseStrokeScript(
            R"({"materials": [{"name": "clay", "toughness": 0.7}], "ops": []})");
        runStrokeScript(v, s);
        REQUIRE(v.materials().find("clay").has_value());
        CHECK(*v.materials().find("clay") == 2);
        CHECK(v.materials().at(2).toughness == Approx(0.7f));
    }
}

TEST_CASE("scripts that ask for absurd work are refused before any op runs, naming the op and the limit", "[script][limits]")
{
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(6.0), at({0.0, 0.0, 0.0}), 1);
    const Volume before = v.clone();
    auto refuse = [&](const json& lastOp, const std::string& expected) {
        json script{{"ops", json::array({{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"at", {20, 0, 0}}},
                                         lastOp})}};
        INFO(script.dump());
        try {
            runStrokeScript(v, parseStrokeScript(script.dump()));
            FAIL("accepted");
        } catch (const ScriptError& e) {
            CHECK_THAT(e.what(), Catch::Contains(expected));
        }
        CHECK(identical(v, before)); // the first, harmless op did not run either
    };
    refuse({{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"at", {9e8, 9e8, 9e8}}},
           "ops[1]: the brush reaches 9e+08 voxels");
    refuse({{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 6}}}, {"path", {{-1e6, 0, 0}, {1e6, 0, 0}}}},
           "ops[1]: the brush reaches 1e+06 voxels");
    refuse({{"mode", "add"}, {"brush", {{"shape", "box"}, {"size", {5000, 5000, 5000}}}}}, "more than the 6e+07 an edit may make");
    // Long strokes across the volume: too many brush widths, or a tube with too much surface (its
    // tube's surface, not its bounds' box, is what counts). Both are refused before anything is built.
    json path = json::array();
    for (int i = 0; i < 4000; ++i) path.push_back({(i % 2 ? 1 : -1) * 100000.0, 0.0, i * 0.01});
    refuse({{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 30}}}, {"path", path}},
           "brush reaches long, more than the 1000000 allowed");
    path.erase(path.begin() + 400, path.end());
    refuse({{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 300}}}, {"path", path}}, "an edit may make");
}

TEST_CASE("scripts over the size limits of paths and blends are refused while parsing", "[script][limits]")
{
    json path = json::array();
    for (std::size_t i = 0; i <= kMaxPathPoints; ++i) path.push_back({0.0, 0.0, double(i)});
    json op{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 1}}}, {"path", path}};
    CHECK_THROWS_WITH(parseStrokeScript(json{{"ops", {op}}}.dump()), Catch::Contains("ops[0].path: has 100001 points"));
    json parts = json::array();
    for (std::size_t i = 0; i <= kMaxBlendParts; ++i) parts.push_back({{"shape", "sphere"}, {"radius", 1}, {"at", {double(i), 0, 0}}});
    json blend{{"mode", "add"}, {"brush", {{"shape", "blend"}, {"parts", parts}}}};
    CHECK_THROWS_WITH(parseStrokeScript(json{{"ops", {blend}}}.dump()), Catch::Contains("at most 256"));
}

TEST_CASE("duplicate keys and files that are not regular are script errors", "[script][limits]")
{
    CHECK_THROWS_WITH(parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 1}, "at": [0,0,0], "at": [1,1,1]}]})"),
                      Catch::Contains("'at' appears twice"));
    CHECK_THROWS_WITH(parseStrokeScript(R"({"ops": [], "ops": []})"), Catch::Contains("'ops' appears twice"));
    // The same key in two different objects is fine.
    CHECK_NOTHROW(parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 1}},
                                                {"mode": "add", "brush": {"shape": "sphere", "radius": 2}}]})"));
    TempDir dir;
    REQUIRE(::mkfifo(dir.file("pipe.json").c_str(), 0644) == 0);
    CHECK_THROWS_WITH(loadStrokeScript(dir.file("pipe.json")), Catch::Contains("not a regular file"));
    CHECK_THROWS_WITH(loadStrokeScript("/dev/zero"), Catch::Contains("not a regular file"));
}

TEST_CASE("voxel sizes outside 2e-5 .. 1e6 are refused, a 10 cm scan in metres at 2048 voxels is not", "[script][limits]")
{
    CHECK_THROWS_AS(Volume(1e300), std::invalid_argument);
    CHECK_THROWS_AS(Volume(1e-9), std::invalid_argument);
    CHECK_THROWS_AS(Volume(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
    CHECK_NOTHROW(Volume(1e-4));
    CHECK_THROWS_AS(Volume(1e-5), std::invalid_argument);
    CHECK_NOTHROW(Volume(1e6));
    // 0.1 m / 2048 voxels: a volume at that size saves and loads (OpenVDB's transform takes it).
    TempDir dir;
    Volume scan(0.1 / 2048.0);
    apply(scan, CsgMode::Add, sphere(0.002), at({0.0, 0.0, 0.0}), 1); // 41 voxels
    saveVolume(scan, dir.file("scan.vdb"));
    const Volume back = loadVolume(dir.file("scan.vdb"));
    CHECK(back.voxelSize() == scan.voxelSize());
    CHECK(back.stats().activeVoxels == scan.stats().activeVoxels);
}

TEST_CASE("numbers too large for a double and raw bytes in a script are clean script errors", "[script]")
{
    // Found by fuzz_script_parser: nlohmann::json throws out_of_range, not parse_error, for 98E9889898798989.
    CHECK_THROWS_AS(parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 98E9889898798989}}]})"),
                    ScriptError);
    try {
        parseStrokeScript(std::string("{\"ops\": [\xff\xfe\x01]}"));
        FAIL("accepted");
    } catch (const ScriptError& e) {
        const std::string what = e.what();
        CHECK(std::all_of(what.begin(), what.end(), [](char c) { return c >= 32 && c < 127; }));
    }
}

TEST_CASE("scripts name material textures, empty or unprintable paths are refused", "[script]")
{
    const StrokeScript script = parseStrokeScript(
        R"({"materials": [{"name": "brick", "texture": "textures/brick.png"}], "ops": []})");
    REQUIRE(script.materials.size() == 1);
    CHECK(script.materials[0].texture == "textures/brick.png");
    CHECK_THROWS_AS(parseStrokeScript(R"({"materials": [{"name": "brick", "texture": ""}], "ops": []})"), ScriptError);
    CHECK_THROWS_AS(parseStrokeScript(R"({"materials": [{"name": "brick", "texture": "a\u001bb"}], "ops": []})"), ScriptError);
    CHECK_THROWS_AS(parseStrokeScript(R"({"materials": [{"name": "brick", "texture": 3}], "ops": []})"), ScriptError);
}

namespace {

double distanceToPolyline(const Vec3d& p, const std::vector<Vec3d>& line)
{
    double best = (p - line.front()).length();
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
        const Vec3d ab = line[i + 1] - line[i];
        const double t = ab.lengthSqr() > 0.0 ? std::clamp((p - line[i]).dot(ab) / ab.lengthSqr(), 0.0, 1.0) : 0.0;
        best = std::min(best, (p - (line[i] + ab * t)).length());
    }
    return best;
}

} // namespace

TEST_CASE("strokes: a dense path is simplified within its tolerance, and a stroke costs its voxels, not its points", "[script][stroke]")
{
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> step(-0.02, 0.02), turn(-1.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
        // A pointer's samples: a wandering path of a few thousand points a fraction of a voxel apart.
        std::vector<Vec3d> path{Vec3d(0.0)};
        Vec3d heading(1.0, 0.0, 0.0);
        const int points = 1000 + 300 * trial;
        for (int i = 1; i < points; ++i) {
            const double dx = turn(random), dy = turn(random), dz = turn(random);
            heading = (heading + Vec3d(dx, dy, dz) * 0.05).unit();
            path.push_back(path.back() + heading * (0.01 + std::fabs(step(random))) + Vec3d(step(random), 0.0, 0.0) * 0.1);
        }
        const double tolerance = 1.0 / 64.0;
        const std::vector<Vec3d> simple = simplifyStrokePath(path, tolerance);
        CAPTURE(trial);
        CHECK(simple.front() == path.front());
        CHECK(simple.back() == path.back());
        CHECK(simple.size() < path.size() / 4);
        // Every kept point is a point of the path, in order; every point lies within twice the tolerance.
        std::size_t at = 0;
        for (const Vec3d& p : simple) {
            while (at < path.size() && !(path[at] == p)) ++at;
            CHECK(at < path.size());
        }
        double worst = 0.0;
        for (const Vec3d& p : path) worst = std::max(worst, distanceToPolyline(p, simple));
        CHECK(worst <= 2.0 * tolerance);
    }
    // Straight runs collapse to their ends; a path of distinct far points is kept as it is.
    std::vector<Vec3d> line;
    for (int i = 0; i <= 100000; i += 7) line.push_back(Vec3d(i * 1e-3, 2.0 * i * 1e-3, 0.0));
    CHECK(simplifyStrokePath(line, 1.0 / 64.0).size() == 2);
    const std::vector<Vec3d> corners{Vec3d(0, 0, 0), Vec3d(5, 0, 0), Vec3d(5, 5, 0), Vec3d(0, 5, 3)};
    CHECK(simplifyStrokePath(corners, 1.0 / 64.0) == corners);

    // A stroke of 100,000 points makes what the same stroke of 600 points makes, within the tolerance.
    const auto arc = [](int n) {
        json points = json::array();
        for (int i = 0; i < n; ++i) {
            const double a = M_PI * i / (n - 1);
            points.push_back({30.0 * std::cos(a), 30.0 * std::sin(a), 4.0});
        }
        return points;
    };
    for (const char* mode : {"add", "smooth"}) {
        CAPTURE(mode);
        Volume dense(1.0), sparse(1.0);
        for (Volume* v : {&dense, &sparse}) apply(*v, CsgMode::Add, box(Vec3d(36.0, 36.0, 4.0)), at(Vec3d(0.0)));
        const auto script = [&](int n) {
            return json{{"ops", {{{"mode", mode}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"path", arc(n)}}}}}.dump();
        };
        runStrokeScript(dense, parseStrokeScript(script(100000)));
        runStrokeScript(sparse, parseStrokeScript(script(600)));
        TempDir dir;
        saveVolume(dense, dir.file("dense.vdb"));
        saveVolume(sparse, dir.file("sparse.vdb"));
        const SceneDiff d = diffScenes(dir.file("dense.vdb"), dir.file("sparse.vdb"));
        // Each simplified path lies within 2 x 1/256 voxel of the arc, so the two within 1/64: only voxels
        // whose centres lie that close to the surface may change sides, and the meshes (whose vertices
        // a feature's normals place, and which a sharp fan that would fold moves towards its loop's
        // mean point) stay within a sixth of a voxel.
        CHECK(d.occupancyDifferences <= 8);
        CHECK(d.surfaceDistance <= 0.16);
    }
}

TEST_CASE("scripts: limits are reported in their own words", "[script][limits]")
{
    const auto error = [](const json& op) {
        try {
            Volume v(1.0);
            runStrokeScript(v, parseStrokeScript(json{{"ops", {op}}}.dump()));
        } catch (const ScriptError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    CHECK_THAT(error({{"mode", "inflate"}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"distance", 1e9}}),
               Catch::Contains("must be positive and below 1e6"));
    // A store is sculpted brick by brick: an op reaching past the limits says so, not "reaches 0 bricks".
    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 4").exitCode == 0);
    REQUIRE(runCli(dir, "import s.vdb -o s.vdbclay").exitCode == 0);
    writeText(dir.file("huge.json"), json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 1e9}}}}}}}.dump());
    const CommandResult huge = runCli(dir, "sculpt s.vdbclay huge.json -o s.vdbclay");
    checkCleanFailure(huge);
    CHECK_THAT(huge.err, Catch::Contains("the brush reaches 1e+09 voxels"));
    CHECK_THROWS_WITH(parseCameraPath(R"({"fov_degrees": 500, "frames": [{"position": [0, 0, 9], "target": [0, 0, 0]}]})"),
                      Catch::Contains("fov_degrees"));
}
