// Cameras that frame a box: the default view of `vdbclay render`, thumbnails, the demo's picture.
#pragma once

#include "render/RenderTypes.h"

namespace vdbclay::render {

/// A camera looking at the centre of the box [lo, hi] from a three-quarter view (from +x, +y, +z),
/// far enough that the box's bounding sphere fits the vertical and horizontal fields of view, with
/// near and far planes around it.
Camera framingCamera(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double aspect,
                     double fovYDegrees = 40.0);

/// Chooses near and far planes for `camera` that hold the box [lo, hi] (near at least 1e-4 of far).
void fitDepthRange(Camera& camera, const std::array<double, 3>& lo, const std::array<double, 3>& hi);

} // namespace vdbclay::render
