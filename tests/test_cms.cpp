// Cubical Marching Squares on synthetic grids: closed meshes, error bounds against the analytic
// surface, sharp corners reproduced, and the comparison with Marching Cubes the issue asks for.
#include "mesher/MeshChunkSet.h"
#include "mesher/MeshMetrics.h"
#include "mesher/MeshQuality.h"
#include "mesher/Mesher.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeRegions.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <tuple>
#include <unordered_map>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

using Sdf = std::function<double(const Vec3d&)>;

/// Cells for CMS: one voxel each, or adaptive cells up to eight voxels wide.
enum class Cells { Uniform, Adaptive };

MeshOptions optionsFor(MesherKind kind, Cells cells = Cells::Adaptive)
{
    MeshOptions options;
    options.kind = kind;
    options.maxCellWidth = cells == Cells::Uniform ? 1 : 8;
    return options;
}

Mesh meshWith(const Volume& v, MesherKind kind, Cells cells = Cells::Adaptive)
{
    return meshVolume(v, optionsFor(kind, cells));
}

struct SurfaceError {
    double max = 0.0;  // two-sided (Hausdorff), voxels
    double mean = 0.0;
};

/// Two-sided distance between the mesh and the analytic surface, sampled every 0.25 voxel on both.
SurfaceError surfaceError(const Mesh& mesh, const Sdf& sdf)
{
    SurfaceSampling sampling;
    sampling.spacing = 0.25;
    const MeshQuality q = measureAgainstSdf(mesh, [&](const Point3d& p) { return sdf(Vec3d(p[0], p[1], p[2])); }, sampling);
    return {q.maxDistance, q.meanDistance};
}

/// The incremental set has exactly the full rebuild's leaves and chunks; names the first leaf that differs.
void requireSameChunks(const MeshChunkSet& incremental, const MeshChunkSet& full)
{
    REQUIRE(incremental.chunks().size() == full.chunks().size());
    for (const auto& [origin, chunk] : full.chunks()) {
        INFO("leaf at " << origin[0] << "," << origin[1] << "," << origin[2]);
        const auto it = incremental.chunks().find(origin);
        REQUIRE(it != incremental.chunks().end());
        REQUIRE(identical(it->second, chunk));
    }
    CHECK(identical(incremental, full)); // and the library's comparison agrees
}

void requireClosed(const Mesh& mesh)
{
    const MeshTopology topo = analyzeTopology(mesh, kMergeDistanceVoxels); // every volume here has 1-unit voxels
    INFO("boundary " << topo.boundaryEdges << ", non-manifold " << topo.nonManifoldEdges << ", misoriented "
                     << topo.misorientedEdges << ", degenerate " << topo.degenerateTriangles << ", pinched "
                     << topo.pinchedVertices);
    REQUIRE(mesh.triangleCount() > 0);
    REQUIRE(topo.watertight());
    REQUIRE(topo.degenerateTriangles == 0);
    REQUIRE(mesh.triangleMaterials.size() == mesh.triangleCount());
}

} // namespace

TEST_CASE("CMS meshes of sculpted shapes are closed and lie on the analytic surface", "[cms]")
{
    struct Case {
        const char* name;
        std::function<void(Volume&)> build;
        Sdf sdf;
        double maxError;         // voxels (voxel size 1), uniform cells
        double maxAdaptiveError; // adaptive cells (a cell may span 15 degrees of a curved surface)
    };
    const Brush axisBox(box(Vec3d(9.3, 6.2, 5.4)), at(Vec3d(0.25, 0.4, -0.3)));
    const Brush rotatedBox(box(Vec3d(10.3, 7.2, 5.6)), at(Vec3d(0.3, 0.2, 0.1), Vec3d(20, 35, 10)));
    const Brush ball(sphere(14.0), at(Vec3d(0.2, -0.3, 0.1)));
    const Brush cube(box(Vec3d(12.0)), at(Vec3d(0.5)));
    const Brush bite(sphere(8.0), at(Vec3d(12.5)));
    const std::vector<Case> cases = {
        {"axis-aligned box", [&](Volume& v) { applyCsg(v, axisBox, op(CsgMode::Add)); },
         [&](const Vec3d& p) { return axisBox.distance(p); }, 0.02, 0.02},
        {"rotated box", [&](Volume& v) { applyCsg(v, rotatedBox, op(CsgMode::Add)); },
         // Face segments follow sub-voxel wedges along edges nearly parallel to a grid plane (see the
         // next test); without that the maximum is about 0.45.
         [&](const Vec3d& p) { return rotatedBox.distance(p); }, 0.3, 0.3},
        {"sphere", [&](Volume& v) { applyCsg(v, ball, op(CsgMode::Add)); },
         [&](const Vec3d& p) { return ball.distance(p); }, 0.05, 0.15},
        {"box minus sphere",
         [&](Volume& v) {
             applyCsg(v, cube, op(CsgMode::Add));
             applyCsg(v, bite, op(CsgMode::Remove));
         },
         [&](const Vec3d& p) { return std::max(cube.distance(p), -bite.distance(p)); }, 0.1, 0.15},
    };
    for (const Case& c : cases) {
        SECTION(c.name)
        {
            Volume v(1.0);
            c.build(v);
            REQUIRE(checkInvariants(v) == "");
            for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
                const Mesh mesh = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
                requireClosed(mesh);
                const SurfaceError error = surfaceError(mesh, c.sdf);
                INFO((cells == Cells::Uniform ? "uniform" : "adaptive") << " distance to the surface: max " << error.max
                                                                        << ", mean " << error.mean << " voxels");
                CHECK(error.max <= (cells == Cells::Uniform ? c.maxError : c.maxAdaptiveError));
            }
        }
    }
}

