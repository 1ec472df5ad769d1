// vdbclay mesh: extract a triangle mesh from a volume and write it as OBJ or PLY.
#include "Cli.h"

#include "mesher/MeshIO.h"
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <chrono>

namespace vdbclay::cli {

CLI::App* addMeshCommand(CLI::App& parent, MeshCommandOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("mesh", "Extract a triangle mesh from a volume (OBJ, PLY or glTF binary)");
    cmd->add_option("input", o.input, "Volume to mesh (.vdb)")->required()->type_name("IN.vdb");
    cmd->add_option("-o,--output", o.output, "Mesh file to write; the extension picks the format (.obj, .ply or .glb)")
        ->required()
        ->type_name("OUT.obj|OUT.ply|OUT.glb");
    cmd->add_option("--mesher", o.mesher, "cms (cubical marching squares, sharp features) or mc (marching cubes)")
        ->capture_default_str()
        ->type_name("NAME");
    const MeshOptions defaults;
    cmd->add_option("--angle", o.angleDegrees,
                    "CMS: normals spanning more than this angle make a sharp edge or corner (default " +
                        formatNumber(defaults.sharpAngleDegrees) + ")")
        ->type_name("DEG");
    cmd->add_option("--adapt-angle", o.subdivisionAngleDegrees,
                    "Adaptive CMS: a cell wider than one voxel is split while its normals span more than this "
                    "angle (default " + formatNumber(defaults.subdivisionAngleDegrees) + ")")
        ->type_name("DEG");
    cmd->add_flag("--uniform", o.uniform,
                  "CMS: mesh every voxel cell instead of adaptive cells (up to 8 voxels wide on flat surface)");
    cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    return cmd;
}

namespace {

std::string cellsName(const MeshOptions& options)
{
    if (options.kind == MesherKind::MarchingCubes || options.maxCellWidth == 1) return "uniform";
    return "adaptive";
}

} // namespace

int runMesh(const MeshCommandOptions& o)
{
    MeshOptions options;
    try {
        options.kind = parseMesherKind(o.mesher);
    } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--mesher: ") + e.what());
    }
    const bool cms = options.kind == MesherKind::CubicalMarchingSquares;
    // Options that would have no effect are refused rather than silently ignored.
    if (!cms && (o.angleDegrees || o.subdivisionAngleDegrees || o.uniform))
        throw UsageError("--angle, --adapt-angle and --uniform apply to --mesher cms only");
    if (o.uniform && o.subdivisionAngleDegrees) throw UsageError("--adapt-angle applies to adaptive cells, not --uniform");
    options.sharpAngleDegrees = o.angleDegrees.value_or(options.sharpAngleDegrees);
    options.subdivisionAngleDegrees = o.subdivisionAngleDegrees.value_or(options.subdivisionAngleDegrees);
    options.maxCellWidth = o.uniform ? 1 : 8;
    try {
        validateMeshOptions(options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    }
    requireMeshExtension(o.output, "--output");

    const auto start = std::chrono::steady_clock::now();
    const Volume volume = loadVolume(o.input);
    const Mesh mesh = meshVolume(volume, options);
    const MeshTopology topology = analyzeTopology(mesh, kMergeDistanceVoxels * volume.voxelSize());
    writeMesh(mesh, volume.materials(), o.output);
    const double seconds = secondsSince(start);

    if (o.json) {
        printJson({{"output", o.output},
                   {"mesher", mesherName(options.kind)},
                   {"cells", cellsName(options)},
                   {"vertices", mesh.vertexCount()},
                   {"triangles", mesh.triangleCount()},
                   {"watertight", topology.watertight()},
                   {"topology",
                    {{"boundary_edges", topology.boundaryEdges},
                     {"non_manifold_edges", topology.nonManifoldEdges},
                     {"misoriented_edges", topology.misorientedEdges},
                     {"degenerate_triangles", topology.degenerateTriangles},
                     {"pinched_vertices", topology.pinchedVertices},
                     {"components", topology.components}}},
                   {"seconds", seconds}});
    } else {
        std::string closed = topology.watertight() ? "yes" : "no";
        if (!topology.watertight()) {
            closed += " (" + std::to_string(topology.boundaryEdges) + " boundary, " +
                      std::to_string(topology.nonManifoldEdges) + " non-manifold, " +
                      std::to_string(topology.misorientedEdges) + " misoriented edges, " +
                      std::to_string(topology.degenerateTriangles) + " zero-area triangles, " +
                      std::to_string(topology.pinchedVertices) + " pinched vertices)";
        }
        printFields({{"meshed", o.input + " -> " + o.output},
                     {"mesher", mesherName(options.kind)},
                     {"cells", cellsName(options)},
                     {"vertices", std::to_string(mesh.vertexCount())},
                     {"triangles", std::to_string(mesh.triangleCount())},
                     {"watertight", closed},
                     {"time", formatSeconds(seconds)}},
                    0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli
