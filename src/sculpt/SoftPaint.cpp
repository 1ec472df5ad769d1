#include "sculpt/SoftPaint.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vdbclay {

namespace {

/// A hash of a lattice point to [0, 1): the same for a point on every run and machine.
double latticeValue(int64_t x, int64_t y, int64_t z)
{
    uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull ^ uint64_t(y) * 0xC2B2AE3D27D4EB4Full ^ uint64_t(z) * 0x165667B19E3779F9ull;
    h ^= h >> 31;
    h *= 0xD6E8FEB86659FD93ull;
    h ^= h >> 32;
    return double(h >> 11) * (1.0 / 9007199254740992.0); // 53 bits
}

} // namespace

double paintThreshold(const Vec3d& world, double voxelSize)
{
    // Noise cells a voxel wide: the finest patches the mesher draws, so the stipple reads as a soft edge.
    const double spacing = voxelSize;
    int64_t cell[3];
    double t[3];
    for (int a = 0; a < 3; ++a) {
        const double q = world[a] / spacing;
        const double f = std::floor(q);
        cell[a] = int64_t(f);
        const double u = q - f;
        t[a] = u * u * (3.0 - 2.0 * u);
    }
    double value = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
        const double w = (dx ? t[0] : 1.0 - t[0]) * (dy ? t[1] : 1.0 - t[1]) * (dz ? t[2] : 1.0 - t[2]);
        value += w * latticeValue(cell[0] + dx, cell[1] + dy, cell[2] + dz);
    }
    return std::min(value, std::nextafter(1.0, 0.0));
}

SoftPaintField::SoftPaintField(std::shared_ptr<const SdfField> brush, double strength, Falloff falloff, double voxelSize, FalloffCurve curve)
    : brush_(std::move(brush)), strength_(strength), falloff_(falloff), voxelSize_(voxelSize), curve_(std::move(curve))
{
}

double SoftPaintField::distance(const Vec3d& world) const
{
    const double d = brush_->distance(world);
    if (d > 0.0) return d;
    const double weight = strength_ * falloffWeight(falloff_, -d, brush_->innerRadius(), curve_);
    // The threshold's margin in world units: its gradient is at most 1.5 per voxel, so this keeps the
    // field's slope within lipschitz().
    return std::max(d, (paintThreshold(world, voxelSize_) - weight) * voxelSize_);
}

} // namespace vdbclay
