// The Haar transforms and the LOD pyramid: the paper's worked example, a hand-computed 3D case,
// bit-exact integer reconstruction, the pyramid against a dense decomposition of the same voxels,
// incremental updates against full rebuilds, and coarse meshes against the fine surface.
#include "mesher/LodMesh.h"
#include "mesher/MeshChunkSet.h"
#include "mesher/MeshMetrics.h"
#include "mesher/MeshQuality.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "wavelet/Haar.h"
#include "wavelet/LevelDeviation.h"
#include "wavelet/LodPyramid.h"
#include "wavelet/MixedLevels.h"
#include "support/HermiteProbe.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <cmath>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;
using namespace vdbclay::wavelet;

namespace {

std::size_t cubeIndex(int n, int x, int y, int z) { return (std::size_t(x) * n + std::size_t(y)) * n + std::size_t(z); }

/// A sculpted scene: a sphere, a box of a second material half in it, a hole.
Volume testScene()
{
    Volume v(0.5);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, sphere(14.0), at(Vec3d(1.3, -0.7, 2.1)));
    apply(v, CsgMode::Add, box(Vec3d(6.0, 5.0, 7.0)), at(Vec3d(10.0, 3.0, -2.0), Vec3d(0.0, 0.0, 30.0)), red);
    apply(v, CsgMode::Remove, sphere(4.5), at(Vec3d(-6.0, 2.0, 5.0)));
    return v;
}

} // namespace

TEST_CASE("averaging Haar reproduces the paper's worked example", "[wavelet]")
{
    const std::vector<double> coefficients = averagingDecompose1D({9, 7, 3, 5});
    CHECK(coefficients == std::vector<double>{6, 2, 1, -1});
    CHECK(averagingReconstruct1D(coefficients) == std::vector<double>{9, 7, 3, 5});
    CHECK_THROWS_AS(averagingDecompose1D({1, 2, 3}), std::invalid_argument);
}

TEST_CASE("a 2x2x2 cube decomposes into the hand-computed bands", "[wavelet]")
{
    // v(x, y, z) = 1 + 4x + 2y + z: the mean is 4.5, and the halves differ by 4 along x, 2 along y and 1
    // along z, so the averaging details are -2 (x), -1 (y), -0.5 (z) and the mixed bands are 0.
    std::vector<float> values(8);
    for (int x = 0; x < 2; ++x)
        for (int y = 0; y < 2; ++y)
            for (int z = 0; z < 2; ++z) values[cubeIndex(2, x, y, z)] = float(1 + 4 * x + 2 * y + z);
    const DenseHaar<float> haar = averagingDecompose3D(values, 2, 1);
    REQUIRE(haar.low.size() == 1);
    CHECK(haar.low[0] == 4.5f);
    const std::vector<float> expected{-2.0f, -1.0f, 0.0f, -0.5f, 0.0f, 0.0f, 0.0f}; // bands 1 .. 7
    CHECK(haar.details[0] == expected);
    CHECK(averagingExtract3D(haar, 0) == values);

    // The integer variant on the same cube: floor averages, plain differences.
    std::vector<LiftingValue> ints(values.begin(), values.end());
    const DenseHaar<LiftingValue> lifted = liftingDecompose3D(ints, 2, 1);
    // x: lows floor((v0 + v1) / 2) = 3 + 2y + z, details -4; y: lows floor((3+z + 5+z) / 2) = 4 + z,
    // details -2; z: low floor((4 + 5) / 2) = 4, detail -1.
    CHECK(lifted.low[0] == 4);
    CHECK(lifted.details[0] == std::vector<LiftingValue>{-4, -2, 0, -1, 0, 0, 0});
    CHECK(liftingExtract3D(lifted, 0) == ints);
}

