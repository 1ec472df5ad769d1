// Standard .vdb files of other tools: described, checked before OpenVDB parses them, and level sets or
// fog volumes imported as Hermite data within error bounds of the analytic surface.
#include "interop/LevelSetExport.h"
#include "interop/LevelSetImport.h"
#include "scene/LevelSetToStore.h"
#include "interop/StandardVdb.h"
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "support/CliRun.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "support/PyramidCompare.h"
#include "support/TestUtil.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/Quantize.h"
#include "vdb_hermite/VolumeIO.h"

#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

struct FileOptions {
    uint32_t compression = openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK;
    bool half = false;
};

/// A level-set sphere as OpenVDB's tools make it, with a fog volume and an int grid beside it.
std::string writeSphereFile(const TempDir& dir, const std::string& name, double radius, double voxelSize,
                            const openvdb::Vec3f& centre, const FileOptions& o = {},
                            openvdb::math::Transform::Ptr transform = nullptr)
{
    openvdb::initialize();
    openvdb::FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(radius), centre, float(voxelSize));
    if (transform) {
        openvdb::FloatGrid::Ptr moved = openvdb::FloatGrid::create(sphere->background());
        moved->setTransform(transform);
        moved->setGridClass(openvdb::GRID_LEVEL_SET);
        openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(*sphere, *moved);
        sphere = moved;
    }
    sphere->setName("surface");
    sphere->setSaveFloatAsHalf(o.half);
    openvdb::FloatGrid::Ptr fog = sphere->deepCopy();
    openvdb::tools::sdfToFogVolume(*fog);
    fog->setName("density");
    openvdb::Int32Grid::Ptr ids = openvdb::Int32Grid::create(0);
    ids->setName("ids");
    ids->tree().setValue(openvdb::Coord(1, 2, 3), 7);
    const std::string path = dir.file(name);
    openvdb::io::File file(path);
    file.setCompression(o.compression);
    file.write({sphere, fog, ids});
    file.close();
    return path;
}

/// The largest distance, in voxels, of an imported volume's crossings from the sphere's surface, and
/// whether every lattice point farther than `margin` voxels from it has the right sign.
struct SphereError {
    double crossing = 0.0;
    uint64_t wrongSigns = 0;
    uint64_t crossings = 0;
};

SphereError sphereError(const Volume& v, double radius, const openvdb::Vec3d& centre, double margin)
{
    SphereError e;
    const double vs = v.voxelSize();
    const HermiteTree& tree = v.impl().grid->constTree();
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf)
        for (Index i = 0; i < Index(kLeafVoxels); ++i) {
            const Coord p = leaf->offsetToGlobalCoord(i);
            const openvdb::Vec3d w(p.x() * vs, p.y() * vs, p.z() * vs);
            const double d = ((w - centre).length() - radius) / vs;
            if (std::fabs(d) > margin && (d < 0.0) != leaf->getValue(i).solid()) ++e.wrongSigns;
            for (int axis = 0; axis < 3; ++axis) {
                const PackedSample* s = leaf->sample(i, axis);
                if (!s) continue;
                openvdb::Vec3d x = w;
                x[axis] += unpackSample(*s).offset * vs;
                e.crossing = std::max(e.crossing, std::fabs((x - centre).length() - radius) / vs);
                ++e.crossings;
            }
        }
    return e;
}

bool closedMesh(const Volume& v)
{
    MeshOptions cms;
    cms.kind = MesherKind::CubicalMarchingSquares;
    const Mesh mesh = meshVolume(v, cms);
    return mesh.triangleCount() > 0 && analyzeTopology(mesh, kMergeDistanceVoxels * v.voxelSize()).watertight();
}

} // namespace

