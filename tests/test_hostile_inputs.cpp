// What users hit with files and folders of the real world: stores in folders they cannot write,
// temporaries left by killed imports, names with control characters, exit codes that must say
// whether the command line or the file was wrong.
#include "scene/CameraPath.h"
#include "support/CliRun.h"
#include "support/TestUtil.h"
#include "vdb_hermite/Materials.h"
#include "vdb_hermite/PrintableText.h"
#include "voxelize/TriangleMesh.h"

#include <catch2/catch.hpp>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <nlohmann/json.hpp>

#include <random>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace vdbclay;
using namespace vdbclay::test;
using nlohmann::json;

namespace {

/// A PID that ran and ended (a child reaped at once): what a killed writer's temporary names.
pid_t deadPid()
{
    const pid_t pid = ::fork();
    if (pid == 0) ::_exit(0);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return pid;
}

/// Runs `vdbclay ARGS` in `dir` as a user who cannot write there: as root (CI), as "nobody" through
/// setpriv; otherwise as this user, with the folder and its files made read-only first.
CommandResult runAsReader(const TempDir& dir, const std::string& args)
{
    ::chmod(dir.path().c_str(), 0555);
    for (const std::string& name : dir.entries()) ::chmod(dir.file(name).c_str(), 0444);
    if (::geteuid() != 0) return runCli(dir, args);
    const std::string prefix = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
    const std::string command = "cd " + quote(dir.path().string()) + " && " + prefix + quote(kCli) + " " + args +
                                " >/tmp/vdbclay-reader-out-" + std::to_string(::getpid()) + " 2>&1";
    CommandResult r;
    const int status = std::system(command.c_str());
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    const std::string outPath = "/tmp/vdbclay-reader-out-" + std::to_string(::getpid());
    const auto out = readBytes(outPath);
    r.out.assign(out.begin(), out.end());
    std::filesystem::remove(outPath);
    return r;
}

} // namespace

TEST_CASE("cli: a store in a folder the user cannot write is read by every reading command", "[hostile][cli][store]")
{
    if (std::string(kCli).empty()) return;
    if (::geteuid() == 0) {
        if (std::system("command -v setpriv >/dev/null 2>&1") != 0) return; // cannot drop root here
        // A checkout in a folder only root may enter (/root) leaves "nobody" no binary to run.
        const std::string probe = "setpriv --reuid=65534 --regid=65534 --clear-groups test -x " + quote(kCli);
        if (std::system(probe.c_str()) != 0) {
            WARN("skipped: user nobody cannot run " << kCli);
            return;
        }
    }
    TempDir dir;
    REQUIRE(runCli(dir, "synth csg-stack --extent 64 --seed 4 -o c.vdbclay").exitCode == 0);
    REQUIRE(runCli(dir, "lod build c.vdbclay").exitCode == 0);
    writeText(dir.file("path.json"), R"({"frames": [{"position": [-40, 40, -40], "target": [32, 8, 32]},
                                                    {"position": [-30, 40, -40], "target": [32, 8, 32], "t": 0.2}]})");
    const auto before = dir.entries();
    const std::string out = "/tmp/vdbclay-ro-" + std::to_string(::getpid());
    std::filesystem::create_directories(out);
    ::chmod(out.c_str(), 0777);
    for (const std::string& args : std::vector<std::string>{"info c.vdbclay --json", "lod info c.vdbclay", "mesh c.vdbclay -o " + out + "/m.ply",
          "mesh c.vdbclay --lod 1 -o " + out + "/m1.ply", "export c.vdbclay -o " + out + "/c.vdb",
          "diff c.vdbclay c.vdbclay", "lod inspect c.vdbclay --camera-path path.json --memory-budget 64"}) {
        INFO(args);
        const CommandResult r = runAsReader(dir, args);
        INFO(r.out);
        CHECK(r.exitCode == 0);
        CHECK(r.out.find("readonly") == std::string::npos);
    }
    CHECK(dir.entries() == before); // no -wal or -shm left beside the store
    // Writers are refused with a clear line, and the store is untouched.
    const CommandResult write = runAsReader(dir, "lod build c.vdbclay");
    CHECK(write.exitCode == 1);
    CHECK(write.out.find("vdbclay: error: ") != std::string::npos);
    ::chmod(dir.path().c_str(), 0755);
    std::filesystem::remove_all(out);
}

