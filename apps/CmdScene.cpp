// vdbclay import / export: whole scenes between a native .vdb and a store (.vdbclay). The output's
// extension picks the form.
#include "Cli.h"

#include "scene/SceneStore.h"
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

nlohmann::json sceneSummaryJson(const std::string& path, const Volume& volume, double seconds)
{
    const VolumeStats s = volume.stats();
    return {{"output", path},
            {"form", isStorePath(path) ? "store" : "vdb"},
            {"leaf_count", s.leafCount},
            {"active_voxels", s.activeVoxels},
            {"bytes", std::filesystem::file_size(path)},
            {"seconds", seconds}};
}

void printSummary(const std::string& input, const std::string& output, const Volume& volume, double seconds)
{
    printFields({{"converted", input + " -> " + output},
                 {"form", isStorePath(output) ? "store (bricks of 64^3 voxels)" : "native .vdb"},
                 {"leaves", std::to_string(volume.stats().leafCount)},
                 {"size", formatBytes(double(std::filesystem::file_size(output)))},
                 {"time", formatSeconds(seconds)}},
                0);
}

} // namespace

CLI::App* addImportCommand(CLI::App& parent, ImportOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("import", "Bring a scene in: a native .vdb into a store (.vdbclay) or a .vdb");
    cmd->add_option("input", o.input, "Scene to bring in (.vdb, or a .vdbclay store)")->required()->type_name("IN");
    cmd->add_option("-o,--output", o.output, "Scene to write; the extension picks the form (.vdbclay store or .vdb)")
        ->required()
        ->type_name("OUT.vdbclay|OUT.vdb");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("A store keeps the scene in bricks of 64^3 voxels, so that 'sculpt', 'mesh' and 'lod' read only what\n"
                "they need. An existing output is replaced only once the new one is complete.");
    return cmd;
}

int runImport(const ImportOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    const Volume volume = loadScene(o.input, terminalProgress("reading bricks", !o.json));
    writeScene(volume, o.output, !o.json);
    const double seconds = secondsSince(start);
    if (o.json) printJson(sceneSummaryJson(o.output, volume, seconds));
    else printSummary(o.input, o.output, volume, seconds);
    return kExitOk;
}

CLI::App* addExportCommand(CLI::App& parent, ExportOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("export", "Write a whole scene (store or .vdb) as one native .vdb");
    cmd->add_option("input", o.input, "Scene to export (.vdbclay store or .vdb)")->required()->type_name("IN");
    cmd->add_option("-o,--output", o.output, "Native volume file to write (.vdb); saving is atomic")
        ->required()
        ->type_name("OUT.vdb");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    return cmd;
}

int runExport(const ExportOptions& o)
{
    if (isStorePath(o.output)) throw UsageError("export writes a native .vdb; use 'vdbclay import' to make a store");
    const auto start = std::chrono::steady_clock::now();
    const Volume volume = loadScene(o.input, terminalProgress("reading bricks", !o.json));
    saveVolume(volume, o.output);
    const double seconds = secondsSince(start);
    if (o.json) printJson(sceneSummaryJson(o.output, volume, seconds));
    else printSummary(o.input, o.output, volume, seconds);
    return kExitOk;
}

} // namespace vdbclay::cli
