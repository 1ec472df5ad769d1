// bench mesh: meshing speed and accuracy of our meshers (uniform and adaptive CMS, MC) on shapes with sharp
// features and a thin wall, against OpenVDB's tools::volumeToMesh on a narrow-band level set of the same
// shape. Accuracy is the two-sided distance to the analytic signed distance (measureAgainstSdf).
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "mesher/Mesh.h"
#include "mesher/MeshChunkSet.h"
#include "mesher/MeshMetrics.h"
#include "mesher/MeshQuality.h"
#include "mesher/Mesher.h"
#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/Volume.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay::bench {

namespace {

constexpr double kVoxelSize = 1.0;
constexpr float kHalfWidth = 3.0f;
// Meshing times are the best of several runs: the calls take milliseconds, and on a shared VM a
// neighbour's burst can double any one of them; the fastest run is the least disturbed, for both sides.
constexpr int kRepeats = 7;
constexpr double kSampleSpacing = 0.5; // voxels
constexpr double kSampleMargin = 2.0;  // voxels
constexpr double kWallThickness = 0.8; // voxels, kept in --quick

Brush makeBrush(Shape shape, double radius, const Vec3d& halfExtents, const Vec3d& at, const Vec3d& rotation)
{
    Primitive p;
    p.shape = shape;
    p.radius = radius;
    p.size = halfExtents;
    Placement placement;
    placement.translation = at;
    placement.rotationDegrees = rotation;
    return Brush(p, placement);
}

Brush sphere(double radius, const Vec3d& at) { return makeBrush(Shape::Sphere, radius, Vec3d(1.0), at, Vec3d(0.0)); }
Brush box(const Vec3d& half, const Vec3d& rotation = Vec3d(0.0))
{
    return makeBrush(Shape::Box, 1.0, half, Vec3d(0.0), rotation);
}

/// One shape: a brush to add, brushes to remove after it, and the same solid as an analytic SDF.
struct TestShape {
    std::string key;   // JSON key
    std::string title; // table caption
    Brush added;
    std::vector<Brush> removed;
    double extent = 0; // the shape lies inside [-extent, extent]^3 (world units)

