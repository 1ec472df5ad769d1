// The reshaping brushes (smooth, flatten, inflate, deflate, move) against their definitions on analytic
// shapes, measured on the CMS mesh, and closedness after random brushes on random scenes.
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "sculpt/FieldBrushes.h"
#include "sculpt/StrokeScript.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// CMS; `uniform`: a vertex in every surface cell (flat faces keep theirs).
Mesh cmsMesh(const Volume& v, bool uniform = false)
{
    MeshOptions o;
    o.kind = MesherKind::CubicalMarchingSquares;
    if (uniform) o.maxCellWidth = 1;
    return meshVolume(v, o);
}

bool closed(const Volume& v)
{
    const Mesh mesh = cmsMesh(v);
    const MeshTopology t = analyzeTopology(mesh, kMergeDistanceVoxels * v.voxelSize());
    INFO("boundary " << t.boundaryEdges << " non-manifold " << t.nonManifoldEdges << " misoriented " << t.misorientedEdges
                     << " pinched " << t.pinchedVertices << " degenerate " << t.degenerateTriangles);
    return mesh.triangleCount() > 0 && t.watertight();
}

Brush sphereBrush(double radius, const Vec3d& centre) { return Brush(sphere(radius), at(centre)); }

FieldBrushOp fieldOp(FieldMode mode, Falloff falloff = Falloff::Constant)
{
    FieldBrushOp op;
    op.mode = mode;
    op.falloff = falloff;
    return op;
}

Volume sphereVolume(double radius)
{
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(radius), at(Vec3d(0.0)));
    return v;
}

/// Mean and extreme distances of the mesh's vertices from the origin.
std::array<double, 3> radii(const Mesh& mesh)
{
    double sum = 0.0, lo = 1e30, hi = 0.0;
    for (const auto& p : mesh.positions) {
        const double r = std::sqrt(double(p[0]) * p[0] + double(p[1]) * p[1] + double(p[2]) * p[2]);
        sum += r;
        lo = std::min(lo, r);
        hi = std::max(hi, r);
    }
    return {sum / double(mesh.positions.size()), lo, hi};
}

} // namespace

TEST_CASE("field brushes: inflate by d moves a sphere's surface out by d, deflate moves it in", "[field]")
{
    for (const double d : {1.0, 2.5, 4.0}) {
        Volume v = sphereVolume(16.0);
        FieldBrushOp inflate = fieldOp(FieldMode::Inflate);
        inflate.distance = d;
        applyFieldBrush(v, sphereBrush(30.0, Vec3d(0.0)), inflate);
        INFO("d = " << d);
        REQUIRE(closed(v));
        const auto [mean, lo, hi] = radii(cmsMesh(v));
        CHECK(std::fabs(mean - (16.0 + d)) < 0.25);
        CHECK(lo > 16.0 + d - 0.6);
        CHECK(hi < 16.0 + d + 0.6);

        FieldBrushOp deflate = inflate;
        deflate.mode = FieldMode::Deflate;
        applyFieldBrush(v, sphereBrush(30.0, Vec3d(0.0)), deflate);
        REQUIRE(closed(v));
        CHECK(std::fabs(radii(cmsMesh(v))[0] - 16.0) < 0.3);
    }
    // Half the strength, half the distance.
    Volume v = sphereVolume(16.0);
    FieldBrushOp half = fieldOp(FieldMode::Inflate);
    half.distance = 4.0;
    half.strength = 0.5;
    applyFieldBrush(v, sphereBrush(30.0, Vec3d(0.0)), half);
    CHECK(std::fabs(radii(cmsMesh(v))[0] - 18.0) < 0.25);
}