TEST_CASE("integer Haar reconstructs every level bit-exactly", "[wavelet]")
{
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> density(0, 255);
    std::vector<int32_t> seq(64);
    for (int32_t& s : seq) s = density(rng) - 128;
    CHECK(liftingReconstruct1D(liftingDecompose1D(seq)) == seq);

    for (const int edge : {2, 8, 32}) {
        std::vector<LiftingValue> values(std::size_t(edge) * edge * edge);
        for (auto& v : values) v = LiftingValue(density(rng));
        const int levels = int(std::log2(edge));
        const DenseHaar<LiftingValue> haar = liftingDecompose3D(values, edge, levels);
        CHECK(liftingExtract3D(haar, 0) == values);
        // Each level's low-pass is the floor average of the level below, x then y then z.
        std::vector<LiftingValue> below = values;
        for (int k = 1; k <= levels; ++k) {
            const int e = edge >> k;
            std::vector<LiftingValue> expected(std::size_t(e) * e * e);
            for (int x = 0; x < e; ++x)
                for (int y = 0; y < e; ++y)
                    for (int z = 0; z < e; ++z) {
                        auto at = [&](int i, int j, int l) {
                            return int(below[cubeIndex(2 * e, 2 * x + i, 2 * y + j, 2 * z + l)]);
                        };
                        int lx[2][2], ly[2];
                        for (int j = 0; j < 2; ++j)
                            for (int l = 0; l < 2; ++l) lx[j][l] = (at(0, j, l) + at(1, j, l)) >> 1;
                        for (int l = 0; l < 2; ++l) ly[l] = (lx[0][l] + lx[1][l]) >> 1;
                        expected[cubeIndex(e, x, y, z)] = LiftingValue((ly[0] + ly[1]) >> 1);
                    }
            CHECK(liftingExtract3D(haar, k) == expected);
            below = expected;
        }
    }
    CHECK_THROWS_AS(liftingDecompose3D(std::vector<LiftingValue>(27), 3, 1), std::invalid_argument);
    CHECK_THROWS_AS(liftingDecompose3D(std::vector<LiftingValue>(8), 2, 2), std::invalid_argument);
}

TEST_CASE("dropping small details costs at most 7 thresholds per level", "[wavelet]")
{
    std::mt19937 rng(11);
    std::normal_distribution<float> noise(0.0f, 3.0f);
    const int edge = 16, levels = 4;
    std::vector<float> values(std::size_t(edge) * edge * edge);
    for (int x = 0; x < edge; ++x)
        for (int y = 0; y < edge; ++y)
            for (int z = 0; z < edge; ++z) values[cubeIndex(edge, x, y, z)] = float(x + y * y * 0.1) + noise(rng);
    DenseHaar<float> haar = averagingDecompose3D(values, edge, levels);
    CHECK(dropSmallDetails(haar, 0.0f) == 0);
    const float threshold = 1.0f;
    const std::size_t dropped = dropSmallDetails(haar, threshold);
    CHECK(dropped > 0);
    const std::vector<float> lossy = averagingExtract3D(haar, 0);
    double worst = 0.0;
    for (std::size_t i = 0; i < values.size(); ++i) worst = std::max(worst, double(std::fabs(lossy[i] - values[i])));
    CHECK(worst > 0.0);
    CHECK(worst <= 7.0 * levels * threshold + 1e-4);
}

TEST_CASE("the pyramid's densities are the dense integer decomposition of the same voxels", "[wavelet]")
{
    const Volume v = testScene();
    LodPyramid pyramid(3);
    pyramid.build(v);
    // Every level-3 block: its footprint is 64^3 level-0 voxels.
    REQUIRE(!pyramid.blocks(3).empty());
    for (const auto& [origin, block] : pyramid.blocks(3)) {
        const int n = 64;
        std::vector<LiftingValue> dense(std::size_t(n) * n * n);
        for (int x = 0; x < n; ++x)
            for (int y = 0; y < n; ++y)
                for (int z = 0; z < n; ++z) {
                    const std::array<int32_t, 3> ijk{origin[0] * 8 + x, origin[1] * 8 + y, origin[2] * 8 + z};
                    dense[cubeIndex(n, x, y, z)] = v.materialAt(ijk) != kEmptyMaterial ? kFullDensity : 0;
                }
        const DenseHaar<LiftingValue> haar = liftingDecompose3D(dense, n, 3);
        for (int x = 0; x < 8; ++x)
            for (int y = 0; y < 8; ++y)
                for (int z = 0; z < 8; ++z)
                    REQUIRE(int(block.density[std::size_t((x << 6) | (y << 3) | z)]) == int(haar.low[cubeIndex(8, x, y, z)]));
    }
}

