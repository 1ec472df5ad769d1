// Meshing a level-of-detail cut: each brick on its own level's lattice, transition cells where a brick
// meets a finer one. The combined mesh of any mix of levels is a closed, oriented 2-manifold (seed 000
// §5: no cracks, no skirts, no patching), and a cut of level 0 alone meshes exactly as the whole volume.
#include "mesher/LodBrickTable.h"
#include "mesher/LodMesh.h"
#include "mesher/MeshMetrics.h"
#include "mesher/MeshQuality.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/StreamingScene.h"
#include "sculpt/StrokeScript.h"
#include "selftest/RandomScene.h"
#include "support/Sculpt.h"
#include "support/TerrainStore.h"
#include "support/TestUtil.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <tuple>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

MeshOptions cms()
{
    MeshOptions o;
    o.kind = MesherKind::CubicalMarchingSquares;
    return o;
}

/// A store's levels of detail, loaded whole.
struct Levels {
    std::vector<Volume> volumes;
    std::vector<std::set<IndexCoord>> bricks; // per level: the stored bricks
    std::vector<const Volume*> pointers() const
    {
        std::vector<const Volume*> out;
        for (const Volume& v : volumes) out.push_back(&v);
        return out;
    }
};

Levels levelsOf(const Volume& volume, int levels, const TempDir& dir)
{
    const std::string path = dir.file("lod.vdbclay");
    writeStoreFile(volume, path);
    SceneStore store = SceneStore::open(path, StoreAccess::ReadWrite);
    buildStoreLod(store, levels);
    Levels out;
    for (int k = 0; k <= store.lodLevels(); ++k) {
        out.volumes.push_back(store.loadLevel(k));
        out.bricks.emplace_back();
        store.bricks().scan(k, [&](const BrickKey& key, const BrickSummary&) { out.bricks.back().insert(key.brick); });
        // A coarse level may lose a small part altogether: its finer bricks' parents stand for it, empty.
        if (k > 0)
            for (const IndexCoord& b : out.bricks[std::size_t(k - 1)]) out.bricks.back().insert({b[0] >> 1, b[1] >> 1, b[2] >> 1});
    }
    return out;
}

/// A cut chosen from the top level down (a brick of a level no stored brick holds is empty there): each brick is shown, or split into its stored children, by
/// `split(level, brick)`.
template <typename Split>
std::vector<LodBrick> cutOf(const Levels& levels, Split&& split, bool splitEmpty = false)
{
    std::vector<LodBrick> out;
    std::vector<LodBrick> stack;
    const int top = int(levels.bricks.size()) - 1;
    for (const IndexCoord& b : levels.bricks[std::size_t(top)]) stack.push_back({top, b});
    while (!stack.empty()) {
        const LodBrick b = stack.back();
        stack.pop_back();
        const bool stored = levels.bricks[std::size_t(b.level)].count(b.brick) > 0;
        if (b.level == 0 || (!stored && !splitEmpty) || !split(b)) {
            out.push_back(b);
            continue;
        }
        // Every child, the empty ones too: the cut covers the split brick's space at the children's level.
        for (int c = 0; c < 8; ++c) {
            const IndexCoord child{2 * b.brick[0] + (c & 1), 2 * b.brick[1] + ((c >> 1) & 1), 2 * b.brick[2] + ((c >> 2) & 1)};
            stack.push_back({b.level - 1, child});
        }
    }
    return out;
}

Mesh meshCut(const std::vector<const Volume*>& levels, const std::vector<LodBrick>& shown, const MeshOptions& options = cms())
{
    const LodCut cut(shown);
    Mesh all;
    for (const LodBrick& b : shown) appendMesh(all, meshLodBrick(levels, cut, b, options));
    return all;
}

Mesh meshCut(const Levels& levels, const std::vector<LodBrick>& shown, const MeshOptions& options = cms())
{
    return meshCut(levels.pointers(), shown, options);
}

