// Symmetry in stroke scripts: mirrors and radial copies equal the copied ops applied one by one (bit for
// bit, for every shape: the gradients' stencils are mirror-symmetric; turned copies within one
// quantization step), for
// every kind of op (add, remove, paint, reshaping brushes); malformed symmetry is refused naming the place.
#include "sculpt/StrokeScript.h"
#include "selftest/ExactScene.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "vdb_hermite/Quantize.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <nlohmann/json.hpp>

using namespace vdbclay;
using namespace vdbclay::test;
using json = nlohmann::json;

namespace {

Volume run(const std::vector<json>& ops, const json& materials = json::array())
{
    Volume v(1.0);
    apply(v, CsgMode::Add, box(Vec3d(18.0, 6.0, 18.0)), at(Vec3d(0.0)));
    json script = json::object();
    script["materials"] = materials;
    script["ops"] = json::array();
    for (const json& o : ops) script["ops"].push_back(o);
    runStrokeScript(v, parseStrokeScript(script.dump()));
    return v;
}

/// The same voxels and crossings, offsets within one quantization step and normals within half a
/// degree: a box's gradient is a finite difference whose stencil a mirror turns around, which at its
/// edges and corners gives slightly different normals.
bool sameShape(const Volume& a, const Volume& b)
{
    const std::vector<EdgeRecord> ea = collectEdges(a), eb = collectEdges(b);
    if (ea.size() != eb.size()) return false;
    if (solidVoxelsPerMaterial(a) != solidVoxelsPerMaterial(b)) return false;
    for (std::size_t i = 0; i < ea.size(); ++i) {
        const EdgeRecord &x = ea[i], &y = eb[i];
        if (x.voxel != y.voxel || x.axis != y.axis || x.from != y.from || x.to != y.to) return false;
        if (std::abs(int(x.sample.offset) - int(y.sample.offset)) > 1) return false;
        const auto n = decodeNormal(x.sample.normalU, x.sample.normalV), m = decodeNormal(y.sample.normalU, y.sample.normalV);
        if (n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < std::cos(0.5 * M_PI / 180.0)) return false;
    }
    return true;
}

json op(const std::string& mode, const json& brush, const std::array<double, 3>& at)
{
    return json{{"mode", mode}, {"brush", brush}, {"at", at}};
}

} // namespace

TEST_CASE("symmetry: a mirrored op equals the op and its mirror image applied one by one", "[symmetry][script]")
{
    const json sphere{{"shape", "sphere"}, {"radius", 5}};
    const json cube{{"shape", "box"}, {"size", {3, 4, 2}}};
    // Across x = 2: the copy of a brush at x is at 4 - x.
    json mirrored = op("add", sphere, {11, 6, 3});
    mirrored["symmetry"] = {{"mirror", {"x"}}, {"center", {2, 0, 0}}};
    CHECK(changedBlocks(run({mirrored}), run({op("add", sphere, {11, 6, 3}), op("add", sphere, {-7, 6, 3})})).empty());
    // Two planes: four copies.
    json twice = op("remove", cube, {9, 5, -6});
    twice["symmetry"] = {{"mirror", {"x", "z"}}};
    const Volume four = run({twice});
    // Bit for bit for a box too: its gradient's stencil is mirror-symmetric.
    CHECK(changedBlocks(four, run({op("remove", cube, {9, 5, -6}), op("remove", cube, {-9, 5, -6}), op("remove", cube, {9, 5, 6}),
                                   op("remove", cube, {-9, 5, 6})}))
              .empty());
    for (const json& shape : {json{{"shape", "cylinder"}, {"radius", 3}, {"height", 5}}, json{{"shape", "torus"}, {"radius", 4}, {"minor_radius", 1.5}},
                              json{{"shape", "cone"}, {"radius", 3}, {"height", 5}}}) {
        CAPTURE(shape.dump());
        json mirrorX = op("add", shape, {7, 8, 2});
        mirrorX["symmetry"] = {{"mirror", {"x"}}};
        CHECK(changedBlocks(run({mirrorX}), run({op("add", shape, {7, 8, 2}), op("add", shape, {-7, 8, 2})})).empty());
    }
    CHECK_FALSE(sameShape(four, run({op("remove", cube, {9, 5, -6}), op("remove", cube, {-9, 5, -6})})));
    // Paint follows: both sides painted, the shape unchanged.
    const json red = json::array({{{"name", "red"}, {"color", {0.9, 0.1, 0.1}}}});
    json paint = op("paint", sphere, {10, 6, 0});
    paint["material"] = "red";
    paint["symmetry"] = {{"mirror", {"x"}}};
    json left = op("paint", sphere, {-10, 6, 0}), right = op("paint", sphere, {10, 6, 0});
    left["material"] = right["material"] = "red";
    const Volume painted = run({paint}, red);
    CHECK(changedBlocks(painted, run({right, left}, red)).empty());
    CHECK(painted.materialAt({-10, 5, 0}) == painted.materialAt({10, 5, 0}));
    CHECK(painted.materialAt({10, 5, 0}) != painted.materialAt({0, 5, 0}));
}

