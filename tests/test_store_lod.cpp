// The store's LOD pyramid, built brick by brick: equal to the pyramid built in memory from the whole
// of level 0, kept equal to a rebuild by every edit, and refused when its densities are damaged.
#include "scene/DensityBrick.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/StoreSculpt.h"
#include "sculpt/StrokeScript.h"
#include "support/HermiteProbe.h"
#include "support/PyramidCompare.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "wavelet/LodPyramid.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <random>
#include <set>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// Solids on the lattice that touch, far from the origin: integer boxes as users type them.
Volume latticeScene()
{
    Volume v(1.0);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, box(Vec3d(64.0, 32.0, 40.0)), at(Vec3d(-200.0, 64.0, 128.0)));
    apply(v, CsgMode::Add, box(Vec3d(16.0, 16.0, 16.0)), at(Vec3d(-120.0, 64.0, 128.0)), red);
    apply(v, CsgMode::Remove, sphere(20.0), at(Vec3d(-200.0, 96.0, 128.0)));
    return v;
}

/// multiBrickScene in a store of `dir`, opened for writing, with three levels built.
SceneStore storeWithPyramid(const TempDir& dir)
{
    const std::string path = dir.file("s.vdbclay");
    writeStoreFile(multiBrickScene(), path);
    SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
    buildStoreLod(scene, 3);
    return scene;
}

std::string randomEdit(std::mt19937& rng)
{
    std::uniform_real_distribution<double> pos(-70.0, 70.0), radius(2.0, 16.0);
    const char* modes[] = {"add", "remove", "paint", "add", "remove"};
    nlohmann::json ops = nlohmann::json::array();
    for (int i = 0; i < 3; ++i) {
        nlohmann::json op{{"mode", modes[rng() % 5]},
                          {"brush", {{"shape", rng() % 2 ? "sphere" : "box"}, {"radius", std::round(radius(rng))},
                                     {"size", {std::round(radius(rng)), radius(rng), radius(rng)}}}},
                          {"at", {std::round(pos(rng)), std::round(pos(rng)), pos(rng)}}};
        if (op["mode"] != "remove") op["material"] = rng() % 2 ? "red" : "default";
        ops.push_back(op);
    }
    return nlohmann::json{{"materials", {{{"name", "red"}, {"color", {1, 0, 0, 1}}, {"toughness", 0.5}}}}, {"ops", ops}}.dump();
}

} // namespace

TEST_CASE("lod build brick by brick equals the pyramid built in memory from the whole scene", "[store][lod]")
{
    TempDir dir;
    int index = 0;
    for (const Volume& v : {multiBrickScene(), latticeScene()}) {
        const std::string path = dir.file("s" + std::to_string(index++) + ".vdbclay");
        writeStoreFile(v, path);
        SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
        CHECK(buildStoreLod(scene, 3) == 3);
        CHECK(scene.lodLevels() == 3);
        CHECK(lodFollowsEdits(scene));
        wavelet::LodPyramid pyramid(3);
        pyramid.build(v);
        uint64_t previous = scene.summary(0).leaves;
        for (int k = 1; k <= 3; ++k) {
            CAPTURE(index, k);
            const Volume level = scene.loadLevel(k);
            CHECK(level.voxelSize() == v.voxelSize() * double(1 << k));
            CHECK(checkInvariants(level).empty());
            CHECK(sameContent(level, pyramid.coarseVolume(v, k)));
            const uint64_t leaves = scene.summary(k).leaves;
            CHECK(leaves > 0);
            CHECK(leaves < previous);
            previous = leaves;
            // A density record per brick whose footprint holds a leaf, each with the pyramid's blocks.
            uint64_t blocks = 0;
            for (const IndexCoord& b : scene.brickCoords(-k))
                blocks += decodeDensityBrick(scene.bricks().get({-k, b})->payload, v.materials().size(), "d").blocks.size();
            CHECK(blocks == pyramid.blocks(k).size());
        }
    }
}

TEST_CASE("sculpting a store keeps every level of its pyramid equal to a rebuild", "[store][lod]")
{
    TempDir dir;
    SceneStore scene = storeWithPyramid(dir);
    std::mt19937 rng(20261202);
    uint64_t changedCoarse = 0;
    for (int edit = 0; edit < 10; ++edit) {
        CAPTURE(edit);
        const StoreSculptReport report = sculptStore(scene, parseStrokeScript(randomEdit(rng)));
        CHECK_FALSE(scene.lodStale());
        changedCoarse += report.lodBricksWritten;
        if (edit % 3 != 2) continue;
        CHECK(pyramidEqualsRebuild(scene, dir.file("fresh" + std::to_string(edit) + ".vdbclay")));
    }
    CHECK(changedCoarse > 0);
}

TEST_CASE("an edit on a store whose pyramid has no densities marks it stale, a rebuild replaces levels", "[store][lod]")
{
    TempDir dir;
    SceneStore scene = storeWithPyramid(dir);
    // What a store built before densities were kept looks like; and one built before coarse bricks were
    // resampled at their lattice points (refreshed bricks would lie half a voxel off their neighbours).
    const std::string key = GENERATE(std::string("lod_densities"), std::string("lod_aligned"));
    CAPTURE(key);
    {
        StoreTransaction t(scene.bricks());
        scene.bricks().putMeta(key, "0");
        t.commit();
    }
    CHECK_FALSE(lodFollowsEdits(scene));
    sculptStore(scene, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 4}, "at": [0, 75, 0]}]})"));
    CHECK(scene.lodStale());
    CHECK(buildStoreLod(scene, 2) == 2);
    CHECK(lodFollowsEdits(scene));
    CHECK(scene.lodLevels() == 2);
    CHECK(scene.summary(3).bricks == 0);
    CHECK(scene.brickCoords(-3).empty());
}

TEST_CASE("a damaged density record is refused with one line", "[store][lod]")
{
    DensityBrick brick;
    brick.slot[5] = 0;
    brick.blocks.emplace_back();
    brick.blocks[0].density.fill(200);
    brick.blocks[0].material.fill(1);
    brick.uniform[7] = 1;
    const std::string bytes = encodeDensityBrick(brick);
    const DensityBrick back = decodeDensityBrick(bytes, 1, "d");
    for (int s = 0; s < kBlocksPerBrick; ++s) CHECK(back.sameSlot(brick, s));
    CHECK_THROWS_AS(decodeDensityBrick(bytes, 0, "d"), StoreError); // a material the table lacks
    std::mt19937 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        std::string damaged = bytes;
        if (trial % 2) damaged.resize(rng() % damaged.size());
        else damaged[rng() % damaged.size()] ^= char(1 + rng() % 255);
        try {
            const DensityBrick d = decodeDensityBrick(damaged, 1, "d");
            CHECK(d.blocks.size() <= std::size_t(kBlocksPerBrick)); // a flipped density byte still decodes
        } catch (const StoreError& e) {
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
        }
    }
}