TEST_CASE("cli: temporaries a killed store import left behind are removed by the next import", "[hostile][cli][store]")
{
    if (std::string(kCli).empty()) return;
    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 4").exitCode == 0);
    const std::string stale = ".c.vdbclay.vdbclay-tmp-" + std::to_string(deadPid()) + "-123";
    const std::string live = ".c.vdbclay.vdbclay-tmp-" + std::to_string(::getpid()) + "-456"; // this process runs
    for (const std::string& name : {stale, stale + "-wal", stale + "-shm", live}) writeText(dir.file(name), "partial");
    REQUIRE(runCli(dir, "import s.vdb -o c.vdbclay").exitCode == 0);
    const auto entries = dir.entries();
    CHECK(std::find(entries.begin(), entries.end(), stale) == entries.end());
    CHECK(std::find(entries.begin(), entries.end(), stale + "-wal") == entries.end());
    CHECK(std::find(entries.begin(), entries.end(), stale + "-shm") == entries.end());
    CHECK(std::find(entries.begin(), entries.end(), live) != entries.end()); // not ours to judge: its writer lives
}

TEST_CASE("printable text: control characters and bytes that are not UTF-8 are escaped, printable UTF-8 stays", "[hostile]")
{
    CHECK(printableText("stone") == "stone");
    CHECK(printableText("Stein-gr\xc3\xbcn") == "Stein-gr\xc3\xbcn");
    CHECK(printableText("a\x1b]0;owned\x07z") == "a\\x1b]0;owned\\x07z");
    CHECK(printableText("line\nforged") == "line\\x0aforged");
    CHECK(printableText("grid\x1e" "2") == "grid\\x1e2");
    CHECK(printableText("\xc2\x9b" "31m") == "\\xc2\\x9b31m"); // C1 CSI
    CHECK(printableText("\xff\xfe") == "\\xff\\xfe");
    CHECK(printableText("\xe0\x80\xaf") == "\\xe0\\x80\\xaf"); // overlong
    CHECK(printableText("abcdef", 3) == "abc...");
    CHECK(isPrintableName("colour-ff00aa"));
    CHECK_FALSE(isPrintableName("bad\x1b"));
    CHECK_FALSE(isPrintableName("bad\n"));
    CHECK_FALSE(isPrintableName("bad\xff"));
    CHECK_FALSE(isPrintableName(std::string(300, 'a')));
    MaterialTable table;
    Material evil;
    evil.name = "evil\x1b[2J";
    CHECK_THROWS_AS(table.define(evil), std::invalid_argument);
    CHECK_THROWS_AS(MaterialTable::fromJson(R"([{"name": "a\u0007", "color": [1, 1, 1, 1], "toughness": 0.5}])"), std::runtime_error);
}

TEST_CASE("cli: names with control characters are refused where they are made and never printed raw", "[hostile][cli]")
{
    if (std::string(kCli).empty()) return;
    TempDir dir;
    const CommandResult made = runCli(dir, "new s.vdb --shape box --size 2 --material \"$(printf 'evil\\033]0;title\\007')\"");
    CHECK(made.exitCode == 2);
    CHECK(made.err.find('\x1b') == std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("s.vdb")));
    REQUIRE(runCli(dir, "new s.vdb --shape box --size 2").exitCode == 0);
    writeText(dir.file("evil.json"),
              R"({"materials": [{"name": "x\u001b[2Jy", "color": [1, 0, 0, 1], "toughness": 0.5}], "ops": [{"mode": "add", "material": "x\u001b[2Jy", "brush": {"shape": "sphere", "radius": 1}}]})");
    const CommandResult script = runCli(dir, "sculpt s.vdb evil.json -o t.vdb");
    CHECK(script.exitCode == 1);
    CHECK(script.err.find('\x1b') == std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("t.vdb")));
}

