// The voxelizer: analytic meshes within error bounds of their surfaces, lattice-aligned boxes exact,
// messy meshes (duplicated, flipped, holed, degenerate triangles) repaired, the real models closed.
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "support/CliRun.h"
#include "support/HermiteProbe.h"
#include "support/TestUtil.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/Quantize.h"
#include "vdb_hermite/VolumeRegions.h"
#include "voxelize/VoxelizeToStore.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <iterator>
#include <map>
#include <set>
#include <thread>
#include <fstream>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

using Vec = std::array<double, 3>;

/// A UV sphere of `rings` x `sectors` quads, closed, counter-clockwise seen from outside.
TriangleSoup uvSphere(double radius, const Vec& centre, int rings = 48, int sectors = 96)
{
    TriangleSoup s;
    s.materials.push_back({});
    s.positions.push_back({centre[0], centre[1], centre[2] + radius});
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < sectors; ++j) {
            const double th = M_PI * i / rings, ph = 2.0 * M_PI * j / sectors;
            s.positions.push_back({centre[0] + radius * std::sin(th) * std::cos(ph), centre[1] + radius * std::sin(th) * std::sin(ph),
                                   centre[2] + radius * std::cos(th)});
        }
    s.positions.push_back({centre[0], centre[1], centre[2] - radius});
    const uint32_t last = uint32_t(s.positions.size() - 1);
    auto ring = [&](int i, int j) { return uint32_t(1 + i * sectors + (j % sectors)); };
    for (int j = 0; j < sectors; ++j) s.triangles.push_back({0, ring(0, j), ring(0, j + 1)});
    for (int i = 0; i + 1 < rings - 1; ++i)
        for (int j = 0; j < sectors; ++j) {
            s.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            s.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
    for (int j = 0; j < sectors; ++j) s.triangles.push_back({last, ring(rings - 2, j + 1), ring(rings - 2, j)});
    s.triangleMaterials.assign(s.triangles.size(), 0);
    return s;
}

/// A box of half extents h about c, rotated by `degrees` about the axis (1, 1, 0) / sqrt 2.
TriangleSoup box(const Vec& h, const Vec& c, double degrees = 0.0)
{
    TriangleSoup s;
    s.materials.push_back({});
    const double a = degrees * M_PI / 180.0, k = 1.0 / std::sqrt(2.0);
    const double ca = std::cos(a), sa = std::sin(a);
    const Vec axis{k, k, 0.0};
    for (int i = 0; i < 8; ++i) {
        const Vec p{(i & 1 ? 1 : -1) * h[0], (i & 2 ? 1 : -1) * h[1], (i & 4 ? 1 : -1) * h[2]};
        // Rodrigues' rotation.
        const double d = axis[0] * p[0] + axis[1] * p[1] + axis[2] * p[2];
        const Vec x{axis[1] * p[2] - axis[2] * p[1], axis[2] * p[0] - axis[0] * p[2], axis[0] * p[1] - axis[1] * p[0]};
        Vec r;
        for (int j = 0; j < 3; ++j) r[std::size_t(j)] = c[std::size_t(j)] + p[std::size_t(j)] * ca + x[std::size_t(j)] * sa + axis[std::size_t(j)] * d * (1.0 - ca);
        s.positions.push_back(r);
    }
    const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        s.triangles.push_back({f[0], f[1], f[2]});
        s.triangles.push_back({f[0], f[2], f[3]});
    }
    s.triangleMaterials.assign(s.triangles.size(), 0);
    return s;
}

Mesh closedMesh(const Volume& v)
{
    REQUIRE(checkInvariants(v).empty());
    MeshOptions cms;
    cms.kind = MesherKind::CubicalMarchingSquares;
    const Mesh mesh = meshVolume(v, cms);
    const MeshTopology t = analyzeTopology(mesh, kMergeDistanceVoxels * v.voxelSize());
    INFO(t.boundaryEdges << " boundary, " << t.nonManifoldEdges << " non-manifold, " << t.pinchedVertices << " pinched");
    CHECK(t.watertight());
    return mesh;
}

/// The largest distance of a volume's crossings from a sphere, in voxels.
double crossingError(const Volume& v, double radius, const Vec& c)
{
    double worst = 0.0;
    const double vs = v.voxelSize();
    const HermiteTree& tree = v.impl().grid->constTree();
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf)
        for (Index i = 0; i < Index(kLeafVoxels); ++i)
            for (int axis = 0; axis < 3; ++axis)
                if (const PackedSample* s = leaf->sample(i, axis)) {
                    const Coord p = leaf->offsetToGlobalCoord(i);
                    Vec x{p.x() * vs - c[0], p.y() * vs - c[1], p.z() * vs - c[2]};
                    x[std::size_t(axis)] += unpackSample(*s).offset * vs;
                    worst = std::max(worst, std::fabs(std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - radius) / vs);
                }
    return worst;
}

} // namespace

TEST_CASE("a tessellated sphere voxelizes within its tessellation error, closed", "[voxelize]")
{
    const double radius = 10.0;
    for (const Vec& centre : {Vec{0.0, 0.0, 0.0}, Vec{0.3, -0.7, 1.1}}) {
        const TriangleSoup sphere = uvSphere(radius, centre);
        VoxelizeOptions o;
        o.voxelSize = 0.5;
        VoxelizeReport report;
        const Volume v = voxelizeMesh(sphere, o, &report);
        CHECK(report.patchedCrossings == 0);
        CHECK(report.votedPoints < 20); // rays grazing the poles, at most
        // The facets lie inside the sphere by at most r (1 - cos(pi / rings)) = 0.021, 0.04 voxel.
        CHECK(crossingError(v, radius, centre) < 0.06);
        const Mesh mesh = closedMesh(v);
        CHECK(enclosedVolume(mesh) == Approx(4.0 / 3.0 * M_PI * radius * radius * radius).epsilon(0.01));
    }
}

