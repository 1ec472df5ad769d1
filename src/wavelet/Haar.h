// 3D Haar wavelets (seed 001 §2.1-2.2): one level takes the 1D transform along x, then y, then z, and
// splits a cube into a low-pass block (half the edge) and seven detail blocks. Two variants:
//  * integer lifting (the S-transform): low = floor((a + b) / 2), detail = a - b; reconstructs bit-exactly;
//  * the paper's averaging one: low = (a + b) / 2, detail = (a - b) / 2 ([9, 7, 3, 5] -> [6, 2, 1, -1]).
// Dense arrays are indexed (x * n + y) * n + z (z fastest), as OpenVDB's leaves and Dense grids are.
// Light header: no OpenVDB.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vdbclay::wavelet {

/// The integer transform's coefficients: 8-bit densities stay within 16 bits through any number of
/// levels (a level's details are at most 4 x 255 in magnitude).
using LiftingValue = int16_t;
using AveragingValue = float;

// --- one pair, one 2x2x2 block --------------------------------------------------------------------

inline void liftingForward(int32_t a, int32_t b, int32_t& low, int32_t& detail)
{
    detail = a - b;
    low = b + (detail >> 1); // floor((a + b) / 2): the shift floors negative details too
}
inline void liftingInverse(int32_t low, int32_t detail, int32_t& a, int32_t& b)
{
    b = low - (detail >> 1);
    a = detail + b;
}
inline void averagingForward(float a, float b, float& low, float& detail)
{
    low = (a + b) * 0.5f;
    detail = (a - b) * 0.5f;
}
inline void averagingInverse(float low, float detail, float& a, float& b)
{
    a = low + detail;
    b = low - detail;
}

// --- 1D sequences (the paper's worked example) ----------------------------------------------------

/// The full decomposition of a sequence whose length is a power of two: the last level's low-pass value
/// first, then the details from the coarsest level to the finest (the paper's "final sequence").
std::vector<double> averagingDecompose1D(std::vector<double> values);
std::vector<double> averagingReconstruct1D(std::vector<double> coefficients);
std::vector<int32_t> liftingDecompose1D(std::vector<int32_t> values);
std::vector<int32_t> liftingReconstruct1D(std::vector<int32_t> coefficients);

// --- dense cubes ----------------------------------------------------------------------------------

/// A cube of edge `edge` decomposed over `levels` levels. Level k (1 .. levels) has edge e = edge >> k
/// and holds seven detail blocks of e^3 values, block b (1 .. 7) being the one that is high-pass along
/// x where b & 1, along y where b & 2, along z where b & 4. `low` is the last level's low-pass block.
template<typename T>
struct DenseHaar {
    int edge = 0;
    int levels = 0;
    std::vector<std::vector<T>> details; // details[k - 1]: 7 * (edge >> k)^3 values, block-major
    std::vector<T> low;                  // (edge >> levels)^3 values
};

/// Throws std::invalid_argument unless `edge` is a power of two, `values` holds edge^3 values and
/// 1 <= levels <= log2(edge). Parallel over slabs with TBB.
DenseHaar<LiftingValue> liftingDecompose3D(const std::vector<LiftingValue>& values, int edge, int levels);
DenseHaar<AveragingValue> averagingDecompose3D(const std::vector<AveragingValue>& values, int edge, int levels);

/// The field at `level` (0 = the original, edge >> level per side) rebuilt from the coarsest low-pass
/// block and the details of the levels above it. Lifting: bit-exact.
std::vector<LiftingValue> liftingExtract3D(const DenseHaar<LiftingValue>& haar, int level);
std::vector<AveragingValue> averagingExtract3D(const DenseHaar<AveragingValue>& haar, int level);

/// Lossy compression: sets every detail coefficient of magnitude below `threshold` to zero and returns
/// how many it dropped.
std::size_t dropSmallDetails(DenseHaar<AveragingValue>& haar, float threshold);

} // namespace vdbclay::wavelet
