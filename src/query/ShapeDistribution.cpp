#include "query/ShapeDistribution.h"

#include "query/SurfaceSamples.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace vdbclay::query {

Histogram d2Descriptor(const TriangleSoup& mesh, const D2Options& options)
{
    const SurfaceSamples samples = sampleSurface(mesh, options.points, options.seed);
    std::mt19937_64 random(options.seed ^ 0x9e3779b97f4a7c15ull);
    std::uniform_int_distribution<std::size_t> pick(0, samples.points.size() - 1);
    std::vector<double> distances;
    distances.reserve(options.pairs);
    double sum = 0.0;
    for (std::size_t i = 0; i < options.pairs; ++i) {
        const auto& a = samples.points[pick(random)];
        const auto& b = samples.points[pick(random)];
        const double d = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        distances.push_back(d);
        sum += d;
    }
    Histogram h(std::size_t(options.bins), 0.0);
    const double mean = sum / double(distances.size());
    if (!(mean > 0.0)) {
        h.front() = 1.0; // a point-like mesh: every distance is zero
        return h;
    }
    const double scale = double(options.bins) / (options.range * mean);
    for (double d : distances) h[std::min(std::size_t(d * scale), h.size() - 1)] += 1.0;
    for (double& v : h) v /= double(distances.size());
    return h;
}

} // namespace vdbclay::query
