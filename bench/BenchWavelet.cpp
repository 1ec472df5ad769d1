// bench wavelet: the 3D Haar decomposition (5 levels) and the extraction of level 0 on dense cubes of
// 128^3, 256^3 and 512^3 densities, next to seed 001 Table 1 (0.6975 s and 0.7529 s for 128^3 on a
// 3 GHz PC) and to this machine's copy bandwidth measured in the same run on the same number of bytes;
// then the sparse LOD pyramid of a sculpted sphere next to OpenVDB's MultiResGrid on a level set of
// the same sphere; then the error of dropping small detail coefficients.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "wavelet/Haar.h"
#include "wavelet/LodPyramid.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/MultiResGrid.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <random>

namespace vdbclay::bench {

namespace {

constexpr double kPaperBuildSeconds = 0.6975, kPaperExtractSeconds = 0.7529;
constexpr int kLevels = 5;

struct DenseRow {
    int edge = 0;
    double buildSeconds = 0, extractSeconds = 0, copySeconds = 0;
    double averagingBuildSeconds = 0, averagingExtractSeconds = 0;
    std::size_t bytes = 0;
    bool exact = false;
    double bytesPerSecond() const { return double(bytes) / buildSeconds; }
    double copyBytesPerSecond() const { return double(bytes) / copySeconds; }
};

/// A density cube of a sphere with a noisy rim, as a sculpture's voxels would give.
std::vector<wavelet::LiftingValue> sphereDensities(int edge)
{
    std::vector<wavelet::LiftingValue> v(std::size_t(edge) * edge * edge);
    const double c = edge / 2.0, r = edge * 0.4;
    tbb::parallel_for(0, edge, [&](int x) {
        for (int y = 0; y < edge; ++y)
            for (int z = 0; z < edge; ++z) {
                const double d = std::sqrt((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)) - r;
                v[(std::size_t(x) * edge + std::size_t(y)) * edge + std::size_t(z)] =
                    wavelet::LiftingValue(std::clamp(127.5 - 127.5 * d, 0.0, 255.0));
            }
    });
    return v;
}

/// Median of `runs` timings of f, seconds.
template<typename F>
double medianSeconds(int runs, F&& f)
{
    std::vector<double> t;
    for (int i = 0; i < runs; ++i) t.push_back(timeMs(f) / 1000.0);
    return median(t);
}

DenseRow measureDense(int edge)
{
    DenseRow row;
    row.edge = edge;
    const std::vector<wavelet::LiftingValue> values = sphereDensities(edge);
    row.bytes = values.size() * sizeof(wavelet::LiftingValue);
    const int runs = edge >= 512 ? 3 : 7;
    // The copy writes into a buffer allocated per run, as the transforms allocate their output.
    row.copySeconds = medianSeconds(runs, [&] {
        std::vector<wavelet::LiftingValue> copy(values.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size(), 1 << 16), [&](const auto& r) {
            std::memcpy(copy.data() + r.begin(), values.data() + r.begin(), (r.end() - r.begin()) * sizeof(values[0]));
        });
    });
    wavelet::DenseHaar<wavelet::LiftingValue> haar;
    row.buildSeconds = medianSeconds(runs, [&] { haar = wavelet::liftingDecompose3D(values, edge, kLevels); });
    std::vector<wavelet::LiftingValue> back;
    row.extractSeconds = medianSeconds(runs, [&] { back = wavelet::liftingExtract3D(haar, 0); });
    row.exact = back == values;

