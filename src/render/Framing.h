// Cameras that frame a box: the default view of `vdbclay render`, thumbnails, the demo's picture.
#pragma once

#include "render/RenderTypes.h"

#include <vector>

namespace vdbclay::render {

/// A camera looking at the centre of the box [lo, hi] from a three-quarter view (from +x, +y, +z),
/// just far enough that every corner of the box lies inside the view, with near and far planes around it.
Camera framingCamera(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double aspect,
                     double fovYDegrees = 40.0);

/// The same camera, just far enough that every one of `points` lies inside the view (tighter than the
/// box for round shapes); the box [lo, hi] holds the points and sets the depth range.
Camera framingCamera(const std::vector<std::array<float, 3>>& points, const std::array<double, 3>& lo,
                     const std::array<double, 3>& hi, double aspect, double fovYDegrees = 40.0);

/// Adds what frames a mesh to `outline`: a mesh of at most 64 vertices whole (one voxel's), a larger one's
/// every 8th vertex and those farthest along the axes and diagonals both ways (a box's corners).
void appendOutline(const std::vector<std::array<float, 3>>& positions, std::vector<std::array<float, 3>>& outline);

/// Puts the near plane of `camera` just in front of the box [lo, hi] (what may be drawn), or a hair from
/// the eye (1e-6 of the distance to the box's far side) once the eye is in or at the box: zooming up to
/// a surface never cuts it, and the reversed, unbounded depth keeps its precision at every distance.
void fitNearPlane(Camera& camera, const std::array<double, 3>& lo, const std::array<double, 3>& hi);

} // namespace vdbclay::render