TEST_CASE("a standard .vdb is described: grid names, classes, value types", "[interop]")
{
    TempDir dir;
    const std::string path = writeSphereFile(dir, "s.vdb", 10.0, 0.5, {0, 0, 0});
    CHECK(classifyVdbFile(path) == VdbFileKind::Other);
    const StandardVdbInfo info = describeStandardVdb(path);
    REQUIRE(info.grids.size() == 3);
    CHECK(info.grids[0].header.name == "surface");
    CHECK(info.grids[0].levelSet());
    CHECK(info.grids[0].header.valueType == "float");
    CHECK(info.grids[0].voxelSize[0] == Approx(0.5));
    CHECK(info.grids[0].uniformVoxels);
    CHECK(info.grids[1].fogVolume());
    CHECK(info.grids[2].header.valueType == "int32");
    CHECK_FALSE(info.grids[2].importable());
    CHECK(&chooseImportGrid(info, "", path) == &info.grids[0]);
    CHECK(&chooseImportGrid(info, "density", path) == &info.grids[1]);
    CHECK_THROWS_AS(chooseImportGrid(info, "ids", path), VolumeIOError);
    CHECK_THROWS_AS(chooseImportGrid(info, "missing", path), VolumeIOError);
    // VDBClay's own files are told apart by their trailer.
    Volume ours(1.0);
    saveVolume(ours, dir.file("ours.vdb"));
    CHECK(classifyVdbFile(dir.file("ours.vdb")) == VdbFileKind::VdbClay);
}

TEST_CASE("a level set imports within a tenth of a voxel of the sphere, for every compression", "[interop]")
{
    TempDir dir;
    const double radius = 12.0, vs = 0.5;
    const openvdb::Vec3d centre(1.25, -0.5, 3.0);
    int index = 0;
    for (const FileOptions& o : {FileOptions{}, FileOptions{openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK, false},
                                 FileOptions{openvdb::io::COMPRESS_NONE, false}, FileOptions{openvdb::io::COMPRESS_BLOSC, true},
                                 FileOptions{openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK, true}}) {
        CAPTURE(index);
        const std::string path = writeSphereFile(dir, "s" + std::to_string(index++) + ".vdb", radius, vs, centre, o);
        LevelSetImportReport report;
        const Volume v = importLevelSet(path, {}, &report);
        CHECK(report.grid == "surface");
        CHECK(report.resampled.empty());
        CHECK(v.voxelSize() == vs);
        CHECK(checkInvariants(v).empty());
        const SphereError e = sphereError(v, radius, centre, 0.5);
        CHECK(e.wrongSigns == 0);
        CHECK(e.crossings == report.crossings);
        CHECK(e.crossings > 1000);
        // Linear interpolation of a sampled distance, plus half-float rounding where saved as half.
        CHECK(e.crossing < (o.half ? 0.1 : 0.05));
        CHECK(closedMesh(v));
    }
}

TEST_CASE("a fog volume imports at an iso value, without one it is refused", "[interop]")
{
    TempDir dir;
    const double radius = 10.0, vs = 0.5;
    const std::string path = writeSphereFile(dir, "s.vdb", radius, vs, {0, 0, 0});
    LevelSetImportOptions o;
    o.grid = "density";
    CHECK_THROWS_AS(importLevelSet(path, o), std::invalid_argument);
    o.iso = 0.5; // sdfToFogVolume: density 0 at the surface, 1 a half-band inside
    LevelSetImportReport report;
    const Volume v = importLevelSet(path, o, &report);
    CHECK(report.fog);
    CHECK(checkInvariants(v).empty());
    CHECK(closedMesh(v));
    // Density 0.5 lies half a band (3 voxels) inside: 1.5 voxels deep.
    const SphereError e = sphereError(v, radius - 1.5 * vs, {0, 0, 0}, 0.5);
    CHECK(e.wrongSigns == 0);
    CHECK(e.crossing < 0.1);

    // A dense tile beside empty space, with no leaf between them: the crossings on the tile's faces.
    openvdb::FloatGrid::Ptr block = openvdb::FloatGrid::create(0.0f);
    block->setName("block");
    block->setGridClass(openvdb::GRID_FOG_VOLUME);
    block->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(127)), 1.0f, true);
    REQUIRE(block->tree().leafCount() == 0);
    openvdb::io::File file(dir.file("block.vdb"));
    file.write({block});
    file.close();
    o.grid.clear(); // the first fog volume
    const Volume cube = importLevelSet(dir.file("block.vdb"), o);
    CHECK(checkInvariants(cube).empty());
    MeshOptions cms;
    cms.kind = MesherKind::CubicalMarchingSquares;
    const Mesh mesh = meshVolume(cube, cms);
    CHECK(analyzeTopology(mesh, kMergeDistanceVoxels).watertight());
    CHECK(enclosedVolume(mesh) == Approx(128.0 * 128.0 * 128.0).epsilon(1e-3)); // crossings half-way: -0.5 .. 127.5
}