TEST_CASE("camera paths: repeated keys, a target a hair from the camera, raw bytes are refused with one printable line", "[hostile]")
{
    CHECK_THROWS_WITH(parseCameraPath(R"({"frames": [{"position": [0, 0, 0], "target": [1, 0, 0], "target": [2, 0, 0]}]})"),
                      Catch::Contains("'target' appears twice"));
    CHECK_THROWS_WITH(parseCameraPath(R"({"frames": [{"position": [0, 0, 0], "target": [1, 0, 0]}], "frames": []})"),
                      Catch::Contains("'frames' appears twice"));
    // 1e-300 apart: the squared distance underflows; it is not "equal", and it says how far it is.
    CHECK_THROWS_WITH(parseCameraPath(R"({"frames": [{"position": [0, 0, 0], "target": [1e-300, 0, 0]}]})"),
                      Catch::Contains("lies 1e-300 from its position"));
    CHECK_THROWS_WITH(parseCameraPath(R"({"frames": [{"position": [5, 5, 5], "target": [5, 5, 5]}]})"), Catch::Contains("must differ"));
    CHECK_NOTHROW(parseCameraPath(R"({"frames": [{"position": [0, 0, 0], "target": [1e-6, 0, 0]}]})"));
    // An unknown key of control characters is quoted printable (found by fuzz_camera_path: DEL in a key).
    try {
        parseCameraPath("{\"frames\": [{\"position\": [0, 0, 0], \"a\x7f\xc2\x9b" "2J\": [1, 2, 3]}]}"); // DEL, C1 CSI
        FAIL("accepted");
    } catch (const std::invalid_argument& e) {
        CHECK(std::string(e.what()).find("unknown key") != std::string::npos);
        CHECK(isPrintableName(e.what(), 100000));
    }
    try {
        parseCameraPath("{\"frames\": [{\"position\": [0, 0, 0], \"\x1b]0;x\x07\xff\": 1}]}");
        FAIL("accepted");
    } catch (const std::invalid_argument& e) {
        CHECK(isPrintableName(e.what(), 100000));
    }
}

