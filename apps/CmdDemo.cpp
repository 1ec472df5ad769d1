// vdbclay demo: a scripted sculpting session that exercises materials, every CSG mode, blended and
// swept brushes, then meshes the result and writes the volume, the meshes and the script.
#include "Cli.h"

#include "render/ImageFile.h"
#include "render/ScenePicture.h"
#include "render/VulkanContext.h"

#include "mesher/MeshIO.h"
#include "mesher/MeshMetrics.h"
#include "mesher/LodMesh.h"
#include "mesher/Mesher.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>

namespace vdbclay::cli {

namespace {

namespace fs = std::filesystem;

constexpr double kDemoVoxelSize = 0.5;

// A clay ball with a stone pillar through it; erosion later eats the clay around the pillar but
// barely scratches the stone (toughness 0.9 against 0.2).
constexpr const char* kDemoScript = R"json({
  "materials": [
    {"name": "stone", "color": [0.55, 0.55, 0.58, 1], "toughness": 0.9},
    {"name": "clay",  "color": [0.72, 0.45, 0.30, 1], "toughness": 0.2},
    {"name": "moss",  "color": [0.30, 0.55, 0.20, 1], "toughness": 0.5}
  ],
  "ops": [
    {"mode": "add", "brush": {"shape": "sphere", "radius": 24}, "at": [0, 0, 0], "material": "clay"},
    {"mode": "add", "brush": {"shape": "cylinder", "radius": 6, "height": 60}, "at": [0, 0, 0],
     "rotate": [90, 0, 0], "material": "stone"},
    {"mode": "remove", "brush": {"shape": "box", "size": [8, 8, 30], "rounding": 2}, "at": [22, 0, 0],
     "rotate": [0, 20, 30]},
    {"mode": "paint", "brush": {"shape": "sphere", "radius": 6},
     "path": [[-20, 0, 12], [0, 0, 24], [20, 0, 12]], "material": "moss"},
    {"mode": "erode", "brush": {"shape": "capsule", "radius": 6, "length": 20}, "at": [0, 0, 23],
     "rotate": [0, 0, 90], "strength": 1.0},
    {"mode": "add", "brush": {"shape": "blend", "smoothness": 2.0, "parts": [
        {"shape": "sphere", "radius": 5, "at": [0, 0, 0]},
        {"shape": "box", "size": [3, 3, 3], "at": [4, 0, 0], "op": "remove"}]},
     "at": [0, -27, 0], "scale": [1, 2, 1], "material": "stone"},
    {"mode": "add", "brush": {"shape": "sphere", "radius": 2.5},
     "path": [[-18, 10, 14], [-8, 20, 10], [4, 22, 6], [15, 18, 3], [22, 8, -4]], "material": "moss"}
  ]
})json";

// Sculptures as tools: the stone knob under the ball (cut out of the scene by `tool make`'s box) stamped
// turned on both sides of the ball, then swept at half size around its waist.
constexpr const char* kToolScript = R"json({
  "ops": [
    {"mode": "add", "brush": {"shape": "grid", "file": "knob.vdb"}, "at": [-27, 6, 0], "rotate": [0, 0, -70]},
    {"mode": "add", "brush": {"shape": "grid", "file": "knob.vdb"}, "at": [27, 6, 0], "rotate": [0, 0, 70]},
    {"mode": "add", "brush": {"shape": "grid", "file": "knob.vdb"}, "scale": [0.4, 0.4, 0.4], "rotate": [90, 0, 0],
     "path": [[-16, -12, 14], [0, -15, 18], [16, -12, 14]], "material": "moss"}
  ]
})json";
// The box `tool make` cuts the knob out with: the blended stone bump below the clay ball.
const WorldBounds kKnobBox{Vec3d(-7.0, -38.0, -7.0), Vec3d(7.0, -25.0, 7.0)};

std::string describeOp(const ScriptOp& op)
{
    std::string text = opModeName(op);
    if (!op.toolFile.empty()) text += " tool " + op.toolFile;
    if (!op.material.empty()) text += " " + op.material;
    if (op.path.size() > 1) text += ", stroke of " + std::to_string(op.path.size()) + " points";
    return text;
}

} // namespace