TEST_CASE("a grid of no class is a density when its background is below the iso value, a solid background is refused",
          "[interop]")
{
    TempDir dir;
    // As many tools write a density: no class, background 0, dense tiles inside (no leaf between them
    // and empty space), one leaf with a single denser voxel.
    openvdb::FloatGrid::Ptr block = openvdb::FloatGrid::create(0.0f);
    block->setName("density");
    block->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(255)), 1.0f, true);
    block->tree().setValue(openvdb::Coord(300, 300, 300), 2.0f);
    REQUIRE(block->tree().leafCount() == 1);
    openvdb::io::File file(dir.file("block.vdb"));
    file.write({block});
    file.close();

    LevelSetImportOptions o;
    o.iso = 0.5;
    LevelSetImportReport report;
    const Volume cube = importLevelSet(dir.file("block.vdb"), o, &report);
    CHECK(report.fog);
    CHECK(checkInvariants(cube).empty());
    MeshOptions cms;
    cms.kind = MesherKind::CubicalMarchingSquares;
    const Mesh mesh = meshVolume(cube, cms);
    CHECK(analyzeTopology(mesh, kMergeDistanceVoxels).watertight());
    // The block (crossings half-way: -0.5 .. 255.5) and the lone voxel's octahedron-like cell.
    CHECK(enclosedVolume(mesh) == Approx(256.0 * 256.0 * 256.0).epsilon(1e-4));
    const CoordBBox bounds = cube.impl().grid->evalActiveVoxelBoundingBox();
    CHECK(bounds.min().x() >= -8);
    CHECK(bounds.max().x() <= 308);

    // Without an iso value it reads as a level set (solid below 0): nothing is.
    const Volume none = importLevelSet(dir.file("block.vdb"), {}, &report);
    CHECK_FALSE(report.fog);
    CHECK(none.impl().grid->tree().activeVoxelCount() == 0);

    // A reading that makes the background solid would fill everything outside the grid: refused.
    block->setGridClass(openvdb::GRID_FOG_VOLUME);
    openvdb::io::File fogFile(dir.file("fog.vdb"));
    fogFile.write({block});
    fogFile.close();
    o.iso = -0.5;
    CHECK_THROWS_WITH(importLevelSet(dir.file("fog.vdb"), o), Catch::Contains("solid everywhere outside"));
    const std::string sphere = writeSphereFile(dir, "s.vdb", 10.0, 0.5, {0, 0, 0});
    o.grid = "surface";
    o.iso = 100.0; // above the level set's background
    CHECK_THROWS_WITH(importLevelSet(sphere, o), Catch::Contains("solid everywhere outside"));
}

TEST_CASE("a grid holding NaN or infinity is refused as damaged, with where", "[interop]")
{
    TempDir dir;
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        openvdb::FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(6.0f, openvdb::Vec3f(0.0f), 1.0f);
        sphere->setName("surface");
        sphere->tree().setValueOn(openvdb::Coord(6, 0, 0), bad); // on the surface, beside solid and empty points
        openvdb::io::File file(dir.file("bad.vdb"));
        file.write({sphere});
        file.close();
        CHECK_THROWS_WITH(importLevelSet(dir.file("bad.vdb"), {}),
                          Catch::Contains("1 value that is not a finite number") && Catch::Contains("(6, 0, 0)"));
        // The same grid without it imports.
        sphere->tree().setValueOn(openvdb::Coord(6, 0, 0), 0.0f);
        openvdb::io::File good(dir.file("good.vdb"));
        good.write({sphere});
        good.close();
        CHECK(checkInvariants(importLevelSet(dir.file("good.vdb"), {})).empty());
    }
}

