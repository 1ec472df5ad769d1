// Quantization of Hermite samples: offset and normal error bounds, exact round trips of codes.
#include "vdb_hermite/Quantize.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace vdbclay;

namespace {

std::array<double, 3> randomUnit(std::mt19937_64& rng)
{
    std::normal_distribution<double> g(0.0, 1.0);
    for (;;) {
        const std::array<double, 3> v{g(rng), g(rng), g(rng)};
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (len > 1e-9) return {v[0] / len, v[1] / len, v[2] / len};
    }
}

double componentError(const std::array<double, 3>& n, const std::array<float, 3>& d)
{
    return std::max({std::fabs(n[0] - d[0]), std::fabs(n[1] - d[1]), std::fabs(n[2] - d[2])});
}

double worstNormalError(const std::array<double, 3>& n)
{
    const auto uv = quantizeNormal(n);
    return componentError(n, dequantizeNormal(uv[0], uv[1]));
}

} // namespace

TEST_CASE("offset quantization error over 1e6 random offsets", "[quantize]")
{
    std::mt19937_64 rng(0x5eed0001);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const double lo = kOffsetMinCode / 65535.0, hi = kOffsetMaxCode / 65535.0; // inside the corner margin
    double worst = 0.0;
    for (int i = 0; i < 1000000; ++i) {
        const double t = lo + (hi - lo) * uni(rng);
        worst = std::max(worst, std::fabs(dequantizeOffset(quantizeOffset(t)) - t));
    }
    for (double t : {lo, hi, 0.5, lo + 0.5 / 65535.0, hi - 0.5 / 65535.0}) {
        worst = std::max(worst, std::fabs(dequantizeOffset(quantizeOffset(t)) - t));
    }
    INFO("worst offset error " << worst);
    CHECK(worst <= 1.0 / 1024.0);
    CHECK(worst <= 1.0 / 100000.0);
    // Rounding to the nearest of 65536 codes: never worse than half a step.
    CHECK(worst <= 0.5 / 65535.0 + 1e-12);
}

TEST_CASE("offset quantization keeps crossings off the voxel corners", "[quantize]")
{
    CHECK(quantizeOffset(0.0) == kOffsetMinCode);
    CHECK(quantizeOffset(1.0) == kOffsetMaxCode);
    CHECK(quantizeOffset(-0.25) == kOffsetMinCode);
    CHECK(quantizeOffset(7.0) == kOffsetMaxCode);
    CHECK(quantizeOffset(std::numeric_limits<double>::quiet_NaN()) == kOffsetMinCode);
    CHECK(quantizeOffset(kOffsetMinCode / 65535.0) == kOffsetMinCode);
    CHECK(quantizeOffset((kOffsetMinCode + 1) / 65535.0) == kOffsetMinCode + 1);
    // Codes on or near the corners (a foreign file) decode as the nearest code inside the margin.
    CHECK(dequantizeOffset(0) == kOffsetMinCode / 65535.0);
    CHECK(dequantizeOffset(65535) == kOffsetMaxCode / 65535.0);
    CHECK(dequantizeOffset(kOffsetMinCode) > 2.4e-4);
    CHECK(dequantizeOffset(kOffsetMaxCode) < 1.0 - 2.4e-4);
}

TEST_CASE("every offset code round-trips exactly", "[quantize]")
{
    int mismatches = 0;
    for (int q = kOffsetMinCode; q <= kOffsetMaxCode; ++q) {
        const uint16_t code = uint16_t(q);
        if (quantizeOffset(dequantizeOffset(code)) != code) ++mismatches;
        // The float the mesher sees maps back to the same code too.
        if (quantizeOffset(double(unpackSample(PackedSample{code, 0, 0}).offset)) != code) ++mismatches;
    }
    CHECK(mismatches == 0);
}