TEST_CASE("boxes voxelize exactly: on the lattice, off it and rotated", "[voxelize]")
{
    struct Case {
        Vec half, centre;
        double degrees;
    };
    // Integer corners (users model on integers), half-voxel corners, and a rotated box.
    for (const Case& c : {Case{{4, 3, 5}, {0, 0, 0}, 0.0}, Case{{4.25, 3, 2.5}, {1, 2, 0.5}, 0.0}, Case{{4, 3, 5}, {0.2, 0.1, 0.3}, 30.0}}) {
        CAPTURE(c.degrees, c.half[0], c.centre[0]);
        VoxelizeOptions o;
        o.voxelSize = 0.25;
        VoxelizeReport report;
        const Volume v = voxelizeMesh(box(c.half, c.centre, c.degrees), o, &report);
        CHECK(report.patchedCrossings == 0);
        const Mesh mesh = closedMesh(v);
        CHECK(enclosedVolume(mesh) == Approx(8.0 * c.half[0] * c.half[1] * c.half[2]).epsilon(c.degrees == 0.0 ? 1e-3 : 1e-2));
    }
}

TEST_CASE("faces a rounding error off a lattice plane voxelize as if on it", "[voxelize]")
{
    // Exported models keep faces modelled on a plane a hair off it (fandisk's x = 0 side spans 0 .. 2e-6):
    // each corner of a box with four faces on lattice planes moves by up to 1e-3 voxel, every corner its
    // own way, so those faces are no longer flat; the voxels must equal the exact box's.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);
    for (const double voxel : {1.0, 0.5}) {
        const TriangleSoup exact = box({4.685, 2.305, 3.5}, {4.685, 5.305, 1.5}); // x 0 .. 9.37, y 3 .. 7.61, z -2 .. 5
        VoxelizeOptions o;
        o.voxelSize = voxel;
        const Volume reference = voxelizeMesh(exact, o);
        for (int trial = 0; trial < 8; ++trial) {
            CAPTURE(voxel, trial);
            TriangleSoup bumpy = exact;
            for (auto& p : bumpy.positions)
                for (double& c : p)
                    if (std::fabs(c / voxel - std::round(c / voxel)) < 1e-9) c += jitter(rng) * voxel;
            CHECK(identical(voxelizeMesh(bumpy, o), reference));
        }
    }
}

TEST_CASE("messy meshes: duplicated, flipped, holed and degenerate triangles are repaired", "[voxelize]")
{
    VoxelizeOptions o;
    o.voxelSize = 0.5;
    const TriangleSoup clean = uvSphere(8.0, {0.1, 0.2, 0.3}, 24, 48);
    const Volume reference = voxelizeMesh(clean, o);
    const double volume = enclosedVolume(closedMesh(reference));

    TriangleSoup doubled = clean; // every triangle twice
    doubled.triangles.insert(doubled.triangles.end(), clean.triangles.begin(), clean.triangles.end());
    doubled.triangleMaterials.assign(doubled.triangles.size(), 0);
    VoxelizeReport r;
    CHECK(identical(voxelizeMesh(doubled, o, &r), reference));
    CHECK(r.duplicateHits > 0);

    TriangleSoup flipped = clean; // every other triangle wound the wrong way
    for (std::size_t i = 0; i < flipped.triangles.size(); i += 2) std::swap(flipped.triangles[i][1], flipped.triangles[i][2]);
    CHECK(identical(voxelizeMesh(flipped, o), reference));

    TriangleSoup holed = clean; // a hole of 6 triangles
    holed.triangles.erase(holed.triangles.begin() + 300, holed.triangles.begin() + 306);
    holed.triangleMaterials.resize(holed.triangles.size());
    const Volume patched = voxelizeMesh(holed, o, &r);
    CHECK(r.votedPoints > 0);
    CHECK(enclosedVolume(closedMesh(patched)) == Approx(volume).epsilon(0.01));
}

TEST_CASE("open surfaces enclose nothing whatever their orientation: lone triangles, flat polygons", "[voxelize]")
{
    // Each ray through an open surface crosses it an odd number of times: none can say which side is
    // inside. A tilted lone triangle made a solid wedge of thousands of voxels when such rays voted.
    std::mt19937_64 rng(27);
    std::uniform_real_distribution<double> coord(-10.0, 10.0), unit(0.0, 1.0);
    for (int trial = 0; trial < 60; ++trial) {
        TriangleSoup open;
        open.materials.push_back({});
        if (trial % 2 == 0) { // a lone triangle anywhere, any way up
            for (int k = 0; k < 3; ++k) open.positions.push_back({coord(rng), coord(rng), coord(rng)});
            open.triangles.push_back({0u, 1u, 2u});
        } else { // a convex polygon of 4 to 8 corners on a random plane, as a fan
            openvdb::Vec3d e1(coord(rng), coord(rng), coord(rng)), e2(coord(rng), coord(rng), coord(rng));
            e1.normalize();
            e2 = (e2 - e1 * e1.dot(e2)).unit();
            const openvdb::Vec3d centre(coord(rng), coord(rng), coord(rng));
            const int corners = 4 + trial % 5;
            for (int k = 0; k < corners; ++k) {
                const double angle = 2.0 * kPi * (k + 0.8 * unit(rng)) / corners, radius = 3.0 + 7.0 * unit(rng);
                const openvdb::Vec3d p = centre + e1 * (radius * std::cos(angle)) + e2 * (radius * std::sin(angle));
                open.positions.push_back({p[0], p[1], p[2]});
            }
            for (int k = 1; k + 1 < corners; ++k) open.triangles.push_back({0u, uint32_t(k), uint32_t(k + 1)});
        }
        open.triangleMaterials.assign(open.triangles.size(), 0);
        VoxelizeOptions o;
        o.resolution = 16 + 16 * (trial % 4);
        VoxelizeReport report;
        const Volume v = voxelizeMesh(open, o, &report);
        CAPTURE(trial);
        CHECK(report.solidVoxels == 0);
        CHECK(v.stats().activeVoxels == 0);
    }
}

TEST_CASE("a mesh beyond what the lattice indexes is refused, naming the position and the limit", "[voxelize]")
{
    TriangleSoup far = uvSphere(8.0, {1e12, 0.0, 0.0}, 8, 16);
    VoxelizeOptions o;
    o.voxelSize = 0.5;
    CHECK_THROWS_WITH(voxelizeMesh(far, o), Catch::Contains("lattice indexes at most") && Catch::Contains("1e+12"));
}

