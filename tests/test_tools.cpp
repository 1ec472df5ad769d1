// Sculptures as tools: a tool placed on the lattice copies the sculpture's Hermite data exactly, a quarter
// turn permutes it exactly, any other placement resamples it without holes, and scripts use tools in
// every mode with their materials.
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "sculpt/GridTool.h"
#include "sculpt/StrokeScript.h"
#include "scene/SceneStore.h"
#include "support/CliRun.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

using Voxel = std::array<int32_t, 3>;

/// A sharp, asymmetric sculpture of one material: a sphere with a box cut out of it and a rotated bar.
Volume sharpSculpture(double voxelSize = 0.5)
{
    Volume v(voxelSize);
    apply(v, CsgMode::Add, sphere(6.3), at(Vec3d(0.3, 0.1, -0.2)));
    apply(v, CsgMode::Remove, box(Vec3d(3.0, 2.5, 4.0)), at(Vec3d(4.0, 3.0, 0.0), Vec3d(0.0, 0.0, 20.0)));
    apply(v, CsgMode::Add, box(Vec3d(1.5, 6.0, 1.5)), at(Vec3d(-3.0, 2.0, 1.0), Vec3d(25.0, 0.0, 10.0)));
    return v;
}

/// The same with a second material painted over part of it.
Volume twoMaterialSculpture()
{
    Volume v = sharpSculpture();
    const MaterialId red = defineMaterial(v, "red", 0.5f, {1.0f, 0.1f, 0.1f, 1.0f});
    apply(v, CsgMode::Paint, sphere(4.0), at(Vec3d(-4.0, -3.0, 2.0)), red);
    return v;
}

/// Applies a tool as scripts do: one op, or one per tool material for add and paint (ids by name).
void stamp(Volume& v, const std::shared_ptr<const GridTool>& tool, const Placement& pl, CsgMode mode)
{
    if (mode != CsgMode::Add && mode != CsgMode::Paint) {
        applyCsg(v, PlacedTool(tool, pl), op(mode));
        return;
    }
    for (MaterialId region : tool->regions()) {
        const Material& m = tool->materials().at(region);
        const auto id = v.materials().find(m.name);
        applyCsg(v, PlacedTool(tool, pl, region), op(mode, id ? *id : v.materials().define(m)));
    }
}

Vec3d pivotWorld(const GridTool& tool)
{
    return Vec3d(tool.pivot()[0], tool.pivot()[1], tool.pivot()[2]) * tool.voxelSize();
}

std::map<std::pair<Voxel, int>, EdgeRecord> edgesByKey(const Volume& v)
{
    std::map<std::pair<Voxel, int>, EdgeRecord> out;
    for (const EdgeRecord& e : collectEdges(v)) out[{e.voxel, e.axis}] = e;
    return out;
}

/// The voxel a lattice map sends `v` to: (R (v - pivot)) + target, R a quarter-turn matrix.
Voxel mapVoxel(const std::array<std::array<int, 3>, 3>& r, const Voxel& v, const Voxel& pivot, const Voxel& target)
{
    Voxel out;
    for (std::size_t i = 0; i < 3; ++i) {
        int64_t s = 0;
        for (std::size_t j = 0; j < 3; ++j) s += int64_t(r[i][j]) * (v[j] - pivot[j]);
        out[i] = int32_t(s + target[i]);
    }
    return out;
}

