// Sculpting a store in place: only the bricks the script's brushes reach are read, and only those
// whose content changed are written, in one transaction.
#pragma once

#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "sculpt/StrokeScript.h"

#include <functional>
#include <optional>
#include <utility>
#include <vector>

namespace vdbclay {

struct StoreSculptReport {
    std::vector<ScriptOpReport> ops;
    uint64_t bricksRead = 0;
    uint64_t bricksWritten = 0;
    uint64_t lodBricksWritten = 0; // coarse bricks the edit changed (none when no pyramid follows edits)
};

/// The level-0 voxels an op can read or change, min and max inclusive: its brush's bounds grown by two
/// voxels below (edges that start below reach into the brush) and by a leaf and two voxels above (the
/// CSG kernel reads the first layer of the +x, +y, +z neighbours), clamped to +-1e9. Nullopt when the
/// op reaches everything (intersect, unbounded brushes); an empty range (min > max) for a mask op, which
/// changes no voxel.
std::optional<std::pair<IndexCoord, IndexCoord>> voxelsReachedBy(const ScriptOp& op, double voxelSize);

/// The level-0 bricks a script's ops can read or change (sorted): every brush's bounds, grown as the
/// CSG kernel reads; `allBricks` is asked for the stored bricks when an op reaches everything
/// (intersect, unbounded brushes). Throws ScriptError when an op would reach more than 5e7 bricks.
std::vector<IndexCoord> bricksReachedBy(const StrokeScript& script, double voxelSize,
                                        const std::function<std::vector<IndexCoord>()>& allBricks);

/// Runs the script on the bricks its ops reach (all bricks for intersect and unbounded brushes) and
/// commits the changed ones, with the LOD pyramid above them brought up to date in the same transaction
/// (a pyramid that cannot follow edits, see lodFollowsEdits, is marked stale). The store must be open
/// for writing.
StoreSculptReport sculptStore(SceneStore& scene, const StrokeScript& script,
                              const std::function<void(const ScriptOpReport&)>& onOp = {});

} // namespace vdbclay