TEST_CASE("grids that share a name are each picked by their typed name and give their own data", "[interop]")
{
    TempDir dir;
    openvdb::initialize();
    // A fog volume and a level set both named "surface", the fog first (OpenVDB allows it).
    openvdb::FloatGrid::Ptr fog = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(3.0f, openvdb::Vec3f(0.0f), 0.5f);
    openvdb::tools::sdfToFogVolume(*fog);
    fog->setName("surface");
    openvdb::FloatGrid::Ptr ls = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(5.0f, openvdb::Vec3f(0.0f), 0.5f);
    ls->setName("surface");
    {
        openvdb::io::File file(dir.file("dup.vdb"));
        file.write({fog, ls});
        openvdb::io::File alone(dir.file("ls.vdb"));
        alone.write({ls});
        openvdb::io::File fogAlone(dir.file("fog.vdb"));
        fogAlone.write({fog});
    }
    const StandardVdbInfo info = describeStandardVdb(dir.file("dup.vdb"));
    REQUIRE(info.grids.size() == 2);
    CHECK(info.grids[0].name == "surface[0]");
    CHECK(info.grids[1].name == "surface[1]");
    CHECK(info.grids[0].baseName == "surface");
    // The default takes the level set, and reads the level set's data: the same volume as a file of it alone.
    LevelSetImportReport report;
    const Volume picked = importLevelSet(dir.file("dup.vdb"), {}, &report);
    CHECK(report.grid == "surface[1]");
    CHECK(picked.stats().activeVoxels == importLevelSet(dir.file("ls.vdb"), {}).stats().activeVoxels);
    CHECK(sameContent(picked, importLevelSet(dir.file("ls.vdb"), {})));
    LevelSetImportOptions first;
    first.grid = "surface[0]";
    first.iso = 0.5;
    LevelSetImportOptions fogSurface;
    fogSurface.grid = "surface";
    fogSurface.iso = 0.5;
    CHECK(sameContent(importLevelSet(dir.file("dup.vdb"), first), importLevelSet(dir.file("fog.vdb"), fogSurface)));
    // The shared name alone is ambiguous: refused, naming both typed names.
    LevelSetImportOptions shared;
    shared.grid = "surface";
    try {
        importLevelSet(dir.file("dup.vdb"), shared);
        FAIL("an ambiguous name was accepted");
    } catch (const VolumeIOError& e) {
        CHECK(std::string(e.what()).find("'surface[0]', 'surface[1]'") != std::string::npos);
    }
}

TEST_CASE("a grid beyond what the lattice indexes is refused at once, naming the position and the limit", "[interop]")
{
    TempDir dir;
    for (const double shift : {1e12, -3e9, 1e12 + 0.3}) { // on the lattice, and off it (resampling would run)
        CAPTURE(shift);
        openvdb::initialize();
        openvdb::FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(5.0f, openvdb::Vec3f(0.0f), 0.5f);
        sphere->transform().postTranslate(openvdb::Vec3d(shift, 0.0, 0.0)); // the same voxels, moved
        sphere->setName("surface");
        const std::string path = dir.file("far.vdb");
        openvdb::io::File(path).write({sphere});
        try {
            importLevelSet(path, {});
            FAIL("a grid beyond the lattice was imported");
        } catch (const VolumeIOError& e) {
            CHECK(std::string(e.what()).find("lattice indexes at most") != std::string::npos);
        }
    }
}

TEST_CASE("a grid imported into a store brick by brick equals its import into memory", "[interop][store]")
{
    TempDir dir;
    openvdb::initialize();
    // A solid of inside tiles across negative and positive bricks (a 512-voxel cube whose faces are
    // the level set's only leaves), a sphere with a fog beside it, a grid resampled off the lattice.
    openvdb::FloatGrid::Ptr cube = openvdb::FloatGrid::create(1.5f);
    cube->setName("surface");
    cube->setGridClass(openvdb::GRID_LEVEL_SET);
    cube->tree().fill(openvdb::CoordBBox(openvdb::Coord(-300, -40, -257), openvdb::Coord(211, 471, 254)), -1.5f, true);
    openvdb::io::File(dir.file("cube.vdb")).write({cube});
    const std::string spheres = writeSphereFile(dir, "s.vdb", 10.0, 0.5, {3.3f, -2.2f, 7.1f});
    openvdb::math::Transform::Ptr rotated = openvdb::math::Transform::createLinearTransform(0.5);
    rotated->postRotate(0.4, openvdb::math::Z_AXIS);
    const std::string turned = writeSphereFile(dir, "r.vdb", 6.0, 0.5, {1.0f, 2.0f, 3.0f}, {}, rotated);
    struct Case {
        std::string file;
        LevelSetImportOptions options;
    };
    LevelSetImportOptions fog;
    fog.grid = "density";
    fog.iso = 0.5;
    fog.material = "fog";
    for (const Case& c : {Case{dir.file("cube.vdb"), {}}, Case{spheres, {}}, Case{spheres, fog}, Case{turned, {}}}) {
        CAPTURE(c.file, c.options.grid);
        LevelSetImportReport whole;
        const Volume expected = importLevelSet(c.file, c.options, &whole);
        const std::string store = dir.file("out.vdbclay");
        std::filesystem::remove(store);
        const StoreLevelSetReport stored = importLevelSetToStore(c.file, c.options, store);
        const Volume got = loadScene(store);
        CHECK(sameContent(got, expected));
        CHECK(got.materials() == expected.materials());
        CHECK(stored.levelSet.crossings == whole.crossings);
        CHECK(stored.activeVoxels == expected.stats().activeVoxels);
    }
}