/// Every solid voxel and every sample of `source`, moved by the quarter turn `r` about the tool's pivot to
/// `target`, is in `placed` exactly (the offset reversed where the edge turns round, the normal turned
/// and quantized again, and only its sign free on a boundary between two materials), and `placed` holds
/// nothing else.
void checkLatticeCopy(const Volume& source, const Volume& placed, const std::array<std::array<int, 3>, 3>& r,
                      const Voxel& pivot, const Voxel& target)
{
    REQUIRE(checkInvariants(placed) == "");
    const auto expected = collectEdges(source);
    const auto got = edgesByKey(placed);
    REQUIRE(got.size() == expected.size());
    std::size_t mismatches = 0;
    for (const EdgeRecord& e : expected) {
        Voxel end = e.voxel;
        end[std::size_t(e.axis)] += 1;
        const Voxel a = mapVoxel(r, e.voxel, pivot, target), b = mapVoxel(r, end, pivot, target);
        int axis = 0;
        for (int i = 0; i < 3; ++i)
            if (a[std::size_t(i)] != b[std::size_t(i)]) axis = i;
        const bool reversed = b[std::size_t(axis)] < a[std::size_t(axis)];
        const auto found = got.find({reversed ? b : a, axis});
        if (found == got.end()) {
            ++mismatches;
            continue;
        }
        const EdgeRecord& g = found->second;
        const auto n = decodeNormal(e.sample.normalU, e.sample.normalV);
        std::array<double, 3> turned{};
        for (std::size_t i = 0; i < 3; ++i)
            for (std::size_t j = 0; j < 3; ++j) turned[i] += r[i][j] * n[j];
        const auto code = quantizeNormal(turned);
        const auto flipped = quantizeNormal({-turned[0], -turned[1], -turned[2]});
        const bool betweenMaterials = e.from != kEmptyMaterial && e.to != kEmptyMaterial;
        const bool sameNormal = (g.sample.normalU == code[0] && g.sample.normalV == code[1]) ||
                                (betweenMaterials && g.sample.normalU == flipped[0] && g.sample.normalV == flipped[1]);
        const uint16_t offset = reversed ? uint16_t(65535 - e.sample.offset) : e.sample.offset;
        const MaterialId from = reversed ? e.to : e.from, to = reversed ? e.from : e.to;
        if (g.sample.offset != offset || !sameNormal || g.from != from || g.to != to) {
            if (mismatches < 5) {
                UNSCOPED_INFO("voxel " << e.voxel[0] << "," << e.voxel[1] << "," << e.voxel[2] << " axis " << e.axis
                                       << ": offset " << g.sample.offset << " vs " << offset << ", materials " << g.from
                                       << "->" << g.to << " vs " << from << "->" << to << ", normal code " << g.sample.normalU
                                       << "," << g.sample.normalV << " vs " << code[0] << "," << code[1] << " (flipped "
                                       << flipped[0] << "," << flipped[1] << ")");
            }
            ++mismatches;
        }
    }
    CHECK(mismatches == 0);
    CHECK(solidVoxelsPerMaterial(placed) == solidVoxelsPerMaterial(source));
}

constexpr std::array<std::array<int, 3>, 3> kIdentity{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};

} // namespace

TEST_CASE("a tool placed at its pivot copies the sculpture bit for bit", "[tool]")
{
    const Volume source = sharpSculpture();
    const auto tool = std::make_shared<const GridTool>(source.clone());
    Volume placed(source.voxelSize());
    stamp(placed, tool, at(pivotWorld(*tool)), CsgMode::Add);
    CHECK(identical(placed, source));
}