TEST_CASE("CMS reproduces a rotated box's corners and edges better than Marching Cubes", "[cms]")
{
    const Vec3d half(10.3, 7.2, 5.6), rotation(20, 35, 10), centre(0.3, 0.2, 0.1);
    const Brush rotatedBox(box(half), at(centre, rotation));
    Volume v(1.0);
    applyCsg(v, rotatedBox, op(CsgMode::Add));
    const Cells cells = GENERATE(Cells::Uniform, Cells::Adaptive);
    const Mesh cms = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
    const Mesh mc = meshWith(v, MesherKind::MarchingCubes);
    requireClosed(cms);

    const Sdf sdf = [&](const Vec3d& p) { return rotatedBox.distance(p); };
    const SurfaceError cmsError = surfaceError(cms, sdf);
    const SurfaceError mcError = surfaceError(mc, sdf);
    INFO("error: CMS max " << cmsError.max << " mean " << cmsError.mean << ", MC max " << mcError.max << " mean "
                           << mcError.mean);
    CHECK(cmsError.mean * 3.0 <= mcError.mean);
    // Seed 000's figure: about a third of other methods' maximum error. It holds because a face segment
    // follows a box edge's wedge out through a side of its square whose voxel edge the wedge crosses
    // twice (tipChain); without that the maximum is about 0.45 voxel here.
    CHECK(cmsError.max * 3.0 <= mcError.max);

    // Corners: CMS puts a vertex on nearly every one (a corner tip that pokes into a cell seeing only two
    // of its faces is found from the crossings around the cell, but a tip that pokes into a cell between
    // its edges leaves no crossing at all); Marching Cubes on none (it cuts corners).
    const double r = 3.14159265358979323846 / 180.0;
    const double cx = std::cos(rotation.x() * r), sx = std::sin(rotation.x() * r);
    const double cy = std::cos(rotation.y() * r), sy = std::sin(rotation.y() * r);
    const double cz = std::cos(rotation.z() * r), sz = std::sin(rotation.z() * r);
    const Mat3d rot = Mat3d(cz, -sz, 0.0, sz, cz, 0.0, 0.0, 0.0, 1.0) * Mat3d(cy, 0.0, sy, 0.0, 1.0, 0.0, -sy, 0.0, cy) *
                      Mat3d(1.0, 0.0, 0.0, 0.0, cx, -sx, 0.0, sx, cx);
    auto nearest = [](const Mesh& m, const Vec3d& q) {
        double best = 1e300;
        for (const auto& p : m.positions) best = std::min(best, (Vec3d(p[0], p[1], p[2]) - q).length());
        return best;
    };
    int reproduced = 0;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d local((corner & 1) ? half.x() : -half.x(), (corner & 2) ? half.y() : -half.y(),
                          (corner & 4) ? half.z() : -half.z());
        const Vec3d world = rot * local + centre;
        INFO("corner " << corner << " at " << world);
        if (nearest(cms, world) < 0.15) ++reproduced;
        CHECK(nearest(mc, world) > 0.3);
    }
    CHECK(reproduced >= 7);
}

TEST_CASE("CMS keeps a thin wall between two removed spheres closed", "[cms]")
{
    // Seed 000 Fig 12: two spheres carved out next to each other leave a wall thinner than a voxel in
    // places; the mesh must stay closed and manifold.
    Volume v(1.0);
    apply(v, CsgMode::Add, box(Vec3d(14.0)), at(Vec3d(0.2)));
    apply(v, CsgMode::Remove, sphere(7.0), at(Vec3d(-7.6, 0.3, 14.0)));
    apply(v, CsgMode::Remove, sphere(7.0), at(Vec3d(7.1, 0.3, 14.0)));
    REQUIRE(checkInvariants(v) == "");
    requireClosed(meshWith(v, MesherKind::CubicalMarchingSquares, Cells::Uniform));
    requireClosed(meshWith(v, MesherKind::CubicalMarchingSquares, Cells::Adaptive));
}

TEST_CASE("CMS carries materials per triangle across a material boundary", "[cms]")
{
    Volume v(1.0);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f);
    const MaterialId moss = defineMaterial(v, "moss", 0.2f);
    apply(v, CsgMode::Add, sphere(12.0), at(Vec3d(0.3)), stone);
    apply(v, CsgMode::Paint, box(Vec3d(50.0)), at(Vec3d(0.0, 0.0, 50.3)), moss); // the top half becomes moss
    const Cells cells = GENERATE(Cells::Uniform, Cells::Adaptive);
    const Mesh mesh = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
    requireClosed(mesh);
    // Material transitions split the face segments where the interface plane z = 0.3 meets them, and
    // the interface joins each cell's vertex solve, so vertices line the boundary. A crossing keeps the
    // material of its solid voxel (an edge holds one sample), so a triangle may reach up to a voxel
    // past the boundary, never more.
    constexpr double kBoundary = 0.3;
    // Each piece of a segment carries the material of its side of the interface, so a triangle's
    // centroid lies on its material's side.
    std::size_t stoneTriangles = 0, mossTriangles = 0, boundaryVertices = 0;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
        double zMin = 1e300, zMax = -1e300, zCentroid = 0.0;
        for (uint32_t i : mesh.triangles[t]) {
            zMin = std::min(zMin, double(mesh.positions[i][2]));
            zMax = std::max(zMax, double(mesh.positions[i][2]));
            zCentroid += mesh.positions[i][2] / 3.0;
        }
        if (mesh.triangleMaterials[t] == stone) {
            ++stoneTriangles;
            CHECK(zMax < kBoundary + 1.0);
            CHECK(zCentroid < kBoundary);
        } else {
            REQUIRE(mesh.triangleMaterials[t] == moss);
            ++mossTriangles;
            CHECK(zMin > kBoundary - 1.0);
            CHECK(zCentroid > kBoundary);
        }
    }
    for (const auto& p : mesh.positions) boundaryVertices += std::fabs(p[2] - kBoundary) < 0.01;
    CHECK(stoneTriangles > 100);
    CHECK(mossTriangles > 100);
    INFO(boundaryVertices << " vertices on the boundary plane");
    CHECK(boundaryVertices > 50); // the boundary circle is about 75 voxels long
}