TEST_CASE("a rotated, non-uniform or offset grid is resampled onto the lattice, and says so", "[interop]")
{
    TempDir dir;
    const double radius = 8.0;
    openvdb::math::Transform::Ptr rotated = openvdb::math::Transform::createLinearTransform(0.5);
    rotated->postRotate(0.4, openvdb::math::Y_AXIS);
    openvdb::math::Transform::Ptr offset = openvdb::math::Transform::createLinearTransform(0.5);
    offset->postTranslate(openvdb::Vec3d(0.2, 0.0, 0.0));
    openvdb::math::Transform::Ptr scaled = openvdb::math::Transform::createLinearTransform(0.5);
    scaled->postScale(openvdb::Vec3d(1.0, 1.2, 1.0));
    int index = 0;
    for (const auto& transform : {rotated, offset, scaled}) {
        CAPTURE(index);
        const std::string path = writeSphereFile(dir, "r" + std::to_string(index++) + ".vdb", radius, 0.5, {0, 0, 0}, {}, transform);
        LevelSetImportOptions o;
        o.voxelSize = 0.5;
        LevelSetImportReport report;
        const Volume v = importLevelSet(path, o, &report);
        CHECK_FALSE(report.resampled.empty());
        CHECK(checkInvariants(v).empty());
        const SphereError e = sphereError(v, radius, {0, 0, 0}, 1.0);
        CHECK(e.wrongSigns == 0);
        CHECK(e.crossing < 0.35); // two trilinear resamplings of a distance field
        CHECK(closedMesh(v));
    }
    // Another voxel size is a resampling too.
    LevelSetImportOptions o;
    o.voxelSize = 0.25;
    LevelSetImportReport report;
    const Volume v = importLevelSet(writeSphereFile(dir, "fine.vdb", radius, 0.5, {0, 0, 0}), o, &report);
    CHECK(v.voxelSize() == 0.25);
    CHECK_FALSE(report.resampled.empty());
    CHECK(sphereError(v, radius, {0, 0, 0}, 1.0).wrongSigns == 0);
}

TEST_CASE("damaged standard files are refused with one line, never a crash", "[interop][fuzz]")
{
    TempDir dir;
    const std::string path = writeSphereFile(dir, "s.vdb", 6.0, 0.5, {0, 0, 0});
    const std::vector<char> original = readBytes(path);
    const std::string bytes(original.begin(), original.end());
    std::mt19937 rng(17);
    int refused = 0;
    for (int trial = 0; trial < 150; ++trial) {
        std::string damaged = bytes;
        const int kind = trial % 3;
        if (kind == 0) damaged.resize(rng() % damaged.size());
        else if (kind == 1)
            for (int k = 0; k < 4; ++k) damaged[rng() % damaged.size()] = char(rng());
        else
            for (std::size_t k = 0; k < 8; ++k) damaged[std::min(damaged.size() - 1, std::size_t(rng() % 400) + k)] = char(0xff);
        const std::string copy = dir.file("d.vdb");
        writeText(copy, damaged);
        try {
            const Volume v = importLevelSet(copy, {});
            CHECK(checkInvariants(v).empty());
        } catch (const VolumeIOError& e) {
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
            ++refused;
        } catch (const std::invalid_argument& e) {
            ++refused;
        }
    }
    CHECK(refused > 50);
}

