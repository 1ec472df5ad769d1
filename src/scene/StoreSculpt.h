// Sculpting a store in place: only the bricks the script's brushes reach are read, and only those
// whose content changed are written, in one transaction.
#pragma once

#include "scene/SceneStore.h"
#include "sculpt/StrokeScript.h"

#include <functional>
#include <vector>

namespace vdbclay {

struct StoreSculptReport {
    std::vector<ScriptOpReport> ops;
    uint64_t bricksRead = 0;
    uint64_t bricksWritten = 0;
};

/// Runs the script on the bricks its ops reach (all bricks for intersect and unbounded brushes) and
/// commits the changed ones. The store must be open for writing. Marks a built LOD pyramid stale.
StoreSculptReport sculptStore(SceneStore& scene, const StrokeScript& script,
                              const std::function<void(const ScriptOpReport&)>& onOp = {});

} // namespace vdbclay