TEST_CASE("an edit updates the pyramid exactly as a full rebuild", "[wavelet]")
{
    Volume v = testScene();
    LodPyramid pyramid(4);
    pyramid.build(v);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> pos(-20.0, 20.0), radius(1.0, 6.0);
    const CsgMode modes[] = {CsgMode::Add, CsgMode::Remove, CsgMode::Paint};
    for (int edit = 0; edit < 12; ++edit) {
        const CsgMode mode = modes[edit % 3];
        const EditStats stats = apply(v, mode, sphere(radius(rng)), at(Vec3d(pos(rng), pos(rng), pos(rng))), edit % 2 + 1);
        const LodUpdate update = pyramid.update(v, stats.blockChanges);
        LodPyramid rebuilt(4);
        rebuilt.build(v);
        INFO("edit " << edit);
        REQUIRE(pyramid == rebuilt);
        if (!stats.blockChanges.empty()) CHECK(update.blocksRecomputed > 0);
    }
    // Removing everything empties every level.
    const EditStats cleared = applyCsg(v, Brush(sphere(200.0), at(Vec3d(0.0))), op(CsgMode::Remove));
    pyramid.update(v, cleared.blockChanges);
    for (int k = 1; k <= 4; ++k) CHECK(pyramid.blocks(k).empty());
}

TEST_CASE("the pyramid is the same for any thread count", "[wavelet]")
{
    const Volume v = testScene();
    LodPyramid parallel(3), serial(3);
    parallel.build(v);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial.build(v);
    }
    CHECK(parallel == serial);
}

TEST_CASE("coarse levels mesh watertight within an error that grows with 2^k", "[wavelet][lod]")
{
    Volume v(1.0);
    const double r = 40.0;
    apply(v, CsgMode::Add, sphere(r), at(Vec3d(0.3, -0.2, 0.1)));
    LodPyramid pyramid(3);
    pyramid.build(v);
    MeshOptions options;
    options.kind = MesherKind::CubicalMarchingSquares;
    options.maxCellWidth = 1; // voxel cells: each level has about a quarter of the triangles of the one below
    const auto sdf = [&](const Point3d& p) {
        return std::sqrt((p[0] - 0.3) * (p[0] - 0.3) + (p[1] + 0.2) * (p[1] + 0.2) + (p[2] - 0.1) * (p[2] - 0.1)) - r;
    };
    std::size_t previousTriangles = ~std::size_t(0);
    for (int k = 0; k <= 3; ++k) {
        const Mesh mesh = meshLevel(v, pyramid, k, options);
        INFO("level " << k);
        REQUIRE(mesh.triangleCount() > 0);
        CHECK(analyzeTopology(mesh, kMergeDistanceVoxels).watertight());
        const MeshQuality q = measureAgainstSdf(mesh, sdf);
        CHECK(q.maxDistance <= 0.25 * double(1 << k) + 0.25);
        CHECK(mesh.triangleCount() < previousTriangles);
        previousTriangles = mesh.triangleCount();
        const double volume = enclosedVolume(mesh), exact = 4.0 / 3.0 * kPi * r * r * r;
        CHECK(std::fabs(volume - exact) / exact < 0.02 * double(1 << k));
    }
    CHECK_THROWS_AS(meshLevel(v, pyramid, 4, options), std::invalid_argument);
}

