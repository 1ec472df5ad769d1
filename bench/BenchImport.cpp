// bench import: fandisk.obj and rocker-arm.obj voxelized at 256 voxels along the longest side and meshed
// by CMS, against OpenVDB's meshToLevelSet + volumeToMesh at the same voxel size, same run: time,
// triangles, and the two-sided Hausdorff and mean distance to the input mesh, in voxels.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "mesher/MeshQuality.h"
#include "mesher/Mesher.h"
#include "voxelize/Voxelizer.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>

namespace vdbclay::bench {

namespace {

struct Side {
    double seconds = 0.0;
    std::size_t triangles = 0;
    double meanVoxels = 0.0, maxVoxels = 0.0;
};

struct Row {
    std::string model;
    double voxelSize = 0.0;
    Side ours, openvdb;
    VoxelizeReport report;
};

/// Where the real models are: VDBCLAY_MODELS, else ../shared/data/models beside the source tree.
std::string modelsDirectory()
{
    if (const char* env = std::getenv("VDBCLAY_MODELS")) return env;
    return VDBCLAY_MODELS_DIR;
}

Mesh asMesh(const TriangleSoup& soup)
{
    Mesh m;
    for (const auto& p : soup.positions) m.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
    m.triangles = soup.triangles;
    m.normals.assign(m.positions.size(), {0.0f, 0.0f, 1.0f});
    m.materials.assign(m.positions.size(), 1);
    m.triangleMaterials.assign(m.triangles.size(), 1);
    return m;
}

Side measure(const Mesh& mesh, const Mesh& reference, double voxelSize, double seconds)
{
    SurfaceSampling sampling;
    sampling.spacing = 0.25 * voxelSize;
    const MeshQuality q = measureAgainstMesh(mesh, reference, sampling);
    return {seconds, mesh.triangleCount(), q.meanDistance / voxelSize, q.maxDistance / voxelSize};
}

Row run(const std::string& name, int resolution)
{
    const std::string path = modelsDirectory() + "/" + name;
    if (!std::filesystem::exists(path))
        throw std::runtime_error("bench import needs " + path + " (set VDBCLAY_MODELS to the folder of fandisk.obj and rocker-arm.obj)");
    const TriangleSoup soup = loadTriangleMesh(path);
    const Mesh input = asMesh(soup);
    Row row;
    row.model = name;
    VoxelizeOptions options;
    options.resolution = resolution;
    Mesh ours;
    const double oursMs = timeMs([&] {
        const Volume v = voxelizeMesh(soup, options, &row.report);
        MeshOptions cms;
        cms.kind = MesherKind::CubicalMarchingSquares;
        ours = meshVolume(v, cms);
    });
    row.voxelSize = row.report.voxelSize;
    row.ours = measure(ours, input, row.voxelSize, oursMs / 1000.0);

    std::vector<openvdb::Vec3s> points;
    for (const auto& p : soup.positions) points.emplace_back(float(p[0]), float(p[1]), float(p[2]));
    std::vector<openvdb::Vec3I> triangles;
    for (const auto& t : soup.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    Mesh theirs;
    const double theirsMs = timeMs([&] {
        const openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(row.voxelSize);
        const openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, points, triangles, 3.0f);
        std::vector<openvdb::Vec3s> outPoints;
        std::vector<openvdb::Vec3I> outTriangles;
        std::vector<openvdb::Vec4I> outQuads;
        openvdb::tools::volumeToMesh(*grid, outPoints, outTriangles, outQuads, 0.0, 0.0);
        for (const auto& p : outPoints) theirs.positions.push_back({p[0], p[1], p[2]});
        // volumeToMesh winds its polygons the other way round from ours.
        for (const auto& t : outTriangles) theirs.triangles.push_back({t[0], t[2], t[1]});
        for (const auto& q : outQuads) {
            theirs.triangles.push_back({q[0], q[2], q[1]});
            theirs.triangles.push_back({q[0], q[3], q[2]});
        }
        theirs.normals.assign(theirs.positions.size(), {0.0f, 0.0f, 1.0f});
        theirs.materials.assign(theirs.positions.size(), 1);
        theirs.triangleMaterials.assign(theirs.triangles.size(), 1);
    });
    row.openvdb = measure(theirs, input, row.voxelSize, theirsMs / 1000.0);
    return row;
}

} // namespace

int benchImport(bool json, bool quick)
{
    const int resolution = quick ? 96 : 256;
    std::vector<Row> rows;
    for (const char* model : {"fandisk.obj", "rocker-arm.obj"}) rows.push_back(run(model, resolution));
    if (json) {
        nlohmann::json out = jsonPreamble("import", quick);
        out["resolution"] = resolution;
        for (const Row& r : rows) {
            auto side = [](const Side& s) {
                return nlohmann::json{{"seconds", s.seconds}, {"triangles", s.triangles}, {"mean_voxels", s.meanVoxels}, {"max_voxels", s.maxVoxels}};
            };
            out["models"][r.model] = {{"voxel_size", r.voxelSize},
                                      {"ours", side(r.ours)},
                                      {"openvdb", side(r.openvdb)},
                                      {"voted_points", r.report.votedPoints},
                                      {"patched_crossings", r.report.patchedCrossings}};
        }
        std::cout << out.dump() << std::endl;
        return 0;
    }
    printPreamble(std::cout, "import", quick);
    Table t;
    t.header = {"model (" + std::to_string(resolution) + " voxels)", "pipeline", "time", "triangles", "mean error", "max error (Hausdorff)"};
    for (const Row& r : rows) {
        t.rows.push_back({r.model, "voxelize + CMS", fixed(r.ours.seconds * 1000.0, 1) + " ms", std::to_string(r.ours.triangles),
                          fixed(r.ours.meanVoxels, 3) + " vx", fixed(r.ours.maxVoxels, 3) + " vx"});
        t.rows.push_back({"", "OpenVDB meshToLevelSet + volumeToMesh", fixed(r.openvdb.seconds * 1000.0, 1) + " ms",
                          std::to_string(r.openvdb.triangles), fixed(r.openvdb.meanVoxels, 3) + " vx", fixed(r.openvdb.maxVoxels, 3) + " vx"});
        t.rows.push_back({"", "ours / OpenVDB", fixed(r.ours.seconds / r.openvdb.seconds, 2) + "x",
                          fixed(double(r.ours.triangles) / double(r.openvdb.triangles), 2) + "x", fixed(r.ours.meanVoxels / r.openvdb.meanVoxels, 2) + "x",
                          fixed(r.ours.maxVoxels / r.openvdb.maxVoxels, 2) + "x (goal <= 0.33)"});
    }
    t.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
