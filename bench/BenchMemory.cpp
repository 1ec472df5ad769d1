// bench memory: bytes per surface voxel of our Hermite volume against an OpenVDB FloatGrid narrow-band
// level set of the same shape and voxel size. Both figures divide by OUR surface voxel count, so they
// compare memory per unit of surface; each grid's own active voxel count is reported beside them.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/Volume.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/MeshToVolume.h> // createLevelSetBox

#include <iostream>

namespace vdbclay::bench {

namespace {

constexpr double kVoxelSize = 1.0;
constexpr float kHalfWidth = 3.0f;

struct MemoryRow {
    std::string shape;
    double sizeVoxels = 0;
    uint64_t oursBytes = 0;
    uint64_t oursActive = 0;
    uint64_t oursLeaves = 0;
    uint64_t vdbBytes = 0;
    uint64_t vdbActive = 0;
    uint64_t vdbLeaves = 0;

    double oursPerSurfaceVoxel() const { return oursActive ? double(oursBytes) / double(oursActive) : 0.0; }
    double vdbPerSurfaceVoxel() const { return oursActive ? double(vdbBytes) / double(oursActive) : 0.0; }
    double ratio() const { return vdbBytes ? double(oursBytes) / double(vdbBytes) : 0.0; }
};

MemoryRow measure(const std::string& shape, double size)
{
    MemoryRow row;
    row.shape = shape;
    row.sizeVoxels = size;

    Primitive p;
    openvdb::FloatGrid::Ptr levelSet;
    const double s = size * kVoxelSize;
    if (shape == "sphere") {
        p.shape = Shape::Sphere;
        p.radius = s;
        levelSet = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(s), openvdb::Vec3f(0.0f),
                                                                            float(kVoxelSize), kHalfWidth);
    } else {
        p.shape = Shape::Box;
        p.size = Vec3d(s);
        const openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(kVoxelSize);
        levelSet = openvdb::tools::createLevelSetBox<openvdb::FloatGrid>(
            openvdb::math::BBox<openvdb::Vec3d>(openvdb::Vec3d(-s), openvdb::Vec3d(s)), *xform, double(kHalfWidth));
    }
    Volume volume(kVoxelSize);
    CsgOp add;
    add.mode = CsgMode::Add;
    applyCsg(volume, Brush(p, Placement{}), add);

    const VolumeStats stats = volume.stats();
    row.oursBytes = stats.memoryBytes;
    row.oursActive = stats.activeVoxels;
    row.oursLeaves = stats.leafCount;
    row.vdbBytes = levelSet->memUsage();
    row.vdbActive = levelSet->activeVoxelCount();
    row.vdbLeaves = levelSet->tree().leafCount();
    return row;
}

} // namespace

int benchMemory(bool json, bool quick)
{
    std::vector<MemoryRow> rows;
    rows.push_back(measure("sphere", quick ? 40.0 : 100.0));
    rows.push_back(measure("box", quick ? 30.0 : 80.0));

    if (json) {
        nlohmann::json out = jsonPreamble("memory", quick);
        out["voxel_size"] = kVoxelSize;
        out["level_set_half_width"] = kHalfWidth;
        nlohmann::json shapes = nlohmann::json::array();
        for (const auto& r : rows) {
            shapes.push_back({{"shape", r.shape},
                              {"size_voxels", r.sizeVoxels},
                              {"ours_bytes", r.oursBytes},
                              {"ours_active_voxels", r.oursActive},
                              {"ours_leaf_count", r.oursLeaves},
                              {"ours_bytes_per_surface_voxel", r.oursPerSurfaceVoxel()},
                              {"openvdb_bytes", r.vdbBytes},
                              {"openvdb_active_voxels", r.vdbActive},
                              {"openvdb_leaf_count", r.vdbLeaves},
                              {"openvdb_bytes_per_surface_voxel", r.vdbPerSurfaceVoxel()},
                              {"ratio_ours_to_openvdb", r.ratio()}});
        }
        out["shapes"] = shapes;
        std::cout << out.dump() << std::endl;
        return 0;
    }

    printPreamble(std::cout, "memory", quick);
    std::cout << "Bytes per surface voxel = in-memory tree size / OUR surface (active) voxel count, for both;\n"
                 "OpenVDB = FloatGrid narrow-band level set, half-width 3, voxel size 1 (sphere radius, box "
                 "half-extent in voxels):\n\n";
    Table t;
    t.header = {"shape", "ours B/surface voxel", "OpenVDB B/surface voxel", "ours/OpenVDB", "ours MB",
                "OpenVDB MB", "ours active voxels", "OpenVDB active voxels"};
    for (const auto& r : rows) {
        t.rows.push_back({r.shape + " " + fixed(r.sizeVoxels, 0), fixed(r.oursPerSurfaceVoxel(), 2),
                          fixed(r.vdbPerSurfaceVoxel(), 2), fixed(r.ratio(), 2), fixed(double(r.oursBytes) / 1e6, 2),
                          fixed(double(r.vdbBytes) / 1e6, 2), std::to_string(r.oursActive),
                          std::to_string(r.vdbActive)});
    }
    t.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