    double sdf(const Vec3d& p) const
    {
        double d = added.distance(p);
        for (const Brush& b : removed) d = std::max(d, -b.distance(p));
        return d;
    }
};

std::vector<TestShape> makeShapes(bool quick)
{
    const double s = quick ? 0.5 : 1.0;
    std::vector<TestShape> shapes;
    {
        TestShape t;
        t.key = "box";
        const Vec3d half(20 * s + 0.3, 14 * s + 0.3, 11 * s + 0.3);
        t.title = "Axis-aligned box, half-extents " + fixed(half.x(), 1) + ", " + fixed(half.y(), 1) + ", " +
                  fixed(half.z(), 1);
        t.added = box(half);
        t.extent = half.length();
        shapes.push_back(std::move(t));
    }
    {
        TestShape t;
        t.key = "rotated_box";
        const Vec3d half(20 * s, 14 * s, 11 * s);
        t.title = "Rotated box, half-extents " + fixed(half.x(), 1) + ", " + fixed(half.y(), 1) + ", " +
                  fixed(half.z(), 1) + ", rotated [20, 35, 10] degrees";
        t.added = box(half, Vec3d(20, 35, 10));
        t.extent = half.length();
        shapes.push_back(std::move(t));
    }
    {
        TestShape t;
        t.key = "sphere";
        const double r = 40 * s;
        t.title = "Sphere, radius " + fixed(r, 1);
        t.added = sphere(r, Vec3d(0.0));
        t.extent = r;
        shapes.push_back(std::move(t));
    }
    {
        TestShape t;
        t.key = "box_minus_sphere";
        const double h = 24 * s, r = 16 * s;
        t.title = "Cube of half-extent " + fixed(h, 1) + " minus a sphere of radius " + fixed(r, 1) +
                  " centred on the corner (" + fixed(h, 1) + ", " + fixed(h, 1) + ", " + fixed(h, 1) + ")";
        t.added = box(Vec3d(h));
        t.removed.push_back(sphere(r, Vec3d(h)));
        t.extent = h * std::sqrt(3.0);
        shapes.push_back(std::move(t));
    }
    {
        TestShape t;
        t.key = "thin_wall";
        const double h = 28 * s, r = 14 * s;
        const double gap = 2 * r + kWallThickness; // distance between the centres
        t.title = "Thin wall: cube of half-extent " + fixed(h, 1) + " minus two spheres of radius " + fixed(r, 1) +
                  " centred at x = +-" + fixed(gap / 2, 1) + " (a wall " + fixed(kWallThickness, 1) +
                  " voxels thick at x = 0)";
        t.added = box(Vec3d(h));
        t.removed.push_back(sphere(r, Vec3d(-gap / 2, 0, 0)));
        t.removed.push_back(sphere(r, Vec3d(gap / 2, 0, 0)));
        t.extent = h * std::sqrt(3.0);
        shapes.push_back(std::move(t));
    }
    for (auto& t : shapes) t.extent *= kVoxelSize;
    return shapes;
}

Volume buildVolume(const TestShape& shape)
{
    Volume v(kVoxelSize);
    CsgOp add;
    add.mode = CsgMode::Add;
    applyCsg(v, shape.added, add);
    CsgOp remove;
    remove.mode = CsgMode::Remove;
    for (const Brush& b : shape.removed) applyCsg(v, b, remove);
    return v;
}

/// A narrow-band level set (half-width 3 voxels) sampled from the analytic SDF at the voxel centres:
/// |d| < 3 voxels active with value d, deeper inside voxels inactive at -background, then pruned.
openvdb::FloatGrid::Ptr buildLevelSet(const TestShape& shape)
{
    const float background = kHalfWidth * float(kVoxelSize);
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(kVoxelSize));
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    const int n = int(std::ceil(shape.extent / kVoxelSize)) + 4;
    auto acc = grid->getAccessor();
    for (int i = -n; i <= n; ++i) {
        for (int j = -n; j <= n; ++j) {
            for (int k = -n; k <= n; ++k) {
                const openvdb::Coord ijk(i, j, k);
                const Vec3d world = grid->transform().indexToWorld(ijk);
                const double d = shape.sdf(world);
                if (std::abs(d) < background) {
                    acc.setValueOn(ijk, float(d));
                } else if (d < 0.0) {
                    acc.setValueOff(ijk, -background);
                }
            }
        }
    }
    openvdb::tools::pruneLevelSet(grid->tree());
    return grid;
}

struct VdbMeshData {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
};

/// Quads become two triangles each; the winding is flipped when the mesh encloses a negative volume
/// (OpenVDB's level-set winding is the opposite of ours).
Mesh toMesh(const VdbMeshData& data)
{
    Mesh mesh;
    mesh.positions.reserve(data.points.size());
    for (const auto& p : data.points) mesh.positions.push_back({p.x(), p.y(), p.z()});
    mesh.triangles.reserve(data.triangles.size() + 2 * data.quads.size());
    for (const auto& t : data.triangles) mesh.triangles.push_back({t[0], t[1], t[2]});
    for (const auto& q : data.quads) {
        mesh.triangles.push_back({q[0], q[1], q[2]});
        mesh.triangles.push_back({q[0], q[2], q[3]});
    }
    if (enclosedVolume(mesh) < 0.0) {
        for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    }
    mesh.materials.assign(mesh.positions.size(), MaterialId(1));
    mesh.triangleMaterials.assign(mesh.triangles.size(), MaterialId(1));
    return mesh;
}

struct RowResult {
    std::string key;
    std::string label;
    double ms = 0;
    std::size_t triangles = 0;
    double meanDistance = 0;
    double maxDistance = 0;
    bool watertight = false;
};

