// Seeded random scenes through every differential check of src/selftest (the checks are listed in
// SceneChecks.h); `vdbclay selftest --scenes N --seed S` runs the same checks on as many as wanted.
#include "selftest/SceneChecks.h"

#include <catch2/catch.hpp>

using namespace vdbclay;

namespace {

void checkScenes(uint64_t seed, uint64_t count)
{
    for (uint64_t i = 0; i < count; ++i) {
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

TEST_CASE("random scenes, seed 1: lattice, closed meshes, volume, pieces, re-meshing, threads", "[random]")
{
    checkScenes(1, 150);
}

TEST_CASE("random scenes, seed 2: lattice, closed meshes, volume, pieces, re-meshing, threads", "[random]")
{
    checkScenes(2, 150);
}
