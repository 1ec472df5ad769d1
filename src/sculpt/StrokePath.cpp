#include "sculpt/StrokePath.h"

#include <algorithm>
#include <utility>

namespace vdbclay {

namespace {

/// Distance from p to the segment a-b.
double distanceToSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b)
{
    const Vec3d ab = b - a;
    const double length2 = ab.lengthSqr();
    const double t = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
    return (p - (a + ab * t)).length();
}

} // namespace

std::vector<Vec3d> simplifyStrokePath(const std::vector<Vec3d>& path, double tolerance)
{
    if (path.size() < 3) return path;
    // Points within the tolerance of the last one kept: a linear pass bounds what follows by the path's
    // length over the tolerance.
    std::vector<Vec3d> merged{path.front()};
    for (std::size_t i = 1; i + 1 < path.size(); ++i)
        if ((path[i] - merged.back()).length() > tolerance) merged.push_back(path[i]);
    if ((path.back() - merged.back()).length() > 0.0 || merged.size() == 1) merged.push_back(path.back());
    if (merged.size() < 3) return merged;

    // Douglas-Peucker with an explicit stack (no recursion depth to fear on a long stroke).
    std::vector<bool> keep(merged.size(), false);
    keep.front() = keep.back() = true;
    std::vector<std::pair<std::size_t, std::size_t>> spans{{0, merged.size() - 1}};
    while (!spans.empty()) {
        const auto [first, last] = spans.back();
        spans.pop_back();
        double farthest = -1.0;
        std::size_t at = first;
        for (std::size_t i = first + 1; i < last; ++i) {
            const double d = distanceToSegment(merged[i], merged[first], merged[last]);
            if (d > farthest) farthest = d, at = i;
        }
        if (farthest <= tolerance) continue;
        keep[at] = true;
        if (at - first > 1) spans.emplace_back(first, at);
        if (last - at > 1) spans.emplace_back(at, last);
    }
    std::vector<Vec3d> out;
    for (std::size_t i = 0; i < merged.size(); ++i)
        if (keep[i]) out.push_back(merged[i]);
    return out;
}

} // namespace vdbclay
