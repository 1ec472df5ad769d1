// Distances between histograms (seed 004 §4.1.4): chi-square and Jensen-Shannon, both on the histograms
// smoothed by a Gaussian kernel density estimate over their bins, so that a shift of a fraction of a
// bin (sampling noise, a slightly different proportion) costs little.
#pragma once

#include "query/ShapeDistribution.h"

namespace vdbclay::query {

/// The histogram convolved with a Gaussian of `sigmaBins` bins (edges reflect), summing to 1 again.
Histogram smoothHistogram(const Histogram& h, double sigmaBins = 1.0);

/// 1/2 sum (a - b)^2 / (a + b) over bins where a + b > 0: 0 for equal histograms, at most 1.
double chiSquareDistance(const Histogram& a, const Histogram& b);
/// The Jensen-Shannon divergence in bits: 0 for equal histograms, at most 1.
double jensenShannonDistance(const Histogram& a, const Histogram& b);

} // namespace vdbclay::query
