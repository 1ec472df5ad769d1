// The `vdbclay` command, run as a separate process in a temporary directory. Its results are checked
// against the library run in-process on the same input. Registered only when the build has the CLI
// (tests/CMakeLists.txt passes its path as VDBCLAY_CLI).
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "sculpt/StrokeScript.h"
#include "render/ImageFile.h"
#include "support/CliRun.h"
#include "support/ExampleScript.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <random>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

using namespace vdbclay;
using namespace vdbclay::test;
using nlohmann::json;

namespace {


} // namespace

#ifdef VDBCLAY_CLI

TEST_CASE("cli: new, then info --json describes the volume", "[cli]")
{
    TempDir dir;
    const CommandResult made = runCli(dir, "new vol.vdb --shape sphere --size 6 --voxel-size 0.5 --material stone");
    INFO("stderr: " << made.err);
    REQUIRE(made.exitCode == 0);
    REQUIRE(std::filesystem::exists(dir.path() / "vol.vdb"));

    const json info = parseJsonOutput(runCli(dir, "info vol.vdb --json"));
    for (const char* key : {"voxel_size", "active_voxels", "leaf_count", "bbox_min", "bbox_max", "materials",
                            "memory_bytes", "format_version"}) {
        INFO("key " << key);
        CHECK(info.contains(key));
    }
    const Volume v = loadVolume(dir.file("vol.vdb"));
    const VolumeStats s = v.stats();
    CHECK(info["voxel_size"].get<double>() == 0.5);
    CHECK(info["active_voxels"].get<uint64_t>() == s.activeVoxels);
    CHECK(info["leaf_count"].get<uint64_t>() == s.leafCount);
    CHECK(info["memory_bytes"].get<uint64_t>() == s.memoryBytes);
    CHECK(info["bbox_min"].get<std::array<int32_t, 3>>() == s.bboxMin);
    CHECK(info["bbox_max"].get<std::array<int32_t, 3>>() == s.bboxMax);
    CHECK(info["format_version"].get<int>() == 1);
    CHECK(info["materials"] == json::array({"default", "stone"}));
    // A sphere of radius 6 world units is 12 voxels: the box spans about 24 voxels per axis.
    for (int a = 0; a < 3; ++a) {
        CHECK(s.bboxMin[a] >= -13);
        CHECK(s.bboxMin[a] <= -11);
        CHECK(s.bboxMax[a] >= 11);
        CHECK(s.bboxMax[a] <= 13);
    }
    CHECK(v.materialAt({0, 0, 0}) == 2);

    // Without --json the same facts come as text.
    const CommandResult text = runCli(dir, "info vol.vdb");
    CHECK(text.exitCode == 0);
    CHECK(text.out.find("active_voxels") != std::string::npos);
}

TEST_CASE("cli: sculpt runs a script exactly like the library", "[cli]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "new base.vdb --shape box --size 4").exitCode == 0);
    writeText(dir.file("script.json"), kExampleScript);
    const json result = parseJsonOutput(runCli(dir, "sculpt base.vdb script.json -o out.vdb --json"));
    CHECK(result["ops"].get<int>() == 5);

    Volume expected = loadVolume(dir.file("base.vdb"));
    runStrokeScript(expected, parseStrokeScript(kExampleScript));
    const Volume got = loadVolume(dir.file("out.vdb"));
    CHECK(identical(expected, got));
    CHECK(result["active_voxels"].get<uint64_t>() == got.stats().activeVoxels);

    // In place, with progress lines on stderr.
    const CommandResult inPlace = runCli(dir, "sculpt out.vdb script.json -o out.vdb");
    INFO("stderr: " << inPlace.err);
    CHECK(inPlace.exitCode == 0);
    CHECK(inPlace.err.find("op 5/5") != std::string::npos);
    runStrokeScript(expected, parseStrokeScript(kExampleScript));
    CHECK(identical(expected, loadVolume(dir.file("out.vdb"))));
}

