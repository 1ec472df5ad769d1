// vdbclay selftest: seeded random scenes through every differential check (src/selftest/SceneChecks.h).
#include "Cli.h"

#include "selftest/SceneChecks.h"
#include "vdb_hermite/AtomicFile.h"

#include <CLI/CLI.hpp>

#include <fstream>
#include <optional>
#include <vector>
#include <iostream>

namespace vdbclay::cli {

CLI::App* addSelftestCommand(CLI::App& parent, SelftestOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("selftest", "Check random scenes: lattice, meshes, volume, re-meshing, threads");
    cmd->add_option("--scenes", o.scenes, "Number of random scenes")->check(CLI::Range(1, 100000000));
    cmd->add_option("--seed", o.seed, "Seed of the scene sequence (scene i of seed s is always the same)")->check(unsignedInteger());
    cmd->add_option("--first", o.first, "Index of the first scene")->check(unsignedInteger());
    cmd->add_option("--save-failure", o.failurePath,
                    "Write the first failing scene's stroke script here (replay it with 'vdbclay sculpt')")
        ->type_name("SCRIPT.json");
    cmd->add_flag("--sweep", o.sweep,
                  "Instead of random scenes, every primitive of 'vdbclay new' at sizes --from .. --to voxels in --step steps");
    cmd->add_option("--from", o.sweepFrom, "First size of --sweep (voxels)")->capture_default_str();
    cmd->add_option("--to", o.sweepTo, "Last size of --sweep (voxels)")->capture_default_str();
    cmd->add_option("--step", o.sweepStep, "Step of --sweep (voxels)")->capture_default_str()->check(positiveNumber());
    cmd->add_flag("--keep-going", o.keepGoing, "Check every scene, printing one line per failure, instead of stopping at the first");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text (no progress lines)");
    cmd->footer("Each scene is a voxel size and a stroke script; the checks are listed in src/selftest/SceneChecks.h.\n"
                "It stops at the first failing scene and prints it as a bug report with the commands that replay it.\n"
                "Exit code 1 when a scene fails.");
    return cmd;
}

int runSelftest(const SelftestOptions& o)
{
    if (!o.failurePath.empty()) checkOutput(o.failurePath, OutputForm::Json);
    const auto start = std::chrono::steady_clock::now();
    std::vector<RandomScene> sweep;
    SceneCheckOptions checks;
    if (o.sweep) {
        if (!(o.sweepFrom > 0.0 && o.sweepTo >= o.sweepFrom && o.sweepTo <= 1000.0))
            throw UsageError("--from and --to must satisfy 0 < from <= to <= 1000");
        for (const char* shape : {"sphere", "box", "cylinder", "capsule", "torus", "cone"})
            for (double size = o.sweepFrom; size <= o.sweepTo + 1e-9; size += o.sweepStep)
                sweep.push_back(primitiveScene(shape, size, 1.0, sweep.size()));
        checks.checkLattice = false; // one primitive: the random scenes cover the lattice
        checks.compareThreads = false;
    }
    const uint64_t count = o.sweep ? sweep.size() : o.scenes, first = o.sweep ? 0 : o.first;
    std::size_t triangles = 0, failures = 0;
    std::optional<std::pair<RandomScene, SceneCheckResult>> firstFailure;
    for (uint64_t i = first; i < first + count; ++i) {
        const RandomScene scene = o.sweep ? sweep[i] : randomScene(o.seed, i);
        const SceneCheckResult result = checkScene(scene, checks);
        triangles += result.triangles;
        const uint64_t done = i - first + 1;
        if (!o.json && (done % 25 == 0 || !result.passed))
            std::cerr << "selftest: " << done << '/' << count << " scenes, " << formatSeconds(secondsSince(start))
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
            const std::string text = nlohmann::json::parse(scene.script).dump(2) + "\n";
            writeFileAtomically(o.failurePath, [&](std::ostream& out) { out << text; });
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
        printJson({{"passed", true}, {"scenes_checked", count}, {"seed", o.seed}, {"sweep", o.sweep}, {"triangles", triangles},
                   {"seconds", seconds}});
    } else {
        printFields({{"passed", std::to_string(count) + (o.sweep ? " primitives of the sweep" : " scenes (seed " +
                                    std::to_string(o.seed) + ", from " + std::to_string(o.first) + ")")},
                     {"triangles", std::to_string(triangles)},
                     {"time", formatSeconds(seconds)}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
