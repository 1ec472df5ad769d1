// vdbclay lod build / lod info: the levels of detail of a store.
#include "Cli.h"

#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "wavelet/LodPyramid.h"

#include <CLI/CLI.hpp>

#include <chrono>

namespace vdbclay::cli {

namespace {

void requireStore(const std::string& path)
{
    if (!isStorePath(path))
        throw UsageError("'" + path + "' is not a store: levels of detail live in stores (vdbclay import " + path +
                         " -o SCENE.vdbclay); 'vdbclay mesh --lod K' meshes a level of a .vdb directly");
}

nlohmann::json levelsJson(const SceneStore& scene)
{
    nlohmann::json levels = nlohmann::json::array();
    for (int k = 0; k <= scene.lodLevels(); ++k) {
        const LevelSummary s = scene.summary(k);
        levels.push_back({{"level", k},
                          {"voxel_size", scene.voxelSize() * double(1 << k)},
                          {"bricks", s.bricks},
                          {"leaves", s.leaves},
                          {"bytes", s.bytes}});
    }
    return levels;
}

void printLevels(const SceneStore& scene)
{
    std::vector<std::pair<std::string, std::string>> rows;
    for (int k = 0; k <= scene.lodLevels(); ++k) {
        const LevelSummary s = scene.summary(k);
        rows.push_back({"level " + std::to_string(k), std::to_string(s.bricks) + " bricks, " + std::to_string(s.leaves) +
                                                          " leaves, " + formatBytes(double(s.bytes)) + " (voxel " +
                                                          formatNumber(scene.voxelSize() * double(1 << k)) + ")"});
    }
    printFields(rows, 0);
}

} // namespace

LodCommands addLodCommand(CLI::App& parent, LodOptions& o)
{
    CLI::App* lod = parent.add_subcommand("lod", "Levels of detail of a store: build them, list them");
    lod->require_subcommand(1);
    LodCommands cmds;
    cmds.build = lod->add_subcommand("build", "Build or refresh the Haar-wavelet LOD pyramid of a store");
    cmds.build->add_option("scene", o.scene, "Store (.vdbclay)")->required()->type_name("SCENE.vdbclay");
    cmds.build->add_option("--levels", o.levels, "Coarse levels to build (0: enough to bring the scene to about one brick)")
        ->capture_default_str()
        ->check(CLI::Range(0, wavelet::kMaxLodLevels));
    cmds.build->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmds.info = lod->add_subcommand("info", "List the levels of a store: bricks, leaves and bytes per level");
    cmds.info->add_option("scene", o.scene, "Store (.vdbclay)")->required()->type_name("SCENE.vdbclay");
    cmds.info->add_flag("--json", o.json, "Print {\"levels\": [{\"level\", \"bricks\", \"leaves\", \"bytes\"}, ...]}");
    return cmds;
}

int runLodBuild(const LodOptions& o)
{
    requireStore(o.scene);
    const auto start = std::chrono::steady_clock::now();
    SceneStore scene = SceneStore::open(o.scene, StoreAccess::ReadWrite);
    buildStoreLod(scene, o.levels, terminalProgress("building levels", !o.json));
    const double seconds = secondsSince(start);
    if (o.json) {
        printJson({{"scene", o.scene}, {"levels", levelsJson(scene)}, {"seconds", seconds}});
    } else {
        printLevels(scene);
        printFields({{"time", formatSeconds(seconds)}}, 0);
    }
    return kExitOk;
}

int runLodInfo(const LodOptions& o)
{
    requireStore(o.scene);
    const SceneStore scene = SceneStore::open(o.scene, StoreAccess::ReadOnly);
    if (o.json) {
        printJson({{"levels", levelsJson(scene)}, {"stale", scene.lodStale()}});
    } else {
        printLevels(scene);
        if (scene.lodStale()) printFields({{"note", "edited since the last 'vdbclay lod build'"}}, 0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