    const std::vector<float> floats(values.begin(), values.end());
    wavelet::DenseHaar<float> averaging;
    row.averagingBuildSeconds = medianSeconds(runs, [&] { averaging = wavelet::averagingDecompose3D(floats, edge, kLevels); });
    row.averagingExtractSeconds = medianSeconds(runs, [&] { (void)wavelet::averagingExtract3D(averaging, 0); });
    return row;
}

struct SparseRow {
    double radius = 0;
    uint64_t leaves = 0;
    int levels = 0;
    double buildSeconds = 0, extractSeconds = 0;
    uint64_t coarseLeaves = 0;
    double vdbBuildSeconds = 0;
    uint64_t vdbLeaves = 0;
};

SparseRow measureSparse(double radius)
{
    SparseRow row;
    row.radius = radius;
    Volume volume(1.0);
    Primitive p;
    p.shape = Shape::Sphere;
    p.radius = radius;
    CsgOp add;
    add.mode = CsgMode::Add;
    applyCsg(volume, Brush(p, Placement{}), add);
    row.leaves = volume.stats().leafCount;
    row.levels = kLevels;
    wavelet::LodPyramid pyramid(kLevels);
    row.buildSeconds = medianSeconds(5, [&] { pyramid.build(volume); });
    Volume level1(2.0);
    row.extractSeconds = medianSeconds(5, [&] { level1 = pyramid.coarseVolume(volume, 1); });
    row.coarseLeaves = level1.stats().leafCount;

    auto levelSet = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(radius), openvdb::Vec3f(0.0f), 1.0f, 3.0f);
    row.vdbLeaves = levelSet->tree().leafCount();
    row.vdbBuildSeconds = medianSeconds(5, [&] {
        openvdb::tools::MultiResGrid<openvdb::FloatTree> multi(size_t(kLevels + 1), *levelSet);
        (void)multi;
    });
    return row;
}

struct CompressionRow {
    float threshold = 0;
    double droppedFraction = 0, maxError = 0, meanError = 0;
};

std::vector<CompressionRow> measureCompression(int edge)
{
    std::vector<wavelet::LiftingValue> ints = sphereDensities(edge);
    std::mt19937 rng(1);
    std::normal_distribution<float> noise(0.0f, 2.0f);
    std::vector<float> values(ints.begin(), ints.end());
    for (float& v : values) v += noise(rng); // a rough surface: details of every size
    std::vector<CompressionRow> rows;
    for (const float threshold : {0.5f, 1.0f, 2.0f, 4.0f}) {
        wavelet::DenseHaar<float> haar = wavelet::averagingDecompose3D(values, edge, kLevels);
        std::size_t nonZero = 0;
        for (const auto& level : haar.details)
            for (float d : level) nonZero += d != 0.0f;
        CompressionRow row;
        row.threshold = threshold;
        row.droppedFraction = double(wavelet::dropSmallDetails(haar, threshold)) / double(std::max<std::size_t>(nonZero, 1));
        const std::vector<float> lossy = wavelet::averagingExtract3D(haar, 0);
        double sum = 0.0;
        for (std::size_t i = 0; i < values.size(); ++i) {
            const double e = std::fabs(double(lossy[i]) - double(values[i]));
            row.maxError = std::max(row.maxError, e);
            sum += e;
        }
        row.meanError = sum / double(values.size());
        rows.push_back(row);
    }
    return rows;
}

} // namespace

