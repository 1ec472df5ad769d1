// bench retrieval: shape retrieval measured as the Princeton Shape Benchmark measures it. DIR holds one
// folder per class of models (absent: the synthetic labeled set of src/query, six parametric families).
// Every model queries the others (leave one out) through the library (FLANN's shortlist ranked exactly);
// per descriptor (ClusterD2+Color, D2 the baseline, the light field, combined) and metric: nearest
// neighbour, first tier, second tier, DCG, mean average precision, mean query time; the library's build
// time and each descriptor's time per 100k triangles; then a k=10 query over 100k indexed descriptors
// (FLANN's k-means tree on clustered data, as real libraries are). Without a Vulkan device the light
// field is left out.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "query/ClusterD2Color.h"
#include "query/DescriptorIndex.h"
#include "query/HistogramDistance.h"
#include "query/ModelLibrary.h"
#include "query/SyntheticModels.h"
#include "render/ModelViews.h"
#include "render/VulkanContext.h"
#include "voxelize/TriangleMesh.h"

#include <cmath>
#include <functional>
#include <filesystem>
#include <iostream>
#include <map>
#include <random>
#include <type_traits>

namespace vdbclay::bench {

namespace {

namespace fs = std::filesystem;

struct Model {
    std::string label, name, path;
    TriangleSoup mesh;
};

std::vector<Model> readClasses(const std::string& dir)
{
    std::vector<Model> out;
    std::vector<fs::path> classes;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.is_directory()) classes.push_back(e.path());
    std::sort(classes.begin(), classes.end());
    for (const fs::path& c : classes) {
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(c))
            if (e.is_regular_file() && isMeshPath(e.path().string())) files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const fs::path& f : files) {
            try {
                out.push_back({c.filename().string(), c.filename().string() + "/" + f.stem().string(), f.string(), loadTriangleMesh(f.string())});
            } catch (const std::exception& e) {
                std::cerr << "bench retrieval: skipped " << f.string() << ": " << e.what() << "\n";
            }
        }
    }
    return out;
}

struct Measures {
    double nn = 0, firstTier = 0, secondTier = 0, dcg = 0, map = 0, queryMs = 0;
};

/// The PSB measures of one ranking (the query left out) for a query of class `label` of `classSize` models.
void score(const std::vector<std::string>& ranked, const std::string& label, std::size_t classSize, Measures& m)
{
    const std::size_t relevant = classSize - 1;
    if (relevant == 0 || ranked.empty()) return;
    m.nn += ranked.front() == label;
    std::size_t found = 0, inFirst = 0, inSecond = 0;
    double dcg = 0.0, ideal = 0.0, precisionSum = 0.0;
    for (std::size_t i = 0; i < ranked.size(); ++i) {
        const bool hit = ranked[i] == label;
        const double gain = i == 0 ? 1.0 : 1.0 / std::log2(double(i + 1));
        if (hit) {
            ++found;
            dcg += gain;
            precisionSum += double(found) / double(i + 1);
            if (i < relevant) ++inFirst;
            if (i < 2 * relevant) ++inSecond;
        }
        if (i < relevant) ideal += gain;
    }
    m.firstTier += double(inFirst) / double(relevant);
    m.secondTier += double(inSecond) / double(relevant);
    m.dcg += dcg / ideal;
    m.map += precisionSum / double(relevant);
}

} // namespace