/// meshCut with each coarse brick's mesh simplified as streaming scenes do (simplifyLodBrickMesh).
Mesh meshCutSimplified(const std::vector<const Volume*>& levels, const std::vector<LodBrick>& shown, const MeshOptions& options)
{
    const LodCut cut(shown);
    Mesh all;
    for (const LodBrick& b : shown) {
        Mesh m = meshLodBrick(levels, cut, b, options);
        simplifyLodBrickMesh(m, b.level, levels[std::size_t(b.level)]->voxelSize(), options);
        appendMesh(all, m);
    }
    return all;
}

std::string describe(const std::vector<LodBrick>& shown)
{
    std::string s;
    for (const LodBrick& b : shown)
        s += "L" + std::to_string(b.level) + "(" + std::to_string(b.brick[0]) + "," + std::to_string(b.brick[1]) + "," +
             std::to_string(b.brick[2]) + ") ";
    return s;
}

void requireClosed(const Mesh& mesh, double voxel, const std::vector<LodBrick>& shown, bool nonEmpty = true)
{
    const MeshTopology t = analyzeTopology(mesh, kMergeDistanceVoxels * voxel);
    INFO("cut: " << describe(shown));
    INFO("boundary " << t.boundaryEdges << ", non-manifold " << t.nonManifoldEdges << ", misoriented " << t.misorientedEdges
                     << ", degenerate " << t.degenerateTriangles << ", pinched " << t.pinchedVertices);
    if (nonEmpty) CHECK(mesh.triangleCount() > 0);
    CHECK(t.watertight());
}

/// A scene spanning bricks on both sides of the origin, with a box's sharp edges and two materials.
Volume wideScene()
{
    Volume v(1.0);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, sphere(100.0), at(Vec3d(3.1, -2.0, 1.0)));
    apply(v, CsgMode::Add, box(Vec3d(40.0, 30.0, 36.0)), at(Vec3d(90.0, 40.0, -20.0), Vec3d(0.0, 30.0, 0.0)), red);
    apply(v, CsgMode::Add, box(Vec3d(64.0, 20.0, 50.0)), at(Vec3d(-64.0, -96.0, 0.0)));
    apply(v, CsgMode::Remove, sphere(24.0), at(Vec3d(-60.0, 0.0, 50.0)));
    return v;
}

} // namespace

TEST_CASE("lod mesh: a cut of level 0 alone meshes exactly as the whole volume", "[lod]")
{
    TempDir dir;
    const Volume volume = wideScene();
    const Levels levels = levelsOf(volume, 2, dir);
    const std::vector<LodBrick> shown = cutOf(levels, [](const LodBrick&) { return true; }, true);
    for (const LodBrick& b : shown)
        if (levels.bricks[std::size_t(b.level)].count(b.brick)) REQUIRE(b.level == 0); // the rest are empty
    const Mesh cut = meshCut(levels, shown);
    const Mesh whole = meshVolume(volume, cms());
    CHECK(cut.triangleCount() == whole.triangleCount());
    requireClosed(cut, volume.voxelSize(), shown);
}

TEST_CASE("lod mesh: checkerboards of levels 0-1 and 0-3 are closed 2-manifolds", "[lod]")
{
    TempDir dir;
    const Volume volume = wideScene();
    const Levels levels = levelsOf(volume, 3, dir);
    for (int parity = 0; parity < 2; ++parity) {
        // Level 1 bricks alternate between shown and split into level 0.
        const auto shown = cutOf(levels, [&](const LodBrick& b) {
            if (b.level > 1) return true;
            return ((b.brick[0] + b.brick[1] + b.brick[2]) & 1) == parity;
        });
        std::set<int> used;
        for (const LodBrick& b : shown)
            if (levels.bricks[std::size_t(b.level)].count(b.brick)) used.insert(b.level);
        CHECK(used == std::set<int>{0, 1});
        requireClosed(meshCut(levels, shown), volume.voxelSize(), shown);
    }
    for (int parity = 0; parity < 2; ++parity) {
        // Every level 0..3 side by side: a brick splits where its coordinates' sum has the parity.
        const auto shown = cutOf(levels, [&](const LodBrick& b) { return ((b.brick[0] + b.brick[1] + b.brick[2] + b.level) & 1) == parity; });
        requireClosed(meshCut(levels, shown), volume.voxelSize(), shown);
    }
}