TEST_CASE("field brushes: flatten makes the cap under the brush planar", "[field]")
{
    Volume v = sphereVolume(20.0);
    const Vec3d centre(0.0, 20.0, 0.0);
    applyFieldBrush(v, sphereBrush(8.0, centre), fieldOp(FieldMode::Flatten));
    REQUIRE(closed(v));
    const Mesh mesh = cmsMesh(v);
    std::vector<double> heights;
    for (const auto& p : mesh.positions)
        if ((Vec3d(p[0], p[1], p[2]) - centre).length() < 6.0) heights.push_back(p[1]);
    REQUIRE(heights.size() > 20);
    const auto [lo, hi] = std::minmax_element(heights.begin(), heights.end());
    CHECK(*hi - *lo < 0.3); // planar within a bound
    CHECK(*hi < 19.9);      // the cap is cut down to the plane through its surface
    CHECK(*lo > 17.0);
}

TEST_CASE("field brushes: smooth leaves planes where they are and rounds a box's edge", "[field]")
{
    // On a face, far from the box's edges: a plane's distance is linear, and blurring keeps it.
    {
        Volume v(1.0);
        apply(v, CsgMode::Add, box(Vec3d(40.0)), at(Vec3d(0.0)));
        const Vec3d centre(40.0, 0.0, 0.0);
        applyFieldBrush(v, sphereBrush(16.0, centre), fieldOp(FieldMode::Smooth));
        REQUIRE(closed(v));
        double faceError = 0.0;
        int faceVertices = 0;
        for (const auto& p : cmsMesh(v, true).positions) {
            const Vec3d q(p[0], p[1], p[2]);
            if ((q - centre).length() > 14.0) continue;
            faceError = std::max(faceError, std::fabs(q[0] - 40.0));
            ++faceVertices;
        }
        CHECK(faceVertices > 10);
        CHECK(faceError < 0.05);
    }
    // Across an edge: the edge rounds, by less than the filter reaches.
    Volume v(1.0);
    apply(v, CsgMode::Add, box(Vec3d(20.0)), at(Vec3d(0.0)));
    const Vec3d edge(20.0, 20.0, 0.0);
    const Brush brush = sphereBrush(16.0, edge);
    applyFieldBrush(v, brush, fieldOp(FieldMode::Smooth));
    REQUIRE(closed(v));
    const int r = smoothingRadiusVoxels(brush, 1.0);
    double inset = 0.0;
    for (const auto& p : cmsMesh(v, true).positions) {
        const Vec3d q(p[0], p[1], p[2]);
        // Along the diagonal of the edge: how far in the surface now lies.
        if ((q - edge).length() <= 14.0 && std::fabs(q[0] - q[1]) < 0.5) inset = std::max(inset, (40.0 - q[0] - q[1]) / std::sqrt(2.0));
    }
    CHECK(inset > 1.0);   // the edge rounded
    CHECK(inset < 2 * r); // by less than the filter's two passes reach
}

TEST_CASE("field brushes: move displaces the grabbed point by the drag", "[field]")
{
    for (const Falloff falloff : {Falloff::Smooth, Falloff::Linear}) {
        Volume v = sphereVolume(16.0);
        FieldBrushOp move = fieldOp(FieldMode::Move, falloff);
        move.offset = Vec3d(0.0, 4.0, 0.0);
        applyFieldBrush(v, sphereBrush(10.0, Vec3d(0.0, 16.0, 0.0)), move);
        INFO("falloff " << falloffName(falloff));
        REQUIRE(closed(v));
        double top = 0.0;
        for (const auto& p : cmsMesh(v).positions) top = std::max(top, double(p[1]));
        CHECK(std::fabs(top - 20.0) < 0.35);
    }
}