TEST_CASE("welding keeps the chunks' vertices in order, each shared key once at its first holder", "[cms][weld]")
{
    // weldChunks matches only keys on a leaf's border (an edge or face inside a leaf is met by that
    // leaf's cells alone) and works in parallel shards; a plain serial weld over every key is the reference.
    auto referenceWeld = [](const std::vector<MeshChunk>& chunks) {
        Mesh out;
        std::unordered_map<uint64_t, uint32_t> index;
        for (const MeshChunk& c : chunks) {
            std::vector<uint32_t> remap(c.mesh.vertexCount());
            for (std::size_t v = 0; v < remap.size(); ++v) {
                const uint32_t next = uint32_t(out.positions.size());
                const uint64_t key = c.vertexKeys[v];
                const bool fresh = key == kUnsharedVertex || index.emplace(key, next).second;
                remap[v] = fresh ? next : index.at(key);
                if (!fresh) continue;
                out.positions.push_back(c.mesh.positions[v]);
                out.normals.push_back(c.mesh.normals[v]);
                out.materials.push_back(c.mesh.materials[v]);
            }
            for (const auto& t : c.mesh.triangles) out.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
            out.triangleMaterials.insert(out.triangleMaterials.end(), c.mesh.triangleMaterials.begin(), c.mesh.triangleMaterials.end());
        }
        return out;
    };
    Volume v(1.0);
    applyCsg(v, Brush(box(Vec3d(14.0)), at(Vec3d(0.4, 0.3, 0.2), Vec3d(10, 20, 5))), op(CsgMode::Add));
    applyCsg(v, Brush(sphere(9.0), at(Vec3d(-14.0, 3.0, 12.0))), op(CsgMode::Remove));
    applyCsg(v, Brush(sphere(6.0), at(Vec3d(14.0, -10.0, 0.0))), op(CsgMode::Add));
    MeshOptions depths = optionsFor(MesherKind::CubicalMarchingSquares, Cells::Adaptive);
    depths.leafMaxCellWidth = [](const std::array<int32_t, 3>& origin) {
        return 1 << ((((origin[0] + origin[1] + origin[2]) / kLeafDim) % 4 + 4) % 4);
    };
    const std::vector<std::pair<const char*, MeshOptions>> meshers = {
        {"mc", optionsFor(MesherKind::MarchingCubes)},
        {"cms uniform", optionsFor(MesherKind::CubicalMarchingSquares, Cells::Uniform)},
        {"cms adaptive", optionsFor(MesherKind::CubicalMarchingSquares, Cells::Adaptive)},
        {"cms at mixed depths", depths},
    };
    for (const auto& [name, options] : meshers) {
        INFO(name);
        const std::vector<MeshChunk> chunks = meshVolumeChunks(v, options);
        const Mesh expected = referenceWeld(chunks), welded = weldChunks(chunks);
        REQUIRE(welded.vertexCount() == expected.vertexCount());
        CHECK(welded.vertexCount() < std::accumulate(chunks.begin(), chunks.end(), std::size_t(0), [](std::size_t n, const MeshChunk& c) {
                  return n + c.mesh.vertexCount();
              })); // chunks do share vertices
        CHECK(welded.positions == expected.positions);
        CHECK(welded.normals == expected.normals);
        CHECK(welded.materials == expected.materials);
        CHECK(welded.triangles == expected.triangles);
        CHECK(welded.triangleMaterials == expected.triangleMaterials);
    }
}

TEST_CASE("re-meshing the leaves an edit touched gives exactly the full re-mesh", "[cms][incremental]")
{
    Volume v(1.0);
    const MaterialId moss = defineMaterial(v, "moss", 0.2f);
    apply(v, CsgMode::Add, sphere(18.0), at(Vec3d(0.3)));
    const MeshOptions options = optionsFor(MesherKind::CubicalMarchingSquares, GENERATE(Cells::Uniform, Cells::Adaptive));
    MeshChunkSet incremental(options);
    incremental.rebuild(v);

    const EditStats edits[] = {
        apply(v, CsgMode::Remove, sphere(6.0), at(Vec3d(17.0, 2.0, 1.0))),
        apply(v, CsgMode::Paint, sphere(7.0), at(Vec3d(-5.0, 15.0, 4.0)), moss),
        apply(v, CsgMode::Add, box(Vec3d(4.0, 4.0, 9.0)), at(Vec3d(0.0, -18.0, 0.0), Vec3d(0, 0, 30))),
        apply(v, CsgMode::Remove, box(Vec3d(40.0)), at(Vec3d(0.0, 0.0, 44.5))), // slices the top off
    };
    std::size_t remeshed = 0;
    for (const EditStats& e : edits) remeshed += incremental.update(v, e.blockChanges);

    MeshChunkSet full(options);
    full.rebuild(v);
    REQUIRE(remeshed > 0);
    requireSameChunks(incremental, full);
    requireClosed(incremental.weld());
}

TEST_CASE("small edits at leaf borders re-mesh only the leaves that read what changed, and still give the full re-mesh", "[cms][incremental]")
{
    // Brushes of a voxel or two change only part of a block: the leaves beside it are re-meshed only if
    // they read a changed voxel. Sharp boxes put scans for sharp features next to the changes.
    Volume v(1.0);
    const MaterialId moss = defineMaterial(v, "moss", 0.2f);
    apply(v, CsgMode::Add, box(Vec3d(14.0, 12.0, 10.0)), at(Vec3d(0.4, 0.3, 0.2), Vec3d(10, 20, 30)));
    const MeshOptions options = optionsFor(MesherKind::CubicalMarchingSquares, GENERATE(Cells::Uniform, Cells::Adaptive));
    MeshChunkSet incremental(options), fromBlocks(options); // the second told only which blocks changed
    incremental.rebuild(v);
    fromBlocks.rebuild(v);
    std::size_t remeshed = 0, remeshedFromBlocks = 0;
    for (int i = 0; i < 16; ++i) {
        // Centres on or beside the leaf borders at multiples of 8, on the box's surface.
        const Vec3d centre(-8.0 + 8.0 * (i % 3) + 0.5 * (i % 4) - 0.7, 7.6 + 0.45 * i - 8.0 * (i % 2), 10.0 - 0.35 * (i % 5));
        const CsgMode mode = i % 3 == 0 ? CsgMode::Remove : (i % 3 == 1 ? CsgMode::Add : CsgMode::Paint);
        const Primitive shape = i % 2 ? box(Vec3d(1.2, 0.8, 1.6)) : sphere(1.3 + 0.1 * i);
        const EditStats e = apply(v, mode, shape, at(centre, Vec3d(7.0 * i, 11.0 * i, 0.0)), mode == CsgMode::Paint ? moss : 1);
        remeshed += incremental.update(v, e.blockChanges);
        remeshedFromBlocks += fromBlocks.update(v, e.dirtyBlocks);

        MeshChunkSet full(options);
        full.rebuild(v);
        INFO("after edit " << i);
        requireSameChunks(incremental, full);
        requireSameChunks(fromBlocks, full);
    }
    REQUIRE(remeshed > 0);
    CHECK(remeshed < remeshedFromBlocks);
    requireClosed(incremental.weld());
}

