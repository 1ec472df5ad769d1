// vdbclay info: what a volume file holds.
#include "Cli.h"

#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

namespace vdbclay::cli {

namespace {

std::string coordText(const std::array<int32_t, 3>& c)
{
    return "(" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + ")";
}

} // namespace

CLI::App* addInfoCommand(CLI::App& parent, InfoOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("info", "Describe a volume file");
    cmd->add_option("input", o.input, "Volume file (.vdb)")->required()->type_name("IN.vdb");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("bbox_min/bbox_max are index-space voxel coordinates of the solid and surface voxels\n"
                "(both (0, 0, 0) for an empty volume); memory_bytes is the in-memory size of the tree.");
    return cmd;
}

int runInfo(const InfoOptions& o)
{
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
                 {"format_version", std::to_string(volume.formatVersion())}},
                0);
    return kExitOk;
}

} // namespace vdbclay::cli