TEST_CASE("cli: info describes a standard .vdb, import brings it in, other commands say how", "[interop][cli]")
{
    if (std::string(kCli).empty()) return; // no CLI in this build
    TempDir dir;
    writeSphereFile(dir, "houdini.vdb", 8.0, 0.5, {0, 0, 0});
    const nlohmann::json info = parseJsonOutput(runCli(dir, "info houdini.vdb --json"));
    CHECK(info["form"] == "standard");
    REQUIRE(info["grids"].size() == 3);
    CHECK(info["grids"][0]["name"] == "surface");
    CHECK(info["grids"][0]["class"] == "level set");
    CHECK(info["grids"][0]["value_type"] == "float");
    CHECK(info["grids"][0]["importable"] == true);
    CHECK(info["grids"][2]["importable"] == false);
    const CommandResult text = runCli(dir, "info houdini.vdb");
    CHECK(text.exitCode == 0);
    CHECK(text.out.find("vdbclay import houdini.vdb") != std::string::npos);

    const CommandResult mesh = runCli(dir, "mesh houdini.vdb -o m.obj");
    checkCleanFailure(mesh);
    CHECK(mesh.err.find("'surface' (level set, float)") != std::string::npos);
    CHECK(mesh.err.find("vdbclay import") != std::string::npos);

    const nlohmann::json imported = parseJsonOutput(runCli(dir, "import houdini.vdb -o s.vdbclay --json"));
    CHECK(imported["levelset"]["grid"] == "surface");
    CHECK(imported["levelset"]["resampled"] == false);
    const nlohmann::json fog = parseJsonOutput(runCli(dir, "import houdini.vdb --grid density --iso 0.5 --material fog -o f.vdb --json"));
    CHECK(fog["levelset"]["fog"] == true);
    CHECK(parseJsonOutput(runCli(dir, "info f.vdb --json"))["materials"] == nlohmann::json::array({"default", "fog"}));
    const nlohmann::json meshed = parseJsonOutput(runCli(dir, "mesh s.vdbclay -o s.obj --json"));
    CHECK(meshed["watertight"] == true);

    checkCleanFailure(runCli(dir, "import houdini.vdb --grid density -o x.vdb")); // fog without --iso
    // A reading with no solid voxel (the density never exceeds 2) would write an empty scene: refused.
    const CommandResult empty = runCli(dir, "import houdini.vdb --grid density --iso 2 -o x.vdb");
    checkCleanFailure(empty);
    CHECK(empty.exitCode == 1); // the file's content, not the command line
    CHECK_THAT(empty.err, Catch::Contains("holds no solid voxel"));
    for (const char* iso : {"nan", "inf", "-inf"}) { // every comparison with NaN is false: nothing was solid
        INFO(iso);
        const CommandResult r = runCli(dir, std::string("import houdini.vdb --grid density --iso ") + iso + " -o x.vdb");
        checkCleanFailure(r);
        CHECK(r.exitCode == 2);
    }
    checkCleanFailure(runCli(dir, "import houdini.vdb --grid ids -o x.vdb"));
    checkCleanFailure(runCli(dir, "import houdini.vdb --grid nothing -o x.vdb"));
    checkCleanFailure(runCli(dir, "import s.vdbclay --iso 2 -o x.vdb")); // options for standard files only
    CHECK_FALSE(std::filesystem::exists(dir.path() / "x.vdb"));
}


