// bench csg: creating a large sphere, then remove-sphere stamps on its surface, against OpenVDB's
// level-set path (createLevelSetSphere for the tool + tools::csgDifference) on the same points.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/Volume.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>
#include <iostream>
#include <random>

namespace vdbclay::bench {

namespace {

constexpr double kVoxelSize = 1.0;
constexpr float kHalfWidth = 3.0f;
constexpr unsigned kSeed = 20261122u;
constexpr int kCreateRepeats = 3;

Brush sphereBrush(double radius, const Vec3d& at)
{
    Primitive p;
    p.shape = Shape::Sphere;
    p.radius = radius;
    Placement placement;
    placement.translation = at;
    return Brush(p, placement);
}

/// Uniformly distributed points on a sphere about the origin (deterministic for a given generator).
std::vector<Vec3d> surfacePoints(std::mt19937& rng, double radius, int count)
{
    std::uniform_real_distribution<double> height(-1.0, 1.0);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI);
    std::vector<Vec3d> points;
    for (int i = 0; i < count; ++i) {
        const double z = height(rng);
        const double t = angle(rng);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        points.emplace_back(radius * r * std::cos(t), radius * r * std::sin(t), radius * z);
    }
    return points;
}

struct StampResult {
    double radius = 0;
    int count = 0;
    std::vector<double> oursMs;
    std::vector<double> openvdbMs;
    std::vector<double> blocks;
};

} // namespace

int benchCsg(bool json, bool quick)
{
    const double sphereRadius = quick ? 60.0 : 200.0;
    const std::vector<double> stampRadii = quick ? std::vector<double>{4, 12, 24} : std::vector<double>{8, 32, 64};
    const int stamps = quick ? 8 : 30;

    // Creation: ours (one Add of a sphere brush) and OpenVDB's narrow-band sphere, median of a few runs.
    std::vector<double> oursCreate, vdbCreate;
    Volume base(kVoxelSize);
    openvdb::FloatGrid::Ptr baseLevelSet;
    for (int i = 0; i < kCreateRepeats; ++i) {
        Volume v(kVoxelSize);
        CsgOp add;
        add.mode = CsgMode::Add;
        oursCreate.push_back(timeMs([&] { applyCsg(v, sphereBrush(sphereRadius, Vec3d(0.0)), add); }));
        openvdb::FloatGrid::Ptr ls;
        vdbCreate.push_back(timeMs([&] {
            ls = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(sphereRadius), openvdb::Vec3f(0.0f),
                                                                          float(kVoxelSize), kHalfWidth);
        }));
        base = std::move(v);
        baseLevelSet = ls;
    }
    const VolumeStats baseStats = base.stats();

    // Stamps: the same deterministic surface points for both, on fresh copies of the sphere per radius.
    std::mt19937 rng(kSeed);
    std::vector<StampResult> results;
    for (double r : stampRadii) {
        StampResult res;
        res.radius = r;
        res.count = stamps;
        const std::vector<Vec3d> points = surfacePoints(rng, sphereRadius * kVoxelSize, stamps);

        Volume volume = base.clone();
        CsgOp remove;
        remove.mode = CsgMode::Remove;
        for (const Vec3d& p : points) {
            const Brush brush = sphereBrush(r * kVoxelSize, p);
            EditStats st;
            res.oursMs.push_back(timeMs([&] { st = applyCsg(volume, brush, remove); }));
            res.blocks.push_back(double(st.blocksComputed));
        }

        openvdb::FloatGrid::Ptr levelSet = baseLevelSet->deepCopy();
        for (const Vec3d& p : points) {
            res.openvdbMs.push_back(timeMs([&] {
                openvdb::FloatGrid::Ptr tool = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
                    float(r * kVoxelSize), openvdb::Vec3f(float(p.x()), float(p.y()), float(p.z())),
                    float(kVoxelSize), kHalfWidth);
                openvdb::tools::csgDifference(*levelSet, *tool);
            }));
        }
        results.push_back(std::move(res));
    }

    if (json) {
        nlohmann::json out = jsonPreamble("csg", quick);
        out["voxel_size"] = kVoxelSize;
        out["sphere_radius_voxels"] = sphereRadius;
        out["create"] = {{"ours_ms", median(oursCreate)},
                         {"openvdb_ms", median(vdbCreate)},
                         {"ours_active_voxels", baseStats.activeVoxels},
                         {"ours_leaf_count", baseStats.leafCount},
                         {"openvdb_active_voxels", baseLevelSet->activeVoxelCount()},
                         {"openvdb_leaf_count", baseLevelSet->tree().leafCount()}};
        nlohmann::json rows = nlohmann::json::array();
        for (const auto& r : results) {
            const double ours = median(r.oursMs), vdb = median(r.openvdbMs);
            rows.push_back({{"radius_voxels", r.radius},
                            {"stamps", r.count},
                            {"ours_median_ms", ours},
                            {"ours_max_ms", maximum(r.oursMs)},
                            {"ours_median_blocks", median(r.blocks)},
                            {"openvdb_median_ms", vdb},
                            {"openvdb_max_ms", maximum(r.openvdbMs)},
                            {"speedup", ours > 0.0 ? vdb / ours : 0.0}});
        }
        out["stamps"] = rows;
        std::cout << out.dump() << std::endl;
        return 0;
    }

    printPreamble(std::cout, "csg", quick);
    std::cout << "Sphere of radius " << sphereRadius << " voxels (voxel size " << kVoxelSize << "), median of "
              << kCreateRepeats << " runs:\n\n";
    Table create;
    create.header = {"create sphere", "ms", "active voxels", "leaves"};
    create.rows.push_back({"ours (applyCsg add)", fixed(median(oursCreate), 1), std::to_string(baseStats.activeVoxels),
                           std::to_string(baseStats.leafCount)});
    create.rows.push_back({"OpenVDB createLevelSetSphere (half-width 3)", fixed(median(vdbCreate), 1),
                           std::to_string(baseLevelSet->activeVoxelCount()),
                           std::to_string(baseLevelSet->tree().leafCount())});
    create.print(std::cout);

    std::cout << "\nRemove-sphere stamps at " << stamps
              << " pseudo-random points on the surface (seed " << kSeed
              << "); OpenVDB = createLevelSetSphere(tool) + csgDifference, in place:\n\n";
    Table stampTable;
    stampTable.header = {"stamp radius (voxels)", "stamps", "ours median ms", "ours max ms", "blocks (median)",
                         "OpenVDB median ms", "OpenVDB max ms", "speedup (OpenVDB/ours)"};
    for (const auto& r : results) {
        const double ours = median(r.oursMs), vdb = median(r.openvdbMs);
        stampTable.rows.push_back({fixed(r.radius, 0), std::to_string(r.count), fixed(ours, 3),
                                   fixed(maximum(r.oursMs), 3), fixed(median(r.blocks), 0), fixed(vdb, 3),
                                   fixed(maximum(r.openvdbMs), 3), ours > 0.0 ? fixed(vdb / ours, 2) + "x" : "-"});
    }
    stampTable.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
