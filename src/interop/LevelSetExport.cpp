#include "interop/LevelSetExport.h"

#include "mesher/Mesher.h"
#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/NumberText.h"

#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>

#include <stdexcept>

namespace vdbclay {

namespace {

/// Materials as their ids, voxel for voxel (tiles stay tiles); 0 is empty space.
template <typename GridT>
typename GridT::Ptr materialGrid(const Volume& volume, const openvdb::math::Transform& xf)
{
    using ValueT = typename GridT::ValueType;
    typename GridT::Ptr material = GridT::create(ValueT(0));
    material->setTransform(xf.copy());
    material->setName("material");
    const HermiteTree& tree = volume.impl().grid->constTree();
    for (auto value = tree.cbeginValueAll(); value; ++value) {
        if (!value->solid()) continue;
        CoordBBox box;
        value.getBoundingBox(box);
        if (value.isVoxelValue()) material->tree().setValueOn(box.min(), ValueT(value->id));
        else material->tree().fill(box, ValueT(value->id), true);
    }
    return material;
}

} // namespace

void exportLevelSet(const Volume& volume, const std::string& path, const LevelSetExportOptions& options,
                    LevelSetExportReport* report)
{
    if (!(options.halfWidth >= 1.0 && options.halfWidth <= 64.0))
        throw std::invalid_argument("a half width of " + formatNumber(options.halfWidth) + " voxels is outside 1 .. 64");
    openvdb::initialize();
    // CMS on voxel cells: its sharp features keep the corners the Hermite data holds, and no wide cell
    // cuts a chord through a curved stretch (distances are measured to this mesh).
    MeshOptions cms;
    cms.kind = MesherKind::CubicalMarchingSquares;
    cms.maxCellWidth = 1;
    const Mesh mesh = meshVolume(volume, cms);
    std::vector<openvdb::Vec3s> points(mesh.positions.size());
    for (std::size_t i = 0; i < points.size(); ++i) points[i] = {mesh.positions[i][0], mesh.positions[i][1], mesh.positions[i][2]};
    std::vector<openvdb::Vec3I> triangles(mesh.triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
        triangles[i] = {mesh.triangles[i][0], mesh.triangles[i][1], mesh.triangles[i][2]};
    const openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(volume.voxelSize());

    openvdb::GridPtrVec grids;
    openvdb::FloatGrid::Ptr surface = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xf, points, triangles, float(options.halfWidth));
    surface->setName("surface");
    surface->setGridClass(openvdb::GRID_LEVEL_SET);
    grids.push_back(surface);

    if (options.int32Material) grids.push_back(materialGrid<openvdb::Int32Grid>(volume, *xf));
    else grids.push_back(materialGrid<openvdb::FloatGrid>(volume, *xf));

    if (options.fog) {
        openvdb::FloatGrid::Ptr density = surface->deepCopy();
        openvdb::tools::sdfToFogVolume(*density);
        density->setName("density");
        grids.push_back(density);
    }
    // OpenVDB's own file writer (grid offsets, Blosc), into a temporary file renamed over `path`.
    writeFileAtomically(path, [](std::ostream&) {}, [&](const std::string& temp, uint64_t) {
        openvdb::io::File file(temp);
        file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        openvdb::MetaMap marker;
        marker.insertMeta(kLevelSetExportMarker, openvdb::StringMetadata("1"));
        file.write(grids, marker);
        file.close();
    });
    if (report) {
        report->triangles = mesh.triangleCount();
        report->surfaceVoxels = surface->activeVoxelCount();
        report->materialVoxels = grids[1]->activeVoxelCount();
    }
}

} // namespace vdbclay
