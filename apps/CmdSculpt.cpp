// vdbclay sculpt: apply a JSON stroke script to a volume file.
#include "Cli.h"

#include "sculpt/StrokeScript.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <iostream>

namespace vdbclay::cli {

CLI::App* addSculptCommand(CLI::App& parent, SculptOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("sculpt", "Apply a JSON stroke script to a volume");
    cmd->add_option("input", o.input, "Volume to start from (.vdb)")->required()->type_name("IN.vdb");
    cmd->add_option("script", o.script, "Stroke script (JSON, see docs/SCRIPTS.md)")->required()->type_name("SCRIPT.json");
    cmd->add_option("-o,--output", o.output, "Volume file to write; may be IN.vdb itself (saving is atomic)")
        ->required()
        ->type_name("OUT.vdb");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text (no progress lines)");
    cmd->footer("Without --json, one progress line per op goes to stderr, e.g. \"op 3/7 remove: 120 blocks, 0.8 ms\".\n"
                "The script is checked completely before the volume is touched.");
    return cmd;
}

int runSculpt(const SculptOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    // Parse the script first: a typo in it should not cost a large volume load.
    const StrokeScript script = loadStrokeScript(o.script);
    Volume volume = loadVolume(o.input);

    const std::size_t total = script.ops.size();
    auto progress = [&](const ScriptOpReport& r) {
        if (o.json) return;
        std::cerr << "op " << (r.index + 1) << '/' << total << ' ' << csgModeName(r.mode) << ": "
                  << r.stats.blocksComputed << " blocks, " << formatSeconds(r.seconds) << std::endl;
    };
    const std::vector<ScriptOpReport> reports = runStrokeScript(volume, script, progress);
    saveVolume(volume, o.output);
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