TEST_CASE("field brushes: random brushes on random solids leave closed surfaces", "[field]")
{
    std::mt19937 rng(29);
    const auto integer = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    const FieldMode modes[] = {FieldMode::Smooth, FieldMode::Flatten, FieldMode::Inflate, FieldMode::Deflate, FieldMode::Move};
    const Falloff falloffs[] = {Falloff::Smooth, Falloff::Linear, Falloff::Constant};
    for (int scene = 0; scene < 6; ++scene) {
        Volume v(1.0);
        for (int i = 0; i < 3; ++i) {
            const Vec3d c(integer(-8, 8), integer(-8, 8), integer(-8, 8));
            if (i % 2) apply(v, CsgMode::Add, box(Vec3d(integer(4, 10), integer(4, 10), integer(4, 10))), at(c));
            else apply(v, CsgMode::Add, sphere(integer(5, 12)), at(c));
        }
        for (int i = 0; i < 5; ++i) {
            FieldBrushOp op = fieldOp(modes[integer(0, 4)], falloffs[integer(0, 2)]);
            op.strength = integer(1, 4) / 4.0;
            op.distance = integer(1, 4);
            op.offset = Vec3d(integer(-3, 3), integer(-3, 3), integer(-3, 3));
            const Vec3d c(integer(-14, 14), integer(-14, 14), integer(-14, 14));
            applyFieldBrush(v, sphereBrush(integer(3, 10), c), op);
            INFO("scene " << scene << " brush " << i << ": " << fieldModeName(op.mode) << " " << falloffName(op.falloff));
            REQUIRE(closed(v));
            REQUIRE(checkInvariants(v).empty());
        }
    }
}

TEST_CASE("field brushes in scripts: each mode runs as an op, equal to the brush applied directly, strokes, bad ops refused", "[field][script]")
{
    const std::vector<std::pair<std::string, FieldBrushOp>> cases = [] {
        std::vector<std::pair<std::string, FieldBrushOp>> out;
        FieldBrushOp op = fieldOp(FieldMode::Smooth, Falloff::Smooth);
        op.strength = 0.75;
        out.push_back({R"({"mode": "smooth", "strength": 0.75})", op});
        op = fieldOp(FieldMode::Flatten, Falloff::Linear);
        out.push_back({R"({"mode": "flatten", "falloff": "linear"})", op});
        op = fieldOp(FieldMode::Inflate, Falloff::Smooth);
        op.distance = 2.0;
        out.push_back({R"({"mode": "inflate", "distance": 2})", op});
        op = fieldOp(FieldMode::Deflate, Falloff::Constant);
        op.distance = 1.5;
        out.push_back({R"({"mode": "deflate", "distance": 1.5, "falloff": "constant"})", op});
        op = fieldOp(FieldMode::Move, Falloff::Smooth);
        op.offset = Vec3d(1.0, 3.0, 0.0);
        out.push_back({R"({"mode": "move", "offset": [1, 3, 0]})", op});
        return out;
    }();
    for (const auto& [json, op] : cases) {
        INFO(json);
        std::string text = json;
        text.insert(1, R"("brush": {"shape": "sphere", "radius": 7}, "at": [3, 15, 2], )");
        Volume byScript = sphereVolume(16.0), direct = sphereVolume(16.0);
        const auto reports = runStrokeScript(byScript, parseStrokeScript(R"({"ops": [)" + text + "]}"));
        REQUIRE(reports.size() == 1);
        CHECK(std::string(reports[0].modeName) == fieldModeName(op.mode));
        applyFieldBrush(direct, sphereBrush(7.0, Vec3d(3.0, 15.0, 2.0)), op);
        CHECK(changedBlocks(byScript, direct).empty());
        CHECK_FALSE(changedBlocks(byScript, sphereVolume(16.0)).empty());
    }
    // A stroke: the swept brush reshapes the whole path.
    Volume stroke = sphereVolume(16.0);
    runStrokeScript(stroke, parseStrokeScript(
                                R"({"ops": [{"mode": "inflate", "distance": 2, "falloff": "constant", "brush": {"shape": "sphere", "radius": 4}, "path": [[-10, 13, 0], [10, 13, 0]]}]})"));
    REQUIRE(closed(stroke));
    for (const double x : {-8.0, 0.0, 8.0}) {
        // The surface above the path rose by 2 voxels: the voxel just outside the old sphere is solid now.
        const double y = std::floor(std::sqrt(16.0 * 16.0 - x * x)) + 1.0;
        CHECK(stroke.materialAt({int32_t(x), int32_t(y), 0}) != kEmptyMaterial);
    }
    // Refused, naming the place.
    const auto refused = [](const std::string& op, const std::string& where) {
        try {
            parseStrokeScript(R"({"ops": [)" + op + "]}");
            FAIL("accepted: " << op);
        } catch (const ScriptError& e) {
            INFO(e.what());
            CHECK(std::string(e.what()).find(where) != std::string::npos);
        }
    };
    const std::string brush = R"("brush": {"shape": "sphere", "radius": 4}, "at": [0, 0, 0])";
    refused(R"({"mode": "inflate", )" + brush + "}", "ops[0].distance");
    refused(R"({"mode": "move", )" + brush + "}", "ops[0].offset");
    refused(R"({"mode": "smooth", "distance": 2, )" + brush + "}", "ops[0].distance");
    refused(R"({"mode": "add", "falloff": "smooth", )" + brush + "}", "ops[0].falloff");
    refused(R"({"mode": "smooth", "falloff": "cubic", )" + brush + "}", "ops[0].falloff");
    refused(R"({"mode": "deflate", "distance": -1, )" + brush + "}", "ops[0].distance");
    refused(R"({"mode": "smooth", "depth": 2, )" + brush + "}", "ops[0].depth");
    refused(R"({"mode": "smooth", "brush": {"shape": "grid", "file": "t.vdb"}})", "ops[0].brush");
    refused(R"({"mode": "flatten", "brush": {"shape": "half-space", "normal": [0, 1, 0]}})", "needs a bounded brush");
    refused(R"({"mode": "wobble", )" + brush + "}", "ops[0].mode");
    // Too large for the rebuilt field: refused by the run, before anything changes.
    Volume v = sphereVolume(8.0);
    CHECK_THROWS_AS(runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "smooth", "brush": {"shape": "sphere", "radius": 500}}]})")), ScriptError);
    CHECK(changedBlocks(v, sphereVolume(8.0)).empty());
}

