// The differential checks run on each random scene (vdbclay selftest and the suite):
//   - the script parses and runs, and every mesher meshes the result without an exception;
//   - every voxel corner holds the material the exact replay of the ops gives it (ExactScene);
//   - Marching Cubes, uniform CMS and adaptive CMS each give a closed 2-manifold (analyzeTopology);
//   - the CMS mesh encloses the scene's exact volume, estimated by Monte Carlo, within its error bound;
//   - uniform and adaptive CMS have the same number of connected pieces;
//   - re-meshing after each op (MeshChunkSet::update) gives exactly the full re-mesh;
//   - one and two threads give bit-identical volumes and meshes.
#pragma once

#include "selftest/RandomScene.h"

#include <cstddef>
#include <string>

namespace vdbclay {

struct SceneCheckResult {
    bool passed = true;
    std::string failure;      // the first check that failed, in words
    std::size_t triangles = 0; // of the adaptive CMS mesh
    double volume = 0.0;      // enclosed by the uniform (or, adaptiveOnly, adaptive) CMS mesh
    double exactVolume = 0.0; // the Monte Carlo estimate
};

struct SceneCheckOptions {
    std::size_t volumeSamples = 20000; // Monte Carlo points for the exact volume
    bool compareThreads = true;        // also run on one and two threads
    bool checkIncremental = true;      // re-mesh op by op and compare with a full re-mesh
    bool checkLattice = true;          // every voxel corner against the exact replay
    bool adaptiveOnly = false;         // mesh with the default mesher (adaptive CMS) only
};

SceneCheckResult checkScene(const RandomScene& scene, const SceneCheckOptions& options = {});

/// The scene as a bug report: the failure and the commands that replay it, as JSON with the script.
std::string sceneReport(const RandomScene& scene, const SceneCheckResult& result);

} // namespace vdbclay