CLI::App* addDemoCommand(CLI::App& parent, DemoOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("demo", "Run a scripted sculpting session and write its results");
    cmd->add_option("--out", o.outDir, "Directory for the results (created if needed)")
        ->capture_default_str()
        ->type_name("DIR");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("Writes DIR/scene.vdb, DIR/scene.obj (with DIR/scene.mtl), DIR/scene.ply and DIR/script.json (the stroke script it ran;\n"
                "replay it with 'vdbclay sculpt'); DIR/knob.vdb, a part of the sculpture made a tool, and DIR/tools.json,\n"
                "the second script, which stamps and sweeps it; then the same scene as a store with two levels of detail\n"
                "(DIR/scene.vdbclay) and the mesh of level 2 (DIR/scene-lod2.obj); and a picture of the scene (DIR/scene.png),\n"
                "drawn with Vulkan (lavapipe where there is no GPU).");
    return cmd;
}

int runDemo(const DemoOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    const fs::path dir(o.outDir);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) {
        throw std::runtime_error("cannot create directory '" + o.outDir + "'" + (ec ? ": " + ec.message() : ""));
    }
    const std::string vdbPath = (dir / "scene.vdb").string();
    const std::string objPath = (dir / "scene.obj").string();
    const std::string plyPath = (dir / "scene.ply").string();
    const std::string scriptPath = (dir / "script.json").string();
    const std::string toolPath = (dir / "knob.vdb").string();
    const std::string toolScriptPath = (dir / "tools.json").string();
    const std::string storePath = (dir / "scene.vdbclay").string();
    const std::string lodPath = (dir / "scene-lod2.obj").string();
    const std::string picturePath = (dir / "scene.png").string();
    // Every file is checked before the session: a folder of other files is never overwritten.
    for (const std::string& path : {vdbPath, toolPath}) checkOutput(path, OutputForm::NativeVolume);
    for (const std::string& path : {objPath, lodPath}) checkOutput(path, OutputForm::ObjMesh);
    for (const std::string& path : {scriptPath, toolScriptPath}) checkOutput(path, OutputForm::Json);
    checkOutput(plyPath, OutputForm::PlyMesh);
    checkOutput(storePath, OutputForm::Store);
    checkOutput(picturePath, OutputForm::Png);

    const StrokeScript script = parseStrokeScript(kDemoScript);
    Volume volume(kDemoVoxelSize);
    const auto sculptStart = std::chrono::steady_clock::now();
    std::vector<std::pair<std::string, ScriptOpReport>> reports;
    for (ScriptOpReport& r : runStrokeScript(volume, script)) reports.emplace_back(describeOp(script.ops[r.index]), std::move(r));
    // A part of the sculpture becomes a tool, and the second script sculpts with it.
    saveVolume(toolFromScene(volume.clone(), kKnobBox), toolPath);
    StrokeScript toolScript = parseStrokeScript(kToolScript);
    loadScriptTools(toolScript, dir.string());
    for (ScriptOpReport& r : runStrokeScript(volume, toolScript)) {
        const std::string what = describeOp(toolScript.ops[r.index]);
        r.index += script.ops.size();
        reports.emplace_back(what, std::move(r));
    }
    const double sculptSeconds = secondsSince(sculptStart);

    saveVolume(volume, vdbPath);
    writeFileAtomically(scriptPath, [](std::ostream& out) { out << kDemoScript << '\n'; });
    writeFileAtomically(toolScriptPath, [](std::ostream& out) { out << kToolScript << '\n'; });

    const auto meshStart = std::chrono::steady_clock::now();
    MeshOptions meshOptions;
    meshOptions.kind = MesherKind::CubicalMarchingSquares;
    const Mesh mesh = meshVolume(volume, meshOptions);
    const double meshSeconds = secondsSince(meshStart);
    const MeshTopology topology = analyzeTopology(mesh, kMergeDistanceVoxels * volume.voxelSize());
    writeMesh(mesh, volume.materials(), objPath);
    writeMesh(mesh, volume.materials(), plyPath);
    // The same scene out of core: a store with its levels of detail, and the coarsest level's mesh.
    writeStoreFile(volume, storePath);
    {
        SceneStore store = SceneStore::open(storePath, StoreAccess::ReadWrite);
        buildStoreLod(store, 2);
        const Mesh coarse = meshVolume(store.loadLevel(2), meshOptions);
        writeMesh(coarse, volume.materials(), lodPath);
    }
    // The picture: without a Vulkan device the demo still writes everything else, and says why.
    std::optional<std::string> pictureSkipped;
    render::Picture picture;
    try {
        render::VulkanContext context;
        render::PictureRequest request;
        picture = render::renderVolume(context, volume, request);
        render::writePng(picture.image, picturePath);
    } catch (const render::NoVulkanDevice& e) {
        pictureSkipped = e.what();
    }
    const double seconds = secondsSince(start);
    const VolumeStats stats = volume.stats();

    if (o.json) {
        nlohmann::json ops = nlohmann::json::array();
        for (const auto& [what, r] : reports) {
            nlohmann::json op = opReportJson(r);
            op["description"] = what;
            ops.push_back(std::move(op));
        }
        printJson({{"out_dir", o.outDir},
                   {"voxel_size", kDemoVoxelSize},
                   {"materials", volume.materials().names()},
                   {"ops", reports.size()},
                   {"op_reports", ops},
                   {"sculpt_seconds", sculptSeconds},
                   {"leaf_count", stats.leafCount},
                   {"active_voxels", stats.activeVoxels},
                   {"mesher", mesherName(MesherKind::CubicalMarchingSquares)},
                   {"mesh_seconds", meshSeconds},
                   {"vertices", mesh.vertexCount()},
                   {"triangles", mesh.triangleCount()},
                   {"watertight", topology.watertight()},
                   {"files", {{"volume", vdbPath}, {"obj", objPath}, {"mtl", (dir / "scene.mtl").string()}, {"ply", plyPath}, {"script", scriptPath},
                              {"tool", toolPath}, {"tool_script", toolScriptPath}, {"store", storePath}, {"lod2_obj", lodPath}}},
                   {"picture", pictureSkipped ? nlohmann::json() : nlohmann::json(picturePath)},
                   {"picture_skipped", pictureSkipped ? nlohmann::json(*pictureSkipped) : nlohmann::json()},
                   {"seconds", seconds}});
        return kExitOk;
    }

    std::cout << "VDBClay demo: " << reports.size() << " ops on a " << formatNumber(kDemoVoxelSize)
              << "-unit voxel grid, materials stone (toughness 0.9), clay (0.2), moss (0.5)\n";
    for (const auto& [what, r] : reports) {
        char line[160];
        std::snprintf(line, sizeof line, "  op %2zu/%zu  %-44s %8llu blocks  %s\n", r.index + 1, reports.size(), what.c_str(),
                      static_cast<unsigned long long>(r.stats.blocksComputed), formatSeconds(r.seconds).c_str());
        std::cout << line;
    }
    printFields({{"sculpt time", formatSeconds(sculptSeconds)},
                 {"leaves", std::to_string(stats.leafCount)},
                 {"active voxels", std::to_string(stats.activeVoxels)},
                 {"mesh", std::to_string(mesh.triangleCount()) + " triangles, " + std::to_string(mesh.vertexCount()) +
                              " vertices (" + mesherName(MesherKind::CubicalMarchingSquares) + ", " +
                              formatSeconds(meshSeconds) + ")"},
                 {"watertight", topology.watertight() ? "yes" : "no"},
                 {"volume", vdbPath},
                 {"meshes", objPath + " (materials in scene.mtl), " + plyPath},
                 {"scripts", scriptPath + ", then " + toolScriptPath + " with the tool " + toolPath},
                 {"store", storePath + " (2 levels of detail; level 2 meshed to " + lodPath + ")"},
                 {"total time", formatSeconds(seconds)}},
                0);
    if (pictureSkipped) {
        std::cout << "picture: skipped (" << *pictureSkipped << ")" << std::endl;
    } else {
        printFields({{"picture", picturePath + " (" + std::to_string(picture.image.width) + "x" + std::to_string(picture.image.height) +
                                     ", " + std::to_string(picture.stats.triangles) + " triangles, gpu " +
                                     formatSeconds(picture.stats.gpuMs / 1000.0) + ")"}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
