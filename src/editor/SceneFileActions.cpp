#include "editor/SceneFileActions.h"

#include "interop/LevelSetExport.h"
#include "interop/LevelSetImport.h"
#include "mesher/MeshIO.h"
#include "mesher/Mesher.h"
#include "scene/OutputCheck.h"
#include "scene/SceneStore.h"
#include "sculpt/GridTool.h"
#include "vdb_hermite/VolumeIO.h"
#include "voxelize/TriangleMesh.h"
#include "voxelize/Voxelizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <filesystem>
#include <stdexcept>

namespace vdbclay {

namespace {

std::string absolute(const std::string& path) { return std::filesystem::absolute(path).lexically_normal().string(); }

/// Level 0 as the store holds it after an autosave.
Volume committedScene(EditingSession& session)
{
    session.autosave();
    return session.scene().storedLevel0();
}

/// The files an export must never replace: the scene and the store it is edited through.
std::vector<std::string> sessionInputs(const EditingSession& session) { return {session.scenePath(), session.scene().storePath()}; }

} // namespace

namespace {

/// Saves `volume` as a tool in SCENE.imports/NAME.vdb and returns the op that adds it where it lies.
nlohmann::json addToolOp(const EditingSession& session, const Volume& volume, const std::string& name, const std::string& material,
                         const std::string& source)
{
    if (volume.stats().empty)
        throw std::runtime_error("'" + source + "' holds no solid on the scene's lattice (voxel size " + std::to_string(volume.voxelSize()) + ")");
    const double voxelSize = volume.voxelSize();
    const std::filesystem::path folder = std::filesystem::path(session.scenePath()).string() + ".imports";
    std::filesystem::create_directories(folder);
    const std::string toolPath = absolute((folder / (name + ".vdb")).string());
    saveVolume(volume, toolPath);
    const GridTool tool(loadVolume(toolPath)); // as the op will read it: its pivot goes where it was
    nlohmann::json op = {{"mode", "add"}, {"brush", {{"shape", "grid"}, {"file", toolPath}}}};
    op["at"] = {tool.pivot()[0] * voxelSize, tool.pivot()[1] * voxelSize, tool.pivot()[2] * voxelSize};
    if (!material.empty()) op["material"] = material;
    return op;
}

} // namespace

nlohmann::json importIntoScene(const EditingSession& session, const std::string& path, const std::string& material)
{
    const double voxelSize = session.scene().voxelSize();
    Volume volume(voxelSize);
    if (isMeshPath(path)) {
        VoxelizeOptions options;
        options.voxelSize = voxelSize;
        options.material = material;
        volume = voxelizeMesh(loadTriangleMesh(path), options);
    } else {
        LevelSetImportOptions options;
        options.voxelSize = voxelSize;
        if (!material.empty()) options.material = material;
        volume = importLevelSet(path, options);
    }
    return addToolOp(session, volume, std::filesystem::path(path).stem().string(), material, path);
}

nlohmann::json placeModelIntoScene(const EditingSession& session, const std::string& path, const std::array<double, 3>& centre, double radius,
                                   const std::string& material)
{
    if (!(radius > 0.0) || !std::isfinite(radius)) throw std::invalid_argument("a model is placed with a positive radius");
    TriangleSoup mesh = loadTriangleMesh(path);
    // The bounding box's centre to `centre`, its farthest corner `radius` from it.
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const auto& p : mesh.positions)
        for (int a = 0; a < 3; ++a) {
            lo[std::size_t(a)] = std::min(lo[std::size_t(a)], p[std::size_t(a)]);
            hi[std::size_t(a)] = std::max(hi[std::size_t(a)], p[std::size_t(a)]);
        }
    const double halfDiagonal = 0.5 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(halfDiagonal > 0.0)) throw std::runtime_error("'" + path + "' has no extent to place");
    const double scale = radius / halfDiagonal;
    for (auto& p : mesh.positions)
        for (int a = 0; a < 3; ++a)
            p[std::size_t(a)] = centre[std::size_t(a)] + (p[std::size_t(a)] - 0.5 * (lo[std::size_t(a)] + hi[std::size_t(a)])) * scale;
    VoxelizeOptions options;
    options.voxelSize = session.scene().voxelSize();
    options.material = material;
    // A name of its own per placement: a recorded op reads its tool again on replay, so a later placement
    // must not write over an earlier one's.
    char tag[32];
    std::snprintf(tag, sizeof tag, "%016llx",
                  static_cast<unsigned long long>(std::hash<std::string>()(path + "|" + std::to_string(centre[0]) + "," + std::to_string(centre[1]) + "," +
                                                                          std::to_string(centre[2]) + "|" + std::to_string(radius) + "|" + material)));
    return addToolOp(session, voxelizeMesh(mesh, options), std::filesystem::path(path).stem().string() + "-" + tag, material, path);
}

void exportSceneMesh(EditingSession& session, const std::string& path)
{
    checkOutput(path, meshFormOf(path), sessionInputs(session));
    const Volume volume = committedScene(session);
    MeshOptions options;
    options.kind = MesherKind::CubicalMarchingSquares;
    writeMesh(meshVolume(volume, options), volume.materials(), path);
}

void exportSceneLevelSet(EditingSession& session, const std::string& path)
{
    checkOutput(path, OutputForm::StandardVdb, sessionInputs(session));
    exportLevelSet(committedScene(session), path, LevelSetExportOptions{});
}

nlohmann::json makeToolFromBox(EditingSession& session, const WorldBounds& box, const std::string& path)
{
    for (int a = 0; a < 3; ++a)
        if (!(box.max[a] > box.min[a]) || !std::isfinite(box.min[a]) || !std::isfinite(box.max[a]))
            throw std::invalid_argument("a tool's box needs finite corners, each minimum below its maximum");
    checkOutput(path, OutputForm::NativeVolume, sessionInputs(session));
    session.autosave();
    const double vs = session.scene().voxelSize();
    std::vector<IndexCoord> bricks;
    IndexCoord lo, hi;
    double count = 1.0;
    for (std::size_t a = 0; a < 3; ++a) {
        lo[a] = int32_t(std::floor(std::floor(std::max(box.min[int(a)] / vs, -1e9)) / kBrickEdge));
        hi[a] = int32_t(std::floor(std::ceil(std::min(box.max[int(a)] / vs, 1e9)) / kBrickEdge));
        count *= double(hi[a] - lo[a] + 1);
    }
    if (count > 1e5) throw std::invalid_argument("the box reaches too many bricks for a tool; choose a smaller box");
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
            for (int32_t z = lo[2]; z <= hi[2]; ++z) bricks.push_back({x, y, z});
    saveVolume(toolFromScene(session.scene().storedBricks(bricks), box), path);
    return {{"shape", "grid"}, {"file", absolute(path)}};
}

} // namespace vdbclay