TEST_CASE("field brushes: bad ops are refused before anything changes", "[field]")
{
    Volume v = sphereVolume(10.0);
    FieldBrushOp op = fieldOp(FieldMode::Inflate);
    op.distance = 2.0;
    op.strength = 1.5;
    CHECK_THROWS_AS(applyFieldBrush(v, sphereBrush(5.0, Vec3d(0.0, 10.0, 0.0)), op), std::invalid_argument);
    op.strength = 1.0;
    op.material = MaterialId(7); // not in the table
    CHECK_THROWS_AS(applyFieldBrush(v, sphereBrush(5.0, Vec3d(0.0, 10.0, 0.0)), op), std::invalid_argument);
    op.material.reset();
    op.distance = std::nan("");
    CHECK_THROWS_AS(applyFieldBrush(v, sphereBrush(5.0, Vec3d(0.0, 10.0, 0.0)), op), std::invalid_argument);
    op.distance = 2.0;
    CHECK_THROWS_AS(applyFieldBrush(v, sphereBrush(150.0, Vec3d(0.0)), op), std::invalid_argument); // wider than 200 voxels
    CHECK_THROWS_AS(applyFieldBrush(v, Brush(halfSpace(Vec3d(0.0, 1.0, 0.0)), at(Vec3d(0.0))), op), std::invalid_argument);
    CHECK_THROWS_AS(applyFieldBrush(v, sphereBrush(5.0, Vec3d(3e5, 0.0, 0.0)), op), std::invalid_argument); // beyond the lattice's reach
    CHECK(changedBlocks(v, sphereVolume(10.0)).empty());
    // Empty space: nothing to reshape, nothing changes.
    Volume empty(1.0);
    CHECK(applyFieldBrush(empty, sphereBrush(5.0, Vec3d(0.0)), op).blocksComputed == 0);
    CHECK(empty.stats().activeVoxels == 0);
}