TEST_CASE("a tool stamped at 0 degrees equals the same shape made directly, within quantization", "[tool]")
{
    // The tool is a sphere; stamped whole voxels away it must match the sphere made there by the analytic
    // brush: the same voxels, crossings within the offset quantization, normals within the normal's.
    const double vs = 0.5;
    const Vec3d centre(0.3, 0.1, -0.2);
    Volume source(vs);
    apply(source, CsgMode::Add, sphere(7.3), at(centre));
    const auto tool = std::make_shared<const GridTool>(source.clone());
    const Voxel shift{5, -3, 12};
    const Vec3d moved = Vec3d(shift[0], shift[1], shift[2]) * vs;
    Volume placed(vs), direct(vs);
    stamp(placed, tool, at(pivotWorld(*tool) + moved), CsgMode::Add);
    apply(direct, CsgMode::Add, sphere(7.3), at(centre + moved));
    REQUIRE(solidVoxelsPerMaterial(placed) == solidVoxelsPerMaterial(direct));
    const auto got = edgesByKey(placed);
    const auto want = collectEdges(direct);
    REQUIRE(got.size() == want.size());
    int worstOffset = 0;
    double worstNormal = 0.0;
    for (const EdgeRecord& e : want) {
        const auto found = got.find({e.voxel, e.axis});
        REQUIRE(found != got.end());
        worstOffset = std::max(worstOffset, std::abs(int(found->second.sample.offset) - int(e.sample.offset)));
        const auto a = dequantizeNormal(e.sample.normalU, e.sample.normalV);
        const auto b = dequantizeNormal(found->second.sample.normalU, found->second.sample.normalV);
        for (int i = 0; i < 3; ++i) worstNormal = std::max(worstNormal, double(std::fabs(a[i] - b[i])));
    }
    INFO("worst offset " << worstOffset << " codes, worst normal component " << worstNormal);
    CHECK(worstOffset <= 2);       // the analytic search lands within a code or two of the same point
    CHECK(worstNormal <= 2.5e-3);  // two normal codes
}