TEST_CASE("symmetry: radial copies equal the turned ops, a reshaping brush's offset turns with it", "[symmetry][script]")
{
    const json sphere{{"shape", "sphere"}, {"radius", 4}};
    // Four copies about y: (x, z) -> (z, -x) -> (-x, -z) -> (-z, x).
    json radial = op("add", sphere, {12, 6, 5});
    radial["symmetry"] = {{"radial", {{"axis", "y"}, {"count", 4}}}};
    CHECK(changedBlocks(run({radial}), run({op("add", sphere, {12, 6, 5}), op("add", sphere, {5, 6, -12}), op("add", sphere, {-12, 6, -5}),
                                           op("add", sphere, {-5, 6, 12})}))
              .empty());
    // Six copies: every one reaches the volume (the others are off the lattice's quarter turns).
    json six = op("remove", sphere, {12, 6, 0});
    six["symmetry"] = {{"radial", {{"axis", "y"}, {"count", 6}}}};
    const Volume hex = run({six});
    for (int i = 0; i < 6; ++i) {
        const double a = 2.0 * M_PI * i / 6.0;
        CHECK(hex.materialAt({int32_t(std::lround(12 * std::cos(a))), 5, int32_t(std::lround(-12 * std::sin(a)))}) == kEmptyMaterial);
    }
    // A move mirrored across x: the copy drags the other way.
    json move = op("move", json{{"shape", "sphere"}, {"radius", 6}}, {9, 6, 0});
    move["offset"] = {2, 3, 0};
    move["symmetry"] = {{"mirror", {"x"}}};
    json other = op("move", json{{"shape", "sphere"}, {"radius", 6}}, {-9, 6, 0});
    other["offset"] = {-2, 3, 0};
    json plain = move;
    plain.erase("symmetry");
    CHECK(changedBlocks(run({move}), run({plain, other})).empty());
}

TEST_CASE("symmetry: malformed symmetry is refused naming the place", "[symmetry][script]")
{
    const auto refused = [](const json& symmetry, const std::string& where) {
        json o = op("add", json{{"shape", "sphere"}, {"radius", 2}}, {0, 0, 0});
        o["symmetry"] = symmetry;
        try {
            json script = json::object();
            script["ops"] = json::array({o});
            parseStrokeScript(script.dump());
            FAIL("accepted " << symmetry.dump());
        } catch (const ScriptError& e) {
            INFO(e.what());
            CHECK(std::string(e.what()).find(where) != std::string::npos);
        }
    };
    refused({{"mirror", {"w"}}}, "ops[0].symmetry.mirror[0]");
    refused({{"mirror", {"x", "x"}}}, "ops[0].symmetry.mirror");
    refused({{"mirror", "x"}}, "ops[0].symmetry.mirror");
    refused({{"radial", {{"axis", "y"}, {"count", 0}}}}, "ops[0].symmetry.radial.count");
    refused({{"radial", {{"axis", "y"}, {"count", 2.5}}}}, "ops[0].symmetry.radial.count");
    refused({{"radial", {{"axis", "y"}, {"count", 65}}}}, "ops[0].symmetry.radial.count");
    refused({{"radial", {{"axis", "q"}, {"count", 3}}}}, "ops[0].symmetry.radial.axis");
    refused({{"spin", 3}}, "ops[0].symmetry");
    refused(json::array(), "ops[0].symmetry");
    refused({{"center", {1, 2}}}, "ops[0].symmetry.center");
}

TEST_CASE("symmetry: the exact evaluation of the selftest follows the copies, it refuses reshaping brushes", "[symmetry][script]")
{
    const std::string text =
        R"({"ops": [{"mode": "add", "brush": {"shape": "box", "size": [3, 2, 4]}, "at": [9.5, 1, 4], "rotate": [0, 30, 0],
                     "symmetry": {"mirror": ["x"], "radial": {"axis": "y", "count": 3}, "center": [1, 0, 0]}}]})";
    const StrokeScript script = parseStrokeScript(text);
    Volume v(1.0);
    runStrokeScript(v, script);
    const ExactScene exact(script, v.materials(), 1.0);
    int solid = 0, checked = 0;
    for (int32_t x = -16; x <= 16; ++x)
        for (int32_t y = -4; y <= 4; ++y)
            for (int32_t z = -16; z <= 16; ++z) {
                const Vec3d p(x, y, z);
                if (exact.nearSurface(p, 0.01)) continue;
                INFO(x << "," << y << "," << z);
                CHECK(v.materialAt({x, y, z}) == exact.materialAt(p));
                solid += exact.materialAt(p) != kEmptyMaterial;
                ++checked;
            }
    CHECK(solid > 6 * 40); // six copies of the box, each about 3 x 2 x 4 x 8 voxels, some overlapping
    CHECK(checked > 9000);
    CHECK_THROWS_AS(ExactScene(parseStrokeScript(
                                   R"({"ops": [{"mode": "smooth", "brush": {"shape": "sphere", "radius": 3}}]})"),
                               v.materials(), 1.0),
                    std::invalid_argument);
}