TEST_CASE("cli: mesh --json reports a watertight mesh and writes it", "[cli]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "new vol.vdb --shape torus --size 10").exitCode == 0);
    const json obj = parseJsonOutput(runCli(dir, "mesh vol.vdb -o vol.obj --json"));
    CHECK(obj["watertight"] == true);
    CHECK(obj["mesher"] == "cms"); // the default, with adaptive cells
    CHECK(obj["cells"] == "adaptive");
    MeshOptions cms;
    cms.kind = MesherKind::CubicalMarchingSquares;
    const Mesh mesh = meshVolume(loadVolume(dir.file("vol.vdb")), cms);
    CHECK(obj["triangles"].get<std::size_t>() == mesh.triangleCount());
    CHECK(obj["vertices"].get<std::size_t>() == mesh.vertexCount());

    // On flat faces adaptive cells take fewer triangles than --uniform's voxel cells.
    REQUIRE(runCli(dir, "new box.vdb --shape box --size 12.3").exitCode == 0);
    const json adaptive = parseJsonOutput(runCli(dir, "mesh box.vdb -o adaptive.glb --json"));
    const json uniform = parseJsonOutput(runCli(dir, "mesh box.vdb -o uniform.glb --uniform --json"));
    CHECK(uniform["cells"] == "uniform");
    CHECK(uniform["watertight"] == true);
    cms.maxCellWidth = 1;
    CHECK(uniform["triangles"].get<std::size_t>() == meshVolume(loadVolume(dir.file("box.vdb")), cms).triangleCount());
    CHECK(uniform["triangles"].get<std::size_t>() > 2 * adaptive["triangles"].get<std::size_t>());
    CHECK(runCli(dir, "mesh vol.vdb -o bad.ply --adapt-angle 180").exitCode == 2);
    // A plane tolerance keeps more cells whole on a curved surface, exactly as the option meshes.
    const json tolerant = parseJsonOutput(runCli(dir, "mesh vol.vdb -o tolerant.glb --plane-tolerance 0.25 --json"));
    MeshOptions tolerantCms;
    tolerantCms.kind = MesherKind::CubicalMarchingSquares;
    tolerantCms.planeTolerance = 0.25;
    CHECK(tolerant["triangles"].get<std::size_t>() == meshVolume(loadVolume(dir.file("vol.vdb")), tolerantCms).triangleCount());
    CHECK(tolerant["triangles"].get<std::size_t>() < obj["triangles"].get<std::size_t>());
    CHECK(tolerant["watertight"] == true);
    CHECK(runCli(dir, "mesh vol.vdb -o bad.ply --plane-tolerance -1").exitCode == 2);
    CHECK(runCli(dir, "mesh vol.vdb -o bad.ply --uniform --plane-tolerance 0.25").exitCode == 2);
    CHECK(runCli(dir, "mesh vol.vdb -o bad.ply --mesher mc --plane-tolerance 0.25").exitCode == 2);

    // The OBJ holds that many vertices and faces.
    const auto objBytes = readBytes(dir.file("vol.obj"));
    std::istringstream lines(std::string(objBytes.begin(), objBytes.end()));
    std::size_t v = 0, f = 0;
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("v ", 0) == 0) ++v;
        if (line.rfind("f ", 0) == 0) ++f;
    }
    CHECK(v == mesh.vertexCount());
    CHECK(f == mesh.triangleCount());

    // Options that would have no effect are refused, not ignored.
    CHECK(runCli(dir, "mesh vol.vdb -o x.ply --mesher mc --angle 45").exitCode == 2);
    CHECK(runCli(dir, "mesh vol.vdb -o x.ply --uniform --adapt-angle 5").exitCode == 2);
    CHECK_FALSE(std::filesystem::exists(dir.file("x.ply")));
    const json ply = parseJsonOutput(runCli(dir, "mesh vol.vdb -o vol.ply --mesher mc --json"));
    CHECK(ply["watertight"] == true);
    CHECK(ply["mesher"] == "mc");
    CHECK(ply["triangles"].get<std::size_t>() == meshVolume(loadVolume(dir.file("vol.vdb"))).triangleCount());
    CHECK(runCli(dir, "mesh vol.vdb -o bad.ply --angle 0").exitCode == 2);
    const auto plyBytes = readBytes(dir.file("vol.ply"));
    CHECK(std::string(plyBytes.begin(), plyBytes.begin() + 3) == "ply");
}