TEST_CASE("material boundaries survive coarsening where a material spans more than a coarse cell", "[wavelet][lod]")
{
    Volume v(1.0);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, box(Vec3d(20.0, 20.0, 20.0)), at(Vec3d(-20.3, 0.2, 0.1)));
    apply(v, CsgMode::Add, box(Vec3d(20.0, 20.0, 20.0)), at(Vec3d(19.7, 0.2, 0.1)), red);
    LodPyramid pyramid(3);
    pyramid.build(v);
    MeshOptions options;
    options.kind = MesherKind::CubicalMarchingSquares;
    for (int k = 1; k <= 3; ++k) {
        const Mesh mesh = meshLevel(v, pyramid, k, options);
        INFO("level " << k);
        CHECK(analyzeTopology(mesh, kMergeDistanceVoxels).watertight());
        // Every vertex of a red triangle lies on the red side of the boundary plane x = -0.3, within a
        // coarse voxel; and both materials are there.
        std::size_t redTriangles = 0, defaultTriangles = 0;
        double worst = 0.0;
        for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
            const bool isRed = mesh.triangleMaterials[t] == red;
            (isRed ? redTriangles : defaultTriangles)++;
            for (uint32_t i : mesh.triangles[t]) {
                const double x = mesh.positions[i][0] + 0.3;
                worst = std::max(worst, isRed ? -x : x);
            }
        }
        CHECK(redTriangles > 0);
        CHECK(defaultTriangles > 0);
        CHECK(worst <= double(1 << k));
    }
}

TEST_CASE("coarse meshes follow an edit through the pyramid's update", "[wavelet][lod]")
{
    Volume v = testScene();
    const int level = 2;
    LodPyramid pyramid(3);
    pyramid.build(v);
    Volume coarse = pyramid.coarseVolume(v, level);
    MeshOptions options;
    options.kind = MesherKind::CubicalMarchingSquares;
    MeshChunkSet chunks(options);
    chunks.rebuild(coarse);
    const EditStats stats = apply(v, CsgMode::Remove, sphere(5.0), at(Vec3d(12.0, 3.0, 4.0)));
    const LodUpdate update = pyramid.update(v, stats.blockChanges);
    REQUIRE(!update.changedBlocks[level - 1].empty());
    const std::vector<BlockChange> changes =
        pyramid.updateCoarseVolume(v, level, update.changedBlocks[level - 1], coarse);
    CHECK(!changes.empty());
    chunks.update(coarse, changes);
    MeshChunkSet rebuilt(options);
    rebuilt.rebuild(pyramid.coarseVolume(v, level));
    CHECK(identical(chunks, rebuilt));
}

namespace {

/// Meshes a mixed-level volume with every mesher and checks it is closed.
void requireClosedAtMixedLevels(const Volume& v, const LodPyramid& pyramid, const LevelOfBlock& levelOf, const char* what)
{
    const Volume mixed = mixedLevelVolume(v, pyramid, levelOf);
    REQUIRE(checkInvariants(mixed).empty());
    CHECK(!changedBlocks(mixed, v).empty()); // the coarse regions show another surface than level 0
    for (const auto& [kind, width] : {std::pair{MesherKind::CubicalMarchingSquares, 8}, std::pair{MesherKind::CubicalMarchingSquares, 1},
                                      std::pair{MesherKind::MarchingCubes, 1}}) {
        MeshOptions options;
        options.kind = kind;
        options.maxCellWidth = width;
        const Mesh mesh = meshVolume(mixed, options);
        const MeshTopology t = analyzeTopology(mesh, kMergeDistanceVoxels * v.voxelSize());
        INFO(what << ", " << mesherName(kind) << " cells " << width << ": " << t.boundaryEdges << " boundary, "
                  << t.nonManifoldEdges << " non-manifold, " << t.pinchedVertices << " pinched");
        CHECK(mesh.triangleCount() > 0);
        CHECK(t.watertight());
    }
}

} // namespace

