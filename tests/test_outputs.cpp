// Every command that writes, with its output set to each of its inputs and to files of other kinds
// (stores, scripts, meshes, another tool's .vdb, pictures, tables): each is refused as a wrong command
// line and nothing in the folder changes. And the content sniffing the check rests on.
#include "scene/OutputCheck.h"
#include "support/CliRun.h"
#include "support/TestUtil.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <map>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

void writeForeignVdb(const std::string& path)
{
    openvdb::initialize();
    openvdb::FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(4.0f, openvdb::Vec3f(0.0f), 0.5f);
    sphere->setName("surface");
    openvdb::io::File file(path);
    file.write({sphere});
    file.close();
}

/// Every regular file of the folder and its bytes.
std::map<std::string, std::vector<char>> snapshot(const TempDir& dir)
{
    std::map<std::string, std::vector<char>> files;
    for (const std::string& name : dir.entries())
        if (std::filesystem::is_regular_file(dir.path() / name)) files[name] = readBytes(dir.file(name));
    return files;
}

/// A folder with one file of every kind a command reads or writes.
struct Victims {
    TempDir dir;
    Victims()
    {
        REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 4 --voxel-size 0.5").exitCode == 0);
        REQUIRE(runCli(dir, "synth csg-stack --extent 64 --seed 2 -o c.vdbclay").exitCode == 0);
        REQUIRE(runCli(dir, "lod build c.vdbclay").exitCode == 0);
        REQUIRE(runCli(dir, "mesh s.vdb -o m.obj").exitCode == 0);
        REQUIRE(runCli(dir, "mesh s.vdb -o m.ply").exitCode == 0);
        REQUIRE(runCli(dir, "mesh s.vdb -o m.glb").exitCode == 0);
        REQUIRE(runCli(dir, "export-levelset s.vdb -o ls.vdb").exitCode == 0);
        writeText(dir.file("script.json"),
                  R"({"ops": [{"mode": "remove", "brush": {"shape": "sphere", "radius": 2}, "at": [2, 0, 0]}]})");
        writeText(dir.file("path.json"), R"({"frames": [{"position": [-40, 40, -40], "target": [32, 8, 32]},
                                                        {"position": [-30, 40, -40], "target": [32, 8, 32], "t": 0.2}]})");
        REQUIRE(runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --csv f.csv --plot f.png").exitCode == 0);
        writeForeignVdb(dir.file("foreign.vdb"));
        // Files of one kind under another kind's extension: the content decides, not the name.
        std::filesystem::copy_file(dir.file("c.vdbclay"), dir.file("store-named.vdb"));
        std::filesystem::copy_file(dir.file("script.json"), dir.file("script-named.obj"));
        std::filesystem::copy_file(dir.file("script.json"), dir.file("script-named.csv"));
        std::filesystem::copy_file(dir.file("m.ply"), dir.file("ply-named.glb"));
        std::filesystem::copy_file(dir.file("f.csv"), dir.file("csv-named.json"));
        std::filesystem::copy_file(dir.file("s.vdb"), dir.file("volume-named.png"));
        writeText(dir.file("notes.mtl"), "my notes, not a materials file\n");
        std::filesystem::copy_file(dir.file("m.obj"), dir.file("notes.obj"));
        std::filesystem::create_symlink("s.vdb", dir.file("link-to-s.vdb"));
        std::filesystem::create_symlink("c.vdbclay", dir.file("link-to-c.vdbclay"));
        // A session that edits nothing: the replay leaves s.vdb's working store beside it, an input of
        // every later edit of s.vdb.
        writeText(dir.file("session.json"),
                  R"({"vdbclay_session": 1, "commands": [{"frame": 0, "command": "camera", "eye": [9, 9, 9], "target": [0, 0, 0]}]})");
        REQUIRE(runCli(dir, "edit s.vdb --replay session.json --headless").exitCode == 0);
        REQUIRE(std::filesystem::exists(dir.file("s.vdb.edit.vdbclay")));
    }
};

/// A command that writes, with OUT where its output goes, the files it reads (through links too), and the
/// files of its own kind it may replace.
struct Writer {
    std::string command;
    std::vector<std::string> inputs, replaceable;
};

/// Files of every kind in Victims, some under other kinds' extensions.
const std::vector<std::string> kVictimFiles{"s.vdb",           "c.vdbclay",        "script.json",      "path.json",
                                            "m.obj",           "m.ply",            "m.glb",            "foreign.vdb",
                                            "ls.vdb",          "f.csv",            "f.png",            "store-named.vdb",
                                            "script-named.obj", "script-named.csv", "ply-named.glb",   "csv-named.json",
                                            "volume-named.png", "notes.obj",        "session.json",    "s.vdb.edit.vdbclay"};