TEST_CASE("cli: bench memory --quick --json prints one JSON object", "[cli]")
{
    TempDir dir;
    const json j = parseJsonOutput(runCli(dir, "bench memory --quick --json"));
    CHECK(j.at("bench") == "memory");
    REQUIRE(j.at("shapes").size() == 2);
    for (const json& shape : j.at("shapes")) {
        INFO(shape.dump());
        // Bytes per surface voxel are the totals over the active voxels, on both sides.
        CHECK(shape.at("ours_bytes").get<double>() / shape.at("ours_active_voxels").get<double>() ==
              Approx(shape.at("ours_bytes_per_surface_voxel").get<double>()));
        CHECK(shape.at("ratio_ours_to_openvdb").get<double>() ==
              Approx(shape.at("ours_bytes_per_surface_voxel").get<double>() /
                     shape.at("openvdb_bytes_per_surface_voxel").get<double>()));
        CHECK(shape.at("ours_leaf_count").get<int>() > 0);
    }
}

TEST_CASE("cli: bench mesh --quick --json has every shape and mesher", "[cli]")
{
    TempDir dir;
    const json j = parseJsonOutput(runCli(dir, "bench mesh --quick --json"));
    REQUIRE(j.contains("shapes"));
    for (const char* shape : {"box", "rotated_box", "sphere", "box_minus_sphere", "thin_wall"}) {
        INFO(shape);
        REQUIRE(j["shapes"].contains(shape));
        const json& s = j["shapes"][shape];
        CHECK(s["surface_cells"].get<double>() > 0);
        CHECK(s.contains("cms_over_openvdb_cells_per_second"));
        for (const char* mesher :
             {"cms_uniform", "cms_adaptive", "mc", "openvdb_adaptivity_0", "openvdb_adaptivity_0.5"}) {
            INFO(mesher);
            REQUIRE(s["meshers"].contains(mesher));
            const json& m = s["meshers"][mesher];
            for (const char* key : {"ms", "triangles", "mean_distance", "max_distance", "watertight"}) {
                INFO(key);
                CHECK(m.contains(key));
            }
            CHECK(m["triangles"].get<double>() > 0);
        }
        // CMS is closed on every shape, with uniform and with adaptive cells.
        CHECK(s["meshers"]["cms_uniform"]["watertight"] == true);
        CHECK(s["meshers"]["cms_adaptive"]["watertight"] == true);
    }
    // Re-meshing after stamps leaves exactly the chunks a full re-mesh gives.
    for (const char* mesher : {"cms_uniform", "cms_adaptive"}) {
        INFO(mesher);
        REQUIRE(j["remesh_after_stamp"].contains(mesher));
        const json& r = j["remesh_after_stamp"][mesher];
        CHECK(r["median_ms"].get<double>() > 0.0);
        CHECK(r["median_chunks_remeshed"].get<double>() > 0.0);
        CHECK(r["matches_full_mesh"] == true);
    }
}

TEST_CASE("cli: demo writes a volume, meshes and the script it ran", "[cli]")
{
    TempDir dir;
    const json j = parseJsonOutput(runCli(dir, "demo --out demo-out --json"));
    CHECK(j["watertight"] == true);
    for (const char* name : {"scene.vdb", "scene.obj", "scene.mtl", "scene.ply", "script.json", "knob.vdb", "tools.json", "scene.vdbclay",
                             "scene-lod2.obj", "scene-lod2.mtl"}) {
        INFO(name);
        CHECK(std::filesystem::file_size(dir.path() / "demo-out" / name) > 0);
    }
    // The picture, drawn where there is a Vulkan device (the sanitizer run hides the driver): a
    // 1280x720 PNG whose middle shows the scene, not the background of its corner.
    if (j["picture"].is_null()) {
        CHECK(j["picture_skipped"].get<std::string>().find("Vulkan") != std::string::npos);
        CHECK_FALSE(std::filesystem::exists(dir.path() / "demo-out" / "scene.png"));
    } else {
        const render::Image picture = render::readImage((dir.path() / "demo-out" / "scene.png").string());
        CHECK(picture.width == 1280);
        CHECK(picture.height == 720);
        const uint8_t* corner = picture.pixel(0, 0);
        const uint8_t* middle = picture.pixel(640, 360);
        CHECK(std::abs(int(corner[0]) - int(middle[0])) + std::abs(int(corner[1]) - int(middle[1])) +
                  std::abs(int(corner[2]) - int(middle[2])) > 60);
    }
    // Replaying the written scripts (the second with the tool it wrote) on a fresh volume of the demo's
    // voxel size gives the written volume.
    const Volume scene = loadVolume((dir.path() / "demo-out" / "scene.vdb").string());
    Volume replay(scene.voxelSize());
    runStrokeScript(replay, loadStrokeScript((dir.path() / "demo-out" / "script.json").string()));
    CHECK_FALSE(identical(scene, replay));
    runStrokeScript(replay, loadStrokeScript((dir.path() / "demo-out" / "tools.json").string()));
    CHECK(identical(scene, replay));
}

