// A scene shown at several levels at once: each leaf-sized block at the level the view gives it, in one
// Hermite volume on the level-0 lattice. A block shown at level k holds level k's field prolongated
// onto the fine lattice (the piecewise-linear reconstruction of the Haar low-pass, sampled at the fine
// voxels), so the geometry is level k's; the mesher's adaptive cells cover it with few triangles where
// it is smooth. As the result is one consistent Hermite volume, the same mesher meshes it without
// cracks at level boundaries, with no crack patching and no skirts; the edges that cross a level
// boundary take their crossing from the fields on both sides.
#pragma once

#include "wavelet/LodPyramid.h"

#include <functional>

namespace vdbclay::wavelet {

/// The level (0 .. pyramid.levels()) each leaf-sized block of level-0 index space is shown at; called
/// from several threads at once.
using LevelOfBlock = std::function<int(const BlockOrigin& blockOrigin)>;

/// The mixed-level volume of `fine` (the volume the pyramid was built from).
Volume mixedLevelVolume(const Volume& fine, const LodPyramid& pyramid, const LevelOfBlock& levelOf);

} // namespace vdbclay::wavelet
