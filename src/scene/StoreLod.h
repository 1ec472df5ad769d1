// The LOD pyramid of a store, built and kept current brick by brick: level k's densities
// (DensityBrick.h) are made from level k-1's, and level k's coarse Hermite bricks from level k's
// densities, so no step holds more than a few bricks of any level (and a bounded cache of them).
#pragma once

#include "scene/SceneStore.h"

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace vdbclay {

/// What a pass over the pyramid did.
struct LodRefresh {
    /// Per level (index k - 1 for level k): the coarse Hermite bricks whose stored record changed, sorted.
    std::vector<std::vector<IndexCoord>> changedBricks;
    /// The coarse bricks' data errors the pass wrote (lodError), in order; nullopt where it erased one.
    std::vector<std::pair<BrickKey, std::optional<double>>> errors;
    uint64_t densityBricksComputed = 0;
    uint64_t hermiteBricksComputed = 0;

    uint64_t bricksWritten() const
    {
        uint64_t n = 0;
        for (const auto& level : changedBricks) n += level.size();
        return n;
    }
};

// Each coarse brick's data error is kept beside it (BrickStore::lodError): how far level k's surface may
// lie from level 0's, in world units. Level 1's is its distance from level 0 (wavelet::levelDeviation),
// and each level above adds its own distance from the level below to its children's largest error.
// Where a level lost or made a feature, the distance counts a whole voxel of that level. buildStoreLod
// and updateStoreLod keep them current (LodRefresh::errors lists what a pass wrote).

/// The number of levels that brings level 0's bounds (its bricks') down to about one brick per side.
int lodLevelsFor(const SceneStore& scene);

/// Builds (or rebuilds) levels 1 .. `levels` of the store from its level 0 (0 picks lodLevelsFor),
/// replacing what was there, in one transaction, brick by brick. Returns the level count.
int buildStoreLod(SceneStore& scene, int levels, const Progress& progress = {});

/// Whether the store's pyramid can follow edits brick by brick: built, not stale, with its densities
/// stored and its coarse bricks resampled at their lattice points (a pyramid built by an older VDBClay
/// lacks either; it is marked stale on an edit, and `vdbclay lod build` makes it anew).
bool lodFollowsEdits(const SceneStore& scene);

/// Brings every built level up to date after the given level-0 bricks were rewritten: recomputes the
/// densities above them and the coarse bricks where those changed. Call inside the transaction that
/// wrote the bricks; the store's pyramid must follow edits (lodFollowsEdits). Afterwards the store
/// equals what buildStoreLod gives.
LodRefresh updateStoreLod(SceneStore& scene, const std::vector<IndexCoord>& changedBricks);

} // namespace vdbclay
