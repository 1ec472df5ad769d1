// .vdb files of other tools (Houdini, Blender, OpenVDB's own): what they hold, checked before OpenVDB
// parses them (vdb_hermite/PayloadCheck.h), so a damaged or hostile file gets one clear line.
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/PayloadCheck.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vdbclay {

struct StandardGridInfo {
    GridHeader header; // header.name is OpenVDB's unique name ("surface", or "surface\x1e1" for a repeated one)
    /// The name a user types to pick this grid: the grid's name, or "surface[1]" where names repeat
    /// (OpenVDB's own form); `baseName` is the name the tool that wrote the file gave it.
    std::string name, baseName;
    bool selectable = false; // OpenVDB can read it by `name` (a crafted unique name may not map back)
    std::array<double, 3> voxelSize{0.0, 0.0, 0.0};
    bool uniformVoxels = false;
    bool axisAligned = false; // a scale and translation only (no rotation or shear)
    bool usableTransform = false; // finite, invertible, voxels within VDBClay's voxel size range
    uint64_t activeVoxels = 0;
    bool levelSet() const { return header.gridClass == "level set"; }
    bool fogVolume() const { return header.gridClass == "fog volume"; }
    /// Whether `vdbclay import` can bring it in: a float or double grid.
    bool importable() const
    {
        return header.treeChecked && usableTransform && selectable && (header.valueType == "float" || header.valueType == "double");
    }
};

struct StandardVdbInfo {
    std::vector<StandardGridInfo> grids;
};

/// Checks a .vdb file that is not VDBClay's own and describes its grids (the ones of types VDBClay
/// does not read too, from their headers). Throws VolumeIOError with one line.
StandardVdbInfo describeStandardVdb(const std::string& path);

/// The grid an import takes: the one named `name` (its typable name, or its base name when no other
/// grid shares it), or (empty name) the first level set, else the first fog volume, else the first
/// float or double grid. Throws VolumeIOError naming what the file holds.
const StandardGridInfo& chooseImportGrid(const StandardVdbInfo& info, const std::string& name, const std::string& path);

/// One line per grid for messages: "name (class, value type)".
std::string listGrids(const StandardVdbInfo& info);

} // namespace vdbclay