TEST_CASE("a mesh of more materials than a scene holds is refused before any work, or imported as one", "[voxelize]")
{
    TriangleSoup many = uvSphere(8.0, {0.0, 0.0, 0.0}, 8, 16);
    many.materials.clear();
    for (int m = 0; m < 70000; ++m) many.materials.push_back({"m" + std::to_string(m), {1.0f, 1.0f, 1.0f, 1.0f}});
    for (std::size_t t = 0; t < many.triangles.size(); ++t) many.triangleMaterials[t] = uint32_t(t * 997 % 70000);
    VoxelizeOptions o;
    o.resolution = 16;
    CHECK_THROWS_WITH(voxelizeMesh(many, o), Catch::Contains("has 70000 materials") && Catch::Contains("--material"));
    o.material = "clay";
    CHECK(voxelizeMesh(many, o).materials().names() == std::vector<std::string>{"default", "clay"});
}

TEST_CASE("the real models voxelize into closed meshes", "[voxelize]")
{
    const std::string models = std::string(VDBCLAY_SHARED_DATA) + "/models/";
    if (!std::filesystem::exists(models)) {
        WARN("no " << models << ": the real models are not checked");
        return;
    }
    for (const char* name : {"teapot.obj", "stanford-bunny.obj", "suzanne.obj", "fandisk.obj"}) {
        CAPTURE(name);
        const TriangleSoup mesh = loadTriangleMesh(models + name);
        VoxelizeOptions o;
        o.resolution = 64;
        VoxelizeReport report;
        const Volume v = voxelizeMesh(mesh, o, &report);
        CHECK(report.solidVoxels > 1000);
        closedMesh(v);
    }
}

TEST_CASE("block by block equals whole: any block size, and into a store brick by brick", "[voxelize][store]")
{
    // Seeded soups of overlapping spheres and rotated boxes (self-intersections), some with holes (odd
    // parity along a ray past the mesh), anywhere on the lattice, negative coordinates included.
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> at(-90.0, 90.0), size(3.0, 30.0);
    TempDir dir;
    for (int trial = 0; trial < 6; ++trial) {
        CAPTURE(trial);
        TriangleSoup soup;
        soup.materials = {{"stone", {0.5f, 0.5f, 0.5f, 1.0f}}, {"moss", {0.2f, 0.6f, 0.2f, 1.0f}}};
        for (int part = 0; part < 4; ++part) {
            const TriangleSoup piece = part % 2 ? uvSphere(size(rng), {at(rng), at(rng), at(rng)}, 12, 24)
                                                : box({size(rng), size(rng), size(rng)}, {at(rng), at(rng), at(rng)}, size(rng) * 3.0);
            const uint32_t base = uint32_t(soup.positions.size());
            soup.positions.insert(soup.positions.end(), piece.positions.begin(), piece.positions.end());
            for (const auto& t : piece.triangles) soup.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
            soup.triangleMaterials.resize(soup.triangles.size(), uint32_t(part % 2));
        }
        if (trial % 2) soup.triangles.resize(soup.triangles.size() - 5), soup.triangleMaterials.resize(soup.triangles.size());
        VoxelizeOptions o;
        o.voxelSize = trial < 3 ? 1.0 : 0.75;
        VoxelizeReport whole;
        const Volume reference = voxelizeMesh(soup, o, &whole);
        REQUIRE(whole.solidVoxels > 0);

        const MeshVoxelizer voxelizer(soup, o);
        Volume pasted(voxelizer.voxelSize());
        pasted.materials() = voxelizer.materials();
        VoxelizeReport counts;
        for (const LeafAlignedBox& box : voxelizer.blocks(trial % 2 ? 8 : 24)) pasteRegion(pasted, voxelizer.voxelizeBlock(box, counts), box);
        CHECK(identical(pasted, reference));
        CHECK(counts.solidVoxels == whole.solidVoxels);
        CHECK(counts.crossings == whole.crossings);
        CHECK(counts.votedPoints == whole.votedPoints);
        CHECK(counts.patchedCrossings == whole.patchedCrossings);

        const std::string path = dir.file("soup.vdbclay");
        const StoreVoxelizeReport stored = voxelizeMeshToStore(soup, o, path);
        CHECK(identical(loadScene(path), reference));
        CHECK(stored.mesh.solidVoxels == whole.solidVoxels);
        CHECK(stored.leaves == reference.stats().leafCount);
        CHECK(stored.activeVoxels == reference.stats().activeVoxels);
        CHECK(stored.bricks == SceneStore::open(path, StoreAccess::ReadOnly).brickCoords(0).size());
    }
}

TEST_CASE("random triangle soups voxelize into valid volumes whose meshes are closed", "[voxelize][fuzz]")
{
    // What real files hold at worst: triangles at random, open, crossing each other, zero-area and
    // repeated ones, corners on lattice points (users type integers) or anywhere.
    std::mt19937 rng(29);
    std::uniform_int_distribution<int> lattice(-6, 6);
    std::uniform_real_distribution<double> anywhere(-6.0, 6.0);
    for (int trial = 0; trial < 80; ++trial) { // 4 s in Release, under 2 min with the sanitizers
        CAPTURE(trial);
        TriangleSoup soup;
        soup.materials = {{}, {"red", {1.0f, 0.0f, 0.0f, 1.0f}}};
        const int triangles = 1 + int(rng() % 24);
        const bool onLattice = trial % 2 == 0;
        for (int t = 0; t < triangles; ++t) {
            const uint32_t base = uint32_t(soup.positions.size());
            for (int k = 0; k < 3; ++k)
                soup.positions.push_back(onLattice ? Vec{double(lattice(rng)), double(lattice(rng)), double(lattice(rng))}
                                                   : Vec{anywhere(rng), anywhere(rng), anywhere(rng)});
            soup.triangles.push_back({base, base + 1, base + 2});
            if (rng() % 5 == 0) soup.triangles.push_back({base, base + 2, base + 1}); // repeated, flipped
        }
        soup.triangleMaterials.resize(soup.triangles.size());
        for (auto& m : soup.triangleMaterials) m = uint32_t(rng() % 2);
        VoxelizeOptions o;
        o.voxelSize = trial % 3 == 0 ? 1.0 : 0.37;
        VoxelizeReport report;
        const Volume v = voxelizeMesh(soup, o, &report);
        CHECK(report.crossings >= report.patchedCrossings + report.materialInterfaces);
        INFO(checkInvariants(v));
        REQUIRE(checkInvariants(v).empty());
        // Such soups leave solids touching along voxel edges with every tangent line through one point
        // (CMS pinched the surface there until it cut those corners straight).
        if (report.solidVoxels > 0) closedMesh(v);
    }
}