TEST_CASE("a tool turned by quarter turns equals the permuted tool exactly", "[tool]")
{
    const Volume source = twoMaterialSculpture();
    const auto tool = std::make_shared<const GridTool>(source.clone());
    struct Turn {
        Vec3d degrees;
        std::array<std::array<int, 3>, 3> matrix; // column-vector rotation, R = Rz * Ry * Rx
    };
    const Turn turns[] = {
        {Vec3d(0.0, 0.0, 90.0), {{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}}},
        {Vec3d(90.0, 0.0, 0.0), {{{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}}},
        {Vec3d(0.0, 180.0, 0.0), {{{-1, 0, 0}, {0, 1, 0}, {0, 0, -1}}}},
        {Vec3d(90.0, 90.0, 0.0), {{{0, 1, 0}, {0, 0, -1}, {-1, 0, 0}}}},
    };
    const Voxel target{7, -4, 3};
    for (const Turn& turn : turns) {
        INFO("rotate " << turn.degrees);
        Volume placed(source.voxelSize());
        const Vec3d where = Vec3d(target[0], target[1], target[2]) * source.voxelSize();
        stamp(placed, tool, at(where, turn.degrees), CsgMode::Add);
        checkLatticeCopy(source, placed, turn.matrix, tool->pivot(), target);
    }
    // And unturned, whole voxels away.
    Volume moved(source.voxelSize());
    stamp(moved, tool, at(Vec3d(target[0], target[1], target[2]) * source.voxelSize()), CsgMode::Add);
    checkLatticeCopy(source, moved, kIdentity, tool->pivot(), target);
}

TEST_CASE("a rotated or scaled tool never leaves holes", "[tool]")
{
    // A box tool turned by arbitrary angles, off the lattice and scaled: every voxel deeper than the
    // resampling's reach inside the analytic box is solid, every one as far outside is empty, and the
    // CMS mesh is one closed piece of the box's volume.
    const double vs = 0.5;
    const Vec3d half(5.0, 3.0, 2.0);
    Volume source(vs);
    apply(source, CsgMode::Add, box(half), at(Vec3d(0.0)));
    const auto tool = std::make_shared<const GridTool>(source.clone());
    REQUIRE(pivotWorld(*tool) == Vec3d(0.0));
    struct Case {
        Vec3d at, degrees, scale;
    };
    const Case cases[] = {{Vec3d(0.13, -0.27, 0.31), Vec3d(17.0, 33.0, 51.0), Vec3d(1.0)},
                          {Vec3d(1.0, 2.0, 3.0), Vec3d(0.0, 0.0, 45.0), Vec3d(1.0)},
                          {Vec3d(-0.4, 0.2, 0.05), Vec3d(61.0, -12.0, 5.0), Vec3d(1.7, 1.3, 2.1)},
                          {Vec3d(0.0), Vec3d(-30.0, 70.0, 110.0), Vec3d(0.6)}};
    for (const Case& c : cases) {
        INFO("at " << c.at << " rotate " << c.degrees << " scale " << c.scale);
        Volume placed(vs);
        stamp(placed, tool, at(c.at, c.degrees, c.scale), CsgMode::Add);
        REQUIRE(checkInvariants(placed) == "");
        // The tool's box faces lie at +-half rounded to the voxel centres it kept; the analytic box
        // through those faces, placed the same way.
        const Brush analytic(box(half), at(c.at, c.degrees, c.scale));
        const double reach = 0.75 * vs * std::max({c.scale.x(), c.scale.y(), c.scale.z()});
        const VolumeStats stats = placed.stats();
        std::size_t holes = 0, strays = 0;
        for (int i = stats.bboxMin[0] - 3; i <= stats.bboxMax[0] + 3; ++i)
            for (int j = stats.bboxMin[1] - 3; j <= stats.bboxMax[1] + 3; ++j)
                for (int k = stats.bboxMin[2] - 3; k <= stats.bboxMax[2] + 3; ++k) {
                    const double d = analytic.distance(Vec3d(i, j, k) * vs);
                    const bool solid = placed.materialAt({i, j, k}) != kEmptyMaterial;
                    if (d < -reach && !solid) ++holes;
                    if (d > reach && solid) ++strays;
                }
        CHECK(holes == 0);
        CHECK(strays == 0);
        const Mesh mesh = meshVolume(placed);
        const MeshTopology topology = analyzeTopology(mesh, kMergeDistanceVoxels * vs);
        CHECK(topology.watertight());
        CHECK(topology.components == 1);
        const double expected = 8.0 * half.x() * half.y() * half.z() * c.scale.x() * c.scale.y() * c.scale.z();
        CHECK(enclosedVolume(mesh) == Approx(expected).epsilon(0.05));
    }
}

TEST_CASE("a placed tool's lattice patches hold the distances it gives point by point", "[tool]")
{
    // The kernel reads a block's distances as patches, which a placed tool walks incrementally; the
    // crossing search and the one-side tests read single points. Both must describe one field.
    const auto tool = std::make_shared<const GridTool>(twoMaterialSculpture());
    std::mt19937 rng(77);
    std::uniform_int_distribution<int32_t> corner(-30, 24);
    std::uniform_real_distribution<double> angle(-180.0, 180.0), scale(0.6, 1.7), shift(-2.0, 2.0);
    const Vec3d quarterTurn(90.0, 0.0, -90.0);
    for (int round = 0; round < 40; ++round) {
        const bool onLattice = round % 4 == 0;
        const Placement placement = onLattice ? at(Vec3d(1.0, -2.0, 0.0), quarterTurn)
                                              : at(Vec3d(shift(rng), shift(rng), shift(rng)), Vec3d(angle(rng), angle(rng), angle(rng)),
                                                   Vec3d(scale(rng), scale(rng), scale(rng)));
        const PlacedTool placed(tool, placement, MaterialId(round % 3));
        for (int n = 0; n < 20; ++n) {
            const LatticePatch patch{{corner(rng), corner(rng), corner(rng)}, n % 2 ? 3 : 1, n % 3 ? 3 : 5, 0.5};
            std::vector<double> batch(patch.size());
            placed.distances(patch, batch.data());
            std::size_t index = 0;
            for (int32_t i = 0; i < patch.count; ++i)
                for (int32_t j = 0; j < patch.count; ++j)
                    for (int32_t k = 0; k < patch.count; ++k) {
                        const double single = placed.distance(patch.point(i, j, k));
                        INFO("round " << round << ", point " << index);
                        REQUIRE(batch[index++] == Approx(single).margin(1e-9));
                    }
        }
    }
}

TEST_CASE("a tool's field changes no faster than its Lipschitz bound", "[tool]")
{
    // The CSG kernel settles whole blocks from one distance and the bound; a field steeper than it
    // claims would leave blocks half carved.
    const auto tool = std::make_shared<const GridTool>(twoMaterialSculpture());
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> coord(-12.0, 12.0), angle(-180.0, 180.0), near(-0.6, 0.6);
    for (MaterialId region : {MaterialId(0), MaterialId(1), MaterialId(2)}) {
        const PlacedTool placed(tool, at(Vec3d(0.2, -0.1, 0.4), Vec3d(angle(rng), angle(rng), angle(rng))), region);
        double worst = 0.0;
        for (int n = 0; n < 20000; ++n) {
            const Vec3d p(coord(rng), coord(rng), coord(rng));
            const Vec3d q = p + (n % 2 ? Vec3d(near(rng), near(rng), near(rng)) : Vec3d(coord(rng), coord(rng), coord(rng)));
            const double ratio = std::fabs(placed.distance(p) - placed.distance(q)) / (p - q).length();
            worst = std::max(worst, ratio);
        }
        INFO("region " << region << ": claimed " << placed.lipschitz() << ", seen " << worst);
        CHECK(worst <= placed.lipschitz() * (1.0 + 1e-9));
        CHECK(placed.lipschitz() < 2.0); // a useful bound, not a blanket one
    }
}

TEST_CASE("tools work in every mode: remove and intersect by exact voxel counts, paint with the tool's materials", "[tool]")
{
    const double vs = 0.5;
    const Volume sculpture = twoMaterialSculpture();
    const auto tool = std::make_shared<const GridTool>(sculpture.clone());
    const Vec3d where = pivotWorld(*tool) + Vec3d(2.0, -1.5, 0.5); // whole voxels away: an exact copy
    const Voxel target{tool->pivot()[0] + 4, tool->pivot()[1] - 3, tool->pivot()[2] + 1};
    uint64_t toolVoxels = 0;
    for (uint64_t n : solidVoxelsPerMaterial(sculpture)) toolVoxels += n;

    auto block = [&] {
        Volume v(vs);
        const MaterialId stone = defineMaterial(v, "stone", 0.5f);
        apply(v, CsgMode::Add, box(Vec3d(15.0)), at(Vec3d(0.0)), stone);
        return v;
    };
    auto solidCount = [](const Volume& v) {
        uint64_t total = 0;
        for (uint64_t n : solidVoxelsPerMaterial(v)) total += n;
        return total;
    };
    const uint64_t blockVoxels = solidCount(block());

    Volume removed = block();
    stamp(removed, tool, at(where), CsgMode::Remove);
    CHECK(solidCount(removed) == blockVoxels - toolVoxels);

    Volume kept = block();
    stamp(kept, tool, at(where), CsgMode::Intersect);
    CHECK(solidCount(kept) == toolVoxels);

    Volume painted = block();
    stamp(painted, tool, at(where), CsgMode::Paint);
    const auto counts = solidVoxelsPerMaterial(painted);
    const auto toolCounts = solidVoxelsPerMaterial(sculpture);
    const MaterialId defaultId = *painted.materials().find("default"), red = *painted.materials().find("red");
    CHECK(counts[defaultId] == toolCounts[1]);
    CHECK(counts[red] == toolCounts[2]);
    CHECK(solidCount(painted) == blockVoxels); // paint never changes the shape
    // Every solid voxel of the tool is painted with its own material, moved to `target`.
    std::size_t wrong = 0;
    for (int32_t i = 0; i < tool->dims()[0]; ++i)
        for (int32_t j = 0; j < tool->dims()[1]; ++j)
            for (int32_t k = 0; k < tool->dims()[2]; ++k) {
                const Voxel voxel{tool->origin()[0] + i, tool->origin()[1] + j, tool->origin()[2] + k};
                const MaterialId m = tool->materialAt(voxel);
                if (m == kEmptyMaterial) continue;
                const MaterialId there = painted.materialAt(mapVoxel(kIdentity, voxel, tool->pivot(), target));
                if (there == kEmptyMaterial || painted.materials().at(there).name != tool->materials().at(m).name) ++wrong;
            }
    CHECK(wrong == 0);

    Volume eroded = block();
    stamp(eroded, tool, at(where), CsgMode::Erode);
    CHECK(solidCount(eroded) < blockVoxels);
    CHECK(solidCount(eroded) > blockVoxels - toolVoxels); // toughness 0.5 bites half as deep
}

TEST_CASE("scripts use tools: grid shapes, relative files, strokes, clear errors", "[tool][script]")
{
    TempDir dir;
    const Volume sculpture = twoMaterialSculpture();
    std::filesystem::create_directories(dir.path() / "tools");
    saveVolume(sculpture, dir.file("tools/knob.vdb"));
    writeText(dir.file("stroke.json"), R"({"ops": [
        {"mode": "add", "brush": {"shape": "grid", "file": "tools/knob.vdb"}, "path": [[0,0,0],[30,0,0]]},
        {"mode": "add", "brush": {"shape": "grid", "file": "tools/knob.vdb"}, "at": [0,30,0], "rotate": [0,0,33], "scale": [0.8,0.8,0.8], "material": "clay"}],
      "materials": [{"name": "clay", "color": [0.7,0.5,0.3]}]})");
    StrokeScript script = loadStrokeScript(dir.file("stroke.json"));
    REQUIRE(script.ops.size() == 2);
    CHECK(script.ops[0].tool == script.ops[1].tool); // loaded once
    Volume v(0.5);
    runStrokeScript(v, script);
    REQUIRE(checkInvariants(v) == "");
    // The stroke runs from one end of the path to the other as one closed piece with both tool
    // materials; the second op is all clay.
    const auto counts = solidVoxelsPerMaterial(v);
    const MaterialId red = *v.materials().find("red"), clay = *v.materials().find("clay");
    CHECK(counts[red] > 0);
    CHECK(counts[clay] > 0);
    std::size_t gaps = 0;
    for (int32_t i = 0; i <= 60; ++i) gaps += v.materialAt({i, 0, 0}) == kEmptyMaterial;
    CHECK(gaps == 0);
    const MeshTopology topology = analyzeTopology(meshVolume(v), kMergeDistanceVoxels * v.voxelSize());
    CHECK(topology.watertight());
    CHECK(topology.components == 2);

    // Errors name the op and the file.
    auto scriptError = [&](const std::string& text) {
        writeText(dir.file("bad.json"), text);
        try {
            (void)loadStrokeScript(dir.file("bad.json"));
        } catch (const ScriptError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    CHECK_THAT(scriptError(R"({"ops": [{"mode": "add", "brush": {"shape": "grid", "file": "missing.vdb"}}]})"),
               Catch::Contains("ops[0].brush.file") && Catch::Contains("missing.vdb"));
    writeText(dir.file("garbage.vdb"), "not a volume");
    CHECK_THAT(scriptError(R"({"ops": [{"mode": "remove", "brush": {"shape": "grid", "file": "garbage.vdb"}}]})"),
               Catch::Contains("ops[0].brush.file"));
    // A store named as a tool: the error says how to make one of it.
    writeText(dir.file("scene.vdbclay"), "SQLite format 3");
    CHECK_THAT(scriptError(R"({"ops": [{"mode": "add", "brush": {"shape": "grid", "file": "scene.vdbclay"}}]})"),
               Catch::Contains("vdbclay tool make"));
    CHECK_THAT(scriptError(R"({"ops": [{"mode": "add", "brush": {"shape": "grid"}}]})"), Catch::Contains("ops[0].brush") && Catch::Contains("file"));
    CHECK_THAT(scriptError(R"({"ops": [{"mode": "add", "brush": {"shape": "grid", "file": "tools/knob.vdb", "radius": 2}}]})"),
               Catch::Contains("unknown key 'radius'"));
    // Paint needs a material unless a tool brings its own.
    CHECK_THAT(scriptError(R"({"ops": [{"mode": "paint", "brush": {"shape": "sphere", "radius": 2}}]})"), Catch::Contains("paint needs"));
    CHECK(scriptError(R"({"ops": [{"mode": "paint", "brush": {"shape": "grid", "file": "tools/knob.vdb"}}]})").empty());
    // A script parsed from text has its tools named but not loaded: running it says so.
    const StrokeScript unloaded = parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "grid", "file": "x.vdb"}}]})");
    Volume untouched(0.5);
    CHECK_THROWS_WITH(runStrokeScript(untouched, unloaded), Catch::Contains("not loaded"));
}