namespace {

/// Four random cuts of each of the random scenes [first, last] of seed 77 mesh into closed 2-manifolds.
void checkRandomCuts(uint64_t first, uint64_t last)
{
    TempDir dir;
    std::mt19937_64 rng(1234 + first);
    for (uint64_t index = first; index <= last; ++index) {
        const RandomScene scene = randomScene(77, index);
        Volume volume(scene.voxelSize);
        runStrokeScript(volume, parseStrokeScript(scene.script));
        if (volume.stats().leafCount == 0) continue;
        const Levels levels = levelsOf(volume, 2, dir);
        for (int trial = 0; trial < 4; ++trial) {
            const auto shown = cutOf(levels, [&](const LodBrick&) { return rng() % 3 != 0; });
            INFO("scene " << index << " trial " << trial);
            // A small part can vanish at a coarse level: an empty cut is closed too.
            requireClosed(meshCut(levels, shown), volume.voxelSize(), shown, false);
        }
    }
}

} // namespace

// In halves: under the sanitizers each takes minutes.
TEST_CASE("lod mesh: random cuts of random scenes 0-7 are closed 2-manifolds", "[lod]") { checkRandomCuts(0, 7); }
TEST_CASE("lod mesh: random cuts of random scenes 8-15 are closed 2-manifolds", "[lod]") { checkRandomCuts(8, 15); }

TEST_CASE("lod cut: a brick is shown exactly when the cut lists it, near the packed table's reach and beyond it", "[lod]")
{
    // The cut answers from a packed table while every brick fits 19 bits a coordinate, else from its set:
    // both must answer as the list does, for the bricks around each listed one and far ones.
    constexpr int32_t reach = 1 << 18;
    std::mt19937 rng(17);
    for (int trial = 0; trial < 30; ++trial) {
        const bool beyond = trial % 3 == 2; // one brick past the table's reach: the set answers
        std::vector<LodBrick> bricks;
        std::set<std::tuple<int, int32_t, int32_t, int32_t>> listed;
        const int32_t centres[] = {0, -5, reach - 2, -reach + 1};
        for (int i = 0; i < 200; ++i) {
            const int32_t c = centres[rng() % 4];
            const LodBrick b{int(rng() % 5), {c + int32_t(rng() % 5) - 2, c + int32_t(rng() % 5) - 2, int32_t(rng() % 7) - 3}};
            bool fits = true;
            for (const int32_t v : b.brick) fits = fits && v >= -reach && v < reach;
            if (!fits) continue;
            if (listed.insert({b.level, b.brick[0], b.brick[1], b.brick[2]}).second) bricks.push_back(b);
        }
        if (beyond) {
            const LodBrick far{1, {reach, 0, -reach - 1}};
            bricks.push_back(far);
            listed.insert({far.level, far.brick[0], far.brick[1], far.brick[2]});
        }
        bricks.push_back(bricks.front()); // listed twice: still one brick
        const LodCut cut(bricks);
        std::size_t shown = 0, asked = 0;
        for (const LodBrick& b : bricks)
            for (int level = b.level - 1; level <= b.level + 1; ++level)
                for (int d = 0; d < 27; ++d) {
                    const LodBrick q{level, {b.brick[0] + d % 3 - 1, b.brick[1] + (d / 3) % 3 - 1, b.brick[2] + d / 9 - 1}};
                    const bool expected = listed.count({q.level, q.brick[0], q.brick[1], q.brick[2]}) > 0;
                    INFO("trial " << trial << ": brick " << q.level << " " << q.brick[0] << "," << q.brick[1] << "," << q.brick[2]);
                    REQUIRE(cut.shows(q) == expected);
                    shown += expected;
                    ++asked;
                }
        CHECK(shown > 0);
        CHECK(shown < asked);
        for (const LodBrick& far : {LodBrick{63, {0, 0, 0}}, LodBrick{0, {INT32_MIN, 0, 0}}, LodBrick{2, {0, INT32_MAX, 0}}})
            CHECK_FALSE(cut.shows(far));
    }
    CHECK_FALSE(LodCut().shows({0, {0, 0, 0}}));
    CHECK(LodCut(std::vector<LodBrick>{{3, {reach - 1, reach - 1, -reach}}}).shows({3, {reach - 1, reach - 1, -reach}}));
}