TEST_CASE("a mesh file is read by the vdbclay-read-mesh program beside the executable, as a fork of this process reads it", "[voxelize]")
{
    TempDir dir;
    std::ofstream(dir.file("quad.obj")) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.5\nf 1 2 3 4\n";
    std::ofstream(dir.file("broken.ply")) << "ply\nformat ascii 1.0\nelement vertex 99\nend_header\n1 2\n";
    const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
    REQUIRE(std::filesystem::exists(std::filesystem::path(self).parent_path() / kMeshReaderProgram));
    const TriangleSoup byProgram = loadTriangleMesh(dir.file("quad.obj"));
    // The same file read in a fork (the reader named by the environment is not there to run).
    ::setenv("VDBCLAY_MESH_READER", dir.file("no-such-reader").c_str(), 1);
    const TriangleSoup byFork = loadTriangleMesh(dir.file("quad.obj"));
    std::string forkError;
    try {
        loadTriangleMesh(dir.file("broken.ply"));
    } catch (const MeshImportError& e) {
        forkError = e.what();
    }
    ::unsetenv("VDBCLAY_MESH_READER");
    CHECK(byProgram.triangles.size() == 2);
    CHECK(byProgram.positions == byFork.positions);
    CHECK(byProgram.triangles == byFork.triangles);
    CHECK(byProgram.triangleMaterials == byFork.triangleMaterials);
    // A damaged file: one line either way.
    try {
        loadTriangleMesh(dir.file("broken.ply"));
        FAIL("a damaged file was read");
    } catch (const MeshImportError& e) {
        CHECK(std::string(e.what()).find('\n') == std::string::npos);
        CHECK_FALSE(forkError.empty());
    }
    // Run by hand without its arguments, the program says what it is for and exits 2.
    const CommandResult r = runCli(dir, "", "", (std::filesystem::path(self).parent_path() / kMeshReaderProgram).string());
    CHECK(r.exitCode == 2);
    CHECK(r.err.find("usage") != std::string::npos);
}

TEST_CASE("a mesh read in a child process comes back whole, its crash, hang or refusal is one line", "[voxelize]")
{
    TriangleSoup sent;
    sent.positions = {{-1.5, 0.25, 1e-7}, {3.0, -2.0, 1e6}, {0.1, 0.2, 0.3}, {7.0, 8.0, -9.0}};
    sent.triangles = {{0, 1, 2}, {1, 3, 2}};
    sent.triangleMaterials = {1, 0};
    sent.materials = {{"", {0.8f, 0.8f, 0.8f, 1.0f}}, {"colour-ff0000", {1.0f, 0.0f, 0.0f, 0.5f}}};
    sent.droppedTriangles = 3;
    sent.colourMaterials = 1;
    sent.colourBinned = true;
    const TriangleSoup got = readInChildProcess("made.obj", [&] { return sent; }, MeshReadLimits{});
    CHECK(got.positions == sent.positions);
    CHECK(got.triangles == sent.triangles);
    CHECK(got.triangleMaterials == sent.triangleMaterials);
    REQUIRE(got.materials.size() == 2);
    CHECK(got.materials[1].name == "colour-ff0000");
    CHECK(got.materials[1].color == sent.materials[1].color);
    CHECK(got.droppedTriangles == 3);
    CHECK(got.colourMaterials == 1);
    CHECK(got.colourBinned);

    auto failure = [](const std::function<TriangleSoup()>& read, const MeshReadLimits& limits) {
        try {
            (void)readInChildProcess("bad.obj", read, limits);
        } catch (const MeshImportError& e) {
            return std::string(e.what());
        }
        return std::string("read");
    };
    const std::string refused = failure([]() -> TriangleSoup { throw MeshImportError("no\nsuch\x01mesh"); }, MeshReadLimits{});
    CHECK(refused == "no\\x0asuch\\x01mesh");
    const std::string crashed = failure([]() -> TriangleSoup {
        std::raise(SIGSEGV);
        std::_Exit(9); // a sanitizer's handler may turn the signal into an exit
    }, MeshReadLimits{});
    CHECK(crashed.find("reading 'bad.obj' failed") == 0);
    const std::string stuck = failure([]() -> TriangleSoup {
        for (;;) std::this_thread::sleep_for(std::chrono::seconds(1)); // a parser in an endless loop
    }, MeshReadLimits{std::chrono::seconds(1)});
    CHECK(stuck.find("took over 1 s and was stopped") != std::string::npos);
    if (meshReadMemoryIsCapped()) {
        // A parser that believes a damaged count: the allocation fails in the child, not the machine.
        const std::string greedy = failure([]() -> TriangleSoup {
            std::vector<std::array<double, 3>> positions(uint64_t(1) << 28); // 6 GiB
            return TriangleSoup{positions, {}, {}, {}};
        }, MeshReadLimits{std::chrono::seconds(60), uint64_t(1) << 30});
        CHECK(greedy == "reading 'bad.obj' needed more than the 1024 MiB it may take: the counts in the file are damaged, or the mesh is too large to import");
    }
    // A soup whose indices do not add up is refused like a crash (the voxelizer would read past the end).
    TriangleSoup broken = sent;
    broken.triangles[1][2] = 4;
    CHECK(failure([&] { return broken; }, MeshReadLimits{}).find("failed") != std::string::npos);
}

