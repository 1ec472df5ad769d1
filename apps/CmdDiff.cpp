// vdbclay diff: the regression check between two scenes in either form. Exit 0 when identical or within
// the tolerance, 1 when they differ, 2 on bad use (as diff(1) and cmp(1) do).
#include "Cli.h"

#include "scene/SceneDiff.h"

#include <CLI/CLI.hpp>

#include <cmath>

namespace vdbclay::cli {

CLI::App* addDiffCommand(CLI::App& parent, DiffOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("diff", "Compare two scenes (.vdb or .vdbclay): exit 0 same, 1 different, 2 trouble");
    cmd->add_option("a", o.a, "First scene")->required()->check(sceneInput())->type_name("A");
    cmd->add_option("b", o.b, "Second scene")->required()->check(sceneInput())->type_name("B");
    cmd->add_option("--tolerance", o.tolerance,
                    "Accept surfaces within this many voxels of each other (two-sided Hausdorff distance), where "
                    "every voxel solid in both holds the same material")
        ->type_name("VOXELS")
        ->check(nonNegativeNumber());
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout: the differing bricks, the volume and the surface "
                                    "distance of the difference");
    return cmd;
}

int runDiff(const DiffOptions& o)
{
    SceneDiff diff;
    try {
        diff = diffScenes(o.a, o.b, o.json || o.tolerance.has_value());
    } catch (const std::exception& e) {
        printError(e.what());
        return kExitUsage;
    }
    const bool same = diff.identical();
    const bool accepted = o.tolerance ? diff.withinTolerance(*o.tolerance) : same;
    const double distanceVoxels = diff.surfaceDistance / diff.voxelSize;
    if (o.json) {
        nlohmann::json bricks = nlohmann::json::array();
        for (const auto& c : diff.differingBricks) bricks.push_back(c);
        nlohmann::json out{{"identical", same},
                           {"accepted", accepted},
                           {"voxel_sizes_differ", diff.voxelSizesDiffer},
                           {"materials_differ", diff.materialTablesDiffer},
                           {"differing_bricks", bricks},
                           {"brick_edge_voxels", 64},
                           {"occupancy_differences", diff.occupancyDifferences},
                           {"material_differences", diff.materialDifferences},
                           {"sample_differences", diff.sampleDifferences},
                           {"difference_volume", diff.differenceVolume},
                           {"surface_distance", std::isfinite(diff.surfaceDistance) ? nlohmann::json(diff.surfaceDistance) : nlohmann::json()},
                           {"surface_distance_voxels", std::isfinite(distanceVoxels) ? nlohmann::json(distanceVoxels) : nlohmann::json()}};
        if (o.tolerance) out["tolerance_voxels"] = *o.tolerance;
        if (diff.voxelSizesDiffer) out["voxel_sizes"] = {diff.voxelSize, diff.otherVoxelSize};
        printJson(out);
    } else if (same) {
        printFields({{"identical", o.a + " = " + o.b}}, 0);
    } else {
        std::vector<std::pair<std::string, std::string>> rows{{accepted ? "within tolerance" : "differ", o.a + " vs " + o.b}};
        if (diff.voxelSizesDiffer) {
            // Other lattices: neither voxels nor bricks correspond, so there is nothing more to count.
            rows.push_back({"voxel size", formatNumber(diff.voxelSize) + " vs " + formatNumber(diff.otherVoxelSize) +
                                              " (other lattices: voxels and surfaces are not compared)"});
            printFields(rows, 0);
            return kExitFailure;
        }
        if (diff.materialTablesDiffer) rows.push_back({"materials", "the tables differ"});
        rows.push_back({"bricks", std::to_string(diff.differingBricks.size()) + " differ"});
        rows.push_back({"voxels", std::to_string(diff.occupancyDifferences) + " solid/empty, " +
                                      std::to_string(diff.materialDifferences) + " of another material, " +
                                      std::to_string(diff.sampleDifferences) + " edges with other samples"});
        if (o.tolerance) rows.push_back({"surface distance", formatNumber(distanceVoxels) + " voxels"});
        printFields(rows, 0);
    }
    return accepted ? kExitOk : kExitFailure;
}

} // namespace vdbclay::cli