TEST_CASE("cli: bad input fails cleanly with a message", "[cli]")
{
    TempDir dir;
    SECTION("info on random bytes")
    {
        const std::vector<char> junk = randomBytes(4096, 0x5eed0201);
        writeBytes(dir.file("junk.vdb"), junk.data(), junk.size());
        checkCleanFailure(runCli(dir, "info junk.vdb"));
        checkCleanFailure(runCli(dir, "info junk.vdb --json"));
        checkCleanFailure(runCli(dir, "mesh junk.vdb -o junk.obj"));
        CHECK_FALSE(std::filesystem::exists(dir.path() / "junk.obj"));
    }
    SECTION("a missing file")
    {
        checkCleanFailure(runCli(dir, "info missing.vdb"));
        writeText(dir.file("script.json"), kExampleScript);
        checkCleanFailure(runCli(dir, "sculpt missing.vdb script.json -o out.vdb"));
        CHECK_FALSE(std::filesystem::exists(dir.path() / "out.vdb"));
    }
    SECTION("bad scripts leave the volume alone")
    {
        REQUIRE(runCli(dir, "new vol.vdb --shape sphere --size 5").exitCode == 0);
        const auto before = readBytes(dir.file("vol.vdb"));
        writeText(dir.file("broken.json"), "{ \"ops\": [ ");
        checkCleanFailure(runCli(dir, "sculpt vol.vdb broken.json -o vol.vdb"));
        json j = json::parse(kExampleScript);
        j["ops"][1]["mode"] = "smash";
        writeText(dir.file("mode.json"), j.dump());
        const CommandResult mode = runCli(dir, "sculpt vol.vdb mode.json -o vol.vdb");
        checkCleanFailure(mode);
        CHECK(mode.err.find("ops[1]") != std::string::npos);
        j = json::parse(kExampleScript);
        j["ops"][2]["material"] = "unobtainium";
        writeText(dir.file("material.json"), j.dump());
        const CommandResult material = runCli(dir, "sculpt vol.vdb material.json -o vol.vdb");
        checkCleanFailure(material);
        CHECK(material.err.find("unobtainium") != std::string::npos);
        checkCleanFailure(runCli(dir, "sculpt vol.vdb missing.json -o vol.vdb"));
        CHECK(readBytes(dir.file("vol.vdb")) == before);
    }
    SECTION("a wrong command line")
    {
        const CommandResult unknown = runCli(dir, "frobnicate");
        checkCleanFailure(unknown);
        CHECK(unknown.exitCode == 2);
        const CommandResult negative = runCli(dir, "new v.vdb --shape sphere --size -3");
        checkCleanFailure(negative);
        CHECK(negative.exitCode == 2);
        checkCleanFailure(runCli(dir, "new v.vdb --shape pyramid --size 3"));
        checkCleanFailure(runCli(dir, "bench nothing --quick"));
        CHECK_FALSE(std::filesystem::exists(dir.path() / "v.vdb"));
    }
    SECTION("seeds and tolerances that would overflow, wrap or compare as NaN")
    {
        for (const char* seed : {"18446744073709551616", "99999999999999999999", "-5", "1.5", "x"}) {
            INFO(seed);
            const CommandResult r = runCli(dir, std::string("synth terrain --extent 16 --seed ") + seed + " -o t.vdbclay");
            checkCleanFailure(r);
            CHECK(r.exitCode == 2);
        }
        CHECK_FALSE(std::filesystem::exists(dir.path() / "t.vdbclay"));
        REQUIRE(runCli(dir, "synth terrain --extent 16 --seed 18446744073709551615 -o t.vdbclay").exitCode == 0);
        for (const char* tolerance : {"nan", "-1", "inf"}) {
            INFO(tolerance);
            const CommandResult r = runCli(dir, std::string("diff t.vdbclay t.vdbclay --tolerance ") + tolerance);
            checkCleanFailure(r);
            CHECK(r.exitCode == 2);
        }
        CHECK(runCli(dir, "diff t.vdbclay t.vdbclay --tolerance 0").exitCode == 0);
    }
}

