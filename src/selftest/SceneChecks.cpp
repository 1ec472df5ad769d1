#include "selftest/SceneChecks.h"

#include "mesher/MeshChunkSet.h"
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "selftest/ExactScene.h"
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/Volume.h"

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include <algorithm>
#include <optional>

#include <cmath>
#include <random>
#include <sstream>

namespace vdbclay {

namespace {

struct SceneFailure {
    std::string what;
};

[[noreturn]] void fail(const std::string& what) { throw SceneFailure{what}; }

MeshOptions mesherOptions(MesherKind kind, int maxCellWidth)
{
    MeshOptions o;
    o.kind = kind;
    o.maxCellWidth = maxCellWidth;
    return o;
}

struct Variant {
    const char* name;
    MeshOptions options;
};

const Variant kVariants[] = {{"mc", mesherOptions(MesherKind::MarchingCubes, 1)},
                             {"cms-uniform", mesherOptions(MesherKind::CubicalMarchingSquares, 1)},
                             {"cms-adaptive", mesherOptions(MesherKind::CubicalMarchingSquares, 8)}};
constexpr int kVariantCount = 3;

/// The first variant a scene is meshed with: all three, or adaptive CMS (the last) alone.
int firstVariant(const SceneCheckOptions& options) { return options.adaptiveOnly ? kVariantCount - 1 : 0; }

struct SceneRun {
    Volume volume;
    Mesh meshes[kVariantCount];
    std::vector<MeshChunk> chunks[kVariantCount];
};

/// Runs the script op by op, keeping incrementally updated chunk sets, and meshes the result.
SceneRun runScene(const RandomScene& scene, const StrokeScript& script, const SceneCheckOptions& options)
{
    SceneRun run{Volume(scene.voxelSize), {}, {}};
    const int first = firstVariant(options);
    std::vector<MeshChunkSet> incremental;
    for (int i = first; i < kVariantCount && options.checkIncremental; ++i) {
        incremental.emplace_back(kVariants[i].options);
        incremental.back().rebuild(run.volume);
    }
    runStrokeScript(run.volume, script, [&](const ScriptOpReport& report) {
        for (MeshChunkSet& set : incremental) set.update(run.volume, report.stats.blockChanges);
    });
    for (int i = first; i < kVariantCount; ++i) {
        run.chunks[i] = meshVolumeChunks(run.volume, kVariants[i].options);
        run.meshes[i] = weldChunks(run.chunks[i]);
        if (!options.checkIncremental) continue;
        MeshChunkSet full(kVariants[i].options);
        full.rebuild(run.volume);
        if (!identical(incremental[std::size_t(i - first)], full))
            fail(std::string(kVariants[i].name) + ": re-meshing op by op differs from a full re-mesh");
    }
    return run;
}

bool sameChunks(const std::vector<MeshChunk>& a, const std::vector<MeshChunk>& b)
{
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (!identical(a[i], b[i])) return false;
    return true;
}

void checkLattice(const Volume& volume, const ExactScene& exact)
{
    const WorldBounds b = exact.solidBounds();
    if (!b.bounded()) return;
    const double vs = volume.voxelSize();
    const int lo[3] = {int(std::floor(b.min.x() / vs)) - 1, int(std::floor(b.min.y() / vs)) - 1, int(std::floor(b.min.z() / vs)) - 1};
    const int hi[3] = {int(std::ceil(b.max.x() / vs)) + 1, int(std::ceil(b.max.y() / vs)) + 1, int(std::ceil(b.max.z() / vs)) + 1};
    for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
            for (int z = lo[2]; z <= hi[2]; ++z) {
                const MaterialId got = volume.materialAt({x, y, z});
                const MaterialId want = exact.materialAt(Vec3d(x, y, z) * vs);
                if (got != want) {
                    std::ostringstream msg;
                    msg << "voxel (" << x << ", " << y << ", " << z << ") holds material " << got
                        << ", the exact replay gives " << want;
                    fail(msg.str());
                }
            }
}

void checkVolume(const Mesh& mesh, const ExactScene& exact, const RandomScene& scene, std::size_t samples,
                 SceneCheckResult& result)
{
    result.volume = enclosedVolume(mesh);
    const WorldBounds b = exact.solidBounds();
    if (!b.bounded()) return;
    std::mt19937_64 rng(scene.seed ^ (scene.index * 0x94D049BB133111EBull));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::size_t inside = 0, nearSurface = 0;
    const double halfVoxel = 0.5 * scene.voxelSize;
    for (std::size_t i = 0; i < samples; ++i) {
        const Vec3d p(b.min.x() + u(rng) * (b.max.x() - b.min.x()), b.min.y() + u(rng) * (b.max.y() - b.min.y()),
                      b.min.z() + u(rng) * (b.max.z() - b.min.z()));
        inside += exact.materialAt(p) != 0;
        nearSurface += exact.nearSurface(p, halfVoxel);
    }
    const double box = (b.max.x() - b.min.x()) * (b.max.y() - b.min.y()) * (b.max.z() - b.min.z());
    const double p = double(inside) / double(samples);
    result.exactVolume = box * p;
    // Sampling error (4 sigma, at least one sample's worth) plus what a mesh on a voxel lattice may miss:
    // features thinner than a voxel, up to half a voxel across the whole surface. The surface's area is
    // the mesh's, or, where the mesh lost a part smaller than a voxel, the exact surfaces' (the samples
    // within half a voxel of one, a band one voxel thick).
    const double sigma = box * std::sqrt(std::max(p * (1.0 - p), 1.0 / double(samples)) / double(samples));
    const double exactArea = box * double(nearSurface) / double(samples) / scene.voxelSize;
    const double tolerance = 4.0 * sigma + 0.5 * scene.voxelSize * std::max(surfaceArea(mesh), exactArea);
    if (std::fabs(result.volume - result.exactVolume) > tolerance) {
        std::ostringstream msg;
        msg << "the CMS mesh encloses " << result.volume << ", the exact scene about " << result.exactVolume
            << " (tolerance " << tolerance << ")";
        fail(msg.str());
    }
}

} // namespace

SceneCheckResult checkScene(const RandomScene& scene, const SceneCheckOptions& options)
{
    SceneCheckResult result;
    try {
        const StrokeScript script = parseStrokeScript(scene.script);
        SceneRun run = tbb::task_arena(2).execute([&] { return runScene(scene, script, options); });
        // Reshaping brushes have no closed form: scenes with them are checked for everything but the
        // comparisons with the exact replay (closed surfaces, meshers, threads and incremental re-meshing).
        const bool reshaped = std::any_of(script.ops.begin(), script.ops.end(), [](const ScriptOp& op) { return bool(op.field); });
        std::optional<ExactScene> exact;
        if (!reshaped) exact.emplace(script, run.volume.materials(), scene.voxelSize);
        if (exact && options.checkLattice) checkLattice(run.volume, *exact);
        std::size_t components[kVariantCount] = {};
        const int first = firstVariant(options);
        for (int i = first; i < kVariantCount; ++i) {
            const MeshTopology t = analyzeTopology(run.meshes[i], kMergeDistanceVoxels * scene.voxelSize);
            components[i] = t.components;
            if (!t.watertight()) {
                std::ostringstream msg;
                msg << kVariants[i].name << " mesh is not a closed 2-manifold: " << t.boundaryEdges << " boundary, "
                    << t.nonManifoldEdges << " non-manifold, " << t.misorientedEdges << " misoriented edges, "
                    << t.degenerateTriangles << " zero-area triangles, " << t.pinchedVertices << " pinched vertices";
                fail(msg.str());
            }
        }
        // Both CMS meshes walk the same squares wherever the surface is not flat, so they agree exactly.
        // Marching Cubes is not compared: it separates the solid corners of every ambiguous face, while
        // CMS joins them where its sharp features cross (a part thinner than a voxel), which can merge
        // two pieces of surface or split off a cavity, so the counts legitimately differ there.
        if (!options.adaptiveOnly && components[1] != components[2]) {
            std::ostringstream msg;
            msg << "connected pieces differ: mc " << components[0] << ", cms-uniform " << components[1]
                << ", cms-adaptive " << components[2];
            fail(msg.str());
        }
        result.triangles = run.meshes[2].triangleCount();
        if (exact) checkVolume(run.meshes[options.adaptiveOnly ? kVariantCount - 1 : 1], *exact, scene, options.volumeSamples, result);
        if (options.compareThreads) {
            SceneRun single = tbb::task_arena(1).execute([&] { return runScene(scene, script, options); });
            if (!identical(single.volume, run.volume)) fail("one and two threads give different volumes");
            for (int i = first; i < kVariantCount; ++i)
                if (!sameChunks(single.chunks[i], run.chunks[i]))
                    fail(std::string(kVariants[i].name) + ": one and two threads give different meshes");
        }
    } catch (const SceneFailure& f) {
        result.passed = false;
        result.failure = f.what;
    } catch (const std::exception& e) {
        result.passed = false;
        result.failure = std::string("exception: ") + e.what();
    }
    return result;
}

std::string sceneReport(const RandomScene& scene, const SceneCheckResult& result)
{
    nlohmann::json report;
    report["seed"] = scene.seed;
    report["scene"] = scene.index;
    report["failure"] = result.failure;
    report["voxel_size"] = scene.voxelSize;
    std::ostringstream replay;
    replay << "vdbclay new scene.vdb --shape sphere --size " << scene.voxelSize << " --voxel-size " << scene.voxelSize
           << " && vdbclay sculpt scene.vdb script.json -o scene.vdb && vdbclay mesh scene.vdb -o scene.obj";
    report["replay"] = replay.str();
    report["script"] = nlohmann::json::parse(scene.script);
    return report.dump(2);
}

} // namespace vdbclay
