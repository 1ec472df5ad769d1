#include "render/Framing.h"

#include <algorithm>
#include <cmath>

namespace vdbclay::render {

void fitNearPlane(Camera& camera, const std::array<double, 3>& lo, const std::array<double, 3>& hi)
{
    double nearest2 = 0.0, farthest2 = 0.0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double e = camera.eye[a];
        const double outside = e < lo[a] ? lo[a] - e : e > hi[a] ? e - hi[a] : 0.0;
        const double far = std::max(std::abs(e - lo[a]), std::abs(e - hi[a]));
        nearest2 += outside * outside;
        farthest2 += far * far;
    }
    // The nearest point of the box may lie off the view's axis, where the view plane is nearer than the
    // point itself: half its distance keeps it in front of the near plane at any field of view below 120.
    const double floor = std::max(1e-6 * std::sqrt(farthest2), 1e-12);
    camera.nearPlane = std::max(0.5 * std::sqrt(nearest2), floor);
}

namespace {

/// The camera frame of the three-quarter view: back (towards the eye), right, up.
struct ViewFrame {
    double back[3], right[3], up[3];
};

ViewFrame threeQuarterFrame()
{
    ViewFrame f{{0.62, 0.52, 0.59}, {}, {}};
    const double bn = std::sqrt(f.back[0] * f.back[0] + f.back[1] * f.back[1] + f.back[2] * f.back[2]);
    for (double& v : f.back) v /= bn;
    const double rn = std::sqrt(f.back[2] * f.back[2] + f.back[0] * f.back[0]);
    f.right[0] = f.back[2] / rn; // world up x back
    f.right[1] = 0.0;
    f.right[2] = -f.back[0] / rn;
    f.up[0] = f.back[1] * f.right[2] - f.back[2] * f.right[1];
    f.up[1] = f.back[2] * f.right[0] - f.back[0] * f.right[2];
    f.up[2] = f.back[0] * f.right[1] - f.back[1] * f.right[0];
    return f;
}

/// Places the eye along the frame's back axis from the box's centre, at the nearest distance from which
/// every point projects inside the view: a point at (x, y) across and z towards the eye needs
/// distance - z >= |x| / tan(half fov x) and |y| / tan(half fov y).
template <typename ForEachPoint>
Camera frame(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double aspect, double fovYDegrees,
             const ForEachPoint& forEachPoint)
{
    Camera camera;
    camera.fovYDegrees = fovYDegrees;
    for (int a = 0; a < 3; ++a) camera.target[std::size_t(a)] = 0.5 * (lo[std::size_t(a)] + hi[std::size_t(a)]);
    const ViewFrame f = threeQuarterFrame();
    const double tanY = std::tan(0.5 * fovYDegrees * M_PI / 180.0), tanX = tanY * aspect;
    double distance = 0.0;
    forEachPoint([&](double px, double py, double pz) {
        const double d[3] = {px - camera.target[0], py - camera.target[1], pz - camera.target[2]};
        const double x = d[0] * f.right[0] + d[1] * f.right[1] + d[2] * f.right[2];
        const double y = d[0] * f.up[0] + d[1] * f.up[1] + d[2] * f.up[2];
        const double z = d[0] * f.back[0] + d[1] * f.back[1] + d[2] * f.back[2];
        distance = std::max({distance, z + std::fabs(x) / tanX, z + std::fabs(y) / tanY});
    });
    distance = std::max(distance * 1.05, 1e-6);
    for (int a = 0; a < 3; ++a) camera.eye[std::size_t(a)] = camera.target[std::size_t(a)] + f.back[a] * distance;
    fitNearPlane(camera, lo, hi);
    return camera;
}

} // namespace

Camera framingCamera(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double aspect, double fovYDegrees)
{
    return frame(lo, hi, aspect, fovYDegrees, [&](const auto& visit) {
        for (int corner = 0; corner < 8; ++corner)
            visit(corner & 1 ? hi[0] : lo[0], corner & 2 ? hi[1] : lo[1], corner & 4 ? hi[2] : lo[2]);
    });
}

Camera framingCamera(const std::vector<std::array<float, 3>>& points, const std::array<double, 3>& lo,
                     const std::array<double, 3>& hi, double aspect, double fovYDegrees)
{
    if (points.empty()) return framingCamera(lo, hi, aspect, fovYDegrees);
    return frame(lo, hi, aspect, fovYDegrees, [&](const auto& visit) {
        for (const auto& p : points) visit(p[0], p[1], p[2]);
    });
}

void appendOutline(const std::vector<std::array<float, 3>>& positions, std::vector<std::array<float, 3>>& outline)
{
    // A small mesh whole; a larger one sampled, with its vertices farthest along the axes and the
    // diagonals (a box's corners), where a sample would miss what sticks out.
    if (positions.size() <= 64) {
        outline.insert(outline.end(), positions.begin(), positions.end());
        return;
    }
    constexpr int kDirections = 13;
    static const int kDirection[kDirections][3] = {{1, 0, 0},  {0, 1, 0},  {0, 0, 1},  {1, 1, 1},  {1, 1, -1}, {1, -1, 1}, {1, -1, -1},
                                                   {-1, 1, 1}, {-1, 1, -1}, {-1, -1, 1}, {-1, -1, -1}, {1, 1, 0}, {1, -1, 0}};
    std::size_t lowest[kDirections] = {}, highest[kDirections] = {};
    double low[kDirections], high[kDirections];
    std::fill(std::begin(low), std::end(low), 1e300);
    std::fill(std::begin(high), std::end(high), -1e300);
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (i % 8 == 0) outline.push_back(positions[i]);
        for (int d = 0; d < kDirections; ++d) {
            const double along = kDirection[d][0] * positions[i][0] + kDirection[d][1] * positions[i][1] + kDirection[d][2] * positions[i][2];
            if (along < low[d]) low[d] = along, lowest[d] = i;
            if (along > high[d]) high[d] = along, highest[d] = i;
        }
    }
    for (int d = 0; d < kDirections; ++d) {
        outline.push_back(positions[lowest[d]]);
        outline.push_back(positions[highest[d]]);
    }
}

} // namespace vdbclay::render
