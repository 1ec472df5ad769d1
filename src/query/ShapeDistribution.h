// D2 (Osada, Funkhouser, Chazelle and Dobkin 2002): the distribution of distances between random pairs of
// points on a surface, as a histogram. Distances are divided by their mean, so the descriptor ignores
// translation, rotation and uniform scale; points are spread by area, so it ignores tessellation.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <cstdint>
#include <vector>

namespace vdbclay::query {

/// A histogram whose bins sum to 1.
using Histogram = std::vector<double>;

struct D2Options {
    std::size_t points = 4096;     // samples on the surface
    std::size_t pairs = 1u << 18;  // random pairs among them
    int bins = 64;
    double range = 3.5;            // the last bin ends at this many mean distances (farther pairs count there)
    uint64_t seed = 1;
};

/// Throws std::invalid_argument for a mesh without area.
Histogram d2Descriptor(const TriangleSoup& mesh, const D2Options& options = {});

} // namespace vdbclay::query