TEST_CASE("normal quantization error over 1e6 random unit normals", "[quantize]")
{
    std::mt19937_64 rng(0x5eed0002);
    double worst = 0.0;
    double worstLength = 0.0;
    for (int i = 0; i < 1000000; ++i) {
        const auto n = randomUnit(rng);
        const auto uv = quantizeNormal(n);
        REQUIRE(uv[0] <= kNormalMax);
        REQUIRE(uv[1] <= kNormalMax);
        const auto d = dequantizeNormal(uv[0], uv[1]);
        worst = std::max(worst, componentError(n, d));
        worstLength = std::max(worstLength, std::fabs(std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] +
                                                                double(d[2]) * d[2]) - 1.0));
    }
    INFO("worst component error " << worst << " (1/" << 1.0 / worst << ")");
    CHECK(worst <= 1.0 / 1000.0);
    CHECK(worstLength <= 1e-6);
}

TEST_CASE("normal quantization at the octahedron's corners, edges and folds", "[quantize]")
{
    const double s = 1.0 / std::sqrt(2.0), t = 1.0 / std::sqrt(3.0);
    const std::array<double, 3> special[] = {
        {1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0},  {0, 0, 1},   {0, 0, -1},  {s, s, 0},   {-s, s, 0},
        {s, -s, 0}, {-s, -s, 0}, {s, 0, s},  {s, 0, -s},  {0, s, -s},  {0, -s, -s}, {t, t, t},   {-t, -t, -t},
        {t, -t, -t}, {-t, t, -t}, {0.6, 0.0, -0.8}, {0.0, 0.8, -0.6}, {1e-9, 1e-9, -1.0}, {-1e-9, 1e-9, -1.0}};
    for (const auto& n : special) {
        INFO("normal " << n[0] << " " << n[1] << " " << n[2]);
        CHECK(worstNormalError(n) <= 1.0 / 1000.0);
    }
    // Any non-zero length is accepted; the direction is what gets encoded.
    const auto scaled = quantizeNormal({0.0, 3.0, 4.0});
    CHECK(componentError({0.0, 0.6, 0.8}, dequantizeNormal(scaled[0], scaled[1])) <= 1.0 / 1000.0);
}

TEST_CASE("decoded normals re-encode to a code with the same normal", "[quantize]")
{
    // Every code decodes to a unit vector; encoding that vector again picks a code that decodes to the
    // same vector (the code itself, except on the fold where two codes name the same normal).
    int codeChanged = 0, normalChanged = 0;
    double worstDrift = 0.0;
    for (int u = 0; u <= kNormalMax; u += 3) {
        for (int v = 0; v <= kNormalMax; v += 3) {
            const auto d = dequantizeNormal(uint16_t(u), uint16_t(v));
            const auto again = quantizeNormal({d[0], d[1], d[2]});
            if (again[0] != u || again[1] != v) {
                ++codeChanged;
                const auto d2 = dequantizeNormal(again[0], again[1]);
                const double drift = componentError({d[0], d[1], d[2]}, d2);
                worstDrift = std::max(worstDrift, drift);
                if (drift > 1e-6) ++normalChanged;
            }
        }
    }
    INFO("codes that changed " << codeChanged << ", worst drift " << worstDrift);
    CHECK(normalChanged == 0);
}

TEST_CASE("packSample and unpackSample agree with the scalar functions", "[quantize]")
{
    std::mt19937_64 rng(0x5eed0003);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int i = 0; i < 1000; ++i) {
        const double t = uni(rng);
        const auto n = randomUnit(rng);
        const PackedSample p = packSample(t, n);
        CHECK(p.offset == quantizeOffset(t));
        const auto uv = quantizeNormal(n);
        CHECK(p.normalU == uv[0]);
        CHECK(p.normalV == uv[1]);
        const UnpackedSample u = unpackSample(p);
        CHECK(std::fabs(u.offset - t) <= 1.0 / 100000.0);
        CHECK(componentError(n, u.normal) <= 1.0 / 1000.0);
        CHECK(packSample(u.offset, {u.normal[0], u.normal[1], u.normal[2]}).offset == p.offset);
    }
}