int benchRetrieval(bool json, bool quick, const std::string& dir)
{
    const ScratchDir scratch("retrieval");
    std::vector<Model> models;
    if (dir.empty()) {
        for (const query::LabeledModel& m : query::syntheticSet(quick ? 6 : 20, 42))
            models.push_back({m.label, m.label + "/" + m.name, "", query::buildShape(m.shape)});
    } else {
        models = readClasses(dir);
    }
    if (models.size() < 2) {
        std::cerr << "vdbclay: error: bench retrieval needs two models or more in class folders under " << dir << "\n";
        return 1;
    }
    std::map<std::string, std::size_t> classSize;
    for (const Model& m : models) ++classSize[m.label];

    std::unique_ptr<render::VulkanContext> context;
    std::unique_ptr<render::ModelViews> views;
    try {
        context = std::make_unique<render::VulkanContext>();
        views = std::make_unique<render::ModelViews>(*context);
    } catch (const std::exception& e) {
        std::cerr << "bench retrieval: no light field (" << e.what() << ")\n";
        views.reset();
    }
    std::vector<query::ModelDescription> descriptions(models.size());
    double shapeMs = 0.0, viewsMs = 0.0;
    for (std::size_t i = 0; i < models.size(); ++i) {
        shapeMs += timeMs([&] { query::describeShape(models[i].mesh, descriptions[i]); });
        if (views) viewsMs += timeMs([&] { query::describeViews(*views, models[i].mesh, descriptions[i]); });
    }
    // Each descriptor's time on a mesh of 100k triangles (an ellipsoid of 2 x 158 x 158 quads), median of 3.
    query::SyntheticShape fine;
    fine.family = "ellipsoid";
    fine.tessellation = 158;
    const TriangleSoup hundredK = query::buildShape(fine);
    const double per100k = 1e5 / double(hundredK.triangles.size());
    const auto medianMs = [&](const std::function<void()>& work) {
        std::vector<double> runs;
        for (int r = 0; r < 3; ++r) runs.push_back(timeMs(work));
        return median(runs) * per100k;
    };
    nlohmann::json describeMs = {{"d2", medianMs([&] { query::d2Descriptor(hundredK); })},
                                 {"clusterd2", medianMs([&] { query::clusterD2ColorDescriptor(hundredK); })}};
    if (views) describeMs["lightfield"] = medianMs([&] { query::lightFieldDescriptor(*views, hundredK); });
    const std::string libraryPath = (scratch.path() / "bench.vdblib").string();
    query::ModelLibrary library(libraryPath, true);
    const double buildMs = timeMs([&] {
        for (std::size_t i = 0; i < models.size(); ++i) library.add(models[i].name, models[i].path, models[i].label, models[i].mesh, descriptions[i]);
        library.query(descriptions.front(), 1, query::Descriptor::Combined); // builds and saves FLANN's indexes
    });

    nlohmann::json out = jsonPreamble("retrieval", quick);
    Table table{{"descriptor", "metric", "NN", "first tier", "second tier", "DCG", "mAP", "query ms", "k=10 ms"}, {}};
    for (const query::Descriptor descriptor : {query::Descriptor::ClusterD2, query::Descriptor::D2, query::Descriptor::LightField, query::Descriptor::Combined}) {
        if (descriptor == query::Descriptor::LightField && !views) continue;
        nlohmann::json perMetric;
        for (const query::Metric metric : {query::Metric::ChiSquare, query::Metric::JensenShannon}) {
            if (descriptor == query::Descriptor::LightField && metric == query::Metric::JensenShannon) continue; // L1 only
            Measures m;
            for (std::size_t i = 0; i < models.size(); ++i) {
                std::vector<query::QueryHit> hits;
                m.queryMs += timeMs([&] { hits = library.query(descriptions[i], models.size(), descriptor, metric); });
                std::vector<std::string> ranked;
                for (const query::QueryHit& h : hits)
                    if (h.model.name != models[i].name) ranked.push_back(h.model.label);
                score(ranked, models[i].label, classSize[models[i].label], m);
            }
            // The query a user makes: the ten nearest (FLANN's shortlist of 64 ranked exactly).
            std::vector<double> k10;
            for (std::size_t i = 0; i < models.size(); ++i) k10.push_back(timeMs([&] { library.query(descriptions[i], 10, descriptor, metric); }));
            const double n = double(models.size());
            const nlohmann::json measures = {{"nn", m.nn / n},   {"first_tier", m.firstTier / n}, {"second_tier", m.secondTier / n},
                                             {"dcg", m.dcg / n}, {"map", m.map / n},              {"query_ms", m.queryMs / n},
                                             {"query_k10_ms", median(k10)}};
            const std::string metricLabel = descriptor == query::Descriptor::LightField ? "l1" : query::metricName(metric);
            if (descriptor == query::Descriptor::LightField) perMetric = measures;
            else perMetric[metricLabel] = measures;
            table.rows.push_back({query::descriptorName(descriptor), metricLabel, fixed(m.nn / n, 3), fixed(m.firstTier / n, 3),
                                  fixed(m.secondTier / n, 3), fixed(m.dcg / n, 3), fixed(m.map / n, 3), fixed(m.queryMs / n, 3),
                                  fixed(median(k10), 3)});
        }
        out[query::descriptorName(descriptor)] = perMetric;
    }
    std::vector<query::Histogram> descriptors;
    for (const query::ModelDescription& d : descriptions) descriptors.push_back(d.d2);

    // A large library: descriptors mixed from the measured ones (pairs of one class, with noise), so the
    // vectors cluster as real libraries' do; FLANN's k-means tree, k = 10, the shortlist ranked exactly.
    const std::size_t large = quick ? 10000 : 100000;
    std::mt19937_64 random(7);
    std::uniform_int_distribution<std::size_t> pick(0, descriptors.size() - 1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    // Every component scaled by 0.8 .. 1.2; a histogram's then summing to 1 again.
    const auto jitter = [&](const auto& v, bool normalize) {
        std::remove_cv_t<std::remove_reference_t<decltype(v)>> out(v.size());
        double sum = 0.0;
        for (std::size_t b = 0; b < v.size(); ++b) sum += out[b] = v[b] * (0.8 + 0.4 * unit(random));
        if (normalize && sum > 0.0)
            for (auto& x : out) x /= sum;
        return out;
    };
    std::vector<std::vector<float>> vectors;
    std::vector<query::Histogram> histograms;
    for (std::size_t i = 0; i < large; ++i) {
        query::Histogram h = jitter(descriptors[pick(random)], true);
        vectors.emplace_back(h.begin(), h.end());
        histograms.push_back(std::move(h));
    }
    std::unique_ptr<query::DescriptorIndex> index;
    const double largeBuildMs = timeMs([&] { index = std::make_unique<query::DescriptorIndex>(vectors); });
    std::vector<double> largeQueryMs;
    for (int q = 0; q < 200; ++q) {
        const query::Histogram& probe = descriptors[std::size_t(q) % descriptors.size()];
        largeQueryMs.push_back(timeMs([&] {
            const std::vector<float> f(probe.begin(), probe.end());
            std::vector<std::pair<double, std::size_t>> ranked;
            for (std::size_t i : index->nearest(f, 64)) ranked.push_back({query::chiSquareDistance(probe, histograms[i]), i});
            std::partial_sort(ranked.begin(), ranked.begin() + std::min<std::ptrdiff_t>(10, std::ptrdiff_t(ranked.size())), ranked.end());
        }));
    }

    // The same size of library through ModelLibrary (SQLite and FLANN as a user's), its descriptions
    // mixed from the measured ones the same way (every component scaled by 0.8 .. 1.2, histograms summing
    // to 1 again), added in batches; then k = 10 for each ranking, as the editor asks.
    const std::string largePath = (scratch.path() / "large.vdblib").string();
    std::map<std::string, std::vector<double>> largeLibraryMs;
    double largeLibraryBuildMs = 0.0;
    {
        query::ModelLibrary big(largePath, true);
        largeLibraryBuildMs = timeMs([&] {
            constexpr std::size_t kBatch = 2000;
            for (std::size_t first = 0; first < large; first += kBatch) {
                std::vector<query::ModelDescription> batch;
                std::vector<std::size_t> source;
                for (std::size_t i = first; i < std::min(large, first + kBatch); ++i) {
                    source.push_back(pick(random));
                    const query::ModelDescription& d = descriptions[source.back()];
                    query::ModelDescription mixed;
                    mixed.d2 = jitter(d.d2, true);
                    mixed.clusterD2 = jitter(d.clusterD2, true);
                    if (!d.lightField.empty()) mixed.lightField = jitter(d.lightField, false);
                    batch.push_back(std::move(mixed));
                }
                std::vector<query::ModelLibrary::NewModel> adds;
                for (std::size_t j = 0; j < batch.size(); ++j)
                    adds.push_back({"m" + std::to_string(first + j), "", models[source[j]].label, &models[source[j]].mesh, &batch[j]});
                big.addAll(adds);
            }
            big.query(descriptions.front(), 1, query::Descriptor::Combined); // builds and saves FLANN's indexes
        });
        for (const query::Descriptor descriptor : {query::Descriptor::ClusterD2, query::Descriptor::D2, query::Descriptor::LightField, query::Descriptor::Combined}) {
            if (descriptor == query::Descriptor::LightField && !views) continue;
            std::vector<double>& ms = largeLibraryMs[query::descriptorName(descriptor)];
            for (int q = 0; q < 100; ++q)
                ms.push_back(timeMs([&] { big.query(descriptions[std::size_t(q) % descriptions.size()], 10, descriptor); }));
        }
    }

    out["models"] = models.size();
    out["classes"] = classSize.size();
    out["library_build_ms"] = buildMs;
    out["describe_ms_per_model"] = {{"clusterd2_and_d2", shapeMs / double(models.size())}, {"lightfield_and_thumbnail", viewsMs / double(models.size())}};
    out["descriptor_ms_per_100k_triangles"] = describeMs;
    out["large_library"] = {{"models", large}, {"build_ms", largeBuildMs}, {"query_ms_median", median(largeQueryMs)},
                            {"query_ms_p99", percentile(largeQueryMs, 0.99)}};
    nlohmann::json largeLibrary = {{"models", large}, {"build_ms", largeLibraryBuildMs}, {"bytes", std::filesystem::file_size(largePath)}};
    for (const auto& [name, ms] : largeLibraryMs) largeLibrary["k10_ms"][name] = {{"median", median(ms)}, {"p99", percentile(ms, 0.99)}};
    out["large_model_library"] = largeLibrary;
    if (json) {
        std::cout << out.dump(2) << std::endl;
        return 0;
    }
    printPreamble(std::cout, "retrieval", quick);
    std::cout << models.size() << " models in " << classSize.size() << " classes (" << (dir.empty() ? std::string("the synthetic set") : dir)
              << "), each querying the others\n\n";
    table.print(std::cout);
    std::cout << "\nlibrary built in " << fixed(buildMs, 1) << " ms; per 100k-triangle mesh (goal < 500 ms):";
    for (const auto& [name, ms] : describeMs.items()) std::cout << " " << name << " " << fixed(ms.get<double>(), 1) << " ms";
    std::cout << "\n";
    std::cout << "k=10 over " << large << " indexed descriptors: median " << fixed(median(largeQueryMs), 3) << " ms, p99 "
              << fixed(percentile(largeQueryMs, 0.99), 3) << " ms (goal < 2 at 100k; index built in " << fixed(largeBuildMs / 1000.0, 1) << " s)\n";
    std::cout << "k=10 in a library of " << large << " models (" << megabytes(double(std::filesystem::file_size(largePath))) << ", built in "
              << fixed(largeLibraryBuildMs / 1000.0, 1) << " s), median / p99:";
    for (const auto& [name, ms] : largeLibraryMs) std::cout << " " << name << " " << fixed(median(ms), 3) << " / " << fixed(percentile(ms, 0.99), 3) << " ms";
    std::cout << "\n";
    return 0;
}

} // namespace vdbclay::bench