/// Each writer aimed at each of its inputs and at every file it may not replace: refused as a wrong
/// command line, and nothing in the folder changes.
void checkRefusedEverywhere(const Victims& v, const std::vector<Writer>& writers)
{
    const auto before = snapshot(v.dir);
    for (const Writer& w : writers) {
        std::vector<std::string> targets = w.inputs;
        for (const std::string& f : kVictimFiles)
            if (std::find(w.replaceable.begin(), w.replaceable.end(), f) == w.replaceable.end()) targets.push_back(f);
        for (const std::string& target : targets) {
            std::string command = w.command;
            command.replace(command.find("OUT"), 3, target);
            INFO(command);
            const CommandResult r = runCli(v.dir, command);
            INFO("stderr: " << r.err);
            CHECK(r.exitCode == 2);
            CHECK(r.err.find("vdbclay: error: ") != std::string::npos);
            CHECK(snapshot(v.dir) == before);
        }
    }
}

} // namespace

TEST_CASE("outputs: the content of an existing file is told from its first bytes", "[outputs]")
{
    Victims v;
    const std::map<std::string, FileContent> expected{
        {"s.vdb", FileContent::NativeVolume},          {"c.vdbclay", FileContent::Store},
        {"m.obj", FileContent::ObjMesh},               {"m.mtl", FileContent::MtlLibrary},
        {"m.ply", FileContent::PlyMesh},               {"m.glb", FileContent::GlbMesh},
        {"ls.vdb", FileContent::StandardVdbExport},    {"foreign.vdb", FileContent::ForeignVdb},
        {"script.json", FileContent::Json},            {"path.json", FileContent::Json},
        {"f.csv", FileContent::FlightCsv},             {"f.png", FileContent::Png},
        {"store-named.vdb", FileContent::Store},       {"notes.mtl", FileContent::OtherText},
        {"volume-named.png", FileContent::NativeVolume}, {"missing.vdb", FileContent::Missing},
        {"link-to-s.vdb", FileContent::NativeVolume}};
    for (const auto& [name, content] : expected) {
        INFO(name);
        CHECK(sniffFileContent(v.dir.file(name)) == content);
    }
    writeText(v.dir.file("empty.vdb"), "");
    CHECK(sniffFileContent(v.dir.file("empty.vdb")) == FileContent::Empty);
    CHECK(sniffFileContent(v.dir.path().string()) == FileContent::NotAFile);
    CHECK(sameFile(v.dir.file("link-to-s.vdb"), v.dir.file("s.vdb")));
    CHECK_FALSE(sameFile(v.dir.file("s.vdb"), v.dir.file("ls.vdb")));
    CHECK_FALSE(sameFile(v.dir.file("missing.vdb"), v.dir.file("missing.vdb")));
}