TEST_CASE("cli: import, lod, mesh --lod, sculpt, export and diff on a store", "[cli][store]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 40").exitCode == 0);
    const json imported = parseJsonOutput(runCli(dir, "import s.vdb -o s.vdbclay --json"));
    CHECK(imported["form"] == "store");
    const json info = parseJsonOutput(runCli(dir, "info s.vdbclay --json"));
    CHECK(info["form"] == "store");
    CHECK(info["format_version"] == 2);
    CHECK(info["leaf_count"].get<uint64_t>() == loadVolume(dir.file("s.vdb")).stats().leafCount);

    const json built = parseJsonOutput(runCli(dir, "lod build s.vdbclay --levels 2 --json"));
    REQUIRE(built["levels"].size() == 3);
    const json levels = parseJsonOutput(runCli(dir, "lod info s.vdbclay --json"));
    REQUIRE(levels["levels"].size() == 3);
    for (int k = 0; k < 3; ++k) {
        CHECK(levels["levels"][k]["level"] == k);
        for (const char* key : {"bricks", "leaves", "bytes"}) CHECK(levels["levels"][k][key].get<uint64_t>() > 0);
    }
    CHECK(levels["levels"][2]["leaves"].get<uint64_t>() < levels["levels"][0]["leaves"].get<uint64_t>());
    for (const char* input : {"s.vdbclay", "s.vdb"}) {
        const json mesh = parseJsonOutput(runCli(dir, std::string("mesh ") + input + " --lod 2 -o l2.obj --json"));
        CHECK(mesh["lod"] == 2);
        CHECK(mesh["watertight"] == true);
    }
    checkCleanFailure(runCli(dir, "mesh s.vdbclay --lod 5 -o l5.obj"));

    writeText(dir.file("stamp.json"), R"({"ops": [{"mode": "remove", "brush": {"shape": "sphere", "radius": 9}, "at": [40, 0, 0]}]})");
    const json sculpted = parseJsonOutput(runCli(dir, "sculpt s.vdbclay stamp.json --json"));
    CHECK(sculpted["bricks_written"].get<uint64_t>() > 0);
    CHECK(sculpted["bricks_read"].get<uint64_t>() < info["bricks"].get<uint64_t>());
    REQUIRE(runCli(dir, "sculpt s.vdb stamp.json -o s2.vdb").exitCode == 0);
    REQUIRE(runCli(dir, "export s.vdbclay -o back.vdb").exitCode == 0);
    CHECK(readBytes(dir.file("back.vdb")) == readBytes(dir.file("s2.vdb")));
    CHECK(runCli(dir, "diff s.vdbclay s2.vdb").exitCode == 0);
    const CommandResult differ = runCli(dir, "diff s.vdbclay s.vdb --json");
    CHECK(differ.exitCode == 1);
    CHECK(json::parse(differ.out)["differing_bricks"].size() > 0);
    CHECK(runCli(dir, "diff s.vdbclay missing.vdb").exitCode == 2);
    const CommandResult self = runCli(dir, "import s.vdbclay -o ./s.vdbclay");
    checkCleanFailure(self);
    CHECK(self.exitCode == 2);
    CHECK(parseJsonOutput(runCli(dir, "lod info s.vdbclay --json"))["levels"].size() > 1); // kept
    // Other voxel sizes: other lattices, so nothing is counted, and no distance is claimed.
    REQUIRE(runCli(dir, "new half.vdb --shape sphere --size 4 --voxel-size 0.5").exitCode == 0);
    const CommandResult lattices = runCli(dir, "diff s.vdbclay half.vdb --json --tolerance 100");
    CHECK(lattices.exitCode == 1);
    const json latticesJson = json::parse(lattices.out);
    CHECK(latticesJson["voxel_sizes_differ"] == true);
    CHECK(latticesJson["surface_distance"].is_null());
    CHECK(latticesJson["voxel_sizes"][1] == 0.5);
    CHECK_THAT(runCli(dir, "diff s.vdbclay half.vdb").out, Catch::Contains("0.5 (other lattices"));
    const json lodAfter = parseJsonOutput(runCli(dir, "lod info s.vdbclay --json"));
    CHECK(lodAfter["stale"] == false); // the sculpt kept the levels current
    CHECK(sculpted["lod_bricks_written"].get<uint64_t>() > 0);

    // Bad use of the new commands: clean failures.
    checkCleanFailure(runCli(dir, "sculpt s.vdbclay stamp.json -o other.vdbclay"));
    checkCleanFailure(runCli(dir, "sculpt s.vdb stamp.json --autosave-every 2 -o x.vdb"));
    checkCleanFailure(runCli(dir, "lod build s.vdb"));
    checkCleanFailure(runCli(dir, "export s.vdbclay -o x.vdbclay"));
    checkCleanFailure(runCli(dir, "import stamp.json -o x.vdbclay"));
    writeText(dir.file("not-a-store.vdbclay"), "plain text");
    checkCleanFailure(runCli(dir, "info not-a-store.vdbclay"));
    checkCleanFailure(runCli(dir, "import s.vdb -o not-a-store.vdbclay"));
    CHECK(readBytes(dir.file("not-a-store.vdbclay")).size() == 10); // not replaced
    for (const char* help : {"import --help", "export --help", "lod build --help", "lod info --help", "lod inspect --help",
                             "synth --help", "diff --help"})
        CHECK(runCli(dir, help).exitCode == 0);
}