RowResult measure(const std::string& key, const std::string& label, const std::vector<double>& times,
                  const Mesh& mesh, const TestShape& shape)
{
    RowResult r;
    r.key = key;
    r.label = label;
    r.ms = *std::min_element(times.begin(), times.end());
    r.triangles = mesh.triangleCount();
    SurfaceSampling sampling;
    sampling.spacing = kSampleSpacing * kVoxelSize;
    sampling.margin = kSampleMargin * kVoxelSize;
    const MeshQuality q = measureAgainstSdf(
        mesh, [&shape](const Point3d& p) { return shape.sdf(Vec3d(p[0], p[1], p[2])); }, sampling);
    r.meanDistance = q.meanDistance;
    r.maxDistance = q.maxDistance;
    r.watertight = analyzeTopology(mesh, kMergeDistanceVoxels * kVoxelSize).watertight();
    return r;
}

RowResult runOurs(const Volume& volume, MesherKind kind, int maxCellWidth, const std::string& key,
                  const std::string& label, const TestShape& shape)
{
    MeshOptions options;
    options.kind = kind;
    options.maxCellWidth = maxCellWidth;
    std::vector<double> times;
    Mesh mesh;
    for (int i = 0; i < kRepeats; ++i) times.push_back(timeMs([&] { mesh = meshVolume(volume, options); }));
    return measure(key, label, times, mesh, shape);
}

RowResult runOpenVdb(const openvdb::FloatGrid& grid, double adaptivity, const std::string& key,
                     const std::string& label, const TestShape& shape)
{
    std::vector<double> times;
    VdbMeshData data;
    for (int i = 0; i < kRepeats; ++i) {
        VdbMeshData fresh;
        times.push_back(timeMs([&] {
            openvdb::tools::volumeToMesh(grid, fresh.points, fresh.triangles, fresh.quads, 0.0, adaptivity);
        }));
        data = std::move(fresh);
    }
    return measure(key, label, times, toMesh(data), shape);
}

struct ShapeResult {
    const TestShape* shape = nullptr;
    uint64_t surfaceCells = 0; // our active voxels
    uint64_t levelSetActiveVoxels = 0;
    std::vector<RowResult> rows; // cms uniform, cms adaptive, mc, vdb0, vdb05
};

/// Re-meshing after brush stamps: a MeshChunkSet of a sphere is updated with the block changes of each
/// radius-32 stamp (alternately removing and adding material on the surface).
struct RemeshResult {
    std::string key;
    std::string label;
    double sphereRadius = 0;
    double medianMs = 0;
    double maxMs = 0;
    double medianChunks = 0;
    bool matchesFullMesh = false;
};

constexpr int kReplicas = 3;
constexpr double kStampRadius = 32.0;
constexpr int kStamps = 9;
constexpr int kAdaptiveCellWidth = 8; // the "CMS adaptive" rows: the default widest cell

RemeshResult runRemesh(bool quick, int maxCellWidth, const std::string& key, const std::string& label)
{
    RemeshResult r;
    r.key = key;
    r.label = label;
    r.sphereRadius = quick ? 100.0 : 200.0;
    MeshOptions options;
    options.kind = MesherKind::CubicalMarchingSquares;
    options.maxCellWidth = maxCellWidth;
    // Identical replicas take each stamp in turn and re-mesh right after it, as an editor does: all do
    // the same work on data the stamp has just touched, so the best of them is the stamp's least
    // disturbed time (as for the meshing rows). An update keeps what it learns (the adaptive cells), so
    // updating one set again would do less.
    struct Replica {
        Volume volume{kVoxelSize};
        MeshChunkSet chunks;
    };
    std::vector<std::unique_ptr<Replica>> replicas;
    for (int i = 0; i < kReplicas; ++i) {
        auto& replica = *replicas.emplace_back(std::make_unique<Replica>());
        CsgOp add;
        add.mode = CsgMode::Add;
        applyCsg(replica.volume, sphere(r.sphereRadius, Vec3d(0.0)), add);
        replica.chunks = MeshChunkSet(options);
        replica.chunks.rebuild(replica.volume);
    }
    std::vector<double> times, counts;
    for (int i = 0; i < kStamps; ++i) {
        const double angle = 0.35 * i;
        const Vec3d at(r.sphereRadius * std::cos(angle), r.sphereRadius * std::sin(angle), 5.0 * i);
        CsgOp op;
        op.mode = i % 2 ? CsgMode::Add : CsgMode::Remove;
        std::size_t remeshed = 0;
        double best = std::numeric_limits<double>::infinity();
        for (auto& replica : replicas) {
            const EditStats edit = applyCsg(replica->volume, sphere(kStampRadius, at), op);
            best = std::min(best, timeMs([&] { remeshed = replica->chunks.update(replica->volume, edit.blockChanges); }));
        }
        times.push_back(best);
        counts.push_back(double(remeshed));
    }
    r.medianMs = median(times);
    r.maxMs = *std::max_element(times.begin(), times.end());
    r.medianChunks = median(counts);
    const Replica& first = *replicas.front();
    MeshChunkSet full(options);
    full.rebuild(first.volume);
    r.matchesFullMesh = identical(first.chunks, full);
    return r;
}

