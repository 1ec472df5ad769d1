// Comparing two scenes (vdbclay diff), in either form: brick by brick, so two stores are compared
// without loading either whole. The regression check users run on synthetic scenes.
#pragma once

#include "vdb_hermite/VolumeRegions.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vdbclay {

struct SceneDiff {
    bool voxelSizesDiffer = false;
    bool materialTablesDiffer = false;
    std::vector<IndexCoord> differingBricks;  // brick coordinates (origin / 64), sorted
    uint64_t occupancyDifferences = 0;        // voxels solid in one scene and empty in the other
    uint64_t materialDifferences = 0;         // voxels solid in both, of different materials
    uint64_t sampleDifferences = 0;           // edges whose Hermite samples differ (same materials)
    double differenceVolume = 0.0;            // occupancy differences times the voxel volume, world units^3
    double surfaceDistance = 0.0;             // two-sided Hausdorff distance between the surfaces there, world
                                              // units; NaN where not measured (other voxel sizes)
    double voxelSize = 1.0;                   // a's
    double otherVoxelSize = 1.0;              // b's: where it differs, nothing else is compared

    bool identical() const { return !voxelSizesDiffer && !materialTablesDiffer && differingBricks.empty(); }
    /// Identical, or the same materials and voxel size with surfaces within `toleranceVoxels` of each other
    /// and no solid voxel of another material.
    bool withinTolerance(double toleranceVoxels) const;
};

/// Compares level 0 of two scenes, each a native .vdb or a store; with `measureSurface`, also the
/// surface distance (which meshes the differing bricks). Throws VolumeIOError / StoreError for
/// unreadable scenes.
SceneDiff diffScenes(const std::string& a, const std::string& b, bool measureSurface = true);

} // namespace vdbclay
