// vdbclay new: a volume holding one solid primitive.
#include "Cli.h"

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>

namespace vdbclay::cli {

namespace {

/// Largest primitive extent, in voxels, that `new` accepts (keeps a typo from eating all memory).
constexpr double kMaxExtentVoxels = 2048.0;

} // namespace

CLI::App* addNewCommand(CLI::App& parent, NewOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("new", "Create a volume holding one solid primitive");
    cmd->add_option("output", o.output, "Volume file to write (.vdb)")->required()->type_name("OUT.vdb");
    cmd->add_option("--shape", o.shape, "sphere, box, cylinder, capsule, torus or cone")
        ->required()
        ->type_name("SHAPE");
    cmd->add_option("--size", o.size, "Size S of the shape in world units (see below)")->required()->type_name("S");
    cmd->add_option("--voxel-size", o.voxelSize, "Edge length of a voxel in world units")
        ->capture_default_str()
        ->type_name("V");
    cmd->add_option("--material", o.material, "Material of the solid (default: \"default\")")
        ->type_name("NAME")
        ->check([](const std::string& name) { return name.empty() ? std::string("the name must not be empty") : ""; });
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmd->footer("What S means, per shape (world units; the shape is centred on the origin, axis along +Y):\n"
                "  sphere    radius S\n"
                "  box       half-extent S (a cube of edge 2*S)\n"
                "  cylinder  radius S, height 2*S\n"
                "  cone      base radius S, height 2*S\n"
                "  capsule   radius S, length S between the centres of its two caps\n"
                "  torus     major radius S, minor (tube) radius S/4\n"
                "S / V may be at most 2048 voxels.");
    return cmd;
}

int runNew(const NewOptions& o)
{
    Shape shape;
    try {
        shape = parseShape(o.shape);
    } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--shape: ") + e.what());
    }
    if (shape == Shape::HalfSpace) throw UsageError("--shape: a half-space is unbounded and cannot be a new volume");
    if (!(o.size > 0.0) || !std::isfinite(o.size)) throw UsageError("--size: must be a positive number");
    if (!(o.voxelSize > 0.0) || !std::isfinite(o.voxelSize)) throw UsageError("--voxel-size: must be a positive number");
    if (!(o.voxelSize >= kMinVoxelSize && o.voxelSize <= kMaxVoxelSize))
        throw UsageError("--voxel-size: " + formatNumber(o.voxelSize) + " is outside the supported range 0.0001 .. 1e+06");
    if (o.size / o.voxelSize > kMaxExtentVoxels) {
        throw UsageError("--size: " + formatNumber(o.size) + " is " + formatNumber(o.size / o.voxelSize) +
                         " voxels; at most " + formatNumber(kMaxExtentVoxels) +
                         " are allowed (raise --voxel-size)");
    }

    const auto start = std::chrono::steady_clock::now();
    Volume volume(o.voxelSize);
    CsgOp op;
    op.mode = CsgMode::Add;
    std::string materialName = "default";
    if (!o.material.empty()) {
        Material m;
        m.name = o.material;
        try {
            op.material = volume.materials().define(m);
        } catch (const std::invalid_argument& e) {
            throw UsageError(std::string("--material: ") + e.what());
        }
        materialName = o.material;
    } else {
        op.material = *volume.materials().find("default");
    }
    const Primitive primitive = primitiveOfSize(shape, o.size);
    try {
        primitive.validate();
    } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--size: ") + e.what());
    }
    checkOutput(o.output, OutputForm::NativeVolume);
    applyCsg(volume, Brush(primitive, Placement{}), op);
    saveVolume(volume, o.output);
    const double seconds = secondsSince(start);

    const VolumeStats stats = volume.stats();
    if (o.json) {
        printJson({{"output", o.output},
                   {"shape", shapeName(shape)},
                   {"size", o.size},
                   {"voxel_size", o.voxelSize},
                   {"material", materialName},
                   {"leaf_count", stats.leafCount},
                   {"active_voxels", stats.activeVoxels},
                   {"seconds", seconds}});
    } else {
        printFields({{"created", o.output},
                     {"shape", std::string(shapeName(shape)) + ", size " + formatNumber(o.size)},
                     {"voxel size", formatNumber(o.voxelSize)},
                     {"material", materialName},
                     {"leaves", std::to_string(stats.leafCount)},
                     {"active voxels", std::to_string(stats.activeVoxels)},
                     {"time", formatSeconds(seconds)}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