TEST_CASE("vdbclay tool make cuts a box of a scene into a tool that scripts stamp", "[tool][cli]")
{
    TempDir dir;
    Volume scene = twoMaterialSculpture();
    saveVolume(scene, dir.file("scene.vdb"));
    writeStoreFile(scene, dir.file("scene.vdbclay"));
    for (const char* input : {"scene.vdb", "scene.vdbclay"}) {
        INFO(input);
        const CommandResult made = runCli(dir, std::string("tool make ") + input + " --bbox -8 -8 -8 0 8 8 -o half.vdb --json");
        REQUIRE(made.exitCode == 0);
        const auto report = nlohmann::json::parse(made.out);
        CHECK(report.at("materials").size() == 2);
        // The tool is the scene's half x <= 0: every voxel there as it was (the cut face is new).
        const Volume half = loadVolume(dir.file("half.vdb"));
        std::size_t wrong = 0;
        for (int32_t i = -16; i <= 2; ++i)
            for (int32_t j = -16; j <= 16; ++j)
                for (int32_t k = -16; k <= 16; ++k) {
                    const MaterialId want = i <= 0 ? scene.materialAt({i, j, k}) : kEmptyMaterial;
                    wrong += half.materialAt({i, j, k}) != want;
                }
        CHECK(wrong == 0);
        CHECK(checkInvariants(half) == "");
    }
    writeText(dir.file("use.json"), R"({"ops": [{"mode": "add", "brush": {"shape": "grid", "file": "half.vdb"}, "at": [10, 0, 0], "rotate": [0, 90, 0]}]})");
    CHECK(runCli(dir, "new base.vdb --shape sphere --size 2 --voxel-size 0.5").exitCode == 0);
    const CommandResult sculpted = runCli(dir, "sculpt base.vdb use.json -o out.vdb");
    INFO(sculpted.err);
    CHECK(sculpted.exitCode == 0);

    checkCleanFailure(runCli(dir, "tool make scene.vdb --bbox 1 1 1 0 2 2 -o bad.vdb"));
    CHECK(runCli(dir, "tool make scene.vdb --bbox 1 1 1 0 2 2 -o bad.vdb").exitCode == 2);
    CHECK(runCli(dir, "tool make scene.vdb -o tool.vdbclay").exitCode == 2);
    const CommandResult empty = runCli(dir, "tool make scene.vdb --bbox 100 100 100 101 101 101 -o empty.vdb");
    checkCleanFailure(empty);
    CHECK(empty.exitCode == 1);
    CHECK_THAT(empty.err, Catch::Contains("no solid voxel"));
    CHECK_FALSE(std::filesystem::exists(dir.file("empty.vdb")));
    // A box far larger than the scene (one the brush limits would refuse as a cut) takes all of it.
    REQUIRE(runCli(dir, "tool make scene.vdb --bbox -1e300 -1e300 -1e300 1e300 1e300 1e300 -o all.vdb").exitCode == 0);
    REQUIRE(runCli(dir, "tool make scene.vdb -o whole.vdb").exitCode == 0);
    CHECK(identical(loadVolume(dir.file("all.vdb")), loadVolume(dir.file("whole.vdb"))));
    CHECK(runCli(dir, "tool make missing.vdb -o t.vdb").exitCode == 1);
    CHECK(runCli(dir, "tool --help").exitCode == 0);
}