TEST_CASE("lod brick map: inserts and look-ups agree with a node-based map, packed keys or not", "[lod]")
{
    // Seeded random bricks near the origin (packed, many repeats: growth under collisions) and beyond the
    // packing's reach of +-2^18 (the fallback), levels 0-63 (63 does not pack), against std::map.
    constexpr int32_t reach = 1 << 18;
    for (const uint32_t seed : {1u, 2u, 3u}) {
        std::mt19937 rng(seed);
        LodBrickMap<uint32_t> map(seed == 1 ? 1 : 100);
        std::map<std::tuple<int, int32_t, int32_t, int32_t>, uint32_t> expected;
        const auto randomBrick = [&]() -> std::pair<int, std::array<int32_t, 3>> {
            std::uniform_int_distribution<int> level(0, 63), kind(0, 9), near(-6, 6), far(reach - 2, reach + 2);
            std::array<int32_t, 3> b{};
            for (int32_t& c : b) {
                const int k = kind(rng);
                c = k == 0 ? far(rng) : k == 1 ? -far(rng) : k == 2 ? INT32_MIN : k == 3 ? INT32_MAX : near(rng);
            }
            return {level(rng) % (kind(rng) == 0 ? 64 : 4), b};
        };
        for (int step = 0; step < 20000; ++step) {
            const auto [level, brick] = randomBrick();
            const auto key = std::make_tuple(level, brick[0], brick[1], brick[2]);
            if (step % 3 == 0) {
                const uint32_t* found = map.find(level, brick);
                const auto it = expected.find(key);
                REQUIRE((found != nullptr) == (it != expected.end()));
                if (found) REQUIRE(*found == it->second);
                continue;
            }
            const auto [value, inserted] = map.insert(level, brick);
            const auto [it, wasNew] = expected.try_emplace(key, 0u);
            REQUIRE(inserted == wasNew);
            REQUIRE(*value == it->second);
            *value = it->second = uint32_t(step);
        }
        REQUIRE(expected.size() > 1000);
        for (const auto& [key, value] : expected) {
            const uint32_t* found = map.find(std::get<0>(key), {std::get<1>(key), std::get<2>(key), std::get<3>(key)});
            REQUIRE(found != nullptr);
            REQUIRE(*found == value);
        }
    }
    uint64_t packed = 0;
    CHECK(packLodBrick(62, {reach - 1, -reach, 0}, packed));
    CHECK(packed != ~uint64_t(0));
    CHECK_FALSE(packLodBrick(63, {0, 0, 0}, packed));
    CHECK_FALSE(packLodBrick(0, {reach, 0, 0}, packed));
    CHECK_FALSE(packLodBrick(-1, {0, 0, 0}, packed));
}

TEST_CASE("lod cut: the bricks touching a box, looked up around it, are exactly those a pass over the cut finds", "[lod]")
{
    // Random cuts of an octree of levels 0-4 (a brick split into its children or not), and boxes of
    // every size near and across brick faces, negative coordinates included.
    std::mt19937 rng(91);
    for (int trial = 0; trial < 40; ++trial) {
        std::vector<LodBrick> bricks;
        std::vector<LodBrick> stack;
        for (int32_t x = -1; x <= 0; ++x)
            for (int32_t z = -1; z <= 0; ++z) stack.push_back({4, {x, 0, z}});
        const int splitOdds = 1 + trial % 4; // from few to many splits
        while (!stack.empty()) {
            const LodBrick b = stack.back();
            stack.pop_back();
            if (b.level > 0 && int(rng() % 5) < splitOdds) {
                for (int c = 0; c < 8; ++c)
                    stack.push_back({b.level - 1, {2 * b.brick[0] + (c & 1), 2 * b.brick[1] + ((c >> 1) & 1), 2 * b.brick[2] + ((c >> 2) & 1)}});
            } else {
                bricks.push_back(b);
            }
        }
        const LodCut cut(bricks);
        for (int box = 0; box < 50; ++box) {
            const int level = int(rng() % 5);
            const int64_t span = int64_t(kLodBrickVoxels) << level;
            LodCut::Point lo, hi;
            for (std::size_t a = 0; a < 3; ++a) {
                lo[a] = (int64_t(rng() % 4) - 2) * span + (box % 3 == 0 ? int64_t(rng() % 3) - 1 : 0);
                hi[a] = lo[a] + (box % 2 == 0 ? span : int64_t(rng() % 200));
            }
            std::set<std::tuple<int, int32_t, int32_t, int32_t>> found, expected;
            cut.forEachTouching(lo, hi, [&](const LodBrick& b) { CHECK(found.insert({b.level, b.brick[0], b.brick[1], b.brick[2]}).second); });
            for (const LodBrick& b : cut.bricks())
                if (LodCut::touches(b, lo, hi)) expected.insert({b.level, b.brick[0], b.brick[1], b.brick[2]});
            INFO("trial " << trial << " box " << box << " of " << bricks.size() << " bricks");
            CHECK(found == expected);
        }
    }
}

