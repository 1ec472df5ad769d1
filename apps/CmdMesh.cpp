// vdbclay mesh: extract a triangle mesh from a volume and write it as OBJ or PLY.
#include "Cli.h"

#include "mesher/MeshIO.h"
#include "mesher/MeshMetrics.h"
#include "mesher/LodMesh.h"
#include "mesher/Mesher.h"
#include "scene/SceneStore.h"
#include "vdb_hermite/VolumeIO.h"
#include "wavelet/LodPyramid.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <iostream>

namespace vdbclay::cli {

CLI::App* addMeshCommand(CLI::App& parent, MeshCommandOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("mesh", "Extract a triangle mesh from a volume (OBJ, PLY or glTF binary)");
    cmd->add_option("input", o.input, "Scene to mesh: a volume (.vdb) or a store (.vdbclay)")
        ->required()
        ->check(sceneInput())
        ->type_name("IN.vdb|IN.vdbclay");
    cmd->add_option("-o,--output", o.output, "Mesh file to write; the extension picks the format (.obj with its .mtl beside it, .ply or .glb)")
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
    cmd->add_option("--plane-tolerance", o.planeTolerance,
                    "Adaptive CMS: a cell whose normals span wider still stays whole where its crossings lie within "
                    "this many voxels of one plane (default 0: the angle alone decides; streaming scenes use 0.25, "
                    "coarse levels 0.5)")
        ->type_name("VOXELS");
    cmd->add_flag("--uniform", o.uniform,
                  "CMS: mesh every voxel cell instead of adaptive cells (up to 8 voxels wide on flat surface)");
    cmd->add_option("--lod", o.lod,
                    "Mesh level of detail K (voxels 2^K times larger): a store's built level ('vdbclay lod build'), "
                    "or for a .vdb a pyramid built on the fly")
        ->type_name("K")
        ->check(CLI::Range(0, wavelet::kMaxLodLevels));
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
    if (!cms && (o.angleDegrees || o.subdivisionAngleDegrees || o.planeTolerance || o.uniform))
        throw UsageError("--angle, --adapt-angle, --plane-tolerance and --uniform apply to --mesher cms only");
    if (o.uniform && (o.subdivisionAngleDegrees || o.planeTolerance))
        throw UsageError("--adapt-angle and --plane-tolerance apply to adaptive cells, not --uniform");
    options.sharpAngleDegrees = o.angleDegrees.value_or(options.sharpAngleDegrees);
    options.subdivisionAngleDegrees = o.subdivisionAngleDegrees.value_or(options.subdivisionAngleDegrees);
    options.planeTolerance = o.planeTolerance.value_or(options.planeTolerance);
    options.maxCellWidth = o.uniform ? 1 : 8;
    try {
        validateMeshOptions(options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    }
    checkOutput(o.output, meshFormOf(o.output), {o.input});

    const auto start = std::chrono::steady_clock::now();
    const int level = o.lod.value_or(0);
    Mesh mesh;
    MaterialTable materials;
    double voxelSize = 1.0;
    if (isStorePath(o.input)) {
        const SceneStore scene = SceneStore::open(o.input, StoreAccess::ReadOnly);
        if (level > scene.lodLevels())
            throw UsageError("'" + o.input + "' has " + std::to_string(scene.lodLevels()) + " coarse levels; run 'vdbclay lod build " +
                             o.input + "' (with --levels " + std::to_string(level) + " or more)");
        if (level > 0 && scene.lodStale())
            std::cerr << "vdbclay: warning: the levels of detail predate the last edit; 'vdbclay lod build' refreshes them\n";
        const Volume volume = scene.loadLevel(level);
        mesh = meshVolume(volume, options); // a level's surface lies in place
        materials = scene.materials();
        voxelSize = volume.voxelSize();
    } else {
        const Volume volume = loadScene(o.input);
        if (level == 0) {
            mesh = meshVolume(volume, options);
        } else {
            wavelet::LodPyramid pyramid(std::max(level, wavelet::LodPyramid::levelsFor(volume)));
            pyramid.build(volume);
            mesh = meshLevel(volume, pyramid, level, options);
        }
        materials = volume.materials();
        voxelSize = volume.voxelSize() * double(1 << level);
    }
    const MeshTopology topology = analyzeTopology(mesh, kMergeDistanceVoxels * voxelSize);
    writeMesh(mesh, materials, o.output);
    const double seconds = secondsSince(start);

    if (o.json) {
        printJson({{"output", o.output},
                   {"mesher", mesherName(options.kind)},
                   {"cells", cellsName(options)},
                   {"lod", level},
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
