// vdbclay sculpt: apply a JSON stroke script to a volume file.
#include "Cli.h"

#include "scene/SceneStore.h"
#include "scene/StoreSculpt.h"
#include "scene/StreamingScene.h"
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <iostream>

namespace vdbclay::cli {

CLI::App* addSculptCommand(CLI::App& parent, SculptOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("sculpt", "Apply a JSON stroke script to a volume");
    cmd->add_option("input", o.input, "Scene to start from: a volume (.vdb) or a store (.vdbclay), which is edited in place")
        ->required()
        ->check(sceneInput())
        ->type_name("IN.vdb|IN.vdbclay");
    cmd->add_option("script", o.script, "Stroke script (JSON, see docs/SCRIPTS.md)")->required()->type_name("SCRIPT.json");
    cmd->add_option("-o,--output", o.output,
                    "Scene to write (.vdb or .vdbclay); may be IN itself (saving is atomic). Required for a .vdb input; "
                    "a store is edited in place")
        ->type_name("OUT.vdb|OUT.vdbclay");
    cmd->add_option("--memory-budget", o.memoryBudgetMB,
                    "Stores: keep at most this many MB of bricks resident, paging bricks in and out as the ops reach them")
        ->type_name("MB")
        ->check(memoryBudget());
    cmd->add_option("--autosave-every", o.autosaveEvery,
                    "Stores: commit the changed bricks every N ops (a crash loses at most the ops since the last commit)")
        ->type_name("N")
        ->check(positiveNumber());
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text (no progress lines)");
    cmd->footer("Without --json, one progress line per op goes to stderr, e.g. \"op 3/7 remove: 120 blocks, 0.8 ms\".\n"
                "The script is checked completely before the volume is touched. On a store only the bricks the\n"
                "brushes reach are read, and the changed ones written in one transaction.");
    return cmd;
}

namespace {

/// Streams the script's ops through the store under a budget, committing every `autosaveEvery` ops.
StoreSculptReport sculptStreaming(const SculptOptions& o, const StrokeScript& script,
                                  const std::function<void(const ScriptOpReport&)>& progress)
{
    StreamingOptions options;
    options.access = StoreAccess::ReadWrite;
    options.memoryBudgetBytes = uint64_t(o.memoryBudgetMB.value_or(1024.0) * 1048576.0);
    std::unique_ptr<StreamingScene> scene;
    try {
        scene = std::make_unique<StreamingScene>(o.input, options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    }
    StoreSculptReport report;
    const uint64_t every = o.autosaveEvery ? o.autosaveEvery : script.ops.size();
    StrokeScript batch;
    batch.materials = script.materials;
    for (std::size_t i = 0; i < script.ops.size(); ++i) {
        batch.ops.push_back(script.ops[i]);
        if (batch.ops.size() < every && i + 1 < script.ops.size()) continue;
        const StreamingScene::EditReport edit = scene->sculpt(batch);
        for (ScriptOpReport r : edit.ops) {
            r.index = report.ops.size();
            progress(r);
            report.ops.push_back(r);
        }
        report.bricksRead += edit.bricksPagedIn;
        report.bricksWritten += scene->autosave();
        batch.ops.clear();
    }
    report.lodBricksWritten = scene->lodBricksWritten();
    return report;
}

int sculptStoreInPlace(const SculptOptions& o, const StrokeScript& script,
                       const std::function<void(const ScriptOpReport&)>& progress)
{
    const auto start = std::chrono::steady_clock::now();
    StoreSculptReport report;
    if (o.memoryBudgetMB || o.autosaveEvery) {
        report = sculptStreaming(o, script, progress);
    } else {
        SceneStore scene = SceneStore::open(o.input, StoreAccess::ReadWrite);
        report = sculptStore(scene, script, progress);
    }
    const double seconds = secondsSince(start);
    if (o.json) {
        nlohmann::json ops = nlohmann::json::array();
        for (const auto& r : report.ops) ops.push_back(opReportJson(r));
        printJson({{"input", o.input},
                   {"output", o.input},
                   {"ops", report.ops.size()},
                   {"seconds", seconds},
                   {"bricks_read", report.bricksRead},
                   {"bricks_written", report.bricksWritten},
                   {"lod_bricks_written", report.lodBricksWritten},
                   {"op_reports", ops}});
    } else {
        printFields({{"sculpted", o.input + " (in place)"},
                     {"ops", std::to_string(report.ops.size())},
                     {"bricks", std::to_string(report.bricksRead) + " read, " + std::to_string(report.bricksWritten) + " written"},
                     {"lod bricks", std::to_string(report.lodBricksWritten) + " rewritten"},
                     {"total time", formatSeconds(seconds)}},
                    0);
    }
    return kExitOk;
}

} // namespace

int runSculpt(const SculptOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    const bool store = isStorePath(o.input);
    if (!store && o.output.empty()) throw UsageError("--output is required for a .vdb input");
    if (!store && (o.memoryBudgetMB || o.autosaveEvery))
        throw UsageError("--memory-budget and --autosave-every apply to stores (.vdbclay)");
    if (store && !o.output.empty() && o.output != o.input && !sameFile(o.output, o.input))
        throw UsageError("a store is sculpted in place: leave out --output (or make a copy with 'vdbclay import' first)");
    if (!store) {
        requireSceneExtension(o.output);
        // The output may be the scene itself (saving is atomic), never the script.
        checkOutput(o.output, isStorePath(o.output) ? OutputForm::Store : OutputForm::NativeVolume, {o.script});
    }
    // Parse the script first: a typo in it should not cost a large volume load.
    const StrokeScript script = loadStrokeScript(o.script);
    const std::size_t total = script.ops.size();
    auto progress = [&](const ScriptOpReport& r) {
        if (o.json) return;
        std::cerr << "op " << (r.index + 1) << '/' << total << ' ' << r.modeName << ": "
                  << r.stats.blocksComputed << " blocks, " << formatSeconds(r.seconds) << std::endl;
    };
    if (store) return sculptStoreInPlace(o, script, progress);

    Volume volume = loadScene(o.input);
    const std::vector<ScriptOpReport> reports = runStrokeScript(volume, script, progress);
    if (isStorePath(o.output)) writeStoreFile(volume, o.output);
    else saveVolume(volume, o.output);
    const double seconds = secondsSince(start);

    const VolumeStats stats = volume.stats();
    if (o.json) {
        nlohmann::json ops = nlohmann::json::array();
        for (const auto& r : reports) ops.push_back(opReportJson(r));
        printJson({{"input", o.input},
                   {"output", o.output},
                   {"ops", reports.size()},
                   {"seconds", seconds},
                   {"leaf_count", stats.leafCount},
                   {"active_voxels", stats.activeVoxels},
                   {"op_reports", ops}});
    } else {
        double opSeconds = 0.0;
        for (const auto& r : reports) opSeconds += r.seconds;
        printFields({{"sculpted", o.input + " -> " + o.output},
                     {"ops", std::to_string(reports.size()) + " in " + formatSeconds(opSeconds)},
                     {"leaves", std::to_string(stats.leafCount)},
                     {"active voxels", std::to_string(stats.activeVoxels)},
                     {"total time", formatSeconds(seconds)}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