TEST_CASE("a change to part of a block reaches only the leaves that read it", "[cms][incremental]")
{
    // Meshing a leaf reads its voxels -2 .. 10 per axis; subdividing it (adaptive CMS) reads 0 .. 8.
    auto change = [](std::array<uint8_t, 3> lo, std::array<uint8_t, 3> hi) {
        BlockChange c;
        c.origin = {8, 16, -8};
        c.min = lo;
        c.max = hi;
        return std::vector<BlockChange>{c};
    };
    auto leaves = [](std::initializer_list<int> xs, std::initializer_list<int> ys, std::initializer_list<int> zs) {
        std::vector<std::array<int32_t, 3>> out;
        for (int x : xs)
            for (int y : ys)
                for (int z : zs) out.push_back({8 + 8 * x, 16 + 8 * y, -8 + 8 * z});
        std::sort(out.begin(), out.end());
        return out;
    };
    const MeshOptions uniform = optionsFor(MesherKind::CubicalMarchingSquares, Cells::Uniform);
    // Inside 3 .. 5 on every axis: only the block's own leaf reads it.
    CHECK(leavesAffectedBy(change({3, 3, 3}, {5, 5, 5}), uniform) == leaves({0}, {0}, {0}));
    // Voxels 0 .. 2 are read by the leaf below too, 6 .. 7 by the leaf above.
    CHECK(leavesAffectedBy(change({2, 4, 4}, {4, 4, 4}), uniform) == leaves({-1, 0}, {0}, {0}));
    CHECK(leavesAffectedBy(change({4, 4, 6}, {4, 4, 7}), uniform) == leaves({0}, {0}, {0, 1}));
    CHECK(leavesAffectedBy(change({0, 0, 0}, {7, 7, 7}), uniform) == leaves({-1, 0, 1}, {-1, 0, 1}, {-1, 0, 1}));
    // Adaptive CMS without subdividing first adds the face neighbours of the leaves whose subdivision
    // reads a changed voxel: voxels 1 .. 4 are read by the block's own leaf only (the leaf below reads
    // voxel 0), so its six face neighbours join the two leaves that mesh with them.
    const MeshOptions adaptive = optionsFor(MesherKind::CubicalMarchingSquares, Cells::Adaptive);
    std::vector<std::array<int32_t, 3>> faces = leaves({-1, 0, 1}, {0}, {0});
    for (const auto& more : {leaves({0}, {-1, 1}, {0}), leaves({0}, {0}, {-1, 1})}) faces.insert(faces.end(), more.begin(), more.end());
    std::sort(faces.begin(), faces.end());
    CHECK(leavesAffectedBy(change({1, 4, 4}, {4, 4, 4}), adaptive) == faces);
    // Voxel 0 on x is read by the subdivision of the leaf below as well, whose face neighbours join.
    std::vector<std::array<int32_t, 3>> more = faces;
    for (const auto& extra : {leaves({-2}, {0}, {0}), leaves({-1}, {-1, 1}, {0}), leaves({-1}, {0}, {-1, 1})})
        more.insert(more.end(), extra.begin(), extra.end());
    std::sort(more.begin(), more.end());
    CHECK(leavesAffectedBy(change({0, 4, 4}, {4, 4, 4}), adaptive) == more);
}

TEST_CASE("adaptive CMS covers flat faces with a quarter of uniform CMS's triangles at the same error", "[cms][adaptive]")
{
    struct Case {
        const char* name;
        Brush box;
        double maxError; // voxels: the bound both meshes must meet
    };
    const std::vector<Case> cases = {
        {"axis-aligned box", Brush(box(Vec3d(20.3, 14.3, 11.3)), at(Vec3d(0.0))), 0.02},
        // A strip of solid that crosses a square's side twice and goes on into the next square is cut
        // straight at that side (about 0.25 voxel here) in both meshes.
        {"rotated box", Brush(box(Vec3d(20.0, 14.0, 11.0)), at(Vec3d(0.0), Vec3d(20, 35, 10))), 0.3},
    };
    for (const Case& c : cases) {
        SECTION(c.name)
        {
            Volume v(1.0);
            applyCsg(v, c.box, op(CsgMode::Add));
            const Mesh uniform = meshWith(v, MesherKind::CubicalMarchingSquares, Cells::Uniform);
            const Mesh adaptive = meshWith(v, MesherKind::CubicalMarchingSquares, Cells::Adaptive);
            requireClosed(adaptive);
            const Sdf sdf = [&](const Vec3d& p) { return c.box.distance(p); };
            const SurfaceError uniformError = surfaceError(uniform, sdf), adaptiveError = surfaceError(adaptive, sdf);
            INFO("triangles: uniform " << uniform.triangleCount() << ", adaptive " << adaptive.triangleCount()
                                       << "; max error: uniform " << uniformError.max << ", adaptive "
                                       << adaptiveError.max);
            CHECK(adaptive.triangleCount() * 4 <= uniform.triangleCount());
            CHECK(uniformError.max <= c.maxError);
            CHECK(adaptiveError.max <= c.maxError);
        }
    }
}

TEST_CASE("leaves meshed at different depths stay watertight and on the surface", "[cms][adaptive]")
{
    // Seed 000 §5: cells of different widths meet without cracks because the wider face is meshed as the
    // narrower cells' squares. A checkerboard of per-leaf caps puts leaves of every depth side by side.
    const Brush cube(box(Vec3d(20.0)), at(Vec3d(0.4, 0.3, 0.2), Vec3d(0, 10, 5)));
    const Brush bite(sphere(13.0), at(Vec3d(20.0, 20.0, 18.0)));
    Volume v(1.0);
    applyCsg(v, cube, op(CsgMode::Add));
    applyCsg(v, bite, op(CsgMode::Remove));
    const Sdf sdf = [&](const Vec3d& p) { return std::max(cube.distance(p), -bite.distance(p)); };

    MeshOptions mixed = optionsFor(MesherKind::CubicalMarchingSquares, Cells::Adaptive);
    mixed.leafMaxCellWidth = [](const std::array<int32_t, 3>& origin) {
        const int parity = ((origin[0] + origin[1] + origin[2]) / kLeafDim) & 3;
        return 1 << (parity < 0 ? parity + 4 : parity); // 1, 2, 4 or 8 by leaf
    };
    const Mesh mesh = meshVolume(v, mixed);
    requireClosed(mesh);
    const SurfaceError error = surfaceError(mesh, sdf);
    INFO("max " << error.max << ", mean " << error.mean);
    CHECK(error.max <= 0.6);

    // The caps took effect: fewer triangles than uniform cells, more than unconstrained adaptive cells.
    const std::size_t uniform = meshWith(v, MesherKind::CubicalMarchingSquares, Cells::Uniform).triangleCount();
    const std::size_t adaptive = meshWith(v, MesherKind::CubicalMarchingSquares, Cells::Adaptive).triangleCount();
    INFO("triangles: uniform " << uniform << ", mixed " << mesh.triangleCount() << ", adaptive " << adaptive);
    CHECK(mesh.triangleCount() < uniform);
    CHECK(mesh.triangleCount() > adaptive);
}

