#include "wavelet/Haar.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace vdbclay::wavelet {

namespace {

struct Lifting {
    using Value = LiftingValue;
    static void forward(int32_t a, int32_t b, int32_t& low, int32_t& detail) { liftingForward(a, b, low, detail); }
    static void inverse(int32_t low, int32_t detail, int32_t& a, int32_t& b) { liftingInverse(low, detail, a, b); }
    using Work = int32_t;
};
struct Averaging {
    using Value = AveragingValue;
    static void forward(float a, float b, float& low, float& detail) { averagingForward(a, b, low, detail); }
    static void inverse(float low, float detail, float& a, float& b) { averagingInverse(low, detail, a, b); }
    using Work = float;
};
struct DoubleAveraging {
    using Work = double;
    static void forward(double a, double b, double& low, double& detail) { low = (a + b) / 2, detail = (a - b) / 2; }
    static void inverse(double low, double detail, double& a, double& b) { a = low + detail, b = low - detail; }
};

template<typename Ops, typename V>
std::vector<V> decompose1D(std::vector<V> values)
{
    const std::size_t n = values.size();
    if (n == 0 || (n & (n - 1)) != 0) throw std::invalid_argument("a Haar sequence needs a power-of-two length");
    std::vector<V> out(n);
    for (std::size_t len = n; len > 1; len /= 2) {
        for (std::size_t i = 0; i < len / 2; ++i) {
            typename Ops::Work low, detail;
            Ops::forward(typename Ops::Work(values[2 * i]), typename Ops::Work(values[2 * i + 1]), low, detail);
            out[i] = V(low);
            out[len / 2 + i] = V(detail);
        }
        std::copy(out.begin(), out.begin() + std::ptrdiff_t(len), values.begin());
    }
    return values;
}

template<typename Ops, typename V>
std::vector<V> reconstruct1D(std::vector<V> coefficients)
{
    const std::size_t n = coefficients.size();
    if (n == 0 || (n & (n - 1)) != 0) throw std::invalid_argument("a Haar sequence needs a power-of-two length");
    std::vector<V> out(n);
    for (std::size_t len = 2; len <= n; len *= 2) {
        for (std::size_t i = 0; i < len / 2; ++i) {
            typename Ops::Work a, b;
            Ops::inverse(typename Ops::Work(coefficients[i]), typename Ops::Work(coefficients[len / 2 + i]), a, b);
            out[2 * i] = V(a);
            out[2 * i + 1] = V(b);
        }
        std::copy(out.begin(), out.begin() + std::ptrdiff_t(len), coefficients.begin());
    }
    return coefficients;
}

/// One level: the cube `in` of edge 2e becomes the low-pass cube `low` and seven detail cubes of edge e.
/// Each 2x2x2 block is transformed in registers (x, then y, then z), so a level reads and writes its
/// data once.
template<typename Ops>
void forwardLevel(const typename Ops::Value* in, int e, typename Ops::Value* low, typename Ops::Value* details)
{
    using V = typename Ops::Value;
    using W = typename Ops::Work;
    const std::size_t n = std::size_t(2 * e), block = std::size_t(e) * e * e;
    tbb::parallel_for(tbb::blocked_range<int>(0, e, 4), [&](const tbb::blocked_range<int>& xs) {
        for (int X = xs.begin(); X < xs.end(); ++X)
            for (int Y = 0; Y < e; ++Y) {
                const V* r00 = in + (std::size_t(2 * X) * n + std::size_t(2 * Y)) * n; // rows (x, y) of the block
                const V* r01 = r00 + n;
                const V* r10 = r00 + n * n;
                const V* r11 = r10 + n;
                const std::size_t outRow = (std::size_t(X) * e + std::size_t(Y)) * e;
                for (int Z = 0; Z < e; ++Z) {
                    const int z = 2 * Z;
                    // x pass: [y][z] of low (Lx) and detail (Hx) along x
                    W lx00, hx00, lx01, hx01, lx10, hx10, lx11, hx11;
                    Ops::forward(W(r00[z]), W(r10[z]), lx00, hx00);
                    Ops::forward(W(r00[z + 1]), W(r10[z + 1]), lx01, hx01);
                    Ops::forward(W(r01[z]), W(r11[z]), lx10, hx10);
                    Ops::forward(W(r01[z + 1]), W(r11[z + 1]), lx11, hx11);
                    // y pass
                    W ll0, lh0, ll1, lh1, hl0, hh0, hl1, hh1;
                    Ops::forward(lx00, lx10, ll0, lh0);
                    Ops::forward(lx01, lx11, ll1, lh1);
                    Ops::forward(hx00, hx10, hl0, hh0);
                    Ops::forward(hx01, hx11, hl1, hh1);
                    // z pass; band b: high along x where b & 1, y where b & 2, z where b & 4
                    W c[8];
                    Ops::forward(ll0, ll1, c[0], c[4]);
                    Ops::forward(hl0, hl1, c[1], c[5]);
                    Ops::forward(lh0, lh1, c[2], c[6]);
                    Ops::forward(hh0, hh1, c[3], c[7]);
                    const std::size_t at = outRow + std::size_t(Z);
                    low[at] = V(c[0]);
                    for (int b = 1; b < 8; ++b) details[std::size_t(b - 1) * block + at] = V(c[b]);
                }
            }
    });
}

template<typename Ops>
void inverseLevel(const typename Ops::Value* low, const typename Ops::Value* details, int e, typename Ops::Value* out)
{
    using V = typename Ops::Value;
    using W = typename Ops::Work;
    const std::size_t n = std::size_t(2 * e), block = std::size_t(e) * e * e;
    tbb::parallel_for(tbb::blocked_range<int>(0, e, 4), [&](const tbb::blocked_range<int>& xs) {
        for (int X = xs.begin(); X < xs.end(); ++X)
            for (int Y = 0; Y < e; ++Y) {
                V* r00 = out + (std::size_t(2 * X) * n + std::size_t(2 * Y)) * n;
                V* r01 = r00 + n;
                V* r10 = r00 + n * n;
                V* r11 = r10 + n;
                const std::size_t inRow = (std::size_t(X) * e + std::size_t(Y)) * e;
                for (int Z = 0; Z < e; ++Z) {
                    const std::size_t at = inRow + std::size_t(Z);
                    W c[8];
                    c[0] = W(low[at]);
                    for (int b = 1; b < 8; ++b) c[b] = W(details[std::size_t(b - 1) * block + at]);
                    W ll0, ll1, hl0, hl1, lh0, lh1, hh0, hh1;
                    Ops::inverse(c[0], c[4], ll0, ll1);
                    Ops::inverse(c[1], c[5], hl0, hl1);
                    Ops::inverse(c[2], c[6], lh0, lh1);
                    Ops::inverse(c[3], c[7], hh0, hh1);
                    W lx00, lx10, lx01, lx11, hx00, hx10, hx01, hx11;
                    Ops::inverse(ll0, lh0, lx00, lx10);
                    Ops::inverse(ll1, lh1, lx01, lx11);
                    Ops::inverse(hl0, hh0, hx00, hx10);
                    Ops::inverse(hl1, hh1, hx01, hx11);
                    const int z = 2 * Z;
                    W a, b;
                    Ops::inverse(lx00, hx00, a, b), r00[z] = V(a), r10[z] = V(b);
                    Ops::inverse(lx01, hx01, a, b), r00[z + 1] = V(a), r10[z + 1] = V(b);
                    Ops::inverse(lx10, hx10, a, b), r01[z] = V(a), r11[z] = V(b);
                    Ops::inverse(lx11, hx11, a, b), r01[z + 1] = V(a), r11[z + 1] = V(b);
                }
            }
    });
}

void checkCube(std::size_t values, int edge, int levels)
{
    if (edge < 2 || (edge & (edge - 1)) != 0)
        throw std::invalid_argument("a Haar cube needs a power-of-two edge of at least 2, not " + std::to_string(edge));
    if (values != std::size_t(edge) * edge * edge)
        throw std::invalid_argument("a Haar cube of edge " + std::to_string(edge) + " needs edge^3 values");
    if (levels < 1 || (edge >> levels) < 1)
        throw std::invalid_argument("a cube of edge " + std::to_string(edge) + " has at most log2(edge) levels");
}

template<typename Ops>
DenseHaar<typename Ops::Value> decompose3D(const std::vector<typename Ops::Value>& values, int edge, int levels)
{
    checkCube(values.size(), edge, levels);
    DenseHaar<typename Ops::Value> haar;
    haar.edge = edge;
    haar.levels = levels;
    std::vector<typename Ops::Value> current, next;
    for (int k = 1; k <= levels; ++k) {
        const int e = edge >> k;
        const std::size_t block = std::size_t(e) * e * e;
        next.resize(block);
        haar.details.emplace_back(7 * block);
        forwardLevel<Ops>(k == 1 ? values.data() : current.data(), e, next.data(), haar.details.back().data());
        std::swap(current, next);
    }
    haar.low = std::move(current);
    return haar;
}

template<typename Ops>
std::vector<typename Ops::Value> extract3D(const DenseHaar<typename Ops::Value>& haar, int level)
{
    if (level < 0 || level > haar.levels)
        throw std::invalid_argument("level " + std::to_string(level) + " is outside 0 .. " + std::to_string(haar.levels));
    std::vector<typename Ops::Value> current = haar.low, next;
    for (int k = haar.levels; k > level; --k) {
        const int e = haar.edge >> k;
        next.resize(std::size_t(8) * e * e * e);
        inverseLevel<Ops>(current.data(), haar.details[std::size_t(k - 1)].data(), e, next.data());
        std::swap(current, next);
    }
    return current;
}

} // namespace