TEST_CASE("cli: synth and lod inspect with a camera path, CSV and plot", "[cli][store]")
{
    TempDir dir;
    const json made = parseJsonOutput(runCli(dir, "synth csg-stack --extent 96 --seed 3 -o c.vdbclay --json"));
    CHECK(made["bricks"].get<uint64_t>() > 0);
    REQUIRE(runCli(dir, "lod build c.vdbclay").exitCode == 0);
    json frames = json::array();
    for (int i = 0; i < 20; ++i) frames.push_back({{"position", {-60.0 + 4.0 * i, 40.0, -60.0}}, {"target", {48.0, 8.0, 48.0}}});
    writeText(dir.file("path.json"), json{{"fov_degrees", 60}, {"viewport", {1280, 720}}, {"frames", frames}}.dump());
    const json report = parseJsonOutput(
        runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --csv f.csv --plot f.png --json"));
    REQUIRE(report["frames"].size() == 20);
    for (const char* key : {"resident_bricks_per_level", "resident_bytes", "bytes_read", "loads", "evictions", "hit_rate",
                            "screen_error_px", "complete"})
        CHECK(report["frames"][0].contains(key));
    CHECK(report["summary"]["peak_resident_bytes"].get<uint64_t>() <= 64ull << 20);
    CHECK(report["summary"]["first_coarse_complete_s"].is_number());
    CHECK(readBytes(dir.file("f.csv")).size() > 100);
    const std::vector<char> png = readBytes(dir.file("f.png"));
    REQUIRE(png.size() > 1000);
    CHECK(std::string(png.begin() + 1, png.begin() + 4) == "PNG");
    // Bad camera paths and budgets.
    writeText(dir.file("bad.json"), R"({"frames": [{"position": [0, 0, 0], "target": [0, 0, 0]}]})");
    checkCleanFailure(runCli(dir, "lod inspect c.vdbclay --camera-path bad.json --memory-budget 64"));
    checkCleanFailure(runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 0.01"));
    checkCleanFailure(runCli(dir, "synth volcano --extent 64 -o v.vdbclay"));
    checkCleanFailure(runCli(dir, "synth terrain --extent 3 -o v.vdbclay"));
    checkCleanFailure(runCli(dir, "synth terrain --extent 64 -o v.vdb"));
    // A flight longer than an hour (it replays in real time) is refused, and so are unusable outputs:
    // PLplot ended the process when it could not open its file.
    writeText(dir.file("long.json"), R"({"frames": [{"position": [0, 40, 0], "target": [9, 0, 9]},
                                                    {"position": [1, 40, 0], "target": [9, 0, 9], "t": 1e6}]})");
    const CommandResult tooLong = runCli(dir, "lod inspect c.vdbclay --camera-path long.json --memory-budget 64");
    checkCleanFailure(tooLong);
    CHECK(tooLong.exitCode == 1); // the file's content, not the command line
    for (const char* output : {"--plot missing/f.png", "--csv missing/f.csv"}) {
        INFO(output);
        const CommandResult r = runCli(dir, std::string("lod inspect c.vdbclay --camera-path path.json --memory-budget 64 ") + output);
        checkCleanFailure(r);
        CHECK(r.exitCode == 1);
        CHECK(r.err.find("PLPLOT") == std::string::npos);
    }
    checkCleanFailure(runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --csv ."));
}

TEST_CASE("cli: an in-place sculpt killed at random moments leaves the old or the new file, and no temporary file after the next save", "[cli][saves]")
{
    TempDir dir;
    const std::string file = dir.file("scene.vdb");
    REQUIRE(runCli(dir, "new scene.vdb --shape sphere --size 40").exitCode == 0);
    const std::string script = R"({"ops": [
        {"mode": "remove", "brush": {"shape": "box", "size": [12, 12, 50]}, "at": [20, 0, 0], "rotate": [0, 0, 30]},
        {"mode": "add", "brush": {"shape": "torus", "radius": 30, "minor_radius": 6}, "at": [0, 0, 5]},
        {"mode": "remove", "brush": {"shape": "sphere", "radius": 9}, "path": [[-30, -30, 30], [30, 30, 30]]}]})";
    writeText(dir.file("carve.json"), script);
    const Volume before = loadVolume(file);
    Volume after = loadVolume(file);
    runStrokeScript(after, parseStrokeScript(script));
    const std::vector<char> pristine = readBytes(file);

    const auto startSculpt = [&] { return startCli({"sculpt", "scene.vdb", "carve.json", "-o", "scene.vdb", "--threads", "1"}, "", dir.path().string()); };
    // How long one run takes here, so the kills spread over all of it (the save included).
    const auto start = std::chrono::steady_clock::now();
    const int status = finishCli(startSculpt());
    REQUIRE((WIFEXITED(status) && WEXITSTATUS(status) == 0));
    const double runMicros = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    REQUIRE(identical(loadVolume(file), after));

    std::mt19937 rng(20261201);
    std::uniform_real_distribution<double> when(0.0, 1.1 * runMicros);
    int sawOld = 0, sawNew = 0;
    for (int trial = 0; trial < 40; ++trial) {
        writeBytes(file, pristine.data(), pristine.size());
        finishCli(startSculpt(), std::chrono::microseconds(int64_t(when(rng))));
        INFO("trial " << trial);
        const Volume now = loadVolume(file); // never torn: it loads
        const bool isOld = identical(now, before), isNew = identical(now, after);
        CHECK((isOld || isNew));
        sawOld += isOld, sawNew += isNew;
    }
    CHECK(sawOld > 0); // the kills did land before the rename
    // The next save removes whatever the killed saves left behind.
    REQUIRE(runCli(dir, "sculpt scene.vdb carve.json -o scene.vdb").exitCode == 0);
    for (const std::string& name : dir.entries()) CHECK(name.find(".vdbclay-tmp-") == std::string::npos);
}

#endif // VDBCLAY_CLI