TEST_CASE("re-meshing reaches the leaves whose subdivision reads an edited block", "[cms][incremental]")
{
    // A shallow bump just past a block boundary changes samples on that block's first voxel layer. The
    // leaf before it reads that layer when it subdivides: its wide cell splits, and so must the face of
    // the leaf before that, two blocks from the edit. The CSG kernel reports a margin of blocks around
    // an edit, which would hide this; here only the blocks whose samples changed are passed on.
    Volume v(1.0);
    apply(v, CsgMode::Add, box(Vec3d(20.3, 20.3, 20.3)), at(Vec3d(0.0)));
    const MeshOptions options = optionsFor(MesherKind::CubicalMarchingSquares, Cells::Adaptive);
    MeshChunkSet incremental(options);
    incremental.rebuild(v);
    auto blockOf = [](const EdgeRecord& e) {
        std::array<int32_t, 3> b{};
        for (int a = 0; a < 3; ++a) b[a] = e.voxel[a] & ~(kLeafDim - 1);
        return b;
    };
    auto key = [](const EdgeRecord& e) {
        return std::make_tuple(e.voxel, e.axis, e.from, e.to, e.sample.offset, e.sample.normalU, e.sample.normalV);
    };
    const Vec3d bumps[] = {Vec3d(16.5, 4.3, 19.0), Vec3d(4.3, 16.5, 19.0), Vec3d(19.0, 4.3, 8.5),
                           Vec3d(0.5, -11.5, 19.0)};
    for (const Vec3d& centre : bumps) {
        const std::vector<EdgeRecord> before = collectEdges(v);
        apply(v, CsgMode::Add, sphere(1.6), at(centre));
        const std::vector<EdgeRecord> after = collectEdges(v);
        // The blocks holding a sample that appeared, vanished or changed.
        std::set<decltype(key(before[0]))> old, now;
        for (const EdgeRecord& e : before) old.insert(key(e));
        for (const EdgeRecord& e : after) now.insert(key(e));
        std::set<std::array<int32_t, 3>> changed;
        for (const EdgeRecord& e : before) if (!now.count(key(e))) changed.insert(blockOf(e));
        for (const EdgeRecord& e : after) if (!old.count(key(e))) changed.insert(blockOf(e));
        REQUIRE(!changed.empty());
        incremental.update(v, std::vector<std::array<int32_t, 3>>(changed.begin(), changed.end()));

        MeshChunkSet full(options);
        full.rebuild(v);
        INFO("after the bump at " << centre);
        requireSameChunks(incremental, full);
    }
    requireClosed(incremental.weld());
}

TEST_CASE("leavesAffectedBy lists each block around the dirty ones once and in order, near and far, compact and scattered", "[cms][incremental]")
{
    // Compact sets are marked in a grid over their bounds; scattered ones are sorted.
    const int32_t far = 1 << 30;
    const int32_t apart = 4096 * kLeafDim;
    struct Layout {
        const char* name;
        std::vector<std::array<int32_t, 3>> dirty;
    };
    const std::vector<Layout> layouts = {
        {"adjacent near the origin", {{-8, 8, 0}, {-16, 8, 0}, {-8, 8, 0}}},
        {"adjacent far away", {{far + kLeafDim, -far, 8}, {far, -far, 8}}},
        {"scattered near the origin", {{-16, 8, 0}, {-16 + apart, 8, apart}}},
        {"scattered far away", {{far, -far, 8}, {far - apart, -far, 8}}},
    };
    for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
        const MeshOptions options = optionsFor(MesherKind::CubicalMarchingSquares, cells);
        for (const Layout& layout : layouts) {
            INFO((cells == Cells::Uniform ? "uniform, " : "adaptive, ") << layout.name);
            std::vector<std::array<int32_t, 3>> expected;
            auto add = [&](const std::array<int32_t, 3>& b, int dx, int dy, int dz) {
                expected.push_back({b[0] + dx * kLeafDim, b[1] + dy * kLeafDim, b[2] + dz * kLeafDim});
            };
            for (const auto& b : layout.dirty) {
                for (int dx = -1; dx <= 1; ++dx)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dz = -1; dz <= 1; ++dz) add(b, dx, dy, dz);
                if (cells == Cells::Uniform) continue;
                // The face neighbours of the leaves at -1 .. 0 blocks, whose subdivision reads b.
                for (int dx = -1; dx <= 0; ++dx)
                    for (int dy = -1; dy <= 0; ++dy)
                        for (int dz = -1; dz <= 0; ++dz)
                            for (int axis = 0; axis < 3; ++axis)
                                for (int step : {-1, 1})
                                    add(b, dx + (axis == 0) * step, dy + (axis == 1) * step, dz + (axis == 2) * step);
            }
            std::sort(expected.begin(), expected.end());
            expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
            CHECK(leavesAffectedBy(layout.dirty, options) == expected);
        }
    }
}

TEST_CASE("boxes that touch on a lattice plane fuse into one closed solid, in every mesher", "[cms][lattice]")
{
    // Half-extent 10 at the origin and at x = 20 share the plane x = 10: the voxels there are in both.
    Volume v(1.0);
    apply(v, CsgMode::Add, box(Vec3d(10.0)), at(Vec3d(0.0)));
    apply(v, CsgMode::Add, box(Vec3d(10.0)), at(Vec3d(20.0, 0.0, 0.0)));
    for (int y = -10; y <= 10; ++y)
        for (int z = -10; z <= 10; ++z) REQUIRE(v.materialAt({10, y, z}) == 1);
    for (const MesherKind kind : {MesherKind::MarchingCubes, MesherKind::CubicalMarchingSquares})
        for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
            INFO(mesherName(kind) << (cells == Cells::Uniform ? " uniform" : " adaptive"));
            const Mesh mesh = meshWith(v, kind, cells);
            requireClosed(mesh);
            CHECK(analyzeTopology(mesh, kMergeDistanceVoxels).components == 1);
            CHECK(enclosedVolume(mesh) == Approx(40.0 * 20.0 * 20.0).epsilon(0.002)); // no wall inside
        }
}

