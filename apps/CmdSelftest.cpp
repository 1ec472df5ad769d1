// vdbclay selftest: seeded random scenes through every differential check (src/selftest/SceneChecks.h).
#include "Cli.h"

#include "selftest/SceneChecks.h"

#include <CLI/CLI.hpp>

#include <fstream>
#include <optional>
#include <iostream>

namespace vdbclay::cli {

CLI::App* addSelftestCommand(CLI::App& parent, SelftestOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("selftest", "Check random scenes: lattice, meshes, volume, re-meshing, threads");
    cmd->add_option("--scenes", o.scenes, "Number of random scenes")->check(CLI::Range(1, 100000000));
    cmd->add_option("--seed", o.seed, "Seed of the scene sequence (scene i of seed s is always the same)");
    cmd->add_option("--first", o.first, "Index of the first scene")->check(CLI::NonNegativeNumber);
    cmd->add_option("--save-failure", o.failurePath,
                    "Write the first failing scene's stroke script here (replay it with 'vdbclay sculpt')")
        ->type_name("SCRIPT.json");
    cmd->add_flag("--keep-going", o.keepGoing, "Check every scene, printing one line per failure, instead of stopping at the first");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text (no progress lines)");
    cmd->footer("Each scene is a voxel size and a stroke script; the checks are listed in src/selftest/SceneChecks.h.\n"
                "It stops at the first failing scene and prints it as a bug report with the commands that replay it.\n"
                "Exit code 1 when a scene fails.");
    return cmd;
}

int runSelftest(const SelftestOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    std::size_t triangles = 0, failures = 0;
    std::optional<std::pair<RandomScene, SceneCheckResult>> firstFailure;
    for (uint64_t i = o.first; i < o.first + o.scenes; ++i) {
        const RandomScene scene = randomScene(o.seed, i);
        const SceneCheckResult result = checkScene(scene);
        triangles += result.triangles;
        const uint64_t done = i - o.first + 1;
        if (!o.json && (done % 25 == 0 || !result.passed))
            std::cerr << "selftest: " << done << '/' << o.scenes << " scenes, " << formatSeconds(secondsSince(start))
                      << std::endl;
        if (result.passed) continue;
        ++failures;
        if (o.keepGoing && !o.json) std::cerr << "selftest: scene " << i << " failed: " << result.failure << std::endl;
        if (!firstFailure) firstFailure.emplace(scene, result);
        if (!o.keepGoing) break;
    }
    if (firstFailure) {
        const auto& [scene, result] = *firstFailure;
        if (!o.failurePath.empty()) {
            std::ofstream out(o.failurePath);
            out << nlohmann::json::parse(scene.script).dump(2) << '\n';
            if (!out) throw std::runtime_error("cannot write '" + o.failurePath + "'");
        }
        if (o.json) {
            printJson({{"passed", false}, {"failures", failures}, {"report", nlohmann::json::parse(sceneReport(scene, result))}});
        } else {
            std::cout << "selftest: " << failures << " failing scene(s); the first, scene " << scene.index << " of seed "
                      << o.seed << ": " << result.failure << '\n'
                      << sceneReport(scene, result) << '\n';
        }
        return kExitFailure;
    }
    const double seconds = secondsSince(start);
    if (o.json) {
        printJson({{"passed", true}, {"scenes_checked", o.scenes}, {"seed", o.seed}, {"triangles", triangles}, {"seconds", seconds}});
    } else {
        printFields({{"passed", std::to_string(o.scenes) + " scenes (seed " + std::to_string(o.seed) + ", from " +
                                    std::to_string(o.first) + ")"},
                     {"triangles", std::to_string(triangles)},
                     {"time", formatSeconds(seconds)}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