TEST_CASE("bad meshes and options are refused with one line", "[voxelize]")
{
    TempDir dir;
    writeText(dir.file("junk.obj"), "this is not\x01 an obj file\nf 1 2 3\n");
    writeText(dir.file("empty.obj"), "# nothing\n");
    writeText(dir.file("lines.obj"), "v 0 0 0\nv 1 0 0\nl 1 2\n");
    // Files that take Debian's Assimp 5.2 down (found by fuzz_mesh_import) cost only the child process
    // that reads them: a binary PLY cut short (a segmentation fault), an ASCII PLY whose header never
    // ends (an endless loop), an OFF whose face counts lie (an assertion that aborts).
    {
        std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 300\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 100\nproperty list uchar uint vertex_indices\nend_header\n";
        for (int v = 0; v < 300; ++v)
            for (int a = 0; a < 3; ++a) {
                const float x = float((v * (a + 3)) % 17);
                ply.append(reinterpret_cast<const char*>(&x), 4);
            }
        for (uint32_t t = 0; t < 40; ++t) { // 60 faces short
            ply += char(3);
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t index = 3 * t + k;
                ply.append(reinterpret_cast<const char*>(&index), 4);
            }
        }
        writeText(dir.file("cut.ply"), ply);
        writeText(dir.file("unended.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n0\n1\n2\n");
        // The fuzzer's input: a format byte, a resolution byte, then the file.
        std::ifstream found(std::string(VDBCLAY_FUZZ_CORPUS) + "/import/found-off-assimp-assert.bin", std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(found)), std::istreambuf_iterator<char>());
        REQUIRE(bytes.size() > 2);
        writeText(dir.file("lying.off"), bytes.substr(2));
        // Headers that state more elements than the file holds: Assimp would allocate for all of them
        // (12 GB and a minute for these 100 bytes; found by fuzz_mesh_import).
        writeText(dir.file("billion.off"), "OFF\n# a comment\n1000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        writeText(dir.file("claims.ply"), "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty float x\n"
                                          "property float y\nproperty float z\nend_header\n" + std::string(100, '\0'));
    }
    for (const char* f : {"junk.obj", "empty.obj", "lines.obj", "missing.obj", "cut.ply", "unended.ply", "lying.off", "billion.off", "claims.ply"}) {
        CAPTURE(f);
        try {
            (void)loadTriangleMesh(dir.file(f));
            FAIL("loaded");
        } catch (const MeshImportError& e) {
            const std::string message = e.what();
            CAPTURE(message);
            CHECK(message.find('\n') == std::string::npos);
            if (std::string(f) == "billion.off") CHECK(message.find("states 1000000000 vertices, at least 6000000000 bytes") != std::string::npos);
            if (std::string(f) == "claims.ply") CHECK(message.find("states 2000000000 vertex elements, at least 24000000000 bytes, but only 100") != std::string::npos);
        }
    }
    // The counts of a file that holds exactly what its header states, in the fewest bytes, pass.
    writeText(dir.file("least.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                     "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
    writeText(dir.file("least.off"), "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
    for (const char* f : {"least.ply", "least.off"}) CHECK(loadTriangleMesh(dir.file(f)).triangles.size() == 1);
    const TriangleSoup sphere = uvSphere(1.0, {0, 0, 0}, 8, 16);
    CHECK_THROWS_AS(voxelizeMesh(sphere, {}), std::invalid_argument);
    VoxelizeOptions tiny;
    tiny.voxelSize = 1e-7; // 2e7 points a side
    CHECK_THROWS_AS(voxelizeMesh(sphere, tiny), std::invalid_argument);
    VoxelizeOptions zero;
    zero.resolution = 0;
    CHECK_THROWS_AS(voxelizeMesh(sphere, zero), std::invalid_argument);
}

namespace {

/// An ASCII PLY of an axis-aligned cube [0, 4]^3 whose faces carry vertex colours: face f takes
/// colour(f), and corner 0 of each face a stray colour (two corners out of three agree anyway).
std::string colouredCubePly(const std::function<std::array<int, 3>(int face)>& colour)
{
    // Per face: the axis it is normal to, its side, then four corners counter-clockwise seen from outside.
    const int quads[6][4][3] = {{{0, 0, 0}, {0, 0, 4}, {0, 4, 4}, {0, 4, 0}}, {{4, 0, 0}, {4, 4, 0}, {4, 4, 4}, {4, 0, 4}},
                                {{0, 0, 0}, {4, 0, 0}, {4, 0, 4}, {0, 0, 4}}, {{0, 4, 0}, {0, 4, 4}, {4, 4, 4}, {4, 4, 0}},
                                {{0, 0, 0}, {0, 4, 0}, {4, 4, 0}, {4, 0, 0}}, {{0, 0, 4}, {4, 0, 4}, {4, 4, 4}, {0, 4, 4}}};
    std::string ply = "ply\nformat ascii 1.0\nelement vertex 24\nproperty float x\nproperty float y\nproperty float z\n"
                      "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 12\n"
                      "property list uchar int vertex_indices\nend_header\n";
    for (int f = 0; f < 6; ++f)
        for (int c = 0; c < 4; ++c) {
            const std::array<int, 3> rgb = c == 1 ? std::array<int, 3>{1, 2, 3} : colour(f); // corner 1: a stray colour
            ply += std::to_string(quads[f][c][0]) + " " + std::to_string(quads[f][c][1]) + " " + std::to_string(quads[f][c][2]) + " " +
                   std::to_string(rgb[0]) + " " + std::to_string(rgb[1]) + " " + std::to_string(rgb[2]) + "\n";
        }
    for (int f = 0; f < 6; ++f) {
        const int v = 4 * f;
        ply += "3 " + std::to_string(v) + " " + std::to_string(v + 1) + " " + std::to_string(v + 2) + "\n";
        ply += "3 " + std::to_string(v) + " " + std::to_string(v + 2) + " " + std::to_string(v + 3) + "\n";
    }
    return ply;
}

} // namespace

TEST_CASE("each face's material covers the solid nearest it, touching parts keep their own", "[voxelize]")
{
    // A cube from 0 to 6 whose top (+y) faces are red and the rest blue, at voxel sizes on and off the
    // lattice: a solid point takes the material of its nearest face (rays along every axis).
    for (const double vs : {0.5, 0.37}) {
        CAPTURE(vs);
        TriangleSoup cube = box({3.0, 3.0, 3.0}, {3.0, 3.0, 3.0});
        cube.materials = {{"blue", {0.0f, 0.0f, 1.0f, 1.0f}}, {"red", {1.0f, 0.0f, 0.0f, 1.0f}}};
        for (std::size_t t = 0; t < cube.triangles.size(); ++t) {
            bool top = true;
            for (const uint32_t i : cube.triangles[t]) top = top && cube.positions[i][1] > 5.9;
            cube.triangleMaterials[t] = top ? 1 : 0;
        }
        VoxelizeOptions o;
        o.voxelSize = vs;
        const Volume v = voxelizeMesh(cube, o);
        const MaterialId red = *v.materials().find("red"), blue = *v.materials().find("blue");
        int reds = 0, blues = 0;
        const int n = int(std::ceil(6.0 / vs));
        for (int x = 0; x <= n; ++x)
            for (int y = 0; y <= n; ++y)
                for (int z = 0; z <= n; ++z) {
                    const MaterialId m = v.materialAt({x, y, z});
                    if (m == kEmptyMaterial) continue;
                    const double p[3] = {x * vs, y * vs, z * vs};
                    const double top = 6.0 - p[1];
                    const double others = std::min({p[0], 6.0 - p[0], p[1], p[2], 6.0 - p[2]});
                    if (top < others - 1e-6) {
                        CHECK(m == red);
                        ++reds;
                    } else if (others < top - 1e-6) {
                        CHECK(m == blue);
                        ++blues;
                    }
                }
        CHECK(reds > 0);
        CHECK(blues > reds);
        closedMesh(v);
    }
    // Two boxes sharing the face x = 4, stone on the left and moss on the right: every solid point on
    // the left of it is stone, on the right moss, whichever part's id is larger.
    for (const bool mossFirst : {false, true}) {
        TriangleSoup soup = box({2.0, 2.0, 2.0}, {2.0, 0.0, 0.0});
        const TriangleSoup right = box({2.0, 2.0, 2.0}, {6.0, 0.0, 0.0});
        const uint32_t base = uint32_t(soup.positions.size());
        soup.positions.insert(soup.positions.end(), right.positions.begin(), right.positions.end());
        for (const auto& t : right.triangles) soup.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
        soup.materials = {{"stone", {0.5f, 0.5f, 0.5f, 1.0f}}, {"moss", {0.2f, 0.6f, 0.2f, 1.0f}}};
        soup.triangleMaterials.assign(soup.triangles.size(), mossFirst ? 1 : 0);
        std::fill(soup.triangleMaterials.begin() + std::ptrdiff_t(soup.triangles.size() / 2), soup.triangleMaterials.end(), mossFirst ? 0 : 1);
        VoxelizeOptions o;
        o.voxelSize = 0.5;
        const Volume v = voxelizeMesh(soup, o);
        const MaterialId left = *v.materials().find(mossFirst ? "moss" : "stone");
        const MaterialId rightId = *v.materials().find(mossFirst ? "stone" : "moss");
        for (int x = -1; x <= 17; ++x)
            for (int y = -5; y <= 5; ++y)
                for (int z = -5; z <= 5; ++z) {
                    const MaterialId m = v.materialAt({x, y, z});
                    if (m == kEmptyMaterial || x == 8) continue;
                    CHECK(m == (x < 8 ? left : rightId));
                }
        CHECK(checkInvariants(v).empty());
    }
}

TEST_CASE("vertex colours become materials: few exactly, many binned", "[voxelize]")
{
    TempDir dir;
    // Two colours: the x faces red, the others blue.
    writeText(dir.file("two.ply"), colouredCubePly([](int face) { return face < 2 ? std::array<int, 3>{255, 0, 0} : std::array<int, 3>{0, 0, 255}; }));
    const TriangleSoup two = loadTriangleMesh(dir.file("two.ply"));
    REQUIRE(two.triangles.size() == 12);
    CHECK(two.colourMaterials == 2);
    CHECK_FALSE(two.colourBinned);
    std::set<std::string> names;
    for (std::size_t t = 0; t < two.triangles.size(); ++t) names.insert(two.materials[two.triangleMaterials[t]].name);
    CHECK(names == std::set<std::string>{"colour-0000ff", "colour-ff0000"}); // the stray corner outvoted
    const std::size_t red = std::size_t(std::find_if(two.materials.begin(), two.materials.end(),
                                                     [](const MeshMaterial& m) { return m.name == "colour-ff0000"; }) -
                                        two.materials.begin());
    CHECK(two.materials[red].color == std::array<float, 4>{1.0f, 0.0f, 0.0f, 1.0f});
    VoxelizeOptions o;
    o.voxelSize = 0.5;
    const Volume v = voxelizeMesh(two, o);
    CHECK(v.materials().find("colour-ff0000").has_value());
    CHECK(v.materials().find("colour-0000ff").has_value());
    CHECK(checkInvariants(v).empty());

    // Six faces of different colours but each face's 2 triangles alike; then a cube whose faces spread
    // over more than 64 colours per channel mix: binned onto 4 levels per channel.
    writeText(dir.file("six.ply"), colouredCubePly([](int face) { return std::array<int, 3>{40 * face, 255 - 40 * face, 7}; }));
    CHECK(loadTriangleMesh(dir.file("six.ply")).colourMaterials == 6);
    std::string many = "ply\nformat ascii 1.0\nelement vertex 300\nproperty float x\nproperty float y\nproperty float z\n"
                       "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 100\n"
                       "property list uchar int vertex_indices\nend_header\n";
    for (int t = 0; t < 100; ++t)
        for (int c = 0; c < 3; ++c)
            many += std::to_string(t + (c == 1 ? 1 : 0)) + " " + std::to_string(c == 2 ? 1 : 0) + " " + std::to_string(t % 7) + " " +
                    std::to_string((t * 37) % 256) + " " + std::to_string((t * 91) % 256) + " " + std::to_string((t * 13) % 256) + "\n";
    for (int t = 0; t < 100; ++t) many += "3 " + std::to_string(3 * t) + " " + std::to_string(3 * t + 1) + " " + std::to_string(3 * t + 2) + "\n";
    writeText(dir.file("many.ply"), many);
    const TriangleSoup binned = loadTriangleMesh(dir.file("many.ply"));
    CHECK(binned.colourBinned);
    CHECK(binned.colourMaterials <= 64);
    CHECK(binned.colourMaterials > 8);
    for (std::size_t t = 0; t < binned.triangles.size(); ++t) {
        const std::array<float, 4>& c = binned.materials[binned.triangleMaterials[t]].color;
        const int exact[3] = {int((t * 37) % 256), int((t * 91) % 256), int((t * 13) % 256)};
        for (int i = 0; i < 3; ++i) {
            CHECK(std::fabs(c[std::size_t(i)] * 255.0f - float(exact[i])) <= 42.5f + 1e-3f); // the nearest of 0, 85, 170, 255
            CHECK(std::fmod(std::lround(c[std::size_t(i)] * 255.0f), 85) == 0);
        }
    }
}

TEST_CASE("cli: import voxelizes a mesh with its materials and says what it repaired", "[voxelize][cli]")
{
    if (std::string(kCli).empty()) return; // no CLI in this build
    TempDir dir;
    writeText(dir.file("two.mtl"), "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n");
    std::string obj = "mtllib two.mtl\n";
    const char* corners = "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 4\nv 4 0 4\nv 4 4 4\nv 0 4 4\n";
    obj += corners;
    obj += "usemtl red\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nusemtl blue\nf 3 4 8 7\nf 1 5 8 4\nf 2 3 7 6\n";
    writeText(dir.file("cube.obj"), obj);
    const nlohmann::json out = parseJsonOutput(runCli(dir, "import cube.obj --voxel-size 0.5 -o cube.vdbclay --json"));
    CHECK(out["mesh"]["triangles"] == 12);
    CHECK(out["mesh"]["patched_crossings"] == 0);
    CHECK(out["mesh"]["materials"] == nlohmann::json::array({"default", "red", "blue"}));
    const nlohmann::json meshed = parseJsonOutput(runCli(dir, "mesh cube.vdbclay -o cube-out.obj --json"));
    CHECK(meshed["watertight"] == true);
    // VDBClay's own OBJ comes back with its materials' names (from the .mtl beside it), not as the
    // vertex colours it also carries.
    const nlohmann::json back = parseJsonOutput(runCli(dir, "import cube-out.obj --voxel-size 0.5 -o back.vdb --json"));
    std::set<std::string> names;
    for (const auto& name : back["mesh"]["materials"]) names.insert(name.get<std::string>());
    names.erase("default");
    CHECK_FALSE(names.empty());
    for (const std::string& name : names) CHECK((name == "red" || name == "blue"));
    CHECK(back["mesh"]["colour_materials"] == 0);
    const CommandResult text = runCli(dir, "import cube.obj --resolution 16 --material clay -o c.vdb");
    CHECK(text.exitCode == 0);
    CHECK(text.out.find("repaired") != std::string::npos);
    CHECK(parseJsonOutput(runCli(dir, "info c.vdb --json"))["materials"] == nlohmann::json::array({"default", "clay"}));
    checkCleanFailure(runCli(dir, "import cube.obj -o x.vdb"));                 // no voxel size
    checkCleanFailure(runCli(dir, "import cube.obj --resolution 0 -o x.vdb"));
    checkCleanFailure(runCli(dir, "import cube.obj --voxel-size 1 --resolution 4 -o x.vdb"));
    checkCleanFailure(runCli(dir, "import cube.obj --iso 1 --resolution 4 -o x.vdb"));
    const CommandResult unnamed = runCli(dir, "import cube.obj --resolution 4 --material '' -o x.vdb");
    checkCleanFailure(unnamed);
    CHECK(unnamed.exitCode == 2);
    writeText(dir.file("junk.stl"), "solid junk\n garbage\n");
    checkCleanFailure(runCli(dir, "import junk.stl --resolution 8 -o x.vdb"));
    // A lone triangle encloses nothing: refused in both forms, and no empty scene is left behind.
    writeText(dir.file("flat.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    for (const char* output : {"flat.vdb", "flat.vdbclay"}) {
        const CommandResult flat = runCli(dir, std::string("import flat.obj --resolution 16 -o ") + output);
        checkCleanFailure(flat);
        CHECK(flat.exitCode == 1); // the file's content: the command line was right
        CHECK(flat.err.find("encloses no solid") != std::string::npos);
        CHECK_FALSE(std::filesystem::exists(dir.path() / output));
    }
    // Errors say what is wrong in the user's terms: a missing file before missing options, an output
    // whose extension picks no form, a voxel size of zero without quoting the largest double.
    const CommandResult missing = runCli(dir, "import nothere.obj -o x.vdb");
    checkCleanFailure(missing);
    CHECK(missing.err.find("does not exist") != std::string::npos);
    const CommandResult typo = runCli(dir, "import cube.obj --resolution 8 -o x.vbd");
    checkCleanFailure(typo);
    CHECK(typo.err.find(".vdbclay") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.path() / "x.vbd"));
    const CommandResult zero = runCli(dir, "import cube.obj --voxel-size 0 -o x.vdb");
    checkCleanFailure(zero);
    CHECK(zero.err.find("positive") != std::string::npos);
    CHECK(zero.err.size() < 200);
    const CommandResult tiny = runCli(dir, "import cube.obj --voxel-size 1e-9 -o x.vdb");
    checkCleanFailure(tiny);
    CHECK(tiny.err.find("1e-09 is outside 2e-05 .. 1e+06") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.path() / "x.vdb"));
    // A mesh given where a scene is read is pointed at import, in every command that reads scenes.
    for (const char* command : {"info cube.obj", "mesh cube.obj -o m.obj", "sculpt cube.obj s.json -o x.vdb", "export cube.obj -o x.vdb",
                                "export-levelset cube.obj -o x.vdb", "diff c.vdb cube.obj", "tool make cube.obj -o t.vdb"}) {
        CAPTURE(command);
        const CommandResult mesh = runCli(dir, command);
        checkCleanFailure(mesh);
        CHECK(mesh.exitCode == 2);
        CHECK(mesh.err.find("'cube.obj' is a mesh, not a scene: bring it in first with 'vdbclay import cube.obj") != std::string::npos);
    }
}

TEST_CASE("a glTF reads its buffers from inside its own folder only", "[voxelize]")
{
    TempDir model, elsewhere;
    // A tetrahedron: 4 float positions and 12 uint16 indices in one buffer.
    const float positions[12] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 0, 0, 4};
    const uint16_t indices[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
    std::string bin(reinterpret_cast<const char*>(positions), sizeof positions);
    bin.append(reinterpret_cast<const char*>(indices), sizeof indices);
    writeText(model.file("tet.bin"), bin);
    writeText(elsewhere.file("secret.bin"), bin);
    std::filesystem::create_directories(model.path() / "sub");
    writeText(model.file("sub/inner.bin"), bin);
    const auto gltf = [&](const std::string& uri) {
        return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"uri": ")" + uri + R"(", "byteLength": 72}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [4, 4, 4]},
                          {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}]})";
    };
    writeText(model.file("inside.gltf"), gltf("tet.bin"));
    writeText(model.file("nested.gltf"), gltf("sub/inner.bin"));
    writeText(model.file("absolute.gltf"), gltf(elsewhere.file("secret.bin")));
    writeText(model.file("climbing.gltf"), gltf("../" + elsewhere.path().filename().string() + "/secret.bin"));
    CHECK(loadTriangleMesh(model.file("inside.gltf")).triangles.size() == 4);
    CHECK(loadTriangleMesh(model.file("nested.gltf")).triangles.size() == 4);
    for (const char* name : {"absolute.gltf", "climbing.gltf"}) {
        CAPTURE(name);
        CHECK_THROWS_AS(loadTriangleMesh(model.file(name)), MeshImportError);
    }
}