TEST_CASE("a box with faces on lattice planes keeps its exact, symmetric edges and corners", "[cms][lattice]")
{
    for (const double h : {20.0, 7.0, 12.5}) {
        Volume v(1.0);
        apply(v, CsgMode::Add, box(Vec3d(h)), at(Vec3d(0.0)));
        for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
            INFO("half-extent " << h << (cells == Cells::Uniform ? ", uniform" : ", adaptive"));
            const Mesh mesh = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
            requireClosed(mesh);
            const SurfaceError e = surfaceError(mesh, [h](const Vec3d& p) {
                const Vec3d q(std::fabs(p.x()) - h, std::fabs(p.y()) - h, std::fabs(p.z()) - h);
                const Vec3d o(std::max(q.x(), 0.0), std::max(q.y(), 0.0), std::max(q.z(), 0.0));
                return o.length() + std::min(std::max({q.x(), q.y(), q.z()}), 0.0);
            });
            CHECK(e.max < 2e-3); // was 0.48 voxel; what is left is the crossings' 2.4e-4 corner margin and sampling
            for (int a = 0; a < 3; ++a) {
                float lo = 1e9f, hi = -1e9f;
                for (const auto& p : mesh.positions) lo = std::min(lo, p[a]), hi = std::max(hi, p[a]);
                CHECK(lo == Approx(-h).margin(1e-3));
                CHECK(hi == Approx(h).margin(1e-3));
                CHECK(std::fabs(lo + hi) < 5e-4); // symmetric to the corner margin
            }
        }
    }
}

TEST_CASE("boxes far from the origin at odd voxel sizes keep their edges and corners", "[cms][lattice]")
{
    // A crossing's position is a float: far from the origin it rounds up to ~1e-4 voxel off the side of
    // the square it lies on, and a side must not clip it off the face's sharp feature (fandisk's top
    // edge was chamfered by 0.95 voxel that way). Seeded boxes, on and off lattice planes.
    std::mt19937 rng(41);
    std::uniform_int_distribution<int> centre(-900, 900), half(3, 14);
    std::uniform_real_distribution<double> fraction(0.0, 1.0);
    for (const double voxel : {0.02048632875084877, 0.37, 3.1}) {
        for (int trial = 0; trial < 6; ++trial) {
            // Half the boxes put their faces on lattice planes, the others anywhere.
            const bool onLattice = trial % 2 == 0;
            Vec3d c, h;
            for (int a = 0; a < 3; ++a) {
                c[a] = (centre(rng) + (onLattice ? 0.0 : fraction(rng))) * voxel;
                h[a] = (half(rng) + (onLattice ? 0.0 : fraction(rng))) * voxel;
            }
            Volume v(voxel);
            apply(v, CsgMode::Add, box(h), at(c));
            for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
                INFO("voxel " << voxel << ", box " << c << " half " << h << (cells == Cells::Uniform ? ", uniform" : ", adaptive"));
                const Mesh mesh = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
                REQUIRE(analyzeTopology(mesh, kMergeDistanceVoxels * voxel).watertight());
                SurfaceSampling sampling;
                sampling.spacing = 0.25 * voxel;
                const MeshQuality q = measureAgainstSdf(mesh, [&](const Point3d& p) {
                    const Vec3d d(std::fabs(p[0] - c.x()) - h.x(), std::fabs(p[1] - c.y()) - h.y(), std::fabs(p[2] - c.z()) - h.z());
                    const Vec3d o(std::max(d.x(), 0.0), std::max(d.y(), 0.0), std::max(d.z(), 0.0));
                    return o.length() + std::min(std::max({d.x(), d.y(), d.z()}), 0.0);
                }, sampling);
                CHECK(q.maxDistance / voxel < 5e-3);
            }
        }
    }
}

TEST_CASE("the leaves an edit's compared bounds reach hold every chunk the edit changed, on random integer stamps", "[cms][incremental]")
{
    // What the streaming scene's re-mesh relies on: compareRegion's bounds per changed leaf, through
    // leavesAffectedBy, reach every leaf whose chunk a full re-mesh makes differently. Small stamps at
    // integer positions beside leaf borders change a voxel or two next to a neighbour's cells.
    const MeshOptions options = optionsFor(MesherKind::CubicalMarchingSquares, GENERATE(Cells::Uniform, Cells::Adaptive));
    std::mt19937 rng(41);
    const auto integer = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    Volume v(1.0);
    const MaterialId moss = defineMaterial(v, "moss", 0.2f);
    apply(v, CsgMode::Add, box(Vec3d(12.0, 10.0, 9.0)), at(Vec3d(0.0)));
    apply(v, CsgMode::Add, sphere(9.0), at(Vec3d(8.0, 8.0, 0.0)));
    const auto chunksOf = [&](const Volume& volume) {
        std::map<std::array<int32_t, 3>, Mesh> out;
        for (MeshChunk& chunk : meshVolumeChunks(volume, options)) out[chunk.leafOrigin] = std::move(chunk.mesh);
        return out;
    };
    std::map<std::array<int32_t, 3>, Mesh> before = chunksOf(v);
    std::size_t changedChunks = 0, affectedLeaves = 0;
    for (int i = 0; i < 20; ++i) {
        Volume edited = v.clone();
        // Near a leaf border (multiples of 8) on the solids' surfaces, or anywhere.
        // Each draw on its own (braces evaluate in order; a call's arguments do not).
        Vec3d where{double(integer(-16, 20)), double(integer(-12, 18)), double(integer(-12, 12))};
        if (i % 2) {
            const int border = 8 * integer(-1, 2);
            where[i % 3] = border + integer(-1, 1);
        }
        const double size = integer(1, 2);
        const CsgMode mode = std::array<CsgMode, 3>{CsgMode::Add, CsgMode::Remove, CsgMode::Paint}[std::size_t(i % 3)];
        if (i % 4 < 2) apply(edited, mode, sphere(size), at(where), mode == CsgMode::Paint ? moss : 1);
        else apply(edited, mode, box(Vec3d(1.0, size, 1.0)), at(where), mode == CsgMode::Paint ? moss : 1);

        std::vector<BlockChange> changes;
        for (int32_t z = -32; z < 32; z += kLeafDim)
            for (int32_t y = -32; y < 32; y += kLeafDim)
                for (int32_t x = -32; x < 32; x += kLeafDim) {
                    const RegionDifference d = compareRegion(v, edited, {{x, y, z}, kLeafDim});
                    if (!d.any()) continue;
                    BlockChange& c = changes.emplace_back();
                    c.origin = {x, y, z};
                    for (std::size_t a = 0; a < 3; ++a) {
                        c.min[a] = uint8_t(d.lo[a] - c.origin[a]);
                        c.max[a] = uint8_t(d.hi[a] - c.origin[a]);
                    }
                }
        const std::vector<std::array<int32_t, 3>> affected = leavesAffectedBy(changes, options);
        affectedLeaves += affected.size();
        std::map<std::array<int32_t, 3>, Mesh> after = chunksOf(edited);
        std::set<std::array<int32_t, 3>> leaves;
        for (const auto& entry : before) leaves.insert(entry.first);
        for (const auto& entry : after) leaves.insert(entry.first);
        for (const auto& leaf : leaves) {
            const auto b = before.find(leaf), a = after.find(leaf);
            const bool same = b != before.end() && a != after.end() && b->second.positions == a->second.positions &&
                              b->second.triangles == a->second.triangles && b->second.triangleMaterials == a->second.triangleMaterials;
            if (same) continue;
            ++changedChunks;
            INFO("stamp " << i << " at " << where << ": the chunk of leaf " << leaf[0] << "," << leaf[1] << "," << leaf[2] << " changed");
            CHECK(std::binary_search(affected.begin(), affected.end(), leaf));
        }
        v = std::move(edited);
        before = std::move(after);
    }
    CHECK(changedChunks > 20);
    CHECK(affectedLeaves > changedChunks);
}

