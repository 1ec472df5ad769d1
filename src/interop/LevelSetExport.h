// Standard grids out: a scene as the OpenVDB ecosystem reads it (Houdini, Blender, OpenVDB's tools): a
// narrow-band level set "surface", an Int32 grid "material", and optionally a fog volume "density".
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"

#include <cstdint>
#include <string>

namespace vdbclay {

struct LevelSetExportOptions {
    double halfWidth = 3.0; // voxels on each side of the surface
    bool fog = false;       // also a density grid (FOG_VOLUME): 1 inside, falling to 0 across the band
    // Material ids in an Int32Grid. Off: a FloatGrid of the same ids, since pyopenvdb (readAll) and
    // Blender read float grids only; ids below 2^24 are exact as floats.
    bool int32Material = false;
};

/// The file metadata key that marks a file as export-levelset's (so that a later export may replace
/// it, and nothing else's .vdb); its value is the VDBClay version that wrote it.
inline constexpr const char* kLevelSetExportMarker = "vdbclay_levelset_export";

struct LevelSetExportReport {
    uint64_t triangles = 0;       // of the mesh the distances are measured to
    uint64_t surfaceVoxels = 0;   // active voxels of the level set
    uint64_t materialVoxels = 0;  // active voxels of the material grid
};

/// Writes the standard grids of `volume` to `path` (atomically). Distances are exact to the scene's
/// CMS mesh on voxel cells (OpenVDB's meshToLevelSet over it), so sharp features keep their corners;
/// the sign is negative inside. Throws std::invalid_argument for a half width outside 1 .. 64.
void exportLevelSet(const Volume& volume, const std::string& path, const LevelSetExportOptions& options,
                    LevelSetExportReport* report = nullptr);

} // namespace vdbclay
