// Synthetic scenes and scene comparison: synth is deterministic across thread counts and closed, diff
// finds a one-voxel change and accepts a re-save.
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "scene/SceneDiff.h"
#include "scene/SceneStore.h"
#include "scene/Synthesize.h"
#include "sculpt/StrokeScript.h"
#include "support/HermiteProbe.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <tbb/global_control.h>

using namespace vdbclay;
using namespace vdbclay::test;

TEST_CASE("synth is the same for any thread count and meshes closed", "[synth]")
{
    TempDir dir;
    for (const SynthKind kind : {SynthKind::Terrain, SynthKind::Asteroids, SynthKind::CsgStack}) {
        SynthOptions options;
        options.kind = kind;
        options.extent = 128;
        options.seed = 4;
        const std::string parallel = dir.file(std::string(synthKindName(kind)) + "-n.vdbclay");
        const std::string serial = dir.file(std::string(synthKindName(kind)) + "-1.vdbclay");
        const SynthReport report = synthesizeStore(options, parallel);
        {
            tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
            synthesizeStore(options, serial);
        }
        INFO(synthKindName(kind));
        CHECK(report.bricks > 0);
        CHECK(report.leaves > 0);
        const Volume a = loadScene(parallel), b = loadScene(serial);
        CHECK(identical(a, b));
        CHECK(diffScenes(parallel, serial, false).identical());
        CHECK(checkInvariants(a).empty());
        MeshOptions mo;
        mo.kind = MesherKind::CubicalMarchingSquares;
        CHECK(analyzeTopology(meshVolume(a, mo), kMergeDistanceVoxels).watertight());
        CHECK(a.materials().size() == 3);
        // Another seed gives another scene.
        options.seed = 5;
        synthesizeStore(options, serial);
        CHECK_FALSE(diffScenes(parallel, serial, false).identical());
    }
    SynthOptions bad;
    bad.extent = 4;
    CHECK_THROWS_AS(validateSynthOptions(bad), std::invalid_argument);
}

TEST_CASE("diff finds a one-voxel change, accepts a re-save, and measures the surface distance", "[diff]")
{
    TempDir dir;
    SynthOptions options;
    options.kind = SynthKind::CsgStack;
    options.extent = 96;
    options.seed = 2;
    const std::string store = dir.file("s.vdbclay");
    synthesizeStore(options, store);
    // A re-save through the native form, and back into a store.
    saveVolume(loadScene(store), dir.file("s.vdb"));
    writeStoreFile(loadVolume(dir.file("s.vdb")), dir.file("again.vdbclay"));
    CHECK(diffScenes(store, dir.file("s.vdb")).identical());
    CHECK(diffScenes(dir.file("s.vdb"), dir.file("again.vdbclay")).identical());

    // One voxel added against the face of a box on the lattice: one voxel of occupancy, in the two bricks
    // whose leaves hold its edges, and a surface moved by at most about a voxel.
    Volume v = loadScene(store);
    runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "box", "size": [10, 10, 10]},
                                                        "at": [200, 200, 200]}]})"));
    saveVolume(v, dir.file("boxed.vdb"));
    runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "box", "size": [0.5, 0.5, 0.5]},
                                                        "at": [211, 200, 200]}]})"));
    saveVolume(v, dir.file("changed.vdb"));
    const SceneDiff d = diffScenes(dir.file("boxed.vdb"), dir.file("changed.vdb"));
    CHECK_FALSE(d.identical());
    CHECK(d.differingBricks == std::vector<IndexCoord>{{3, 3, 3}});
    CHECK(d.occupancyDifferences == 1);
    CHECK(d.materialDifferences == 0);
    CHECK(d.differenceVolume == Approx(1.0));
    CHECK(d.surfaceDistance > 0.3);
    CHECK(d.surfaceDistance < 1.5);
    CHECK(d.withinTolerance(1.5));
    CHECK_FALSE(d.withinTolerance(0.0));

    // A repaint is never within tolerance.
    runStrokeScript(v, parseStrokeScript(R"({"materials": [{"name": "green"}], "ops": [{"mode": "paint", "material": "green",
                                             "brush": {"shape": "sphere", "radius": 4}, "at": [200, 210, 200]}]})"));
    saveVolume(v, dir.file("painted.vdb"));
    const SceneDiff painted = diffScenes(dir.file("changed.vdb"), dir.file("painted.vdb"));
    CHECK(painted.materialDifferences > 0);
    CHECK_FALSE(painted.withinTolerance(100.0));

    Volume other(0.5);
    saveVolume(other, dir.file("other.vdb"));
    const SceneDiff lattices = diffScenes(store, dir.file("other.vdb"));
    CHECK(lattices.voxelSizesDiffer);
    CHECK(lattices.otherVoxelSize == 0.5);
    CHECK(std::isnan(lattices.surfaceDistance)); // not measured, not zero
    CHECK_FALSE(lattices.withinTolerance(1e9));
}
