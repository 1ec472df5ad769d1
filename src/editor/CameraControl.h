// Camera moves as a sculptor makes them (orbit about the target, pan, zoom towards the cursor, fly),
// and the pointer's ray: pure functions of the camera, so front ends turn mouse and keys into one
// `camera` command holding the result.
#pragma once

#include "editor/Ray.h"
#include "render/RenderTypes.h"
#include "scene/ViewSelection.h"

#include <array>
#include <optional>

namespace vdbclay {


/// The ray through pixel (x, y) (top left 0, 0; pixel centres at +0.5) of a viewport.
Ray pointerRay(const render::Camera& camera, const std::array<int, 2>& viewport, double x, double y);
/// Turns the eye about the target: yaw about the up axis, pitch towards it (kept 1 degree off the poles).
render::Camera orbit(const render::Camera& camera, double yawDegrees, double pitchDegrees);
/// Turns the camera about `pivot` (the surface point under the cursor when the orbit began): eye and
/// target turn together, so the view turns as much as orbit() would and the pivot stays where it is on
/// the screen. Pitch is kept 1 degree off the poles.
render::Camera orbitAbout(const render::Camera& camera, const std::array<double, 3>& pivot, double yawDegrees, double pitchDegrees);
/// The axis views (Blender's numpad): the camera looks at its target along an axis from the front (+z),
/// the right (+x) or the top (+y), or from the opposite side, at the same distance.
enum class AxisView { Front, Back, Right, Left, Top, Bottom };
render::Camera axisView(const render::Camera& camera, AxisView view);
/// How much farther a parallel view's eye stands than the perspective view it replaces.
constexpr double kParallelViewDistance = 300.0;
/// A parallel ("orthographic") view of what `camera` frames: the eye kParallelViewDistance times farther
/// back with the field of view narrowed so that the target's plane is drawn at the same scale. Rays then
/// cross the view within a third of a degree of each other, and everything that works for a perspective
/// camera (rays, levels of detail, the unbounded depth) works unchanged.
render::Camera parallelView(const render::Camera& camera);
/// The perspective view a parallel one stands for, with field of view `fovYDegrees`.
render::Camera perspectiveView(const render::Camera& parallel, double fovYDegrees);
/// Zooms a view by `factor` (> 1 zooms in) by narrowing its field of view about `toward` (the surface under
/// the cursor): what the wheel does to a parallel view, which has no distance to give up.
render::Camera zoomByFieldOfView(const render::Camera& camera, double factor, const std::optional<std::array<double, 3>>& toward);
/// Centres the view on `point` from the same direction, at `distance` from it.
render::Camera frameOn(const render::Camera& camera, const std::array<double, 3>& point, double distance);
/// Slides eye and target across the view by a pointer drag of (dx, dy) pixels: the point at the target's
/// depth follows the pointer.
render::Camera pan(const render::Camera& camera, const std::array<int, 2>& viewport, double dxPixels, double dyPixels);
/// Moves the eye towards `toward` (the surface under the cursor; the target when absent) so that the
/// distance shrinks by `factor` (> 1 zooms in); the target moves along so that the point stays put.
render::Camera zoomToward(const render::Camera& camera, double factor, const std::optional<std::array<double, 3>>& toward);
/// Moves eye and target together: `forward` along the view, `right` and `up` across it (world units).
render::Camera fly(const render::Camera& camera, double forward, double right, double up);
/// Where a ray meets the plane through `point` facing the camera (what a move brush drags along).
std::optional<std::array<double, 3>> dragPoint(const render::Camera& camera, const Ray& ray, const std::array<double, 3>& point);
/// The streaming scene's viewer for the camera and viewport.
Viewer viewerOf(const render::Camera& camera, const std::array<int, 2>& viewport);

} // namespace vdbclay