namespace {

/// Whether every directed edge of the soup has its reverse exactly once and appears once itself: a closed
/// surface whose triangles all turn the same way.
bool closedAndConsistent(const TriangleSoup& soup)
{
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (const auto& t : soup.triangles)
        for (int k = 0; k < 3; ++k) ++edges[{t[std::size_t(k)], t[std::size_t((k + 1) % 3)]}];
    for (const auto& [edge, count] : edges) {
        const auto reverse = edges.find({edge.second, edge.first});
        if (count != 1 || reverse == edges.end() || reverse->second != 1) return false;
    }
    return !edges.empty();
}

/// The signed volume the soup encloses (enclosedVolume of the same triangles as a mesh).
double signedVolume(const TriangleSoup& soup)
{
    Mesh mesh;
    for (const auto& p : soup.positions) mesh.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
    mesh.triangles = soup.triangles;
    return enclosedVolume(mesh);
}

} // namespace

TEST_CASE("a PLY of triangle strips is read: -1 restarts a strip, every other triangle turns back, the surface is closed", "[voxelize]")
{
    TempDir dir;
    // A tetrahedron as four one-triangle strips (binary, little-endian), as one strip of six corners whose
    // triangles alternate (ASCII), and as that strip in big-endian with 16-bit indices and a stitch.
    const float vertices[12] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 0, 0, 4};
    const int32_t strip[16] = {0, 2, 1, -1, 0, 1, 3, -1, 1, 2, 3, -1, 0, 3, 2, -1};
    const std::string header = "format binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
    std::string ply = "ply\n" + header + "element tristrips 1\nproperty list int int vertex_indices\nend_header\n";
    ply.append(reinterpret_cast<const char*>(vertices), sizeof vertices);
    const int32_t count = 16;
    ply.append(reinterpret_cast<const char*>(&count), sizeof count);
    ply.append(reinterpret_cast<const char*>(strip), sizeof strip);
    writeText(dir.file("strips.ply"), ply);
    writeText(dir.file("one.ply"), "ply\nformat ascii 1.0\ncomment one strip\nelement vertex 4\nproperty float x\nproperty float y\n"
                                    "property float z\nproperty uchar red\nelement tristrips 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n0 0 0 9\n4 0 0 9\n0 4 0 9\n0 0 4 9\n6 0 2 1 3 0 2\n");
    std::string big = "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
                      "element tristrips 1\nproperty list uchar short vertex_indices\nend_header\n";
    const auto putBig = [&](const void* value, std::size_t bytes) {
        const auto* p = static_cast<const char*>(value);
        for (std::size_t i = bytes; i-- > 0;) big.push_back(p[i]);
    };
    for (float v : vertices) {
        const double d = v;
        putBig(&d, 8);
    }
    const int16_t stitched[] = {0, 2, 1, 3, 0, 2, 2, -1}; // the last corner repeats (a stitch), then the strip ends
    big.push_back(char(std::size(stitched)));
    for (int16_t i : stitched) putBig(&i, 2);
    writeText(dir.file("big.ply"), big);

    double volume = 0.0;
    for (const char* name : {"strips.ply", "one.ply", "big.ply"}) {
        CAPTURE(name);
        const TriangleSoup soup = loadTriangleMesh(dir.file(name));
        CHECK(soup.triangles.size() == 4);
        CHECK(soup.droppedTriangles == 0);
        CHECK(closedAndConsistent(soup));
        // The same orientation whatever the form: the tetrahedron's volume (4^3 / 6), outward-facing.
        const double v = signedVolume(soup);
        CHECK(std::fabs(std::fabs(v) - 64.0 / 6.0) < 1e-6);
        if (volume == 0.0) volume = v;
        CHECK(v == volume);
    }
    // The strip file voxelizes into a solid as the same tetrahedron given as faces does.
    writeText(dir.file("faces.obj"), "v 0 0 0\nv 4 0 0\nv 0 4 0\nv 0 0 4\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n");
    REQUIRE(runCli(dir, "import strips.ply -o a.vdb --voxel-size 0.25").exitCode == 0);
    REQUIRE(runCli(dir, "import faces.obj -o b.vdb --voxel-size 0.25").exitCode == 0);
    CHECK(runCli(dir, "diff a.vdb b.vdb").exitCode == 0);
    // A damaged strip file is refused in one line.
    writeText(dir.file("short.ply"), ply.substr(0, ply.size() - 8));
    CHECK_THROWS_AS(loadTriangleMesh(dir.file("short.ply")), MeshImportError);
}
