// vdbclay bench: the benchmarks of bench/ (ours next to the OpenVDB baseline, same data, same run).
#include "Cli.h"

#include "Bench.h"

#include <CLI/CLI.hpp>

namespace vdbclay::cli {

CLI::App* addBenchCommand(CLI::App& parent, BenchCommandOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("bench", "Benchmark against OpenVDB's level-set baseline");
    std::string names;
    for (const auto& n : bench::benchNames()) names += (names.empty() ? "" : ", ") + n;
    cmd->add_option("name", o.which, "Which benchmark: " + names)->required()->type_name("NAME");
    cmd->add_option("dir", o.dir, "retrieval: a folder of models, one subfolder per class (default: the synthetic labeled set)")
        ->type_name("DIR")
        ->check(CLI::ExistingDirectory);
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of a table");
    cmd->add_flag("--quick", o.quick, "Small sizes (seconds, for CI); the default runs the full sizes");
    cmd->add_option("--memory-budget", o.memoryBudgetMb, "stream, render, editor and vr: the memory budget (stream: 192, or 2 with --quick; render, editor and vr: 384)")
        ->type_name("MB")
        ->check(memoryBudget());
    cmd->add_option("--extent", o.extents, "render: the terrain extents to run (default 1024 4096, or 512 768 with --quick)")
        ->type_name("VOXELS")
        ->check(CLI::Range(64, 16384));
    cmd->footer("csg     sphere creation, then median time of remove-sphere stamps on its surface\n"
                "        vs createLevelSetSphere + csgDifference on a FloatGrid level set\n"
                "memory  bytes per surface voxel of a sphere and a box vs a narrow-band level set\n"
                "io      save/load time and file size vs a Blosc-compressed FloatGrid level set\n"
                "mesh    uniform CMS and MC meshing time, triangles and distance to the exact surface of\n"
                "        sharp and thin shapes vs tools::volumeToMesh (adaptivity 0 and 0.5) on level sets\n"
                "wavelet integer Haar build and level-0 extraction of 128^3, 256^3, 512^3 cubes vs seed 001\n"
                "        Table 1 and this machine's copy bandwidth; the sparse pyramid vs tools::MultiResGrid\n"
                "stream  a terrain store 4x the memory budget, flown over at 90 Hz with strokes: peak RSS, time to\n"
                "        coarse and refined views, stroke latency, read rate vs the disk, bytes per voxel^2 of surface\n"
                "import  fandisk.obj and rocker-arm.obj voxelized at 256 voxels and meshed by CMS vs meshToLevelSet +\n"
                "        volumeToMesh: time, triangles, mean and Hausdorff distance to the input (VDBCLAY_MODELS: their folder)\n"
                "tool    rotated 8^3 .. 128^3 box tools stamped onto a slab vs the analytic box brush and vs\n"
                "        GridTransformer resampling + csgUnion of the tool's level set\n"
                "render  terrains of extent 1024 and 4096 streamed for 1080p views: triangles of a complete view, CPU\n"
                "        per frame of a 90 Hz flight, uploads, GPU time, an r=32 stamp to its chunks uploaded vs volumeToMesh\n"
                "editor  a stroke-heavy session (r=32 strokes of every mode, mirrored) replayed frame by frame on a terrain\n"
                "        of extent 1024 (512 with --quick): CPU frame p50/p99, edit-to-visible frames, triangles, uploads,\n"
                "        resident memory vs the budget, the rotated 64^3 tool stamp vs OpenVDB's csgUnion + volumeToMesh\n"
                "inputs  large and hostile inputs: sessions of 400,000 objects vs nlohmann's plain parse, a stroke of\n"
                "        100,000 points vs 600 and vs OpenVDB sphere stamps, a tangled 2,000-point stroke, an 8192^2\n"
                "        material picture to its mipmaps vs a full-size filter per level\n"
                "retrieval  [DIR] models of labeled classes (default: the synthetic set), each querying the others:\n"
                "        nearest neighbour, first and second tier, DCG, mAP, query time; descriptor time; k=10 over 100k\n"
                "vr      the editor session's strokes in a headset (the test build's fake OpenXR runtime at 90 Hz, two\n"
                "        512^2 eyes) on a terrain of extent 1024 (512 with --quick): CPU frame p50/p99, display refreshes\n"
                "        missed, edit-to-visible frames, pose-to-submit latency\n"
                "Build in Release for meaningful figures; docs/BENCHMARKS.md has measured tables.");
    return cmd;
}

int runBenchCommand(const BenchCommandOptions& o)
{
    bool known = false;
    for (const auto& n : bench::benchNames()) known = known || n == o.which;
    if (!known) throw UsageError("unknown benchmark '" + o.which + "' (expected csg, memory, io, mesh, wavelet, stream, import, tool, render, editor, inputs, vr or retrieval)");
    if (o.memoryBudgetMb > 0.0 && o.which != "stream" && o.which != "render" && o.which != "editor" && o.which != "vr")
        throw UsageError("--memory-budget is for 'bench stream', 'bench render', 'bench editor' and 'bench vr'");
    if (!o.extents.empty() && o.which != "render") throw UsageError("--extent is for 'bench render'");
    if (!o.dir.empty() && o.which != "retrieval") throw UsageError("a folder goes with 'bench retrieval' only");
    return bench::runBench(o.which, o.json, o.quick, o.memoryBudgetMb, o.extents, o.dir);
}

} // namespace vdbclay::cli