TEST_CASE("field brushes: the rebuilt distance is that of the nearest crossing, within the band, on random solids", "[field]")
{
    // Brute force beside the propagation: each point's distance to every crossing of the solid's boundary
    // (the tangent plane's distance, or the distance to the crossing less 0.87 farther along the plane).
    std::mt19937 rng(41);
    const auto real = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
    const std::array<int32_t, 3> origin{-24, -24, -24}, dims{49, 49, 49};
    for (int scene = 0; scene < 6; ++scene) {
        Volume v(1.0);
        // Drawn one at a time (an argument list's order of evaluation is the compiler's): the same scenes
        // whatever builds the test.
        const auto vec = [&](double lo, double hi) {
            const double x = real(lo, hi), y = real(lo, hi), z = real(lo, hi);
            return Vec3d(x, y, z);
        };
        for (int i = 0; i < 3; ++i) {
            const Vec3d c = vec(-6, 6);
            if (i % 2) {
                const Vec3d half = vec(3, 9);
                const double yaw = real(0, 90), pitch = real(0, 90);
                apply(v, CsgMode::Add, box(half), at(c, Vec3d(yaw, pitch, 0.0)));
            } else {
                apply(v, CsgMode::Add, sphere(real(4, 11)), at(c));
            }
        }
        if (scene % 3 == 2) {
            const double radius = real(3, 6);
            apply(v, CsgMode::Remove, sphere(radius), at(vec(-4, 4)));
        }
        const float band = scene % 2 ? 5.0f : std::numeric_limits<float>::infinity();
        const SolidDistances solid = solidDistances(v, origin, dims, band);
        const std::vector<SurfaceSample> samples = surfaceSamples(v, origin, dims);
        REQUIRE(samples.size() > 100);
        double worst = 0.0, nearWorst = 0.0;
        int checked = 0;
        for (int t = 0; t < 1500; ++t) {
            const std::array<int32_t, 3> p{int32_t(rng() % 49), int32_t(rng() % 49), int32_t(rng() % 49)};
            const Vec3d world(p[0] + origin[0], p[1] + origin[1], p[2] + origin[2]);
            double exact = std::numeric_limits<double>::infinity();
            for (const SurfaceSample& s : samples) {
                const Vec3d r = world - s.point;
                exact = std::min(exact, std::max(std::fabs(s.normal.dot(r)), r.length() - 0.87));
            }
            const std::size_t n = (std::size_t(p[0]) * 49 + std::size_t(p[1])) * 49 + std::size_t(p[2]);
            const float got = solid.distance[n];
            INFO("scene " << scene << " point " << world << " exact " << exact << " got " << got);
            REQUIRE((got < 0.0f) == (solid.material[n] != kEmptyMaterial));
            if (exact >= band + 2.0) {
                CHECK(std::fabs(got) == band); // capped
                continue;
            }
            if (exact > band - 0.5) continue; // where the cap begins
            // Never nearer than the nearest crossing (a minimum over fewer of them). Near the surface within
            // a few hundredths of a voxel of it, a tenth or so at two voxels; farther, the crossing a
            // neighbour passes on may miss the nearest by a few percent of the distance.
            CHECK(std::fabs(got) >= exact - 1e-4);
            if (exact < 2.5) worst = std::max(worst, std::fabs(got) - exact);
            if (exact < 1.5) nearWorst = std::max(nearWorst, std::fabs(got) - exact);
            else CHECK(std::fabs(got) - exact < 0.1 + 0.05 * exact);
            ++checked;
        }
        INFO("scene " << scene);
        CHECK(checked > 100);
        CHECK(nearWorst < 0.05);
        CHECK(worst < 0.15);
    }
}