namespace {

/// How many of a mesh's triangles have a normal more than 120 degrees from `normalAt(centroid)`, the
/// analytic surface's outward normal (any length).
template<typename NormalAt>
std::size_t foldedCount(const Mesh& m, NormalAt&& normalAt)
{
    int folded = 0;
    for (const auto& t : m.triangles) {
        const Vec3d a(m.positions[t[0]][0], m.positions[t[0]][1], m.positions[t[0]][2]);
        const Vec3d b(m.positions[t[1]][0], m.positions[t[1]][1], m.positions[t[1]][2]);
        const Vec3d c(m.positions[t[2]][0], m.positions[t[2]][1], m.positions[t[2]][2]);
        const Vec3d n = (b - a).cross(c - a), g = normalAt((a + b + c) / 3.0);
        if (n.length() < 1e-12 || g.length() < 1e-9) continue;
        folded += n.dot(g) < -0.5 * n.length() * g.length();
    }
    return std::size_t(folded);
}

/// Folded and all triangles summed over seeds.
struct FoldTally {
    std::size_t folded = 0, triangles = 0;
    void add(const Mesh& m, std::size_t foldedInIt)
    {
        folded += foldedInIt;
        triangles += m.triangleCount();
    }
};

} // namespace

TEST_CASE("CMS at concave creases: few triangles face against the union's normal, none of a sharp fan folds back", "[cms][crease]")
{
    // Seeded unions of a ball and three spheres crossing it at general angles, off the lattice: the
    // triangles whose normal lies more than 120 degrees from the analytic normal of the union at their
    // centroid (the nearest sphere's). Before sharp fans were kept from folding and only convex corners
    // could poke out of a square, about 1 in 180 did; then about 1 in 500; with folded fans given another
    // centre or triangulated without one, and a concave crease's leaning fans triangulated without their
    // vertex, about 1 in 9,000 over seeds 1-12 (36 in 210,942, adaptive); with no face feature where the
    // normals themselves are less than the sharp angle apart, and a fan whose crease vertex lies in a
    // sub-voxel gap between the crease's sheets placed elsewhere in its cell, 3 in 210,342. With a fan's
    // bridges also judged against the sheet nearer their centroid: 1 in 210,684 over seeds 1-12 (seed 3,
    // where a third sphere's sliver passes between the lattice's edges), 21 in 702,164 over seeds 1-40,
    // most where two small spheres leave a gap under a voxel wide that the edges' single crossings
    // cannot show. Marching Cubes makes about 1 in 10,000. The goal is none (a bridge across a crease
    // may lean, never fold back): this bounds what is left.
    FoldTally uniform, adaptive, marchingCubes;
    for (unsigned seed = 1; seed <= 4; ++seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        struct Ball {
            Vec3d c;
            double r;
        };
        std::vector<Ball> balls{{Vec3d(0.0), 20.0}};
        for (int i = 0; i < 3; ++i) {
            Vec3d d(u(rng), u(rng), u(rng));
            d.normalize();
            const double r = 6.0 + 4.0 * std::fabs(u(rng));
            balls.push_back({d * (20.0 + 0.3 * r) + Vec3d(0.37 * u(rng), 0.0, 0.0), r});
        }
        Volume v(1.0);
        for (const Ball& b : balls) applyCsg(v, Brush(sphere(b.r), at(b.c)), op(CsgMode::Add));
        // The union's normal at a point: that of the sphere nearest to it.
        const auto folded = [&](const Mesh& m) {
            return foldedCount(m, [&](const Vec3d& x) {
                const Ball* nearest = &balls[0];
                for (const Ball& s : balls)
                    if ((x - s.c).length() - s.r < (x - nearest->c).length() - nearest->r) nearest = &s;
                return x - nearest->c;
            });
        };
        for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
            const Mesh m = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
            requireClosed(m);
            (cells == Cells::Uniform ? uniform : adaptive).add(m, folded(m));
        }
        const Mesh mc = meshWith(v, MesherKind::MarchingCubes, Cells::Uniform);
        marchingCubes.add(mc, folded(mc));
    }
    INFO("folded over seeds 1-4: uniform " << uniform.folded << " of " << uniform.triangles << ", adaptive " << adaptive.folded << " of "
                                           << adaptive.triangles << ", Marching Cubes " << marchingCubes.folded << " of " << marchingCubes.triangles);
    // GCC's Release build: uniform 1 of 149,538, adaptive 1 of 68,104, Marching Cubes 5 of 74,188; clang's
    // sanitizer build, whose floating point rounds the stamps a little differently: 4 of 149,384, 4 of
    // 67,748 and 7 of 74,116.
    CHECK(uniform.folded * 10000 <= uniform.triangles);
    CHECK(adaptive.folded * 10000 <= adaptive.triangles);
    CHECK(marchingCubes.folded * 5000 <= marchingCubes.triangles);
}