TEST_CASE("export-levelset writes standard grids: a level set with the right sign and distances, materials, a fog", "[interop]")
{
    TempDir dir;
    Volume v(0.5);
    Material redMaterial;
    redMaterial.name = "red";
    const MaterialId red = v.materials().define(redMaterial);
    const double radius = 8.0;
    apply(v, CsgMode::Add, sphere(radius), at({0.0, 0.0, 0.0}), 1);
    apply(v, CsgMode::Paint, box({10.0, 10.0, 10.0}), at({10.0, 0.0, 0.0}), red); // x >= 0 is red
    LevelSetExportOptions o;
    o.fog = true;
    LevelSetExportReport report;
    exportLevelSet(v, dir.file("out.vdb"), o, &report);
    CHECK(report.triangles > 0);

    openvdb::io::File file(dir.file("out.vdb"));
    file.open();
    openvdb::FloatGrid::Ptr surface = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("surface"));
    openvdb::FloatGrid::Ptr material = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("material"));
    openvdb::FloatGrid::Ptr density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
    file.close();
    REQUIRE(surface);
    REQUIRE(material);
    REQUIRE(density);
    CHECK(surface->getGridClass() == openvdb::GRID_LEVEL_SET);
    CHECK(density->getGridClass() == openvdb::GRID_FOG_VOLUME);
    CHECK(surface->voxelSize()[0] == Approx(0.5));
    CHECK(surface->background() == Approx(1.5f)); // three voxels of 0.5

    // Every lattice point within a voxel of the sphere: the right sign, the distance within a tenth of
    // a voxel (the CMS mesh's own error), and the material of the solid side.
    const auto values = surface->getConstAccessor();
    const auto ids = material->getConstAccessor();
    const auto fog = density->getConstAccessor();
    uint64_t near = 0;
    for (int x = -20; x <= 20; ++x)
        for (int y = -20; y <= 20; ++y)
            for (int z = -20; z <= 20; ++z) {
                const openvdb::Coord c(x, y, z);
                const double exact = (std::sqrt(double(x * x + y * y + z * z)) * 0.5 - radius) / 0.5;
                if (exact < -3.0) CHECK(values.getValue(c) < 0.0f);
                if (std::fabs(exact) > 1.0) continue;
                ++near;
                CHECK(std::fabs(values.getValue(c) / 0.5 - exact) < 0.1);
                if (exact < -0.1) {
                    CHECK(ids.getValue(c) == (x >= 0 ? float(red) : 1.0f)); // the paint box starts at x = 0
                    CHECK(fog.getValue(c) > 0.0f);
                }
                if (exact > 0.1) CHECK(ids.getValue(c) == 0);
            }
    CHECK(near > 1000);
    CHECK(ids.getValue(openvdb::Coord(-4, 0, 0)) == 1.0f);
    CHECK(ids.getValue(openvdb::Coord(4, 0, 0)) == float(red));
    CHECK(fog.getValue(openvdb::Coord(0, 0, 0)) == 1.0f);
    CHECK(fog.getValue(openvdb::Coord(40, 0, 0)) == 0.0f);
    CHECK_THROWS_AS(exportLevelSet(v, dir.file("bad.vdb"), LevelSetExportOptions{0.5, false}), std::invalid_argument);

    // On request the same ids as an Int32Grid, voxel for voxel.
    o.int32Material = true;
    exportLevelSet(v, dir.file("int.vdb"), o);
    openvdb::io::File intFile(dir.file("int.vdb"));
    intFile.open();
    openvdb::Int32Grid::Ptr intIds = openvdb::gridPtrCast<openvdb::Int32Grid>(intFile.readGrid("material"));
    intFile.close();
    REQUIRE(intIds);
    CHECK(intIds->activeVoxelCount() == material->activeVoxelCount());
    for (auto it = material->cbeginValueOn(); it; ++it) CHECK(float(intIds->tree().getValue(it.getCoord())) == *it);
}

TEST_CASE("import, export-levelset, import again loses no more than quantization", "[interop]")
{
    TempDir dir;
    const std::string path = writeSphereFile(dir, "s.vdb", 10.0, 0.5, {0.3f, -0.2f, 0.1f});
    const Volume first = importLevelSet(path, {});
    exportLevelSet(first, dir.file("back.vdb"), {});
    const Volume second = importLevelSet(dir.file("back.vdb"), {});
    // The same solid lattice points and crossing edges, but where the surface passes within a hair of
    // a lattice point (the level set's distances are measured to the CMS mesh, which may pass that point
    // on its other side); crossings within a few hundredths of a voxel.
    const HermiteTree& a = first.impl().grid->constTree();
    const HermiteTree& b = second.impl().grid->constTree();
    uint64_t compared = 0, differing = 0;
    double worst = 0.0;
    for (auto leaf = a.cbeginLeaf(); leaf; ++leaf) {
        const HermiteLeaf* other = b.probeConstLeaf(leaf->origin());
        REQUIRE(other);
        for (Index i = 0; i < Index(kLeafVoxels); ++i) {
            if (leaf->getValue(i) != other->getValue(i)) {
                ++differing;
                // Such a point lies a hair from the surface: one of its edges crosses right beside it.
                bool beside = false;
                for (int axis = 0; axis < 3; ++axis)
                    if (const PackedSample* s = leaf->sample(i, axis)) beside = beside || unpackSample(*s).offset < 0.02;
                const Coord p = leaf->offsetToGlobalCoord(i);
                for (int axis = 0; axis < 3; ++axis) {
                    Coord q = p;
                    q[axis] -= 1;
                    const HermiteLeaf* below = a.probeConstLeaf(q);
                    if (!below) continue;
                    if (const PackedSample* s = below->sample(below->coordToOffset(q), axis)) beside = beside || unpackSample(*s).offset > 0.98;
                }
                CHECK(beside);
                continue;
            }
            for (int axis = 0; axis < 3; ++axis) {
                const PackedSample* s = leaf->sample(i, axis);
                const PackedSample* t = other->sample(i, axis);
                if (!s || !t) continue; // an edge of a point that changed side
                worst = std::max(worst, double(std::fabs(unpackSample(*s).offset - unpackSample(*t).offset)));
                ++compared;
            }
        }
    }
    CHECK(compared > 1000);
    CHECK(differing * 100 < compared);
    CHECK(worst < 0.05);
}

