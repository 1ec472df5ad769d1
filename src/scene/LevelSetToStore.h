// A standard grid of another tool's .vdb imported straight into a new store, brick by brick: the
// volume is never whole in memory, so a small file holding a huge solid (a few inside tiles) imports
// in bounded memory.
#pragma once

#include "interop/LevelSetImport.h"
#include "scene/SceneStore.h"

#include <string>

namespace vdbclay {

struct StoreLevelSetReport {
    LevelSetImportReport levelSet;
    uint64_t bricks = 0, leaves = 0, activeVoxels = 0;
};

/// Imports `input` (importLevelSet's options and refusals) into a new store at `output` (createStoreFile:
/// replaced only once complete). Throws std::runtime_error when the reading holds no solid voxel.
StoreLevelSetReport importLevelSetToStore(const std::string& input, const LevelSetImportOptions& options, const std::string& output,
                                          const Progress& progress = {});

} // namespace vdbclay