TEST_CASE("CMS at concave creases of boxes added to a ball, on and off the lattice: few triangles face against the union's normal", "[cms][crease]")
{
    // Three boxes crossing a ball at random places, centred on lattice points (odd seeds) or off them; the
    // union's analytic normal is its distance's gradient at each triangle's centroid. The goal is none;
    // 13 in 113,338 were left over seeds 1-12 (adaptive), 56 in 376,058 over seeds 1-40. With a corner
    // read from the planes around a cell taken only on the cell's own edge line (a box's edge beside
    // another box's face made a corner of neither), and fans judged against the sheet nearer each
    // triangle's centroid: 5 in 113,398 and 25 in 376,296, slivers a few hundredths of a voxel wide where
    // a box's face lies that close to a lattice plane and the sphere's crossing.
    FoldTally uniform, adaptive;
    for (unsigned seed = 1; seed <= 4; ++seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        Volume v(1.0);
        applyCsg(v, Brush(sphere(20.0), at(Vec3d(0.0))), op(CsgMode::Add));
        std::vector<std::pair<Vec3d, Vec3d>> boxes; // centre, half extents
        for (int i = 0; i < 3; ++i) {
            Vec3d d(u(rng), u(rng), u(rng));
            d.normalize();
            const Vec3d half(4.0 + 3.0 * std::fabs(u(rng)), 4.0 + 3.0 * std::fabs(u(rng)), 4.0 + 3.0 * std::fabs(u(rng)));
            Vec3d c = d * 21.0;
            if (seed % 2) c = Vec3d(std::round(c[0]), std::round(c[1]), std::round(c[2]));
            boxes.push_back({c, half});
            applyCsg(v, Brush(box(half), at(c)), op(CsgMode::Add));
        }
        const auto distance = [&](const Vec3d& p) {
            double d = p.length() - 20.0;
            for (const auto& [c, h] : boxes) {
                const Vec3d q(std::fabs(p[0] - c[0]) - h[0], std::fabs(p[1] - c[1]) - h[1], std::fabs(p[2] - c[2]) - h[2]);
                const Vec3d outside(std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0));
                d = std::min(d, outside.length() + std::min(std::max(q[0], std::max(q[1], q[2])), 0.0));
            }
            return d;
        };
        // The union's normal at a point: its distance's gradient.
        const auto folded = [&](const Mesh& m) {
            return foldedCount(m, [&](const Vec3d& x) {
                constexpr double e = 1e-3;
                return Vec3d(distance(x + Vec3d(e, 0, 0)) - distance(x - Vec3d(e, 0, 0)), distance(x + Vec3d(0, e, 0)) - distance(x - Vec3d(0, e, 0)),
                             distance(x + Vec3d(0, 0, e)) - distance(x - Vec3d(0, 0, e)));
            });
        };
        for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
            const Mesh m = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
            requireClosed(m);
            (cells == Cells::Uniform ? uniform : adaptive).add(m, folded(m));
        }
    }
    INFO("folded over seeds 1-4: uniform " << uniform.folded << " of " << uniform.triangles << ", adaptive " << adaptive.folded << " of "
                                           << adaptive.triangles);
    // GCC's Release build: uniform 3 of 135,648, adaptive 4 of 37,338; clang's sanitizer build: 2 of 135,630
    // and 4 of 37,326.
    CHECK(uniform.folded * 6000 <= uniform.triangles);
    CHECK(adaptive.folded * 6000 <= adaptive.triangles);
}

TEST_CASE("CMS on a cylinder tangent to lattice planes with its rims on others, turned by right angles: no triangle folds back", "[cms][crease]")
{
    // A radius-6 cylinder about a lattice line touches the lattice planes x = +-6 and y = +-6 along lines
    // of corners, and its caps lie on lattice planes: turned by 90 degrees (the demo's stone axle), the
    // rotation's rounding leaves the side within 1e-15 of those corners and the crossings there with
    // normals within a hair of the planes' axes. Their tangent lines on those faces have no direction,
    // and a 2D feature solved from them landed anywhere on the face: 12 of 13,800 triangles folded
    // (uniform), 9 of 4,416 (adaptive). Marching Cubes folds none.
    for (const double turn : {0.0, 90.0, 180.0, 270.0})
        for (const Vec3d axisTurn : {Vec3d(0.0), Vec3d(90.0, 0.0, 0.0), Vec3d(0.0, 90.0, 0.0)}) {
            Volume v(1.0);
            const Vec3d rotation = axisTurn + Vec3d(0.0, 0.0, turn);
            applyCsg(v, Brush(cylinder(6.0, 60.0), at(Vec3d(0.0), rotation)), op(CsgMode::Add));
            // The cylinder's axis, turned as the brush was (found from the mesh's extent: 60 long).
            for (const Cells cells : {Cells::Uniform, Cells::Adaptive}) {
                const Mesh m = meshWith(v, MesherKind::CubicalMarchingSquares, cells);
                requireClosed(m);
                std::array<double, 3> lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
                for (const auto& p : m.positions)
                    for (int a = 0; a < 3; ++a) lo[std::size_t(a)] = std::min(lo[std::size_t(a)], double(p[std::size_t(a)])), hi[std::size_t(a)] = std::max(hi[std::size_t(a)], double(p[std::size_t(a)]));
                int axis = 0;
                for (int a = 1; a < 3; ++a)
                    if (hi[std::size_t(a)] - lo[std::size_t(a)] > hi[std::size_t(axis)] - lo[std::size_t(axis)]) axis = a;
                REQUIRE(hi[std::size_t(axis)] - lo[std::size_t(axis)] == Approx(60.0).margin(0.01));
                const auto normalAt = [&](const Vec3d& p) {
                    const double x = p[(axis + 1) % 3], y = p[(axis + 2) % 3], z = p[axis];
                    const double r = std::hypot(x, y), side = r - 6.0, cap = std::fabs(z) - 30.0;
                    Vec3d radial(0.0), along(0.0);
                    if (r > 1e-9) radial[(axis + 1) % 3] = x / r, radial[(axis + 2) % 3] = y / r;
                    along[axis] = z > 0.0 ? 1.0 : -1.0;
                    if (side > 0.0 && cap > 0.0) return radial * side + along * cap;
                    return side > cap ? radial : along;
                };
                INFO("turned " << rotation << ", " << (cells == Cells::Uniform ? "uniform" : "adaptive") << " cells");
                CHECK(foldedCount(m, normalAt) == 0);
            }
        }
}
