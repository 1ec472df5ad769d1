// Quantization of Hermite samples: the crossing offset along a voxel edge and the unit normal there.
//
// A sample is three 16-bit words (6 bytes):
//   offset  : t along the edge, t = q / 65535 with q in [16, 65519] (error <= 1/131070 of the edge
//             inside that range, at most 16/65535 ~ 2.4e-4 at its ends)
//   normalU : 12-bit octahedral coordinate u, stored in 16 bits (top 4 bits zero)
//   normalV : 12-bit octahedral coordinate v
// Why 24 bits for a normal and not 16: covering the unit sphere with codes whose worst component
// error is <= 1/1000 needs at least pi / (sqrt(3) * 1e-6) ~ 1.8 million codes (21 bits). 12+12 bit
// octahedral codes give a measured worst component error of 1/1782; 11+11 bits give only 1/890.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace vdbclay {

struct PackedSample {
    uint16_t offset = 0;
    uint16_t normalU = 0;
    uint16_t normalV = 0;

    friend bool operator==(const PackedSample& a, const PackedSample& b)
    {
        return a.offset == b.offset && a.normalU == b.normalU && a.normalV == b.normalV;
    }
    friend bool operator!=(const PackedSample& a, const PackedSample& b) { return !(a == b); }
};
static_assert(sizeof(PackedSample) == 6, "PackedSample is part of the file format");

/// A crossing never lies on a voxel corner: its offset keeps kOffsetMarginCode / 65535 (2.4e-4 voxel)
/// from either end. A surface through a corner (a sphere through a lattice point, a box face on a lattice
/// plane) then gives each edge from that corner its own point, 2.4e-4 voxel from the corner and at least
/// 3.4e-4 from the others, instead of several vertices at one position; sharp features built from those
/// crossings (a lattice-aligned box's edges and corners) lie strictly inside their cells too. The margin
/// stays far above float rounding for meshes within ~10,000 voxels of the origin, and far below the
/// mesher's error.
constexpr uint16_t kOffsetMarginCode = 16;
constexpr uint16_t kOffsetMinCode = kOffsetMarginCode, kOffsetMaxCode = 65535 - kOffsetMarginCode;

constexpr int kNormalBits = 12;
constexpr uint16_t kNormalMax = (1u << kNormalBits) - 1;

/// The nearest code in [kOffsetMinCode, kOffsetMaxCode]; NaN maps to the lowest.
uint16_t quantizeOffset(double t);
/// Codes outside the margin (only a foreign or older file holds them) decode as the nearest valid one.
inline double dequantizeOffset(uint16_t q) { return std::clamp(q, kOffsetMinCode, kOffsetMaxCode) / 65535.0; }

/// Encodes a unit (or any non-zero) vector; picks, among the neighbouring codes, the one whose decoded
/// normal has the smallest worst component error.
std::array<uint16_t, 2> quantizeNormal(const std::array<double, 3>& n);

// Decoding is inline: the mesher decodes every crossing it reads.
namespace quantize_detail {

extern const std::array<double, kNormalMax + 1> kCodeCoords; // code q: q / kNormalMax * 2 - 1

/// +1 or -1, never 0: the octahedral fold's sign.
inline double signNotZero(double v) { return v >= 0.0 ? 1.0 : -1.0; }

inline std::array<double, 3> decodeOctahedral(double u, double v)
{
    double x = u, y = v;
    const double z = 1.0 - std::fabs(u) - std::fabs(v);
    if (z < 0.0) {
        x = (1.0 - std::fabs(v)) * signNotZero(u);
        y = (1.0 - std::fabs(u)) * signNotZero(v);
    }
    const double inv = 1.0 / std::sqrt(x * x + y * y + z * z);
    return {x * inv, y * inv, z * inv};
}

} // namespace quantize_detail

/// The unit normal of a code in double precision: quantizing it gives the code back, so Hermite data
/// copied through it (a grid tool stamped on the lattice) keep their codes exactly.
inline std::array<double, 3> decodeNormal(uint16_t u, uint16_t v)
{
    using namespace quantize_detail;
    return decodeOctahedral(kCodeCoords[std::min(u, kNormalMax)], kCodeCoords[std::min(v, kNormalMax)]);
}

inline std::array<float, 3> dequantizeNormal(uint16_t u, uint16_t v)
{
    using namespace quantize_detail;
    const auto d = decodeOctahedral(kCodeCoords[std::min(u, kNormalMax)], kCodeCoords[std::min(v, kNormalMax)]);
    return {float(d[0]), float(d[1]), float(d[2])};
}

inline PackedSample packSample(double t, const std::array<double, 3>& normal)
{
    const auto uv = quantizeNormal(normal);
    return PackedSample{quantizeOffset(t), uv[0], uv[1]};
}

struct UnpackedSample {
    float offset;
    std::array<float, 3> normal;
};

inline UnpackedSample unpackSample(const PackedSample& s)
{
    return UnpackedSample{static_cast<float>(dequantizeOffset(s.offset)),
                          dequantizeNormal(s.normalU, s.normalV)};
}

} // namespace vdbclay
