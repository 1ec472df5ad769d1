// The modified ISODATA clustering of ClusterD2+Color (Liu et al.; seed 004 §4.1.4): k-means whose
// clusters split when they spread too wide, merge when their centres come too close, and dissolve when
// too few points stay in them, so the number of clusters follows the points.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vdbclay::query {

struct IsodataOptions {
    std::size_t minMembers = 1;   // Pn: a cluster with fewer points dissolves
    double maxSpread = 1.0;       // Ps: a cluster whose standard deviation along an axis passes this splits
    double mergeDistance = 1.0;   // Pc: clusters whose centres are closer merge
    int maxIterations = 100;      // I: split-and-merge rounds at most
    int minIterations = 10;       // Imin: rounds at least, converged or not
    int maxSweeps = 200;          // Inc: assignment sweeps at most over all rounds (no convergence: stop)
    std::size_t initialClusters = 8;
    uint64_t seed = 1;            // the first centres (farthest points from a seeded start)
};

struct Clustering {
    std::vector<uint32_t> cluster;               // per point
    std::vector<std::array<double, 3>> centres; // per cluster
    int iterations = 0, sweeps = 0;
    bool converged = false;
};

/// Deterministic for the same points and options. An empty input gives no clusters.
Clustering isodataClusters(const std::vector<std::array<double, 3>>& points, const IsodataOptions& options);

} // namespace vdbclay::query
