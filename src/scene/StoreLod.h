// The LOD pyramid of a store: built from level 0 and kept as coarse bricks, one level per voxel size.
#pragma once

#include "scene/SceneStore.h"

namespace vdbclay {

/// Builds (or refreshes) levels 1 .. `levels` of the store from its level 0 (0 picks
/// LodPyramid::levelsFor), replacing what was there, in one transaction. Returns the level count.
/// For now the whole of level 0 is loaded to build the pyramid.
int buildStoreLod(SceneStore& scene, int levels, const Progress& progress = {});

} // namespace vdbclay
