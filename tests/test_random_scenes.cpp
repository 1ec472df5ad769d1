// Seeded random scenes through every differential check of src/selftest (the checks are listed in
// SceneChecks.h); `vdbclay selftest --scenes N --seed S` runs the same checks on as many as wanted.
#include "selftest/SceneChecks.h"

#include <catch2/catch.hpp>

#include <cstdlib>

using namespace vdbclay;

namespace {

void checkScenes(uint64_t seed, uint64_t first, uint64_t count)
{
    for (uint64_t i = first; i < first + count; ++i) {
        const RandomScene scene = randomScene(seed, i);
        const SceneCheckResult result = checkScene(scene);
        INFO(sceneReport(scene, result));
        REQUIRE(result.passed);
    }
}


} // namespace

TEST_CASE("random scenes: the same seed and index give the same scene", "[random]")
{
    CHECK(randomScene(7, 3).script == randomScene(7, 3).script);
    CHECK(randomScene(7, 3).script != randomScene(7, 4).script);
    CHECK(randomScene(7, 3).script != randomScene(8, 3).script);
}

// Each seed's 150 scenes in two halves: CTest runs them side by side, each well inside its timeout under
// the sanitizers (the reshaping brushes at the end of a third of the scenes cost more than CSG ops).
TEST_CASE("random scenes, seed 1, scenes 0-74: lattice, closed meshes, volume, pieces, re-meshing, threads", "[random]")
{
    checkScenes(1, 0, 75);
}

TEST_CASE("random scenes, seed 1, scenes 75-149: lattice, closed meshes, volume, pieces, re-meshing, threads", "[random]")
{
    checkScenes(1, 75, 75);
}

TEST_CASE("random scenes, seed 2, scenes 0-74: lattice, closed meshes, volume, pieces, re-meshing, threads", "[random]")
{
    checkScenes(2, 0, 75);
}

TEST_CASE("random scenes, seed 2, scenes 75-149: lattice, closed meshes, volume, pieces, re-meshing, threads", "[random]")
{
    checkScenes(2, 75, 75);
}

// Scenes that larger selftest runs once found failing, kept so that they stay fixed: two wedge chains
// reaching into one clear square from opposite sides shared a point (seeds 3 and 31), two components
// of one cell had their sharp vertices clamped to the same corner (seed 104), and a material
// transition landed on a lattice line that a square at right angles also used (seed 109).
TEST_CASE("random scenes that once failed stay fixed", "[random]")
{
    for (const auto& [seed, index] : {std::pair<uint64_t, uint64_t>{3, 228}, {31, 401}, {104, 974}, {109, 596}}) {
        const RandomScene scene = randomScene(seed, index);
        const SceneCheckResult result = checkScene(scene);
        INFO("seed " << seed << " scene " << index << ": " << sceneReport(scene, result));
        CHECK(result.passed);
    }
}

// Every primitive of `vdbclay new`, every quarter voxel from 40 to 100 voxels (integer sizes put faces
// on lattice planes and spheres through lattice points), meshed by the default mesher: closed
// 2-manifold and the exact volume. `vdbclay selftest --sweep` runs it with every mesher.
namespace {

void sweepSizes(const char* shape)
{
    SceneCheckOptions options;
    options.checkLattice = false;
    options.compareThreads = false;
    options.checkIncremental = false;
    options.adaptiveOnly = true;
    options.volumeSamples = 4000;
    // The sanitizer build walks the same sizes in whole voxels (VDBCLAY_SWEEP_STEP=1, set by
    // scripts/bootstrap.sh): the same code paths, at a fifth of its cost.
    const char* stepText = std::getenv("VDBCLAY_SWEEP_STEP");
    const double step = stepText && std::atof(stepText) > 0.0 ? std::atof(stepText) : 0.25;
    for (double size = 40.0; size <= 100.0; size += step) {
        const RandomScene scene = primitiveScene(shape, size, 1.0);
        const SceneCheckResult result = checkScene(scene, options);
        INFO(shape << " of size " << size << ": " << sceneReport(scene, result));
        REQUIRE(result.passed);
    }
}

} // namespace

TEST_CASE("size sweep 40 .. 100 voxels: spheres", "[random][sweep]") { sweepSizes("sphere"); }
TEST_CASE("size sweep 40 .. 100 voxels: boxes", "[random][sweep]") { sweepSizes("box"); }
TEST_CASE("size sweep 40 .. 100 voxels: cylinders", "[random][sweep]") { sweepSizes("cylinder"); }
TEST_CASE("size sweep 40 .. 100 voxels: capsules", "[random][sweep]") { sweepSizes("capsule"); }
TEST_CASE("size sweep 40 .. 100 voxels: tori", "[random][sweep]") { sweepSizes("torus"); }
TEST_CASE("size sweep 40 .. 100 voxels: cones", "[random][sweep]") { sweepSizes("cone"); }