namespace {

/// A cut meshed with a plane tolerance against the same cut by the normals alone: closed, at least
/// `fewer` of the triangles gone, and within twice the tolerance of it (both read the same crossings:
/// they part by the tolerance and what a wider cell's polygon spans of a surface curving under it).
void checkMerged(const Mesh& exact, const Mesh& merged, const std::vector<LodBrick>& shown, double voxel, int level, double tolerance,
                 double fewer)
{
    INFO("level " << level << ": " << exact.triangleCount() << " triangles by the normals alone, " << merged.triangleCount()
                  << " with the plane tolerance");
    requireClosed(merged, voxel, shown);
    CHECK(double(merged.triangleCount()) < (1.0 - fewer) * double(exact.triangleCount()));
    const double levelVoxel = voxel * double(1 << level);
    const MeshQuality q = measureAgainstMesh(merged, exact, SurfaceSampling{0.5 * levelVoxel});
    INFO("two-sided distance " << q.maxDistance / levelVoxel << " voxels of the level, mean " << q.meanDistance / levelVoxel);
    CHECK(q.maxDistance < 2.0 * tolerance * levelVoxel);
    CHECK(q.meanDistance < 0.3 * tolerance * levelVoxel);
}

MeshOptions withTolerances(double level0, double coarse)
{
    MeshOptions o = cms();
    o.planeTolerance = level0;
    o.coarseLevelPlaneTolerance = coarse;
    return o;
}

} // namespace

TEST_CASE("lod mesh: coarse levels keep rippled cells whole within the plane tolerance: fewer triangles, the same surface within it, closed beside level 0", "[lod][plane]")
{
    // A coarse level's 8-bit densities leave ripples a fraction of a voxel high on smooth surfaces,
    // whose normals tilt past the subdivision angle: with the plane tolerance (half a voxel of the
    // level) their cells stay whole where the crossings lie that close to one plane.
    TempDir dir;
    const Volume volume = wideScene();
    const Levels levels = levelsOf(volume, 2, dir);
    for (int level = 1; level <= 2; ++level) {
        const auto shown = cutOf(levels, [&](const LodBrick& b) { return b.level > level; });
        checkMerged(meshCut(levels, shown, withTolerances(0.0, 0.0)), meshCut(levels, shown, withTolerances(0.0, 0.5)), shown,
                    volume.voxelSize(), level, 0.5, 0.1);
    }
    // Beside level 0 (the transition cells stay voxel cells): closed.
    for (int parity = 0; parity < 2; ++parity) {
        const auto shown = cutOf(levels, [&](const LodBrick& b) { return b.level > 1 || ((b.brick[0] + b.brick[1] + b.brick[2]) & 1) == parity; });
        requireClosed(meshCut(levels, shown, withTolerances(0.0, 0.5)), volume.voxelSize(), shown);
    }
}