TEST_CASE("cli: no command writes over its inputs or over a file of another kind", "[outputs][cli]")
{
    if (std::string(kCli).empty()) return;
    Victims v;
    checkRefusedEverywhere(v, {
        {"new OUT --shape sphere --size 3", {}, {"s.vdb"}},
        {"sculpt s.vdb script.json -o OUT", {"script.json"}, {"s.vdb", "c.vdbclay"}}, // in place is allowed
        {"sculpt c.vdbclay script.json -o OUT", {"script.json"}, {"c.vdbclay"}},
        {"mesh s.vdb -o OUT", {"s.vdb", "link-to-s.vdb"}, {"m.obj", "m.ply", "m.glb"}},
        {"mesh c.vdbclay -o OUT", {"c.vdbclay", "link-to-c.vdbclay"}, {"m.obj", "m.ply", "m.glb"}},
        {"import s.vdb -o OUT", {"s.vdb", "link-to-s.vdb"}, {"c.vdbclay"}},
        {"import c.vdbclay -o OUT", {"c.vdbclay", "link-to-c.vdbclay"}, {"s.vdb"}},
        {"import m.obj --resolution 16 -o OUT", {"m.obj"}, {"s.vdb", "c.vdbclay"}},
        {"import foreign.vdb -o OUT", {"foreign.vdb"}, {"s.vdb", "c.vdbclay"}},
        {"export c.vdbclay -o OUT", {"c.vdbclay", "link-to-c.vdbclay"}, {"s.vdb"}},
        {"export-levelset s.vdb -o OUT", {"s.vdb", "link-to-s.vdb"}, {"ls.vdb"}},
        {"lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --csv OUT", {"c.vdbclay", "path.json"}, {"f.csv"}},
        {"lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --plot OUT", {"c.vdbclay", "path.json"}, {"f.png"}},
        {"synth csg-stack --extent 64 -o OUT", {}, {"c.vdbclay"}},
        {"tool make s.vdb -o OUT", {"s.vdb", "link-to-s.vdb"}, {}},
        {"selftest --scenes 1 --save-failure OUT", {}, {"script.json", "path.json", "session.json"}},
    });
    const auto before = snapshot(v.dir);
    // An OBJ's materials file beside it is checked too: notes.obj would replace notes.mtl.
    CHECK(sniffFileContent(v.dir.file("notes.obj")) == FileContent::ObjMesh);
    const CommandResult notes = runCli(v.dir, "mesh s.vdb -o notes.obj");
    CHECK(notes.exitCode == 2);
    CHECK(notes.err.find("notes.mtl") != std::string::npos);
    // The extension must name what is written.
    for (const char* command : {"export-levelset s.vdb -o out.xyz", "tool make s.vdb -o knob.xyz", "new out.txt --shape box --size 2",
                                "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --csv out.txt",
                                "selftest --scenes 1 --save-failure out.txt", "mesh s.vdb -o out.stl"}) {
        INFO(command);
        CHECK(runCli(v.dir, command).exitCode == 2);
    }
    CHECK(snapshot(v.dir) == before);
    // What each writer may replace, it replaces (its own kind, not an input).
    CHECK(runCli(v.dir, "export-levelset s.vdb -o ls.vdb").exitCode == 0);
    CHECK(runCli(v.dir, "mesh s.vdb -o m.ply").exitCode == 0);
    CHECK(runCli(v.dir, "sculpt s.vdb script.json -o s.vdb").exitCode == 0);
    CHECK(runCli(v.dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --csv f.csv").exitCode == 0);
}

TEST_CASE("cli: no output of the editor writes over its inputs or over a file of another kind", "[outputs][cli][editor]")
{
    if (std::string(kCli).empty()) return;
    Victims v;
    // Never the scene (however spelled), its working store, the session replayed, nor a file of another kind.
    checkRefusedEverywhere(v, {
        {"edit s.vdb --replay session.json --headless -o OUT", {"s.vdb", "link-to-s.vdb", "session.json", "s.vdb.edit.vdbclay"}, {"c.vdbclay"}},
        {"edit s.vdb --replay session.json --headless --screenshot OUT", {"session.json"}, {"f.png"}},
        {"edit s.vdb --replay session.json --headless --export-script OUT", {"session.json"}, {"script.json", "path.json"}},
        {"edit s.vdb --replay session.json --headless --record OUT", {"session.json"}, {"script.json", "path.json"}},
        {"edit c.vdbclay --replay session.json --headless -o OUT", {"c.vdbclay", "link-to-c.vdbclay", "session.json"}, {"s.vdb"}},
    });
}

TEST_CASE("cli: a command's outputs never name one file, nor make more than their own folder", "[outputs][cli]")
{
    if (std::string(kCli).empty()) return;
    Victims v;
    const auto before = snapshot(v.dir);
    // Two outputs of one command on the same file, however spelled.
    const std::string folder = v.dir.path().filename().string();
    for (const std::string& line : {std::string("edit s.vdb --replay session.json --headless --record out.json --export-script ./out.json"),
                                    "edit s.vdb --replay session.json --headless --record ../" + folder + "/out.json --export-script out.json"}) {
        INFO(line);
        const CommandResult r = runCli(v.dir, line);
        CHECK(r.exitCode == 2);
        CHECK(r.err.find("name the same file") != std::string::npos);
    }
    std::filesystem::create_directory(v.dir.file("shots"));
    for (const char* command : {"lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --frames shots --plot shots/frame-00000.png",
                                "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --frames shots --plot shots/settled.png"}) {
        INFO(command);
        const CommandResult r = runCli(v.dir, command);
        CHECK(r.exitCode == 2);
        CHECK(r.err.find("a picture of --frames") != std::string::npos);
    }
    // --frames makes its own folder at most: not a chain of them.
    const CommandResult deep = runCli(v.dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --frames no/such/folder");
    CHECK(deep.exitCode == 2);
    CHECK(deep.err.find("does not exist") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(v.dir.file("no")));
    std::filesystem::remove(v.dir.file("shots"));
    CHECK(snapshot(v.dir) == before);
}