TEST_CASE("field brushes: an inner band leaves the distances outside the solid exactly as they were, and caps those inside", "[field]")
{
    // Differential: the same random solids rebuilt with and without a thin inner band (what a blended add
    // reads); solids off the lattice, turned boxes, touching and crossing spheres, holes.
    std::mt19937 rng(57);
    const auto real = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
    const std::array<int32_t, 3> origin{-20, -20, -20}, dims{41, 43, 40};
    std::size_t outsideChecked = 0, insideBeyond = 0;
    for (int scene = 0; scene < 8; ++scene) {
        Volume v(1.0);
        for (int i = 0; i < 4; ++i) {
            const double x = real(-8, 8), y = real(-8, 8), z = real(-8, 8);
            if (i % 2) {
                const double hx = real(2, 9), hy = real(2, 9), hz = real(2, 9), yaw = real(0, 90);
                apply(v, CsgMode::Add, box(Vec3d(hx, hy, hz)), at(Vec3d(x, y, z), Vec3d(yaw, 0.0, 0.0)));
            } else {
                apply(v, CsgMode::Add, sphere(real(3, 12)), at(scene % 2 ? Vec3d(std::round(x), std::round(y), std::round(z)) : Vec3d(x, y, z)));
            }
        }
        if (scene % 3 == 1) apply(v, CsgMode::Remove, sphere(real(2, 5)), at(Vec3d(real(-3, 3), real(-3, 3), real(-3, 3))));
        for (const float band : {6.0f, 15.0f}) {
            const float inner = scene % 2 ? 3.0f : 1.5f;
            const SolidDistances full = solidDistances(v, origin, dims, band);
            const SolidDistances thin = solidDistances(v, origin, dims, band, inner);
            REQUIRE(thin.material == full.material);
            std::size_t wrong = 0, firstWrong = 0;
            for (std::size_t n = 0; n < full.distance.size(); ++n) {
                const float a = full.distance[n], b = thin.distance[n];
                bool right;
                if (a > 0.0f) {
                    right = b == a;
                    ++outsideChecked;
                } else if (a <= -inner) {
                    right = b == -inner;
                    ++insideBeyond;
                } else {
                    // Within the inner band: the nearest crossing, carried through points of the band.
                    right = b <= 0.0f && b >= a - 1e-6f && b <= a + 0.02f * inner;
                }
                if (!right && wrong++ == 0) firstWrong = n;
            }
            INFO("scene " << scene << " band " << band << ": " << wrong << " points differ, the first " << firstWrong << ": "
                          << full.distance[firstWrong] << " and " << thin.distance[firstWrong]);
            CHECK(wrong == 0);
        }
    }
    CHECK(outsideChecked > 100000);
    CHECK(insideBeyond > 10000);
}

TEST_CASE("field brushes: a symmetric op's copies prepared side by side give exactly the copies applied one by one", "[field]")
{
    // Mirror copies far apart (prepared together) and close (one by one either way), every reshaping mode
    // and a blended add, a continued inflate stroke (its start kept for both copies), on a ball whose
    // mirror plane is off its centre and off the lattice.
    const std::vector<std::string> modes = {R"("mode": "smooth", "strength": 1)",
                                            R"("mode": "flatten", "strength": 0.8)",
                                            R"("mode": "inflate", "distance": 2, "strength": 1)",
                                            R"("mode": "deflate", "distance": 1.5, "strength": 1)",
                                            R"("mode": "move", "offset": [0, 3, 1], "strength": 1)",
                                            R"("mode": "add", "blend": 2.5)"};
    // On the surface, x from the mirror plane: 17 (the copies' regions lie apart, but for smooth's, which
    // reaches twice its filter's radius further and goes one by one) and 4 (they meet).
    for (const auto& [x, y] : {std::pair<double, double>{17.0, 6.0}, {4.0, 17.5}})
        for (const std::string& mode : modes) {
            const std::string brush = R"("brush": {"shape": "sphere", "radius": 5}, "symmetry": {"mirror": ["x"], "center": [0.3, 0, 0]})";
            const std::string first = "[" + std::to_string(x) + ", " + std::to_string(y) + ", 2.2]";
            const std::string next = "[" + std::to_string(x) + ", " + std::to_string(y - 0.5) + ", 4.7]";
            std::string ops = "{" + mode + ", " + brush + R"(, "at": )" + first + "}";
            if (mode.find("inflate") != std::string::npos)
                ops += ", {" + mode + ", " + brush + R"(, "at": )" + next + R"(, "stroke": "continue"})";
            const StrokeScript script = parseStrokeScript(R"({"ops": [)" + ops + "]}");
            Volume together = sphereVolume(18.0), oneByOne = sphereVolume(18.0);
            runStrokeScript(together, script);
            runStrokeScript(oneByOne, script, {}, nullptr, false);
            INFO(mode << " at x = " << x);
            CHECK(changedBlocks(together, oneByOne).empty());
            CHECK_FALSE(changedBlocks(together, sphereVolume(18.0)).empty());
        }
}
