// vdbclay import / export: whole scenes between a native .vdb and a store (.vdbclay), and standard
// grids of other tools (level sets, fog volumes) in. The output's extension picks the form.
#include "Cli.h"

#include "interop/LevelSetExport.h"
#include "interop/LevelSetImport.h"
#include "scene/LevelSetToStore.h"
#include "scene/SceneStore.h"
#include "voxelize/VoxelizeToStore.h"
#include "vdb_hermite/FileStatus.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>

namespace vdbclay::cli {

namespace {

/// Writes a scene in the form its path's extension names.
void writeScene(const Volume& volume, const std::string& path, bool progress)
{
    if (isStorePath(path)) writeStoreFile(volume, path, terminalProgress("writing bricks", progress));
    else saveVolume(volume, path);
}

/// What a written scene holds, for the summary.
struct SceneCounts {
    uint64_t leaves = 0, activeVoxels = 0;
    explicit SceneCounts(const VolumeStats& stats) : leaves(stats.leafCount), activeVoxels(stats.activeVoxels) {}
    SceneCounts(uint64_t leafCount, uint64_t active) : leaves(leafCount), activeVoxels(active) {}
};

nlohmann::json sceneSummaryJson(const std::string& path, const SceneCounts& counts, double seconds)
{
    return {{"output", path},
            {"form", isStorePath(path) ? "store" : "vdb"},
            {"leaf_count", counts.leaves},
            {"active_voxels", counts.activeVoxels},
            {"bytes", std::filesystem::file_size(path)},
            {"seconds", seconds}};
}

void printSummary(const std::string& input, const std::string& output, const SceneCounts& counts, double seconds)
{
    printFields({{"converted", input + " -> " + output},
                 {"form", isStorePath(output) ? "store (bricks of 64^3 voxels)" : "native .vdb"},
                 {"leaves", std::to_string(counts.leaves)},
                 {"size", formatBytes(double(std::filesystem::file_size(output)))},
                 {"time", formatSeconds(seconds)}},
                0);
}

} // namespace

/// A mesh file, voxelized.
int importMesh(const ImportOptions& o, std::chrono::steady_clock::time_point start)
{
    if (const auto why = unreachableFile(o.input)) throw MeshImportError(*why); // before the options: the first thing to fix
    if (!o.grid.empty() || o.iso) throw UsageError("--grid and --iso are for .vdb files of other tools, not meshes");
    VoxelizeOptions options;
    options.voxelSize = o.voxelSize;
    options.resolution = o.resolution;
    if (o.materialGiven) options.material = o.material;
    if (!options.voxelSize && !options.resolution) throw UsageError("a mesh needs --voxel-size V or --resolution N");
    if (options.voxelSize && options.resolution) throw UsageError("give --voxel-size or --resolution, not both");
    const TriangleSoup mesh = loadTriangleMesh(o.input);
    // A store is written brick by brick as the mesh is voxelized: the volume is never whole in memory.
    VoxelizeReport report;
    std::vector<std::string> materials;
    const SceneCounts counts = [&] {
        try {
            if (isStorePath(o.output)) {
                const StoreVoxelizeReport stored = voxelizeMeshToStore(mesh, options, o.output, terminalProgress("voxelizing bricks", !o.json));
                report = stored.mesh;
                materials = stored.materials.names();
                return SceneCounts(stored.leaves, stored.activeVoxels);
            }
            const Volume volume = voxelizeMesh(mesh, options, &report);
            if (report.solidVoxels == 0) throw MeshImportError(noSolidMessage(report.voxelSize));
            saveVolume(volume, o.output);
            materials = volume.materials().names();
            return SceneCounts(volume.stats());
        } catch (const std::invalid_argument& e) {
            throw UsageError(e.what());
        }
    }();
    const double seconds = secondsSince(start);
    if (o.json) {
        nlohmann::json out = sceneSummaryJson(o.output, counts, seconds);
        out["mesh"] = {{"triangles", report.triangles},         {"dropped_triangles", report.droppedTriangles},
                       {"voxel_size", report.voxelSize},        {"hits", report.hits},
                       {"duplicate_hits", report.duplicateHits}, {"voted_points", report.votedPoints},
                       {"patched_crossings", report.patchedCrossings}, {"crossings", report.crossings},
                       {"solid_voxels", report.solidVoxels},    {"material_interfaces", report.materialInterfaces},
                       {"materials", materials},                {"colour_materials", mesh.colourMaterials},
                       {"colours_binned", mesh.colourBinned}};
        printJson(out);
        return kExitOk;
    }
    printFields({{"mesh", std::to_string(report.triangles) + " triangles, voxel size " + formatNumber(report.voxelSize)},
                 {"repaired", std::to_string(report.droppedTriangles) + " degenerate triangles dropped, " +
                                  std::to_string(report.duplicateHits) + " duplicate hits merged, " +
                                  std::to_string(report.votedPoints) + " lattice points settled by the 3-ray vote (holes, seams), " +
                                  std::to_string(report.patchedCrossings) + " crossings patched"},
                 {"materials", std::to_string(materials.size()) +
                                   (mesh.colourMaterials == 0 ? std::string()
                                                              : ", " + std::to_string(mesh.colourMaterials) + " from vertex colours" +
                                                                    (mesh.colourBinned ? " (binned: 4 levels per channel)" : ""))}},
                0);
    printSummary(o.input, o.output, counts, seconds);
    return kExitOk;
}

/// A level set or fog volume of another tool's .vdb. Into a store it is built brick by brick.
int importStandardGrid(const ImportOptions& o, std::chrono::steady_clock::time_point start)
{
    LevelSetImportOptions options;
    options.grid = o.grid;
    options.iso = o.iso;
    options.voxelSize = o.voxelSize;
    options.material = o.material;
    LevelSetImportReport report;
    const SceneCounts counts = [&] {
        try {
            if (isStorePath(o.output)) {
                const StoreLevelSetReport stored =
                    importLevelSetToStore(o.input, options, o.output, terminalProgress("importing bricks", !o.json));
                report = stored.levelSet;
                return SceneCounts(stored.leaves, stored.activeVoxels);
            }
            const Volume volume = importLevelSet(o.input, options, &report);
            const VolumeStats stats = volume.stats();
            if (stats.empty)
                throw std::runtime_error("grid '" + printableText(report.grid, 64) + "' of '" + o.input + "' holds no solid voxel read as a " +
                                         (report.fog ? "fog volume (solid where the density exceeds " + formatNumber(o.iso.value_or(0.0)) + ")"
                                                     : "level set (solid below " + formatNumber(o.iso.value_or(0.0)) + ")") +
                                         ": nothing to import");
            saveVolume(volume, o.output);
            return SceneCounts(stats);
        } catch (const std::invalid_argument& e) {
            throw UsageError(e.what());
        }
    }();
    const double seconds = secondsSince(start);
    if (o.json) {
        nlohmann::json out = sceneSummaryJson(o.output, counts, seconds);
        out["levelset"] = {{"grid", report.grid},   {"class", report.gridClass}, {"value_type", report.valueType},
                           {"fog", report.fog},     {"voxel_size", report.voxelSize},
                           {"resampled", !report.resampled.empty()}, {"resampled_because", report.resampled},
                           {"crossings", report.crossings}};
        printJson(out);
        return kExitOk;
    }
    printFields({{"grid", report.grid + " (" + (report.gridClass.empty() ? "no class" : report.gridClass) + ", " + report.valueType + ")"},
                 {"read as", report.fog ? "fog volume (solid where the value exceeds --iso)" : "level set (solid below the iso value)"},
                 {"voxel size", formatNumber(report.voxelSize)},
                 {"resampled", report.resampled.empty() ? "no" : "yes: " + report.resampled},
                 {"crossings", std::to_string(report.crossings)}},
                0);
    printSummary(o.input, o.output, counts, seconds);
    return kExitOk;
}

CLI::App* addImportCommand(CLI::App& parent, ImportOptions& o)
{
    CLI::App* cmd = parent.add_subcommand(
        "import", "Bring a scene in: a VDBClay .vdb or store, a level set or fog volume of another tool's .vdb, or a mesh");
    cmd->add_option("input", o.input, "Scene to bring in (.vdb of VDBClay or of another tool, a .vdbclay store, or a mesh: "
                                      "obj ply stl off gltf glb fbx dae)")
        ->required()
        ->type_name("IN");
    cmd->add_option("-o,--output", o.output, "Scene to write; the extension picks the form (.vdbclay store or .vdb)")
        ->required()
        ->type_name("OUT.vdbclay|OUT.vdb");
    cmd->add_option("--grid", o.grid, "Grid of a standard .vdb to import (default: the first level set, else fog volume)")
        ->type_name("NAME");
    cmd->add_option("--iso", o.iso, "Iso value: a fog volume is solid where its density exceeds it (required for fog)")
        ->type_name("VALUE")
        ->check(finiteNumber());
    cmd->add_option("--voxel-size", o.voxelSize, "Voxel size of a voxelized mesh, or to resample a standard grid to (default: its own)")
        ->type_name("V")
        ->check(positiveNumber());
    cmd->add_option("--resolution", o.resolution,
                    "Voxels along a mesh's longest side (instead of --voxel-size); up to 16384 for a flat mesh, about 4090 "
                    "for a cube-like one (the mesh's box may span 2^36 lattice points; the error says this mesh's limit)")
        ->type_name("N")
        ->check(CLI::Range(1, 16384));
    cmd->add_option("--material", o.material, "Material of what a standard grid or a mesh brings in (a mesh: default its own materials)")
        ->capture_default_str()
        ->check(CLI::Validator([](const std::string& name) { return name.empty() ? std::string("needs a name") : std::string(); }, ""))
        ->each([&o](const std::string&) { o.materialGiven = true; });
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("A store keeps the scene in bricks of 64^3 voxels, so that 'sculpt', 'mesh' and 'lod' read only what\n"
                "they need. A standard grid becomes Hermite data: materials from the sign at the lattice points,\n"
                "crossings where the field crosses zero, normals from its gradient; a transform that is not a\n"
                "uniform scale on VDBClay's lattice is resampled (the output says so). A mesh is voxelized by\n"
                "axis-aligned rays (exact crossings, triangle normals), solid where two of three rays agree, which\n"
                "closes holes and seams; the output says what was repaired. An existing output is replaced only\n"
                "once the new one is complete.");
    return cmd;
}

int runImport(const ImportOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    requireSceneExtension(o.output);
    if (sameFile(o.input, o.output)) // replacing a store by its own level 0 drops its levels of detail
        throw UsageError("'" + o.output + "' is the input itself: import writes another file (a store's levels of detail "
                         "are refreshed by 'vdbclay lod build')");
    checkOutput(o.output, isStorePath(o.output) ? OutputForm::Store : OutputForm::NativeVolume, {o.input});
    if (isMeshPath(o.input)) return importMesh(o, start);
    if (o.resolution)
        throw UsageError("--resolution is for meshes (obj ply stl off gltf glb fbx dae); '" + o.input + "' is not one");
    const bool standard = !isStorePath(o.input) && classifyVdbFile(o.input) == VdbFileKind::Other;
    if (!standard && (!o.grid.empty() || o.iso || o.voxelSize))
        throw UsageError("--grid, --iso and --voxel-size are for .vdb files of other tools; '" + o.input + "' is VDBClay's own");
    if (standard) return importStandardGrid(o, start);
    const Volume volume = loadScene(o.input, terminalProgress("reading bricks", !o.json));
    const VolumeStats stats = volume.stats();
    writeScene(volume, o.output, !o.json);
    const double seconds = secondsSince(start);
    if (o.json) printJson(sceneSummaryJson(o.output, SceneCounts(stats), seconds));
    else printSummary(o.input, o.output, SceneCounts(stats), seconds);
    return kExitOk;
}

CLI::App* addExportCommand(CLI::App& parent, ExportOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("export", "Write a whole scene (store or .vdb) as one native .vdb");
    cmd->add_option("input", o.input, "Scene to export (.vdbclay store or .vdb)")->required()->check(sceneInput())->type_name("IN");
    cmd->add_option("-o,--output", o.output, "Native volume file to write (.vdb); saving is atomic")
        ->required()
        ->type_name("OUT.vdb");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    return cmd;
}

int runExport(const ExportOptions& o)
{
    requireSceneExtension(o.output);
    if (isStorePath(o.output)) throw UsageError("export writes a native .vdb; use 'vdbclay import' to make a store");
    checkOutput(o.output, OutputForm::NativeVolume, {o.input});
    const auto start = std::chrono::steady_clock::now();
    const Volume volume = loadScene(o.input, terminalProgress("reading bricks", !o.json));
    saveVolume(volume, o.output);
    const double seconds = secondsSince(start);
    const SceneCounts counts(volume.stats());
    if (o.json) printJson(sceneSummaryJson(o.output, counts, seconds));
    else printSummary(o.input, o.output, counts, seconds);
    return kExitOk;
}

CLI::App* addExportLevelSetCommand(CLI::App& parent, ExportLevelSetOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("export-levelset", "Write a scene as standard OpenVDB grids (a level set, materials, a fog)");
    cmd->add_option("input", o.input, "Scene to export (.vdbclay store or .vdb)")->required()->check(sceneInput())->type_name("SCENE");
    cmd->add_option("-o,--output", o.output, "Standard .vdb file to write (atomically)")->required()->type_name("OUT.vdb");
    cmd->add_option("--half-width", o.halfWidth, "Narrow band half width, in voxels (1 to 64)")
        ->capture_default_str()
        ->check(finiteNumber())
        ->check(CLI::Range(1.0, 64.0));
    cmd->add_flag("--fog", o.fog, "Also write a fog volume 'density' (FOG_VOLUME) that Blender's volume objects render");
    cmd->add_flag("--int32-material", o.int32Material,
                  "Write 'material' as an Int32Grid (exact for any id; pyopenvdb's readAll and Blender cannot read it)");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("Grids: 'surface', a FloatGrid narrow-band level set (GRID_LEVEL_SET, negative inside, distances\n"
                "exact to the scene's CMS mesh); 'material', a FloatGrid of material ids (0: empty; whole numbers,\n"
                "exact as floats; an Int32Grid with --int32-material); with --fog, 'density', 1 inside falling to\n"
                "0 across the band. vdb_print, pyopenvdb (read and readAll), Houdini and Blender read every grid of\n"
                "the default file; with --int32-material, pyopenvdb and Blender read 'surface' and 'density' only.\n"
                "'vdbclay import' brings the level set back. A later export may replace this file; no other file\n"
                "is replaced.");
    return cmd;
}

int runExportLevelSet(const ExportLevelSetOptions& o)
{
    if (isStorePath(o.output)) throw UsageError("export-levelset writes a standard .vdb, not a store");
    checkOutput(o.output, OutputForm::StandardVdb, {o.input});
    const auto start = std::chrono::steady_clock::now();
    const Volume volume = loadScene(o.input, terminalProgress("reading bricks", !o.json));
    LevelSetExportOptions options;
    options.halfWidth = o.halfWidth;
    options.fog = o.fog;
    options.int32Material = o.int32Material;
    LevelSetExportReport report;
    exportLevelSet(volume, o.output, options, &report);
    const double seconds = secondsSince(start);
    if (o.json) {
        printJson({{"output", o.output},
                   {"material_grid", o.int32Material ? "int32" : "float"},
                   {"grids", o.fog ? nlohmann::json::array({"surface", "material", "density"}) : nlohmann::json::array({"surface", "material"})},
                   {"half_width", o.halfWidth},
                   {"triangles", report.triangles},
                   {"surface_voxels", report.surfaceVoxels},
                   {"material_voxels", report.materialVoxels},
                   {"bytes", std::filesystem::file_size(o.output)},
                   {"seconds", seconds}});
        return kExitOk;
    }
    printFields({{"exported", o.input + " -> " + o.output},
                 {"grids", std::string("surface (level set), material (") + (o.int32Material ? "int32" : "float") + ")" + (o.fog ? ", density (fog)" : "")},
                 {"band", formatNumber(o.halfWidth) + " voxels each side, " + std::to_string(report.surfaceVoxels) + " voxels"},
                 {"size", formatBytes(double(std::filesystem::file_size(o.output)))},
                 {"time", formatSeconds(seconds)}},
                0);
    return kExitOk;
}

} // namespace vdbclay::cli
