// vdbclay tool make: a scene, or a box of it, saved as a tool that stroke scripts use as
// {"shape": "grid", "file": "TOOL.vdb"}.
#include "Cli.h"

#include "scene/SceneStore.h"
#include "sculpt/GridTool.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <filesystem>

namespace vdbclay::cli {

namespace {

/// The scene, or from a store only the bricks the box reaches.
Volume loadToolSource(const ToolMakeOptions& o, const std::optional<WorldBounds>& box)
{
    if (!box || !isStorePath(o.scene)) return loadScene(o.scene, terminalProgress("reading bricks", !o.json));
    const SceneStore store = SceneStore::open(o.scene, StoreAccess::ReadOnly);
    const double vs = store.voxelSize();
    IndexCoord lo, hi;
    double count = 1.0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double first = std::floor(std::max(box->min[int(a)] / vs, -1e9)), last = std::ceil(std::min(box->max[int(a)] / vs, 1e9));
        lo[a] = int32_t(std::floor(first / kBrickEdge));
        hi[a] = int32_t(std::floor(last / kBrickEdge));
        count *= double(hi[a] - lo[a] + 1);
    }
    if (count > 1e6) throw UsageError("the box reaches " + formatNumber(count) + " bricks; make a tool of a smaller box");
    std::vector<IndexCoord> bricks;
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
            for (int32_t z = lo[2]; z <= hi[2]; ++z) bricks.push_back({x, y, z});
    Volume volume(vs);
    volume.materials() = store.materials();
    store.loadBricks(0, bricks, volume, terminalProgress("reading bricks", !o.json));
    return volume;
}

} // namespace

ToolCommands addToolCommand(CLI::App& parent, ToolMakeOptions& o)
{
    CLI::App* tool = parent.add_subcommand("tool", "Sculptures as tools: make one from a scene");
    tool->require_subcommand(1);
    ToolCommands cmds;
    cmds.make = tool->add_subcommand("make", "Save a scene, or the part of it in a box, as a tool for stroke scripts");
    cmds.make->add_option("scene", o.scene, "Scene to take the tool from (.vdb or .vdbclay store)")->required()->check(sceneInput())->type_name("SCENE");
    cmds.make->add_option("--bbox", o.bbox, "World box to keep: the voxels whose centres lie in it (cut faces stay sharp)")
        ->expected(6)
        ->type_name("X0 Y0 Z0 X1 Y1 Z1");
    cmds.make->add_option("-o,--output", o.output, "Tool file to write (a native .vdb, atomically)")->required()->type_name("TOOL.vdb");
    cmds.make->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmds.make->footer("Use the tool in a stroke script as {\"shape\": \"grid\", \"file\": \"TOOL.vdb\"} with the usual 'at',\n"
                      "'rotate', 'scale' and 'path', in every mode. 'at' places the centre of the tool's solid (the\n"
                      "voxel at the middle of its bounding box). Without a 'material', add and paint use the tool's own\n"
                      "materials. docs/SCRIPTS.md has the details.");
    return cmds;
}

int runToolMake(const ToolMakeOptions& o)
{
    if (isStorePath(o.output)) throw UsageError("a tool is written as a native .vdb, not a store");
    checkOutput(o.output, OutputForm::NativeVolume, {o.scene});
    std::optional<WorldBounds> box;
    if (!o.bbox.empty()) {
        box = WorldBounds{Vec3d(o.bbox[0], o.bbox[1], o.bbox[2]), Vec3d(o.bbox[3], o.bbox[4], o.bbox[5])};
        for (int a = 0; a < 3; ++a)
            if (!(box->max[a] > box->min[a]) || !std::isfinite(box->min[a]) || !std::isfinite(box->max[a]))
                throw UsageError("--bbox needs finite corners with x0 < x1, y0 < y1 and z0 < z1");
    }
    const auto start = std::chrono::steady_clock::now();
    Volume tool;
    try {
        tool = toolFromScene(loadToolSource(o, box), box);
    } catch (const std::invalid_argument& e) {
        throw std::runtime_error(std::string("cannot make a tool: ") + e.what());
    }
    saveVolume(tool, o.output);
    const GridTool built(tool.clone()); // what a script will build: its size and pivot
    const double vs = built.voxelSize();
    const auto& dims = built.dims();
    const Vec3d pivot = Vec3d(built.pivot()[0], built.pivot()[1], built.pivot()[2]) * vs;
    std::vector<std::string> materials;
    for (MaterialId m : built.regions()) materials.push_back(built.materials().at(m).name);
    const double seconds = secondsSince(start);
    if (o.json) {
        printJson({{"output", o.output},
                   {"voxel_size", vs},
                   {"voxels", {dims[0], dims[1], dims[2]}},
                   {"pivot", {pivot[0], pivot[1], pivot[2]}},
                   {"materials", materials},
                   {"leaves", tool.stats().leafCount},
                   {"bytes", std::filesystem::file_size(o.output)},
                   {"seconds", seconds}});
        return kExitOk;
    }
    std::string names;
    for (const std::string& n : materials) names += (names.empty() ? "" : ", ") + n;
    printFields({{"tool", o.scene + " -> " + o.output},
                 {"size", std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]) +
                              " voxels of " + formatNumber(vs) + " (with its margin)"},
                 {"pivot", "(" + formatNumber(pivot[0]) + ", " + formatNumber(pivot[1]) + ", " + formatNumber(pivot[2]) +
                               "): 'at' puts this point"},
                 {"materials", names},
                 {"file", formatBytes(double(std::filesystem::file_size(o.output)))},
                 {"use", "{\"shape\": \"grid\", \"file\": \"" + o.output + "\"}"},
                 {"time", formatSeconds(seconds)}},
                0);
    return kExitOk;
}

} // namespace vdbclay::cli
