#include "render/Framing.h"

#include <algorithm>
#include <cmath>

namespace vdbclay::render {

void fitDepthRange(Camera& camera, const std::array<double, 3>& lo, const std::array<double, 3>& hi)
{
    double radius2 = 0.0, distance2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double c = 0.5 * (lo[std::size_t(a)] + hi[std::size_t(a)]);
        const double r = 0.5 * (hi[std::size_t(a)] - lo[std::size_t(a)]);
        radius2 += r * r;
        const double d = camera.eye[std::size_t(a)] - c;
        distance2 += d * d;
    }
    const double radius = std::max(std::sqrt(radius2), 1e-6), distance = std::sqrt(distance2);
    camera.farPlane = distance + radius * 1.01;
    camera.nearPlane = std::max(distance - radius * 1.01, camera.farPlane * 1e-4);
}

Camera framingCamera(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double aspect, double fovYDegrees)
{
    Camera camera;
    camera.fovYDegrees = fovYDegrees;
    double radius2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        camera.target[std::size_t(a)] = 0.5 * (lo[std::size_t(a)] + hi[std::size_t(a)]);
        const double r = 0.5 * (hi[std::size_t(a)] - lo[std::size_t(a)]);
        radius2 += r * r;
    }
    const double radius = std::max(std::sqrt(radius2), 1e-6);
    const double halfY = 0.5 * fovYDegrees * M_PI / 180.0;
    const double halfX = std::atan(std::tan(halfY) * aspect);
    const double distance = radius / std::sin(std::min(halfX, halfY)) * 1.02;
    const double dir[3] = {0.62, 0.52, 0.59}; // a three-quarter view, a little from above
    const double norm = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int a = 0; a < 3; ++a) camera.eye[std::size_t(a)] = camera.target[std::size_t(a)] + dir[a] / norm * distance;
    fitDepthRange(camera, lo, hi);
    return camera;
}

} // namespace vdbclay::render
