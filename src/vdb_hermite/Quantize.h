// Quantization of Hermite samples: the crossing offset along a voxel edge and the unit normal there.
//
// A sample is three 16-bit words (6 bytes):
//   offset  : t in [0,1] along the edge, t = q / 65535          (error <= 1/131070 of the edge)
//   normalU : 12-bit octahedral coordinate u, stored in 16 bits (top 4 bits zero)
//   normalV : 12-bit octahedral coordinate v
// Why 24 bits for a normal and not 16: covering the unit sphere with codes whose worst component
// error is <= 1/1000 needs at least pi / (sqrt(3) * 1e-6) ~ 1.8 million codes (21 bits). 12+12 bit
// octahedral codes give a measured worst component error of 1/1782; 11+11 bits give only 1/890.
#pragma once

#include <array>
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

constexpr int kNormalBits = 12;
constexpr uint16_t kNormalMax = (1u << kNormalBits) - 1;

uint16_t quantizeOffset(double t);
double dequantizeOffset(uint16_t q);

/// Encodes a unit (or any non-zero) vector; picks, among the neighbouring codes, the one whose decoded
/// normal has the smallest worst component error.
std::array<uint16_t, 2> quantizeNormal(const std::array<double, 3>& n);
std::array<float, 3> dequantizeNormal(uint16_t u, uint16_t v);

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
