// vdbclay synth: large synthetic scenes generated straight into a store.
#include "Cli.h"

#include "scene/Synthesize.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>

namespace vdbclay::cli {

CLI::App* addSynthCommand(CLI::App& parent, SynthCommandOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("synth", "Generate a synthetic scene straight into a store (brick by brick)");
    cmd->add_option("kind", o.kind, "terrain, asteroids or csg-stack")->required()->type_name("KIND");
    cmd->add_option("--extent", o.extent, "Voxels along the scene's longest side")->capture_default_str()->type_name("N");
    cmd->add_option("--seed", o.seed, "Seed: the same seed gives the same scene, whatever the thread count")
        ->capture_default_str()
        ->check(unsignedInteger())
        ->type_name("S");
    cmd->add_option("--voxel-size", o.voxelSize, "World size of a voxel")->capture_default_str()->type_name("V");
    cmd->add_option("-o,--output", o.output, "Store to write (.vdbclay); replaced only once complete")
        ->required()
        ->type_name("SCENE.vdbclay");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text (no progress bar)");
    cmd->footer("terrain    a noise-displaced height field with tunnels carved under it (overhangs), rock, grass and snow\n"
                "asteroids  noise-displaced blobs of rock, ice and iron\n"
                "csg-stack  towers of boxes, cylinders and spheres on the voxel lattice, touching and coplanar, with bores");
    return cmd;
}

int runSynth(const SynthCommandOptions& o)
{
    SynthOptions options;
    try {
        options.kind = parseSynthKind(o.kind);
        options.extent = o.extent;
        options.seed = o.seed;
        options.voxelSize = o.voxelSize;
        validateSynthOptions(options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    }
    if (!isStorePath(o.output)) throw UsageError("synth writes a store: the output must end in .vdbclay");
    checkOutput(o.output, OutputForm::Store);
    const auto start = std::chrono::steady_clock::now();
    const SynthReport report = synthesizeStore(options, o.output, terminalProgress("generating bricks", !o.json));
    const double seconds = secondsSince(start);
    const double voxels = double(report.bricksVisited) * double(kBrickEdge) * kBrickEdge * kBrickEdge;
    if (o.json) {
        printJson({{"output", o.output},
                   {"kind", synthKindName(options.kind)},
                   {"extent", options.extent},
                   {"seed", options.seed},
                   {"bricks", report.bricks},
                   {"bricks_visited", report.bricksVisited},
                   {"leaves", report.leaves},
                   {"payload_bytes", report.bytes},
                   {"file_bytes", std::filesystem::file_size(o.output)},
                   {"seconds", seconds},
                   {"voxels_per_second", voxels / seconds}});
    } else {
        printFields({{"generated", std::string(synthKindName(options.kind)) + " -> " + o.output},
                     {"bricks", std::to_string(report.bricks) + " stored of " + std::to_string(report.bricksVisited) + " visited"},
                     {"leaves", std::to_string(report.leaves)},
                     {"size", formatBytes(double(std::filesystem::file_size(o.output)))},
                     {"time", formatSeconds(seconds) + " (" + formatBytes(double(report.bytes) / seconds) + "/s of payload)"}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