double cellsPerSecond(uint64_t cells, double ms) { return ms > 0.0 ? double(cells) / (ms / 1000.0) : 0.0; }

std::string distanceCell(double d) { return std::isfinite(d) ? fixed(d, 3) : "inf"; }

} // namespace

int benchMesh(bool json, bool quick)
{
    const std::vector<TestShape> shapes = makeShapes(quick);
    std::vector<ShapeResult> results;
    for (const TestShape& shape : shapes) {
        ShapeResult res;
        res.shape = &shape;
        const Volume volume = buildVolume(shape);
        res.surfaceCells = volume.stats().activeVoxels;
        const openvdb::FloatGrid::Ptr levelSet = buildLevelSet(shape);
        res.levelSetActiveVoxels = levelSet->activeVoxelCount();
        res.rows.push_back(runOurs(volume, MesherKind::CubicalMarchingSquares, 1, "cms_uniform", "CMS uniform", shape));
        res.rows.push_back(runOurs(volume, MesherKind::CubicalMarchingSquares, kAdaptiveCellWidth, "cms_adaptive",
                                   "CMS adaptive", shape));
        res.rows.push_back(runOurs(volume, MesherKind::MarchingCubes, 1, "mc", "MC (ours)", shape));
        res.rows.push_back(
            runOpenVdb(*levelSet, 0.0, "openvdb_adaptivity_0", "OpenVDB volumeToMesh adaptivity 0", shape));
        res.rows.push_back(
            runOpenVdb(*levelSet, 0.5, "openvdb_adaptivity_0.5", "OpenVDB volumeToMesh adaptivity 0.5", shape));
        results.push_back(std::move(res));
    }

    const std::vector<RemeshResult> remesh = {runRemesh(quick, 1, "cms_uniform", "CMS uniform"),
                                              runRemesh(quick, kAdaptiveCellWidth, "cms_adaptive", "CMS adaptive")};

    auto ratio = [](const ShapeResult& r) {
        const double cms = cellsPerSecond(r.surfaceCells, r.rows[0].ms);
        const double vdb = cellsPerSecond(r.surfaceCells, r.rows[3].ms);
        return vdb > 0.0 ? cms / vdb : 0.0;
    };
    auto triangleRatio = [](const ShapeResult& r) {
        return r.rows[0].triangles ? double(r.rows[1].triangles) / double(r.rows[0].triangles) : 0.0;
    };

    if (json) {
        nlohmann::json out = jsonPreamble("mesh", quick);
        out["voxel_size"] = kVoxelSize;
        out["repeats"] = kRepeats;
        out["timing"] = "best of repeats";
        out["sample_spacing_voxels"] = kSampleSpacing;
        out["sample_margin_voxels"] = kSampleMargin;
        nlohmann::json shapesJson = nlohmann::json::object();
        for (const auto& r : results) {
            nlohmann::json s;
            s["title"] = r.shape->title;
            s["surface_cells"] = r.surfaceCells;
            s["openvdb_active_voxels"] = r.levelSetActiveVoxels;
            nlohmann::json rows = nlohmann::json::object();
            for (const auto& row : r.rows) {
                rows[row.key] = {{"label", row.label},
                                 {"ms", row.ms},
                                 {"triangles", row.triangles},
                                 {"mean_distance", std::isfinite(row.meanDistance) ? row.meanDistance : -1.0},
                                 {"max_distance", std::isfinite(row.maxDistance) ? row.maxDistance : -1.0},
                                 {"watertight", row.watertight}};
            }
            s["meshers"] = rows;
            s["cms_cells_per_second"] = cellsPerSecond(r.surfaceCells, r.rows[0].ms);
            s["openvdb_adaptivity_0_cells_per_second"] = cellsPerSecond(r.surfaceCells, r.rows[3].ms);
            s["cms_over_openvdb_cells_per_second"] = ratio(r);
            s["adaptive_over_uniform_triangles"] = triangleRatio(r);
            shapesJson[r.shape->key] = s;
        }
        out["shapes"] = shapesJson;
        nlohmann::json remeshJson = nlohmann::json::object();
        for (const auto& r : remesh) {
            remeshJson[r.key] = {{"label", r.label},
                                 {"sphere_radius", r.sphereRadius},
                                 {"stamp_radius", kStampRadius},
                                 {"stamps", kStamps},
                                 {"timing", "best of identical replicas per stamp"},
                                 {"replicas", kReplicas},
                                 {"update_repeats", kReplicas}, // kept for scripts: one update per replica
                                 {"median_ms", r.medianMs},
                                 {"max_ms", r.maxMs},
                                 {"median_chunks_remeshed", r.medianChunks},
                                 {"matches_full_mesh", r.matchesFullMesh}};
        }
        out["remesh_after_stamp"] = remeshJson;
        std::cout << out.dump() << std::endl;
        return 0;
    }

    printPreamble(std::cout, "mesh", quick);
    std::cout << "Voxel size " << kVoxelSize << "; meshing time is the best of " << kRepeats
              << " runs (meshing call only). OpenVDB meshes a FloatGrid level set (half-width 3) sampled from\n"
                 "the same analytic SDF. Distances: two-sided mean / max (Hausdorff) against the analytic SDF, "
                 "samples every "
              << kSampleSpacing << " voxel, margin " << kSampleMargin
              << " voxels.\nCMS adaptive: cells up to " << kAdaptiveCellWidth << " voxels wide, split at a "
              << MeshOptions{}.subdivisionAngleDegrees << " degree normal spread.\n";
    for (const auto& r : results) {
        std::cout << "\n" << r.shape->title << "; " << r.surfaceCells << " surface cells (ours), "
                  << r.levelSetActiveVoxels << " active level-set voxels:\n\n";
        Table table;
        table.header = {"mesher", "ms", "triangles", "mean dist", "max dist", "watertight"};
        for (const auto& row : r.rows) {
            table.rows.push_back({row.label, fixed(row.ms, 2), std::to_string(row.triangles),
                                  distanceCell(row.meanDistance), distanceCell(row.maxDistance),
                                  row.watertight ? "yes" : "no"});
        }
        table.print(std::cout);
        std::cout << "\nsurface cells per second: CMS uniform "
                  << fixed(cellsPerSecond(r.surfaceCells, r.rows[0].ms) / 1e6, 2)
                  << " M/s, OpenVDB adaptivity 0 " << fixed(cellsPerSecond(r.surfaceCells, r.rows[3].ms) / 1e6, 2)
                  << " M/s, ratio CMS/OpenVDB " << fixed(ratio(r), 2) << "; adaptive CMS has "
                  << fixed(triangleRatio(r), 3) << "x uniform CMS's triangles\n";
    }

    std::cout << "\nRe-meshing after a radius-" << kStampRadius << " stamp on a sphere of radius "
              << fixed(remesh[0].sphereRadius, 0)
              << " (MeshChunkSet::update over the stamp's block changes, best of " << kReplicas
              << " identical replicas, each updated right after its stamp;\n"
              << kStamps << " stamps, alternately removing and adding):\n\n";
    Table table;
    table.header = {"mesher", "median ms", "max ms", "chunks re-meshed", "equals full re-mesh"};
    for (const auto& r : remesh) {
        table.rows.push_back({r.label, fixed(r.medianMs, 2), fixed(r.maxMs, 2), fixed(r.medianChunks, 0),
                              r.matchesFullMesh ? "yes" : "no"});
    }
    table.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