TEST_CASE("cli: lod inspect --json streams its frames, budgets beyond a petabyte are refused", "[hostile][cli][store]")
{
    if (std::string(kCli).empty()) return;
    TempDir dir;
    REQUIRE(runCli(dir, "synth csg-stack --extent 64 --seed 5 -o c.vdbclay").exitCode == 0);
    json frames = json::array();
    for (int i = 0; i < 30; ++i) frames.push_back({{"position", {-40.0 + i, 40.0, -40.0}}, {"target", {32.0, 8.0, 32.0}}, {"t", 0.01 * i}});
    writeText(dir.file("path.json"), json{{"frames", frames}}.dump());
    const json report = parseJsonOutput(runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --json"));
    CHECK(report["frames"].size() == 30);
    CHECK(report["summary"]["frames"] == 30);
    for (const char* budget : {"18446744073709551616", "1e10", "0", "-5", "nan"}) {
        INFO(budget);
        const CommandResult r = runCli(dir, std::string("lod inspect c.vdbclay --camera-path path.json --memory-budget ") + budget);
        CHECK(r.exitCode == 2);
        CHECK(r.err.find("--memory-budget") != std::string::npos);
    }
}

TEST_CASE("cli: exit codes and messages name the real cause", "[hostile][cli]")
{
    if (std::string(kCli).empty()) return;
    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 3").exitCode == 0);
    const CommandResult unknown = runCli(dir, "NOSUCHCOMMAND --help"); // printed the general help, exit 0
    CHECK(unknown.exitCode == 2);
    CHECK(unknown.err.find("unknown command 'NOSUCHCOMMAND'") != std::string::npos);
    const CommandResult nanWidth = runCli(dir, "export-levelset s.vdb -o ls.vdb --half-width nan"); // exit 1 before
    CHECK(nanWidth.exitCode == 2);
    std::filesystem::create_symlink("loop.vdb", dir.file("loop.vdb"));
    for (const char* command : {"info loop.vdb", "mesh loop.vdb -o m.ply", "import loop.vdb -o x.vdbclay"}) {
        INFO(command);
        const CommandResult loop = runCli(dir, command); // said "does not exist"
        CHECK(loop.exitCode == 1);
        CHECK(loop.err.find("loop of symbolic links") != std::string::npos);
    }
    // Corners a hair apart collapse in single precision: the message says so, not "holds no triangle".
    writeText(dir.file("collapsed.obj"), "v 1e8 0 0\nv 100000000.000001 0 0\nv 1e8 0.0000001 0\nf 1 2 3\n");
    const CommandResult collapsed = runCli(dir, "import collapsed.obj --resolution 8 -o c.vdb");
    CHECK(collapsed.exitCode == 1);
    CHECK(collapsed.err.find("single precision") != std::string::npos);
}

TEST_CASE("cli: small inputs that ask for more memory than the process may use are refused at once, naming the limit", "[hostile][cli]")
{
    if (std::string(kCli).empty()) return;
    if (!meshReadMemoryIsCapped()) return; // AddressSanitizer reserves terabytes of addresses: no ulimit -v under it
    TempDir dir;
    // A level set of a few hundred bytes: inside tiles of a 4096-voxel cube (3 million surface leaves).
    openvdb::initialize();
    openvdb::FloatGrid::Ptr cube = openvdb::FloatGrid::create(3.0f);
    cube->setName("surface");
    cube->setGridClass(openvdb::GRID_LEVEL_SET);
    cube->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(4095)), -3.0f, true);
    openvdb::io::File(dir.file("tiles.vdb")).write({cube});
    REQUIRE(std::filesystem::file_size(dir.file("tiles.vdb")) < 2000);
    // 20,000 random triangles across their box: billions of ray hits at resolution 128.
    std::string soup;
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int v = 0; v < 60000; ++v) soup += "v " + std::to_string(unit(rng)) + " " + std::to_string(unit(rng)) + " " + std::to_string(unit(rng)) + "\n";
    for (int t = 0; t < 20000; ++t) soup += "f " + std::to_string(3 * t + 1) + " " + std::to_string(3 * t + 2) + " " + std::to_string(3 * t + 3) + "\n";
    writeText(dir.file("soup.obj"), soup);
    // (Into a store the tiles import brick by brick in bounded memory: 77 s for this cube, too long for
    // the suite; "a grid imported into a store brick by brick equals its import into memory" covers it.)
    for (const char* command : {"import tiles.vdb -o t.vdb", "import soup.obj --resolution 128 -o s.vdb"}) {
        INFO(command);
        // Under a 4 GB address-space limit: without the estimate, the work would run into it (out of memory).
        const std::string errPath = dir.file("err.txt");
        const std::string line = "cd " + quote(dir.path().string()) + " && ulimit -v 4000000 && " + quote(kCli) + " " + command +
                                 " >/dev/null 2>" + quote(errPath);
        const int status = std::system(line.c_str());
        CHECK((WIFEXITED(status) && WEXITSTATUS(status) == 1));
        const auto err = readBytes(errPath);
        const std::string text(err.begin(), err.end());
        CHECK(text.find("needs about") != std::string::npos);
        CHECK(text.find("this process may use ") != std::string::npos); // 4 GB, or less on a smaller machine
    }
    CHECK_FALSE(std::filesystem::exists(dir.file("t.vdb")));
    CHECK_FALSE(std::filesystem::exists(dir.file("s.vdb")));
}