TEST_CASE("cli: export-levelset writes a file the stock OpenVDB tools read", "[interop][cli]")
{
    if (std::string(kCli).empty()) return; // no CLI in this build
    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape box --size 6 --voxel-size 0.5").exitCode == 0);
    const nlohmann::json out = parseJsonOutput(runCli(dir, "export-levelset s.vdb -o ls.vdb --fog --half-width 4 --json"));
    CHECK(out["grids"] == nlohmann::json::array({"surface", "material", "density"}));
    CHECK(out["surface_voxels"].get<uint64_t>() > 0);
    const nlohmann::json info = parseJsonOutput(runCli(dir, "info ls.vdb --json"));
    CHECK(info["form"] == "standard");
    checkCleanFailure(runCli(dir, "export-levelset s.vdb -o x.vdbclay"));
    checkCleanFailure(runCli(dir, "export-levelset s.vdb -o x.vdb --half-width 0"));
    checkCleanFailure(runCli(dir, "export-levelset missing.vdb -o x.vdb"));
    CHECK_FALSE(std::filesystem::exists(dir.path() / "x.vdb"));
    // Debian's vdb_print and pyopenvdb (scripts/bootstrap.sh installs both) read it as theirs.
    if (std::system("command -v vdb_print >/dev/null 2>&1") == 0) {
        const std::string cmd = "vdb_print -l " + dir.file("ls.vdb") + " > " + dir.file("print.txt") + " 2>&1";
        CHECK(std::system(cmd.c_str()) == 0);
        const std::vector<char> text = readBytes(dir.file("print.txt"));
        const std::string printed(text.begin(), text.end());
        CHECK(printed.find("class: level set") != std::string::npos);
        CHECK(printed.find("class: fog volume") != std::string::npos);
        CHECK(printed.find("material") != std::string::npos);
    }
    if (std::system("/usr/bin/python3 -c 'import pyopenvdb' >/dev/null 2>&1") == 0) {
        const std::string script = "import pyopenvdb as v; g = v.read('" + dir.file("ls.vdb") +
                                   "', 'surface'); a = g.getConstAccessor(); "
                                   "assert g.gridClass == v.GridClass.LEVEL_SET; assert a.getValue((0, 0, 0)) < 0; "
                                   "assert a.getValue((30, 0, 0)) > 0; assert abs(a.getValue((12, 0, 0))) < 0.05";
        CHECK(std::system(("/usr/bin/python3 -c \"" + script + "\"").c_str()) == 0);
        // The whole file opens in readAll, materials included (pyopenvdb has no Int32Grid).
        const std::string all = "import pyopenvdb as v; gs, m = v.readAll('" + dir.file("ls.vdb") +
                                "'); n = sorted(g.name for g in gs); assert n == ['density', 'material', 'surface'], n; "
                                "g = [g for g in gs if g.name == 'material'][0]; assert g.getConstAccessor().getValue((0, 0, 0)) == 1";
        CHECK(std::system(("/usr/bin/python3 -c \"" + all + "\"").c_str()) == 0);
    }
}
