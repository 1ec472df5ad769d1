#include "vr/WorldPlacement.h"

#include <algorithm>
#include <cmath>

namespace vdbclay::vr {

WorldTransform frameScene(const std::array<double, 3>& lo, const std::array<double, 3>& hi, const Pose& head)
{
    const glm::dvec3 a(lo[0], lo[1], lo[2]), b(hi[0], hi[1], hi[2]);
    const glm::dvec3 size = glm::max(b - a, glm::dvec3(1e-9));
    const double widest = std::max({size.x, size.y, size.z});
    WorldTransform w;
    w.scale = kFramedWidthMetres / widest;
    // Face the viewer: turn about the vertical so that the scene's -Z looks along the head's forward
    // projected on the floor (the desktop's default view looks down -Z).
    glm::dvec3 forward = head.forward();
    forward.y = 0.0;
    if (glm::length(forward) < 1e-6) forward = glm::dvec3(0, 0, -1);
    forward = glm::normalize(forward);
    const double yaw = std::atan2(-forward.x, -forward.z);
    w.rotation = glm::angleAxis(yaw, glm::dvec3(0, 1, 0));
    const double distance = 0.5 * kFramedWidthMetres + 0.6; // the near side a comfortable arm's length away
    glm::dvec3 centre = head.position + forward * distance;
    centre.y = std::max(0.5 * size.y * w.scale, head.position.y - 0.35); // at chest height, never under the floor
    const glm::dvec3 middle = 0.5 * (a + b);
    w.translation = centre - w.scale * (w.rotation * middle);
    return w;
}

namespace {

/// The yaw (about +Y) that turns the horizontal part of `from` onto that of `to`.
double yawBetween(const glm::dvec3& from, const glm::dvec3& to)
{
    const double a = std::atan2(from.x, from.z), b = std::atan2(to.x, to.z);
    return b - a;
}

} // namespace

WorldTransform WorldGrab::update(const std::optional<glm::dvec3>& left, const std::optional<glm::dvec3>& right, const WorldTransform& now)
{
    const bool same = start_ && start_->left.has_value() == left.has_value() && start_->right.has_value() == right.has_value();
    if (!left && !right) {
        start_.reset();
        return now;
    }
    if (!same) {
        start_ = Start{now, left, right};
        return now;
    }
    const WorldTransform& w0 = start_->world;
    WorldTransform w = w0;
    if (left && right) {
        const glm::dvec3 m0 = 0.5 * (*start_->left + *start_->right), m = 0.5 * (*left + *right);
        const glm::dvec3 d0 = *start_->right - *start_->left, d = *right - *left;
        const double spread0 = glm::length(d0), spread = glm::length(d);
        double k = spread0 > 1e-6 && spread > 1e-6 ? spread / spread0 : 1.0;
        k = std::clamp(w0.scale * k, minScale_, maxScale_) / w0.scale;
        const double yaw = glm::length(glm::dvec2(d0.x, d0.z)) > 1e-3 && glm::length(glm::dvec2(d.x, d.z)) > 1e-3 ? yawBetween(d0, d) : 0.0;
        const glm::dquat turn = glm::angleAxis(yaw, glm::dvec3(0, 1, 0));
        // stage' = m + k turn (stage - m0)
        w.scale = k * w0.scale;
        w.rotation = glm::normalize(turn * w0.rotation);
        w.translation = m + k * (turn * (w0.translation - m0));
    } else {
        const glm::dvec3 from = left ? *start_->left : *start_->right, to = left ? *left : *right;
        w.translation = w0.translation + (to - from);
    }
    return w;
}

WorldTransform fly(const WorldTransform& world, const glm::dvec3& direction, double metresPerSecond, double seconds)
{
    WorldTransform w = world;
    w.translation -= direction * (metresPerSecond * seconds);
    return w;
}

} // namespace vdbclay::vr