TEST_CASE("a scene shown at mixed levels meshes watertight", "[wavelet][lod][mixed]")
{
    Volume v(1.0);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, sphere(22.0), at(Vec3d(0.3, -0.4, 0.2)));
    // A box whose sharp edges and corners cross level boundaries, and a second material against it.
    apply(v, CsgMode::Add, box(Vec3d(12.0, 9.0, 14.0)), at(Vec3d(24.0, 3.0, 1.0), Vec3d(0.0, 30.0, 0.0)));
    apply(v, CsgMode::Add, box(Vec3d(10.0, 10.0, 10.0)), at(Vec3d(24.0, -16.0, 1.0)), red);
    LodPyramid pyramid(3);
    pyramid.build(v);

    SECTION("a checkerboard of levels 0 and 1, and of all four levels")
    {
        requireClosedAtMixedLevels(v, pyramid, [](const BlockOrigin& o) { return ((o[0] + o[1] + o[2]) / 8 & 1) ? 1 : 0; },
                                   "checkerboard 0/1");
        requireClosedAtMixedLevels(v, pyramid, [](const BlockOrigin& o) { return std::abs((o[0] / 8) + 2 * (o[1] / 8) + (o[2] / 8)) % 4; },
                                   "levels 0 to 3");
    }
    SECTION("a level boundary across the sharp edges and the material boundary")
    {
        // x >= 24 at level 2: the plane cuts the box's edges and the red box's interface with it.
        requireClosedAtMixedLevels(v, pyramid, [](const BlockOrigin& o) { return o[0] >= 24 ? 2 : 0; }, "plane x = 24");
        requireClosedAtMixedLevels(v, pyramid, [](const BlockOrigin& o) { return o[1] >= -8 ? 0 : 3; }, "plane y = -8");
    }
    SECTION("one level everywhere is that level's surface")
    {
        const Volume allFine = mixedLevelVolume(v, pyramid, [](const BlockOrigin&) { return 0; });
        CHECK(changedBlocks(allFine, v).empty());
    }
}

TEST_CASE("level deviation: a coarse level of a smooth shape lies within a fraction of its voxel, a lost feature counts", "[wavelet][lod]")
{
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(40.0), at(Vec3d(0.3, -0.2, 0.1)));
    LodPyramid pyramid(3);
    pyramid.build(v);
    const std::array<double, 3> lo{-64.0, -64.0, -64.0}, hi{64.0, 64.0, 64.0};
    constexpr double kUnmatched = 1000.0;
    for (int k = 1; k <= 3; ++k) {
        const Volume coarse = pyramid.coarseVolume(v, k);
        const Volume fine = k == 1 ? v.clone() : pyramid.coarseVolume(v, k - 1);
        const double voxel = coarse.voxelSize();
        const double d = levelDeviation(coarse, fine, lo, hi, kUnmatched);
        INFO("level " << k << ": " << d << " against voxel " << voxel);
        CHECK(d > 0.0);
        CHECK(d < 0.4 * voxel); // the box filter's rounding, not a voxel: the levels match in place
        // Symmetric in what it measures: a level against itself lies nowhere off.
        CHECK(levelDeviation(coarse, coarse, lo, hi, kUnmatched) == 0.0);
    }
    // A plate one level-0 voxel thick (lattice points y = 53 only) has half a level-1 voxel's density and
    // vanishes there: its crossings find no surface near them.
    apply(v, CsgMode::Add, box(Vec3d(20.0, 0.4, 20.0)), at(Vec3d(0.2, 53.0, 0.3)));
    pyramid.build(v);
    CHECK(levelDeviation(pyramid.coarseVolume(v, 1), v, lo, hi, kUnmatched) == kUnmatched);
    // Nothing crosses an empty box.
    CHECK(levelDeviation(pyramid.coarseVolume(v, 1), v, {200.0, 200.0, 200.0}, {264.0, 264.0, 264.0}, kUnmatched) == 0.0);
}