int benchWavelet(bool json, bool quick)
{
    std::vector<DenseRow> dense;
    for (const int edge : quick ? std::vector<int>{128} : std::vector<int>{128, 256, 512}) dense.push_back(measureDense(edge));
    const SparseRow sparse = measureSparse(quick ? 100.0 : 400.0);
    const std::vector<CompressionRow> compression = measureCompression(quick ? 64 : 128);

    if (json) {
        nlohmann::json out = jsonPreamble("wavelet", quick);
        out["levels"] = kLevels;
        out["paper_128"] = {{"build_seconds", kPaperBuildSeconds}, {"extract_seconds", kPaperExtractSeconds}};
        nlohmann::json sizes = nlohmann::json::object();
        for (const auto& r : dense) {
            sizes[std::to_string(r.edge)] = {{"build_seconds", r.buildSeconds},
                                             {"extract_seconds", r.extractSeconds},
                                             {"bytes_per_second", r.bytesPerSecond()},
                                             {"bytes", r.bytes},
                                             {"copy_bytes_per_second", r.copyBytesPerSecond()},
                                             {"fraction_of_copy_bandwidth", r.bytesPerSecond() / r.copyBytesPerSecond()},
                                             {"averaging_build_seconds", r.averagingBuildSeconds},
                                             {"averaging_extract_seconds", r.averagingExtractSeconds},
                                             {"lossless", r.exact}};
        }
        out["sizes"] = sizes;
        out["sparse"] = {{"sphere_radius", sparse.radius},
                         {"leaves", sparse.leaves},
                         {"levels", sparse.levels},
                         {"build_seconds", sparse.buildSeconds},
                         {"extract_level1_seconds", sparse.extractSeconds},
                         {"level1_leaves", sparse.coarseLeaves},
                         {"openvdb_multires_seconds", sparse.vdbBuildSeconds},
                         {"openvdb_leaves", sparse.vdbLeaves}};
        nlohmann::json lossy = nlohmann::json::array();
        for (const auto& c : compression)
            lossy.push_back({{"threshold", c.threshold}, {"dropped_fraction", c.droppedFraction}, {"max_error", c.maxError}, {"mean_error", c.meanError}});
        out["compression"] = lossy;
        std::cout << out.dump() << std::endl;
        return 0;
    }

    printPreamble(std::cout, "wavelet", quick);
    std::cout << "Dense cubes of 16-bit densities, integer Haar (lifting), " << kLevels
              << " levels; seed 001 Table 1: 128^3 built in " << kPaperBuildSeconds << " s, level 0 extracted in "
              << kPaperExtractSeconds << " s (3 GHz PC). Copy = a parallel memcpy of the same bytes in this run.\n\n";
    Table t;
    t.header = {"edge", "build ms", "extract ms", "x paper (build)", "build GB/s", "copy GB/s", "of copy", "averaging build ms",
                "averaging extract ms", "lossless"};
    for (const auto& r : dense) {
        t.rows.push_back({std::to_string(r.edge) + "^3", fixed(r.buildSeconds * 1e3, 2), fixed(r.extractSeconds * 1e3, 2),
                          r.edge == 128 ? fixed(kPaperBuildSeconds / r.buildSeconds, 0) : "",
                          fixed(r.bytesPerSecond() / 1e9, 2), fixed(r.copyBytesPerSecond() / 1e9, 2),
                          fixed(r.bytesPerSecond() / r.copyBytesPerSecond(), 2), fixed(r.averagingBuildSeconds * 1e3, 2),
                          fixed(r.averagingExtractSeconds * 1e3, 2), r.exact ? "yes" : "NO"});
    }
    t.print(std::cout);
    std::cout << "\nSparse pyramid of a sculpted sphere (radius " << fixed(sparse.radius, 0) << ", " << sparse.leaves
              << " leaves, " << sparse.levels << " levels) vs OpenVDB tools::MultiResGrid (" << sparse.levels + 1
              << " trees) on a level set of the same sphere (" << sparse.vdbLeaves << " leaves):\n\n";
    Table s;
    s.header = {"ours build ms", "ours level-1 Hermite data ms", "level-1 leaves", "OpenVDB MultiResGrid ms"};
    s.rows.push_back({fixed(sparse.buildSeconds * 1e3, 1), fixed(sparse.extractSeconds * 1e3, 1), std::to_string(sparse.coarseLeaves),
                      fixed(sparse.vdbBuildSeconds * 1e3, 1)});
    s.print(std::cout);
    std::cout << "\nLossy compression (averaging variant, noisy density cube): details below the threshold dropped:\n\n";
    Table c;
    c.header = {"threshold", "details dropped", "max error", "mean error"};
    for (const auto& r : compression)
        c.rows.push_back({fixed(r.threshold, 1), fixed(100.0 * r.droppedFraction, 1) + " %", fixed(r.maxError, 3), fixed(r.meanError, 4)});
    c.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
