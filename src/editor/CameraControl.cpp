#include "editor/CameraControl.h"

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace vdbclay {

namespace {

glm::dvec3 vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
std::array<double, 3> arr(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

struct Frame {
    glm::dvec3 forward, right, up;
    double distance;
};

Frame frameOf(const render::Camera& c)
{
    Frame f;
    const glm::dvec3 d = vec(c.target) - vec(c.eye);
    f.distance = glm::length(d);
    f.forward = d / f.distance;
    f.right = glm::normalize(glm::cross(f.forward, vec(render::usableUp(c))));
    f.up = glm::cross(f.right, f.forward);
    return f;
}

} // namespace

Ray pointerRay(const render::Camera& camera, const std::array<int, 2>& viewport, double x, double y)
{
    const Frame f = frameOf(camera);
    const double tanHalf = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    const double aspect = double(viewport[0]) / double(std::max(1, viewport[1]));
    const double ndcX = 2.0 * x / double(viewport[0]) - 1.0, ndcY = 1.0 - 2.0 * y / double(viewport[1]);
    const glm::dvec3 d = glm::normalize(f.forward + f.right * (ndcX * tanHalf * aspect) + f.up * (ndcY * tanHalf));
    return {camera.eye, arr(d)};
}

render::Camera orbit(const render::Camera& camera, double yawDegrees, double pitchDegrees)
{
    const glm::dvec3 up = glm::normalize(vec(camera.up));
    const glm::dvec3 target = vec(camera.target);
    glm::dvec3 offset = vec(camera.eye) - target;
    const double length = glm::length(offset);
    // Pitch is limited so that the view never flips over the up axis.
    const double elevation = glm::degrees(std::asin(std::clamp(glm::dot(offset / length, up), -1.0, 1.0)));
    const double pitch = std::clamp(elevation + pitchDegrees, -89.0, 89.0) - elevation;
    const glm::dvec3 right = glm::normalize(glm::cross(-offset, up));
    offset = glm::dvec3(glm::rotate(glm::dmat4(1.0), glm::radians(-pitch), right) * glm::dvec4(offset, 0.0));
    offset = glm::dvec3(glm::rotate(glm::dmat4(1.0), glm::radians(-yawDegrees), up) * glm::dvec4(offset, 0.0));
    render::Camera out = camera;
    out.eye = arr(target + offset);
    return out;
}

render::Camera orbitAbout(const render::Camera& camera, const std::array<double, 3>& pivotPoint, double yawDegrees, double pitchDegrees)
{
    const glm::dvec3 up = glm::normalize(vec(camera.up));
    const Frame f = frameOf(camera);
    const double elevation = glm::degrees(std::asin(std::clamp(glm::dot(-f.forward, up), -1.0, 1.0)));
    const double pitch = std::clamp(elevation + pitchDegrees, -89.0, 89.0) - elevation;
    const glm::dmat4 turn = glm::rotate(glm::dmat4(1.0), glm::radians(-yawDegrees), up) * glm::rotate(glm::dmat4(1.0), glm::radians(-pitch), f.right);
    const glm::dvec3 pivot = vec(pivotPoint);
    const auto about = [&](const std::array<double, 3>& p) { return arr(pivot + glm::dvec3(turn * glm::dvec4(vec(p) - pivot, 0.0))); };
    render::Camera out = camera;
    out.eye = about(camera.eye);
    out.target = about(camera.target);
    return out;
}

render::Camera axisView(const render::Camera& camera, AxisView view)
{
    const Frame f = frameOf(camera);
    // Up stays +y: a view along y draws -z (or +z from below) at the top, as usableUp makes it.
    glm::dvec3 back{0, 0, 1};
    switch (view) {
    case AxisView::Front: break;
    case AxisView::Back: back = {0, 0, -1}; break;
    case AxisView::Right: back = {1, 0, 0}; break;
    case AxisView::Left: back = {-1, 0, 0}; break;
    case AxisView::Top: back = {0, 1, 0}; break;
    case AxisView::Bottom: back = {0, -1, 0}; break;
    }
    render::Camera out = camera;
    out.eye = arr(vec(camera.target) + back * f.distance);
    out.up = {0, 1, 0};
    return out;
}

render::Camera frameOn(const render::Camera& camera, const std::array<double, 3>& point, double distance)
{
    const Frame f = frameOf(camera);
    render::Camera out = camera;
    out.target = point;
    out.eye = arr(vec(point) - f.forward * std::max(distance, 1e-9));
    return out;
}

render::Camera parallelView(const render::Camera& camera)
{
    const Frame f = frameOf(camera);
    render::Camera out = camera;
    out.eye = arr(vec(camera.target) - f.forward * (f.distance * kParallelViewDistance));
    const double halfHeight = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    out.fovYDegrees = glm::degrees(2.0 * std::atan(halfHeight / kParallelViewDistance));
    return out;
}

render::Camera perspectiveView(const render::Camera& parallel, double fovYDegrees)
{
    // The distance at which `fovYDegrees` draws the target's plane at the parallel view's scale.
    const Frame f = frameOf(parallel);
    const double halfHeight = f.distance * std::tan(glm::radians(parallel.fovYDegrees) * 0.5);
    const double distance = halfHeight / std::tan(glm::radians(fovYDegrees) * 0.5);
    render::Camera out = parallel;
    out.eye = arr(vec(parallel.target) - f.forward * distance);
    out.fovYDegrees = fovYDegrees;
    return out;
}

render::Camera zoomByFieldOfView(const render::Camera& camera, double factor, const std::optional<std::array<double, 3>>& toward)
{
    render::Camera out = camera;
    const double halfHeight = std::tan(glm::radians(camera.fovYDegrees) * 0.5) / std::max(factor, 1e-6);
    out.fovYDegrees = std::clamp(glm::degrees(2.0 * std::atan(halfHeight)), 1e-4, 170.0);
    if (toward) {
        // The point under the cursor stays there: the view slides towards it as it narrows.
        const Frame f = frameOf(camera);
        const glm::dvec3 p = vec(*toward), t = vec(camera.target);
        const glm::dvec3 across = (p - t) - f.forward * glm::dot(p - t, f.forward);
        const glm::dvec3 shift = across * (1.0 - 1.0 / std::max(factor, 1e-6));
        out.eye = arr(vec(camera.eye) + shift);
        out.target = arr(t + shift);
    }
    return out;
}

render::Camera pan(const render::Camera& camera, const std::array<int, 2>& viewport, double dxPixels, double dyPixels)
{
    const Frame f = frameOf(camera);
    const double worldPerPixel = 2.0 * f.distance * std::tan(glm::radians(camera.fovYDegrees) * 0.5) / double(std::max(1, viewport[1]));
    const glm::dvec3 shift = (-f.right * dxPixels + f.up * dyPixels) * worldPerPixel;
    render::Camera out = camera;
    out.eye = arr(vec(camera.eye) + shift);
    out.target = arr(vec(camera.target) + shift);
    return out;
}

render::Camera zoomToward(const render::Camera& camera, double factor, const std::optional<std::array<double, 3>>& toward)
{
    const glm::dvec3 eye = vec(camera.eye), point = toward ? vec(*toward) : vec(camera.target);
    const glm::dvec3 newEye = point + (eye - point) / std::max(factor, 1e-6);
    render::Camera out = camera;
    out.eye = arr(newEye);
    out.target = arr(vec(camera.target) + (newEye - eye));
    if (!toward) out.target = camera.target;
    return out;
}

render::Camera fly(const render::Camera& camera, double forward, double right, double up)
{
    const Frame f = frameOf(camera);
    const glm::dvec3 shift = f.forward * forward + f.right * right + f.up * up;
    render::Camera out = camera;
    out.eye = arr(vec(camera.eye) + shift);
    out.target = arr(vec(camera.target) + shift);
    return out;
}

std::optional<std::array<double, 3>> dragPoint(const render::Camera& camera, const Ray& ray, const std::array<double, 3>& point)
{
    const glm::dvec3 n = frameOf(camera).forward, o = vec(ray.origin), d = vec(ray.direction);
    const double denom = glm::dot(d, n);
    if (std::abs(denom) < 1e-9) return std::nullopt;
    const double t = glm::dot(vec(point) - o, n) / denom;
    if (!(t > 0.0)) return std::nullopt;
    return arr(o + d * t);
}

Viewer viewerOf(const render::Camera& camera, const std::array<int, 2>& viewport)
{
    Viewer v;
    v.position = camera.eye;
    v.target = camera.target;
    v.fovDegrees = camera.fovYDegrees;
    v.viewport = viewport;
    return v;
}

} // namespace vdbclay