TEST_CASE("lod mesh: a terrain meshed as a streaming scene meshes it (a quarter voxel's plane tolerance at level 0, half a voxel above) takes fewer triangles for the same surface", "[lod][plane]")
{
    // Noise-displaced ground with tunnels: its curved stretches make cells split at 15 degrees although
    // their crossings lie within a fraction of a voxel of one plane.
    TempDir dir;
    const SceneStore store = SceneStore::open(terrainStore(dir, "terrain.vdbclay", 128, 5, 1), StoreAccess::ReadOnly);
    const Volume level0 = store.loadLevel(0), level1 = store.loadLevel(1);
    const std::vector<const Volume*> volumes{&level0, &level1};
    const MeshOptions streaming = StreamingOptions().meshing;
    REQUIRE(streaming.planeTolerance == 0.25);
    REQUIRE(streaming.coarseLevelPlaneTolerance == 0.5);
    for (int level = 0; level <= 1; ++level) {
        std::vector<LodBrick> shown;
        store.bricks().scan(level, [&](const BrickKey& key, const BrickSummary&) { shown.push_back({level, key.brick}); });
        REQUIRE(!shown.empty());
        MeshOptions plain = streaming;
        plain.planeTolerance = plain.coarseLevelPlaneTolerance = 0.0;
        checkMerged(meshCut(volumes, shown, plain), meshCut(volumes, shown, streaming), shown, level0.voxelSize(), level,
                    level == 0 ? streaming.planeTolerance : streaming.coarseLevelPlaneTolerance, 0.2);
    }
}

TEST_CASE("lod mesh: coarse bricks simplified within a tolerance take fewer triangles, stay within it and closed beside each other and level 0", "[lod][simplify]")
{
    // Streaming scenes simplify coarse bricks' meshes (MeshOptions::coarseLevelSimplifyTolerance) brick by
    // brick, keeping each mesh's open edges: the bricks still meet, at every level and beside level 0.
    TempDir dir;
    const Volume terrain = SceneStore::open(terrainStore(dir, "terrain.vdbclay", 128, 5, 2), StoreAccess::ReadOnly).loadLevel(0);
    const Levels levels = levelsOf(terrain, 2, dir);
    const MeshOptions streaming = StreamingOptions().meshing;
    const double tolerance = streaming.coarseLevelSimplifyTolerance;
    REQUIRE(tolerance == 0.25);
    for (int level = 1; level <= 2; ++level) {
        const auto shown = cutOf(levels, [&](const LodBrick& b) { return b.level > level; });
        const Mesh lattice = meshCut(levels, shown, streaming), simplified = meshCutSimplified(levels.pointers(), shown, streaming);
        INFO("level " << level << ": " << lattice.triangleCount() << " triangles on the lattice, " << simplified.triangleCount() << " simplified");
        requireClosed(simplified, terrain.voxelSize(), shown);
        CHECK(double(simplified.triangleCount()) < 0.8 * double(lattice.triangleCount()));
        const double levelVoxel = terrain.voxelSize() * double(1 << level);
        const MeshQuality q = measureAgainstMesh(simplified, lattice, SurfaceSampling{0.25 * levelVoxel});
        INFO("two-sided distance " << q.maxDistance / levelVoxel << " voxels of the level, mean " << q.meanDistance / levelVoxel);
        CHECK(q.maxDistance <= tolerance * levelVoxel);
    }
    // Level 1 beside level 0 in checkerboards: closed.
    for (int parity = 0; parity < 2; ++parity) {
        const auto shown = cutOf(levels, [&](const LodBrick& b) { return b.level > 1 || ((b.brick[0] + b.brick[1] + b.brick[2]) & 1) == parity; });
        requireClosed(meshCutSimplified(levels.pointers(), shown, streaming), terrain.voxelSize(), shown);
    }
}

TEST_CASE("mesh options: plane and simplification tolerances outside 0 .. 8 voxels are refused", "[lod][plane]")
{
    for (const double bad : {-0.1, 8.5, std::nan("")}) {
        MeshOptions o = cms();
        o.planeTolerance = bad;
        CHECK_THROWS_AS(validateMeshOptions(o), std::invalid_argument);
        o = cms();
        o.coarseLevelPlaneTolerance = bad;
        CHECK_THROWS_AS(validateMeshOptions(o), std::invalid_argument);
        o = cms();
        o.coarseLevelSimplifyTolerance = bad;
        CHECK_THROWS_AS(validateMeshOptions(o), std::invalid_argument);
    }
    MeshOptions o = cms();
    o.planeTolerance = 8.0;
    CHECK_NOTHROW(validateMeshOptions(o));
}
