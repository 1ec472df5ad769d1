#include "vdb_hermite/Quantize.h"

#include <algorithm>
#include <cmath>

namespace vdbclay {

uint16_t quantizeOffset(double t)
{
    constexpr double lo = kOffsetMinCode / 65535.0, hi = kOffsetMaxCode / 65535.0;
    if (!(t >= lo)) t = lo; // also maps NaN to the lowest code
    if (t > hi) t = hi;
    return static_cast<uint16_t>(t * 65535.0 + 0.5); // t is positive: truncation rounds to nearest
}

namespace quantize_detail {

// Every code's octahedral coordinate, computed at compile time with the same IEEE operations a
// division at run time would do: decoding sits on the mesher's hot path, a table read does not wait
// for a division.
constexpr std::array<double, kNormalMax + 1> kCodeCoords = [] {
    std::array<double, kNormalMax + 1> coords{};
    for (int q = 0; q <= kNormalMax; ++q) coords[q] = q / double(kNormalMax) * 2.0 - 1.0;
    return coords;
}();

} // namespace quantize_detail

std::array<uint16_t, 2> quantizeNormal(const std::array<double, 3>& nIn)
{
    using namespace quantize_detail;
    double len = std::sqrt(nIn[0] * nIn[0] + nIn[1] * nIn[1] + nIn[2] * nIn[2]);
    std::array<double, 3> n = len > 0.0 && std::isfinite(len)
                                  ? std::array<double, 3>{nIn[0] / len, nIn[1] / len, nIn[2] / len}
                                  : std::array<double, 3>{0.0, 0.0, 1.0};
    const double l1 = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
    double u = n[0] / l1, v = n[1] / l1;
    if (n[2] < 0.0) {
        const double fu = (1.0 - std::fabs(v)) * signNotZero(u);
        const double fv = (1.0 - std::fabs(u)) * signNotZero(v);
        u = fu;
        v = fv;
    }
    // The nearest code is almost always good enough; only when it is not are its neighbours searched
    // for the code with the smallest worst component error (which bounds the error by 1/1782).
    auto errorOf = [&n](int qu, int qv) {
        const auto d = decodeOctahedral(kCodeCoords[qu], kCodeCoords[qv]);
        return std::max({std::fabs(d[0] - n[0]), std::fabs(d[1] - n[1]), std::fabs(d[2] - n[2])});
    };
    const double fu = (u + 1.0) * 0.5 * kNormalMax, fv = (v + 1.0) * 0.5 * kNormalMax;
    // fu and fv lie in [0, kNormalMax]: adding 0.5 and truncating rounds to nearest.
    const int nearU = std::min(int(fu + 0.5), int(kNormalMax));
    const int nearV = std::min(int(fv + 0.5), int(kNormalMax));
    double bestError = errorOf(nearU, nearV);
    std::array<uint16_t, 2> best{uint16_t(nearU), uint16_t(nearV)};
    constexpr double kGoodEnough = 0.5e-3;
    if (bestError <= kGoodEnough) return best;
    const int baseU = static_cast<int>(std::floor(fu));
    const int baseV = static_cast<int>(std::floor(fv));
    for (int du = 0; du <= 1; ++du) {
        for (int dv = 0; dv <= 1; ++dv) {
            const int qu = std::clamp(baseU + du, 0, int(kNormalMax));
            const int qv = std::clamp(baseV + dv, 0, int(kNormalMax));
            const double err = errorOf(qu, qv);
            if (err < bestError) {
                bestError = err;
                best = {uint16_t(qu), uint16_t(qv)};
            }
        }
    }
    return best;
}

} // namespace vdbclay
