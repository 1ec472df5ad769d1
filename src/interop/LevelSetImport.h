// Standard grids in: a level set (or a fog volume at an iso value) of another tool's .vdb file becomes
// Hermite data: materials from the sign at the lattice points, crossings where the linearly
// interpolated field crosses zero, normals from its gradient there.
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeRegions.h"

#include <optional>
#include <memory>
#include <string>
#include <vector>

namespace vdbclay {

struct LevelSetImportOptions {
    std::string grid;                // empty: chooseImportGrid's pick
    std::optional<double> iso;       // a fog volume needs it (solid where density > iso); a level set: solid where < iso (0)
    std::optional<double> voxelSize; // resample to it (default: the grid's own, when uniform)
    std::string material = "default";
    double maxResampledVoxels = double(1u << 28); // a resampling that would make more is refused, not run
    double memoryLimitBytes = 0.0; // the memory the import may count on (0: this machine's, usableMemoryBytes())
};

struct LevelSetImportReport {
    std::string grid, gridClass, valueType;
    bool fog = false;
    double voxelSize = 0.0;
    std::string resampled; // why the grid was resampled ("" where it was not)
    uint64_t crossings = 0;
};

/// Reads a level set or fog volume from a .vdb file that is not VDBClay's own (describeStandardVdb
/// checks it first). A grid whose transform is not a uniform scale with a translation on its lattice
/// (non-uniform voxels, rotation, shear, a translation off the lattice, another voxel size asked for) is
/// resampled onto VDBClay's lattice, and the report says why. A grid of no class reads as a fog volume
/// when its background is below the iso value, else as a level set; a reading that would make the
/// background solid (everything outside the grid's active voxels) is refused. Throws VolumeIOError (the file) or
/// std::invalid_argument (the options) with one line.
Volume importLevelSet(const std::string& path, const LevelSetImportOptions& options, LevelSetImportReport* report = nullptr);

/// importLevelSet in steps: the constructor reads and checks the grid and puts it on the lattice (the
/// same refusals); then the volume is built whole, or one leaf-aligned box at a time, so that a store is
/// written brick by brick whatever the solid's size. Boxes built one by one hold exactly what the whole
/// volume holds there.
class LevelSetImporter {
public:
    LevelSetImporter(const std::string& path, const LevelSetImportOptions& options);
    LevelSetImporter(LevelSetImporter&&) noexcept;
    LevelSetImporter& operator=(LevelSetImporter&&) noexcept;
    ~LevelSetImporter();

    double voxelSize() const;
    const MaterialTable& materials() const;
    /// The grid read and how; `crossings` is counted by whole().
    const LevelSetImportReport& report() const;
    uint64_t surfaceLeaves() const;
    /// The boxes of `edge` voxels (a multiple of 8, coordinates in units of edge) that may hold anything.
    std::vector<IndexCoord> occupiedBoxes(int32_t edge) const;
    /// The content of one box; adds its crossings to `crossings` (optional). Safe on several threads.
    Volume region(const LeafAlignedBox& box, uint64_t* crossings = nullptr) const;
    /// The whole volume; MemoryLimitError when its surface leaves would not fit in memory.
    Volume whole();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace vdbclay
