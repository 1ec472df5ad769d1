#include "sculpt/SyntheticFields.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

namespace vdbclay {

namespace {

uint64_t mix(uint64_t h)
{
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ull;
    h ^= h >> 33;
    return h;
}

/// A lattice value in [-1, 1]: one multiply-xorshift hash of the coordinates and the seed.
double lattice(int64_t x, int64_t y, int64_t z, uint64_t seed)
{
    const uint64_t h = mix(uint64_t(x) * 0x9E3779B97F4A7C15ull + uint64_t(y) * 0xC2B2AE3D27D4EB4Full +
                           uint64_t(z) * 0x165667B19E3779F9ull + seed * 0xD6E8FEB86659FD93ull);
    return double(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
double lerp(double a, double b, double t) { return a + (b - a) * t; }

} // namespace

double valueNoise2(double x, double y, uint64_t seed)
{
    const double fx = std::floor(x), fy = std::floor(y);
    const auto ix = int64_t(fx), iy = int64_t(fy);
    const double u = fade(x - fx), v = fade(y - fy);
    return lerp(lerp(lattice(ix, iy, 0, seed), lattice(ix + 1, iy, 0, seed), u),
                lerp(lattice(ix, iy + 1, 0, seed), lattice(ix + 1, iy + 1, 0, seed), u), v);
}

double valueNoise3(double x, double y, double z, uint64_t seed)
{
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const auto ix = int64_t(fx), iy = int64_t(fy), iz = int64_t(fz);
    const double u = fade(x - fx), v = fade(y - fy), w = fade(z - fz);
    double c[2];
    for (int k = 0; k < 2; ++k) {
        c[k] = lerp(lerp(lattice(ix, iy, iz + k, seed), lattice(ix + 1, iy, iz + k, seed), u),
                    lerp(lattice(ix, iy + 1, iz + k, seed), lattice(ix + 1, iy + 1, iz + k, seed), u), v);
    }
    return lerp(c[0], c[1], w);
}

TerrainField::TerrainField(const TerrainParams& params) : params_(params)
{
    static std::atomic<uint64_t> fields{0};
    id_ = ++fields;
    double slope = 0.0, amplitude = params.amplitude, wavelength = params.wavelength;
    for (int i = 0; i < params.octaves; ++i) {
        amplitudeSum_ += amplitude;
        slope += amplitude / wavelength * kValueNoiseSlope;
        amplitude *= 0.5;
        wavelength *= 0.5;
    }
    // Interpolating the heights between lattice columns keeps each axis's slope within the noise's: the
    // gradient grows by at most sqrt(2).
    slope *= std::sqrt(2.0);
    slopeNorm_ = std::sqrt(1.0 + slope * slope);
}

double TerrainField::latticeHeight(int64_t i, int64_t j) const
{
    // The CSG kernel evaluates whole columns of voxels: a small per-thread cache of column heights
    // spares the octaves of noise for all but the first voxel of a column.
    struct Entry {
        uint64_t field = 0;
        int64_t i = 0, j = 0;
        double height = 0.0;
    };
    thread_local std::array<Entry, 8192> cache{};
    Entry& e = cache[std::size_t((uint64_t(i) * 0x9E3779B1u + uint64_t(j) * 0x85EBCA77u) & 8191u)];
    if (e.field == id_ && e.i == i && e.j == j) return e.height;
    const double x = double(i) * params_.spacing, z = double(j) * params_.spacing;
    double h = params_.baseHeight, amplitude = params_.amplitude, wavelength = params_.wavelength;
    for (int octave = 0; octave < params_.octaves; ++octave) {
        h += amplitude * valueNoise2(x / wavelength, z / wavelength, params_.seed + uint64_t(octave));
        amplitude *= 0.5;
        wavelength *= 0.5;
    }
    e = Entry{id_, i, j, h};
    return h;
}

double TerrainField::height(double x, double z) const
{
    const double u = x / params_.spacing, v = z / params_.spacing;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto i = int64_t(fu), j = int64_t(fv);
    const double a = u - fu, b = v - fv;
    return (1.0 - a) * ((1.0 - b) * latticeHeight(i, j) + b * latticeHeight(i, j + 1)) +
           a * ((1.0 - b) * latticeHeight(i + 1, j) + b * latticeHeight(i + 1, j + 1));
}

double TerrainField::distance(const Vec3d& p) const
{
    // Far above or below every height, the bound needs no noise.
    if (p.y() > maxHeight()) return (p.y() - maxHeight()) / slopeNorm_;
    if (p.y() < minHeight()) return (p.y() - minHeight()) / slopeNorm_;
    return (p.y() - height(p.x(), p.z())) / slopeNorm_;
}

BlobField::BlobField(const Vec3d& centre, double radius, double amplitude, double wavelength, uint64_t seed)
    : centre_(centre), radius_(radius), amplitude_(amplitude), frequency_(1.0 / wavelength), seed_(seed)
{
}

double BlobField::distance(const Vec3d& p) const
{
    const Vec3d d = p - centre_;
    const double r = d.length();
    const double lipschitz = 1.0 + amplitude_ * frequency_ * kValueNoiseSlope3D;
    if (r > radius_ + amplitude_) return (r - radius_ - amplitude_) / lipschitz;
    const double n = valueNoise3(p.x() * frequency_, p.y() * frequency_, p.z() * frequency_, seed_);
    return (r - radius_ - amplitude_ * n) / lipschitz;
}

WorldBounds BlobField::bounds() const
{
    const double reach = radius_ + amplitude_;
    return {centre_ - Vec3d(reach), centre_ + Vec3d(reach)};
}

double ClippedField::distance(const Vec3d& p) const
{
    double box = -1e300;
    for (int i = 0; i < 3; ++i) box = std::max({box, min_[i] - p[i], p[i] - max_[i]});
    if (box > 0.0) {
        // Outside the box: its distance bounds the intersection's from below well enough.
        Vec3d q;
        for (int i = 0; i < 3; ++i) q[i] = std::max({min_[i] - p[i], 0.0, p[i] - max_[i]});
        return std::max(q.length(), inner_.distance(p));
    }
    return std::max(box, inner_.distance(p));
}

WorldBounds ClippedField::bounds() const
{
    WorldBounds b = inner_.bounds();
    for (int i = 0; i < 3; ++i) {
        b.min[i] = std::max(b.min[i], min_[i]);
        b.max[i] = std::min(b.max[i], max_[i]);
    }
    return b;
}

double ClippedField::innerRadius() const
{
    double half = 1e300;
    for (int i = 0; i < 3; ++i) half = std::min(half, 0.5 * (max_[i] - min_[i]));
    return std::min(half, inner_.innerRadius());
}

} // namespace vdbclay
