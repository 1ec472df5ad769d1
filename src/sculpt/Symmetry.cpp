#include "sculpt/Symmetry.h"

#include <algorithm>
#include <cmath>

namespace vdbclay {

namespace {

/// The rotation by `turn` of a full turn about an axis; multiples of a quarter turn are exact.
Mat3d axisRotation(int axis, int step, int count)
{
    double c = 0.0, s = 0.0;
    if ((4 * step) % count == 0) {
        const int quarter = ((4 * step) / count) % 4;
        const double cs[4] = {1.0, 0.0, -1.0, 0.0}, sn[4] = {0.0, 1.0, 0.0, -1.0};
        c = cs[quarter];
        s = sn[quarter];
    } else {
        const double angle = 2.0 * M_PI * double(step) / double(count);
        c = std::cos(angle);
        s = std::sin(angle);
    }
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    Mat3d r = Mat3d::identity();
    r(u, u) = c;
    r(u, v) = -s;
    r(v, u) = s;
    r(v, v) = c;
    return r;
}

} // namespace

std::vector<Mat3d> symmetryCopies(const Symmetry& symmetry)
{
    std::vector<Mat3d> mirrors{Mat3d::identity()};
    for (int a = 0; a < 3; ++a) {
        if (!symmetry.mirror[std::size_t(a)]) continue;
        Mat3d m = Mat3d::identity();
        m(a, a) = -1.0;
        const std::size_t n = mirrors.size();
        for (std::size_t i = 0; i < n; ++i) mirrors.push_back(m * mirrors[i]);
    }
    std::vector<Mat3d> out;
    const int count = std::clamp(symmetry.radialCount, 1, kMaxRadialCopies);
    for (int step = 0; step < count; ++step) {
        const Mat3d r = axisRotation(symmetry.radialAxis, step, count);
        for (const Mat3d& m : mirrors) out.push_back(r * m);
    }
    return out;
}

WorldBounds transformBounds(const WorldBounds& bounds, const Mat3d& linear, const Vec3d& center)
{
    if (!bounds.bounded()) return WorldBounds{};
    WorldBounds out;
    out.min = Vec3d(std::numeric_limits<double>::infinity());
    out.max = Vec3d(-std::numeric_limits<double>::infinity());
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d p((corner & 1) ? bounds.max[0] : bounds.min[0], (corner & 2) ? bounds.max[1] : bounds.min[1],
                      (corner & 4) ? bounds.max[2] : bounds.min[2]);
        const Vec3d q = linear * (p - center) + center;
        for (int a = 0; a < 3; ++a) {
            out.min[a] = std::min(out.min[a], q[a]);
            out.max[a] = std::max(out.max[a], q[a]);
        }
    }
    return out;
}

TransformedField::TransformedField(std::shared_ptr<const SdfField> field, const Mat3d& linear, const Vec3d& center)
    : field_(std::move(field)), linear_(linear), inverse_(linear.transpose()), center_(center)
{
}

double TransformedField::distance(const Vec3d& world) const { return field_->distance(inverse_ * (world - center_) + center_); }

Vec3d TransformedField::gradient(const Vec3d& world, double step) const
{
    return linear_ * field_->gradient(inverse_ * (world - center_) + center_, step);
}

WorldBounds TransformedField::bounds() const { return transformBounds(field_->bounds(), linear_, center_); }

} // namespace vdbclay