std::vector<double> averagingDecompose1D(std::vector<double> values)
{
    return decompose1D<DoubleAveraging>(std::move(values));
}
std::vector<double> averagingReconstruct1D(std::vector<double> coefficients)
{
    return reconstruct1D<DoubleAveraging>(std::move(coefficients));
}

std::vector<int32_t> liftingDecompose1D(std::vector<int32_t> values) { return decompose1D<Lifting>(std::move(values)); }
std::vector<int32_t> liftingReconstruct1D(std::vector<int32_t> coefficients)
{
    return reconstruct1D<Lifting>(std::move(coefficients));
}

DenseHaar<LiftingValue> liftingDecompose3D(const std::vector<LiftingValue>& values, int edge, int levels)
{
    return decompose3D<Lifting>(values, edge, levels);
}
DenseHaar<AveragingValue> averagingDecompose3D(const std::vector<AveragingValue>& values, int edge, int levels)
{
    return decompose3D<Averaging>(values, edge, levels);
}
std::vector<LiftingValue> liftingExtract3D(const DenseHaar<LiftingValue>& haar, int level)
{
    return extract3D<Lifting>(haar, level);
}
std::vector<AveragingValue> averagingExtract3D(const DenseHaar<AveragingValue>& haar, int level)
{
    return extract3D<Averaging>(haar, level);
}

std::size_t dropSmallDetails(DenseHaar<AveragingValue>& haar, float threshold)
{
    std::size_t dropped = 0;
    for (auto& level : haar.details)
        for (float& d : level)
            if (d != 0.0f && std::fabs(d) < threshold) d = 0.0f, ++dropped;
    return dropped;
}

} // namespace vdbclay::wavelet
