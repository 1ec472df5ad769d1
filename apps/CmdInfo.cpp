// vdbclay info: what a volume file holds.
#include "Cli.h"

#include "interop/StandardVdb.h"
#include "scene/SceneStore.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <algorithm>

namespace vdbclay::cli {

namespace {

std::string coordText(const std::array<int32_t, 3>& c)
{
    return "(" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + ")";
}

/// What `info` says of a mask: the leaves it lists and whether it is inverted.
nlohmann::json maskJson(const VoxelMask& mask)
{
    return {{"leaves", mask.listedLeaves().size()}, {"inverted", mask.inverted()}};
}

std::string maskText(const VoxelMask& mask)
{
    if (!mask.any()) return "none";
    const std::string leaves = std::to_string(mask.listedLeaves().size()) + " leaves";
    return mask.inverted() ? "everything but " + leaves : leaves;
}

} // namespace

CLI::App* addInfoCommand(CLI::App& parent, InfoOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("info", "Describe a volume file");
    cmd->add_option("input", o.input, "Scene: a volume file (.vdb) or a store (.vdbclay)")->required()->check(sceneInput())->type_name("IN");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("bbox_min/bbox_max are index-space voxel coordinates of the solid and surface voxels\n"
                "(both (0, 0, 0) for an empty volume), for a store too, with world_min/world_max, the same\n"
                "voxels' positions in world units (to aim a camera path); memory_bytes is the in-memory size\n"
                "of the tree.");
    return cmd;
}

namespace {

int storeInfo(const InfoOptions& o)
{
    const SceneStore scene = SceneStore::open(o.input, StoreAccess::ReadOnly);
    const std::vector<std::string> materials = scene.materials().names();
    nlohmann::json levels = nlohmann::json::array();
    std::vector<std::pair<std::string, std::string>> rows{{"file", o.input},
                                                          {"form", "store (bricks of 64^3 voxels)"},
                                                          {"voxel_size", formatNumber(scene.voxelSize())}};
    for (int k = 0; k <= scene.lodLevels(); ++k) {
        const LevelSummary s = scene.summary(k);
        levels.push_back({{"level", k}, {"bricks", s.bricks}, {"leaves", s.leaves}, {"bytes", s.bytes}});
        rows.push_back({"level " + std::to_string(k),
                        std::to_string(s.bricks) + " bricks, " + std::to_string(s.leaves) + " leaves, " + formatBytes(double(s.bytes))});
    }
    const LevelSummary fine = scene.summary(0);
    const auto box = scene.bounds();
    const IndexCoord lo = box ? box->first : IndexCoord{0, 0, 0}, hi = box ? box->second : IndexCoord{0, 0, 0};
    const auto world = [&](const IndexCoord& c) {
        return std::array<double, 3>{c[0] * scene.voxelSize(), c[1] * scene.voxelSize(), c[2] * scene.voxelSize()};
    };
    if (o.json) {
        printJson({{"form", "store"},
                   {"bbox_min", lo},
                   {"bbox_max", hi},
                   {"world_min", world(lo)},
                   {"world_max", world(hi)},
                   {"voxel_size", scene.voxelSize()},
                   {"leaf_count", fine.leaves},
                   {"bricks", fine.bricks},
                   {"materials", materials},
                   {"levels", levels},
                   {"lod_stale", scene.lodStale()},
                   {"mask", maskJson(scene.mask())},
                   {"format_version", scene.bricks().formatVersion()}});
        return kExitOk;
    }
    std::string names;
    for (const auto& n : materials) names += (names.empty() ? "" : ", ") + n;
    rows.push_back({"mask", maskText(scene.mask())});
    rows.push_back({"bbox_min", box ? coordText(lo) : "(empty)"});
    rows.push_back({"bbox_max", box ? coordText(hi) : "(empty)"});
    if (box) {
        const auto w0 = world(lo), w1 = world(hi);
        rows.push_back({"world bounds", "(" + formatNumber(w0[0]) + ", " + formatNumber(w0[1]) + ", " + formatNumber(w0[2]) + ") .. (" +
                                            formatNumber(w1[0]) + ", " + formatNumber(w1[1]) + ", " + formatNumber(w1[2]) + ")"});
    }
    rows.push_back({"materials", std::to_string(materials.size()) + ": " + names});
    if (scene.lodStale()) rows.push_back({"lod", "stale (edited since 'vdbclay lod build')"});
    printFields(rows, 0);
    return kExitOk;
}

/// A .vdb of another tool: what it holds, and how to bring it in.
int standardInfo(const InfoOptions& o)
{
    const StandardVdbInfo info = describeStandardVdb(o.input);
    const std::string hint = "vdbclay import " + o.input + " -o scene.vdb";
    if (o.json) {
        nlohmann::json grids = nlohmann::json::array();
        for (const StandardGridInfo& g : info.grids)
            grids.push_back({{"name", g.name},
                             {"base_name", g.baseName},
                             {"type", g.header.type},
                             {"value_type", g.header.valueType},
                             {"class", g.header.gridClass},
                             {"voxel_size", g.voxelSize},
                             {"uniform_voxels", g.uniformVoxels},
                             {"axis_aligned", g.axisAligned},
                             {"half_float", g.header.halfFloat},
                             {"active_voxels", g.activeVoxels},
                             {"importable", g.importable()}});
        printJson({{"form", "standard"}, {"grids", grids}, {"import", hint}});
        return kExitOk;
    }
    std::vector<std::pair<std::string, std::string>> rows{{"file", o.input}, {"form", "standard .vdb (not VDBClay's own)"}};
    for (const StandardGridInfo& g : info.grids) {
        std::string text = (g.header.gridClass.empty() ? std::string("no class") : g.header.gridClass) + ", " +
                           (g.header.valueType.empty() ? g.header.type : g.header.valueType) +
                           (g.header.halfFloat ? " (saved as half)" : "") + ", voxel " + formatNumber(g.voxelSize[0]);
        if (!g.uniformVoxels || !g.axisAligned) text += " (transform resampled on import)";
        if (g.activeVoxels) text += ", " + std::to_string(g.activeVoxels) + " active voxels";
        text += g.importable() ? "" : " (not importable)";
        rows.push_back({"grid '" + g.name + "'", text});
    }
    rows.push_back({"import", hint + (std::any_of(info.grids.begin(), info.grids.end(), [](const StandardGridInfo& g) {
                                          return g.fogVolume();
                                      })
                                          ? " (a fog volume needs --iso VALUE)"
                                          : "")});
    printFields(rows, 0);
    return kExitOk;
}

} // namespace

int runInfo(const InfoOptions& o)
{
    if (isStorePath(o.input)) return storeInfo(o);
    if (classifyVdbFile(o.input) == VdbFileKind::Other) return standardInfo(o);
    const Volume volume = loadVolume(o.input);
    const VolumeStats s = volume.stats();
    const std::vector<std::string> materials = volume.materials().names();

    if (o.json) {
        printJson({{"voxel_size", s.voxelSize},
                   {"active_voxels", s.activeVoxels},
                   {"leaf_count", s.leafCount},
                   {"bbox_min", s.bboxMin},
                   {"bbox_max", s.bboxMax},
                   {"materials", materials},
                   {"memory_bytes", s.memoryBytes},
                   {"mask", maskJson(volume.mask())},
                   {"format_version", volume.formatVersion()}});
        return kExitOk;
    }
    std::string names;
    for (const auto& n : materials) names += (names.empty() ? "" : ", ") + n;
    printFields({{"file", o.input},
                 {"voxel_size", formatNumber(s.voxelSize)},
                 {"active_voxels", std::to_string(s.activeVoxels)},
                 {"leaf_count", std::to_string(s.leafCount)},
                 {"bbox_min", s.empty ? "(empty)" : coordText(s.bboxMin)},
                 {"bbox_max", s.empty ? "(empty)" : coordText(s.bboxMax)},
                 {"materials", std::to_string(materials.size()) + ": " + names},
                 {"memory_bytes", std::to_string(s.memoryBytes) + " (" + formatBytes(double(s.memoryBytes)) + ")"},
                 {"mask", maskText(volume.mask())},
                 {"format_version", std::to_string(volume.formatVersion())}},
                0);
    return kExitOk;
}

} // namespace vdbclay::cli
