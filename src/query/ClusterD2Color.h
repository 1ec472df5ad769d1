// ClusterD2+Color (Liu et al.; seed 004 §4.1.3-4.1.4): D2 over the salient points of a surface only,
// clustered. Shape samples are where the difference of curvature maps smoothed at two scales is largest
// (features: tips, rims, creases), colour samples where the colour changes; the modified ISODATA
// clusters them, and the descriptor is the histogram of the distances between samples of different
// clusters, normalized to [0, 1]. Two models of one shape but other colour patterns differ.
#pragma once

#include "query/ShapeDistribution.h"

#include <cstdint>

namespace vdbclay::query {

struct ClusterD2Options {
    int bins = 20;
    std::size_t minSamples = 6144;  // samples at the least (a convex surface, whose |K| integrates to 4 pi)
    std::size_t maxSamples = 16384; // however curved the surface
    double shapeShare = 0.10;       // the samples with the highest difference of curvature maps kept
    double featureFloor = 0.02;     // differences below this share of the mean |C1| count as none
    double colourSameShare = 0.80;  // a colour sample has fewer neighbours of its colour code than this share
    std::size_t minNeighbours = 5;
    uint64_t seed = 1;
    int runs = 4; // the histogram is the mean of this many runs, each with samples of its own
};

/// What the descriptor was built from (for tests and tools that show it).
struct ClusterD2Details {
    std::size_t samples = 0, shapeSamples = 0, colourSamples = 0, clusters = 0;
    double edgeLength = 0.0; // E, of the mesh scaled to area 100 (as the clustering used it)
    double absoluteGaussianCurvature = 0.0;
};

/// Throws std::invalid_argument for a mesh without area.
Histogram clusterD2ColorDescriptor(const TriangleSoup& mesh, const ClusterD2Options& options = {}, ClusterD2Details* details = nullptr);

/// CIELAB's L* a* b* of an sRGB colour (components 0..1, D65 white).
std::array<double, 3> cieLab(const std::array<float, 3>& rgb);
/// The colour code of ClusterD2+Color: L* in 6 bins, a* and b* in 4 each (96 codes).
int colourCode(const std::array<float, 3>& rgb);

} // namespace vdbclay::query
