#include "query/ClusterD2Color.h"

#include "query/Isodata.h"
#include "query/MeshCurvature.h"
#include "query/SurfaceSamples.h"

#include <flann/flann.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace vdbclay::query {

namespace {

using Vec = std::array<double, 3>;

/// The seed's models are scaled to this surface area before anything is measured.
constexpr double kArea = 100.0;

double surfaceArea(const TriangleSoup& mesh)
{
    double total = 0.0;
    for (const auto& t : mesh.triangles) {
        const Vec &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
        const Vec u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const Vec n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        total += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return total;
}

/// For each sample, the indices of its neighbours (itself left out): those within `radius`, or the
/// `atLeast` nearest when fewer lie there.
std::vector<std::vector<int>> neighbourhoods(const std::vector<Vec>& points, double radius, std::size_t atLeast)
{
    std::vector<double> data;
    data.reserve(points.size() * 3);
    for (const Vec& p : points) data.insert(data.end(), p.begin(), p.end());
    flann::Matrix<double> matrix(data.data(), points.size(), 3);
    flann::Index<flann::L2<double>> index(matrix, flann::KDTreeSingleIndexParams(12));
    index.buildIndex();
    std::vector<std::vector<int>> found;
    std::vector<std::vector<double>> distances;
    flann::SearchParams exact(flann::FLANN_CHECKS_UNLIMITED, 0.0f, true);
    index.radiusSearch(matrix, found, distances, float(radius * radius), exact);
    const std::size_t k = std::min(atLeast + 1, points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (found[i].size() >= atLeast + 1) continue; // itself and enough others
        std::vector<std::vector<int>> nearest;
        std::vector<std::vector<double>> d;
        flann::Matrix<double> one(&data[i * 3], 1, 3);
        index.knnSearch(one, nearest, d, k, exact);
        found[i] = nearest[0];
    }
    for (std::size_t i = 0; i < points.size(); ++i) found[i].erase(std::remove(found[i].begin(), found[i].end(), int(i)), found[i].end());
    return found;
}

double srgbToLinear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

} // namespace

std::array<double, 3> cieLab(const std::array<float, 3>& rgb)
{
    const double r = srgbToLinear(std::clamp(double(rgb[0]), 0.0, 1.0)), g = srgbToLinear(std::clamp(double(rgb[1]), 0.0, 1.0)),
                 b = srgbToLinear(std::clamp(double(rgb[2]), 0.0, 1.0));
    // sRGB to XYZ, relative to the D65 white point.
    const double x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047;
    const double y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
    const double z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883;
    const auto f = [](double t) { return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0; };
    return {116.0 * f(y) - 16.0, 500.0 * (f(x) - f(y)), 200.0 * (f(y) - f(z))};
}

int colourCode(const std::array<float, 3>& rgb)
{
    const std::array<double, 3> lab = cieLab(rgb);
    const int l = std::clamp(int(lab[0] / 100.0 * 6.0), 0, 5);
    // a* and b* of displayable colours lie within about +-100: bins 50 wide, the greys (0) in the middle
    // of one rather than on an edge where rounding would scatter them.
    const int a = std::clamp(int(std::floor((lab[1] + 75.0) / 50.0)), 0, 3);
    const int b = std::clamp(int(std::floor((lab[2] + 75.0) / 50.0)), 0, 3);
    return (l * 4 + a) * 4 + b;
}

namespace {

/// What every run of the descriptor shares: the model scaled to area 100, welded, its vertices' mean
/// curvature, E and the number of samples.
struct Prepared {
    TriangleSoup mesh;
    WeldedMesh welded;
    std::vector<double> vertexCurvature;
    double edge = 0.0, curvature = 0.0;
    std::size_t count = 0;
};

Prepared prepare(const TriangleSoup& input, const ClusterD2Options& options)
{
    Prepared p;
    const double area = surfaceArea(input);
    if (!(area > 0.0) || !std::isfinite(area)) throw std::invalid_argument("the mesh has no surface area to describe");
    p.mesh = input;
    const double scale = std::sqrt(kArea / area);
    for (Vec& v : p.mesh.positions)
        for (double& c : v) c *= scale;

    p.welded = weldMesh(p.mesh);
    // E sets the neighbourhoods' and the clustering's scales. The seed takes the mesh's mean edge
    // length; here it is the spacing of the fewest samples on the model scaled to area 100 (the edge of
    // a mesh as fine as the samples), because a file's edges may be far finer or coarser (a box of 12
    // triangles, a scan of millions) and tessellation must not move the descriptor.
    p.edge = std::sqrt(kArea / double(options.minSamples));
    p.curvature = absoluteGaussianCurvature(p.welded);
    const double perSphere = p.curvature / (4.0 * M_PI);
    p.count = std::clamp(std::size_t(std::llround(double(options.minSamples) * std::max(1.0, perSphere))), options.minSamples,
                                         std::max(options.minSamples, options.maxSamples));
    p.vertexCurvature = meanCurvature(p.welded);
    return p;
}

/// One run: samples drawn with `seed`, selected, clustered, their distances binned.
Histogram describeOnce(const Prepared& p, const ClusterD2Options& options, uint64_t seed, ClusterD2Details* details)
{
    const WeldedMesh& welded = p.welded;
    const double edge = p.edge;
    const std::size_t count = p.count;
    const SurfaceSamples samples = sampleSurface(p.mesh, count, seed);
    const std::vector<std::vector<int>> around = neighbourhoods(samples.points, 2.0 * edge, options.minNeighbours);

    // Curvature maps C1..C3, each eight umbrella steps (lambda dt = 1) further than the one before, and
    // the difference of Laplacians D = |C2 - C1| + |C3 - C2|. The seed smooths over the mesh's vertices;
    // the samples, spread evenly by area, smooth the same way at the same geometric scale whatever the
    // tessellation (a vertex graph's eight steps reach eight edges, of any length).
    const std::vector<double>& vertexCurvature = p.vertexCurvature;
    std::vector<double> c0(count);
    for (std::size_t i = 0; i < count; ++i) {
        const auto& t = welded.triangles[samples.triangles[i]];
        c0[i] = 0.0;
        for (int c = 0; c < 3; ++c) c0[i] += samples.barycentric[i][std::size_t(c)] * vertexCurvature[t[std::size_t(c)]];
    }
    const auto smooth = [&](std::vector<double> values) {
        std::vector<double> next(values.size());
        for (int step = 0; step < 8; ++step) {
            for (std::size_t i = 0; i < values.size(); ++i) {
                if (around[i].empty()) {
                    next[i] = values[i];
                    continue;
                }
                double sum = 0.0;
                for (int j : around[i]) sum += values[std::size_t(j)];
                next[i] = sum / double(around[i].size());
            }
            values.swap(next);
        }
        return values;
    };
    const std::vector<double> c1 = smooth(c0), c2 = smooth(c1), c3 = smooth(c2);
    std::vector<double> saliency(count);
    double meanCurvature = 0.0;
    for (std::size_t i = 0; i < count; ++i) {
        saliency[i] = std::abs(c2[i] - c1[i]) + std::abs(c3[i] - c2[i]);
        meanCurvature += std::abs(c1[i]) / double(count);
    }
    // A difference far below the surface's own curvature is no feature, only how the mesh was cut (a
    // sphere's poles, a voxel lattice's facets): such samples rank alike, in the order they were drawn
    // (at random), so a featureless surface gives samples spread evenly rather than its tessellation's.
    const double floor = options.featureFloor * meanCurvature;
    for (double& d : saliency)
        if (d < floor) d = 0.0;
    std::vector<uint32_t> order(count);
    std::iota(order.begin(), order.end(), 0u);
    const std::size_t shapeCount = std::max<std::size_t>(1, std::size_t(double(count) * options.shapeShare));
    std::partial_sort(order.begin(), order.begin() + std::ptrdiff_t(shapeCount), order.end(),
                      [&](uint32_t a, uint32_t b) { return saliency[a] > saliency[b] || (saliency[a] == saliency[b] && a < b); });
    std::vector<bool> selected(count, false);
    for (std::size_t i = 0; i < shapeCount; ++i) selected[order[i]] = true;

    // Colour samples: where fewer than 80% of the neighbours share the colour code.
    std::vector<int> codes(count);
    bool severalCodes = false;
    for (std::size_t i = 0; i < count; ++i) {
        codes[i] = colourCode(samples.colours[i]);
        severalCodes |= codes[i] != codes[0];
    }
    std::size_t colourCount = 0;
    if (severalCodes) {
        for (std::size_t i = 0; i < count; ++i) {
            if (around[i].empty()) continue;
            const auto same = std::count_if(around[i].begin(), around[i].end(), [&](int j) { return codes[std::size_t(j)] == codes[i]; });
            if (double(same) < options.colourSameShare * double(around[i].size())) {
                ++colourCount;
                selected[i] = true;
            }
        }
    }

    std::vector<Vec> points;
    for (std::size_t i = 0; i < count; ++i)
        if (selected[i]) points.push_back(samples.points[i]);
    IsodataOptions clustering;
    clustering.minMembers = std::max<std::size_t>(1, std::size_t(std::llround(0.05 * double(points.size()))));
    clustering.maxSpread = 2.0 * edge;
    clustering.mergeDistance = 10.0 * edge;
    clustering.seed = seed;
    const Clustering clusters = isodataClusters(points, clustering);

    // Distances between samples of different clusters (all of them when one cluster holds every sample).
    std::vector<double> distances;
    const auto distance = [&](std::size_t a, std::size_t b) {
        const Vec &p = points[a], &q = points[b];
        return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
    };
    const bool oneCluster = clusters.centres.size() < 2;
    constexpr std::size_t kAllPairsUpTo = 2048;
    if (points.size() <= kAllPairsUpTo) {
        for (std::size_t a = 0; a < points.size(); ++a)
            for (std::size_t b = a + 1; b < points.size(); ++b)
                if (oneCluster || clusters.cluster[a] != clusters.cluster[b]) distances.push_back(distance(a, b));
    } else {
        std::mt19937_64 random(seed ^ 0x5bd1e995ull);
        std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
        for (std::size_t i = 0; i < kAllPairsUpTo * kAllPairsUpTo / 4; ++i) {
            const std::size_t a = pick(random), b = pick(random);
            if (a != b && (oneCluster || clusters.cluster[a] != clusters.cluster[b])) distances.push_back(distance(a, b));
        }
    }
    if (details) {
        details->samples = count;
        details->shapeSamples = shapeCount;
        details->colourSamples = colourCount;
        details->clusters = clusters.centres.size();
        details->edgeLength = edge;
        details->absoluteGaussianCurvature = p.curvature;
    }
    Histogram h(std::size_t(std::max(1, options.bins)), 0.0);
    if (distances.empty()) {
        h.front() = 1.0;
        return h;
    }
    const auto [lo, hi] = std::minmax_element(distances.begin(), distances.end());
    const double low = *lo, range = *hi - *lo;
    for (double d : distances) {
        const double t = range > 0.0 ? (d - low) / range : 0.0;
        h[std::min(h.size() - 1, std::size_t(t * double(h.size())))] += 1.0;
    }
    for (double& v : h) v /= double(distances.size());
    return h;
}

} // namespace

Histogram clusterD2ColorDescriptor(const TriangleSoup& input, const ClusterD2Options& options, ClusterD2Details* details)
{
    const Prepared prepared = prepare(input, options);
    // Samples, their selection and the clusters vary from one draw to the next: the mean of a few runs
    // (seeds seed, seed + 1, ...) holds still where one run would not.
    // The runs in parallel, summed in order (the same mean on any number of threads).
    const int runs = std::max(1, options.runs);
    std::vector<Histogram> each(static_cast<std::size_t>(runs));
    tbb::parallel_for(0, runs, [&](int r) {
        each[std::size_t(r)] = describeOnce(prepared, options, options.seed + uint64_t(r), r == 0 ? details : nullptr);
    });
    Histogram mean(std::size_t(std::max(1, options.bins)), 0.0);
    for (const Histogram& h : each)
        for (std::size_t b = 0; b < mean.size(); ++b) mean[b] += h[b] / double(runs);
    return mean;
}

} // namespace vdbclay::query
