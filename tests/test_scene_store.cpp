// The scene store: round trips against the native .vdb, sculpting in place against sculpting the
// .vdb, and stores that are damaged, truncated, foreign, newer or open for writing elsewhere.
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/StoreSculpt.h"
#include "sculpt/StrokeScript.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

std::string randomScript(std::mt19937& rng)
{
    std::uniform_real_distribution<double> pos(-60.0, 60.0), radius(2.0, 14.0);
    const char* modes[] = {"add", "remove", "paint", "erode", "add", "remove"};
    nlohmann::json ops = nlohmann::json::array();
    for (int i = 0; i < 6; ++i) {
        nlohmann::json op{{"mode", modes[rng() % 6]}, {"brush", {{"shape", rng() % 2 ? "sphere" : "box"}, {"radius", radius(rng)},
                                                               {"size", {radius(rng), radius(rng), radius(rng)}}}}};
        if (rng() % 3 == 0) op["path"] = {{pos(rng), pos(rng), pos(rng)}, {pos(rng), pos(rng), pos(rng)}};
        else op["at"] = {std::round(pos(rng)), std::round(pos(rng)), pos(rng)};
        if (op["mode"] == "paint" || op["mode"] == "add") op["material"] = rng() % 2 ? "red" : "default";
        ops.push_back(op);
    }
    return nlohmann::json{{"materials", {{{"name", "red"}, {"color", {1, 0, 0, 1}}, {"toughness", 0.5}}}}, {"ops", ops}}.dump();
}

void execSql(const std::string& path, const std::string& sql)
{
    sqlite3* db = nullptr;
    REQUIRE(sqlite3_open(path.c_str(), &db) == SQLITE_OK);
    char* message = nullptr;
    const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message);
    sqlite3_free(message);
    sqlite3_close(db);
    REQUIRE(rc == SQLITE_OK);
}

int64_t storeFormatVersion(const std::string& path)
{
    sqlite3* db = nullptr;
    REQUIRE(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
    sqlite3_stmt* stmt = nullptr;
    REQUIRE(sqlite3_prepare_v2(db, "PRAGMA user_version", -1, &stmt, nullptr) == SQLITE_OK);
    REQUIRE(sqlite3_step(stmt) == SQLITE_ROW);
    const int64_t version = sqlite3_column_int64(stmt, 0);
    sqlite3_finalize(stmt);
    sqlite3_close(db);
    return version;
}

} // namespace

TEST_CASE("a store of format version 1 still loads, and opening it for writing marks it version 2", "[store]")
{
    TempDir dir;
    const Volume v = multiBrickScene();
    const std::string path = dir.file("old.vdbclay");
    writeStoreFile(v, path);
    CHECK(storeFormatVersion(path) == 2);
    {
        // What version 1 wrote: each brick as a .vdb stream of its box.
        SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
        StoreTransaction transaction(scene.bricks());
        for (const IndexCoord& b : scene.brickCoords(0)) {
            std::optional<BrickRecord> record = scene.bricks().get({0, b});
            if (record->uniform) continue;
            record->payload = encodeVolume(copyRegion(v, brickBox(b)));
            scene.bricks().put({0, b}, *record);
        }
        transaction.commit();
    }
    execSql(path, "PRAGMA user_version = 1;");
    CHECK(identical(loadScene(path), v));
    CHECK(storeFormatVersion(path) == 1); // reading leaves it as it is
    CHECK(SceneStore::open(path, StoreAccess::ReadOnly).bricks().formatVersion() == 1);
    CHECK(SceneStore::open(path, StoreAccess::ReadWrite).bricks().formatVersion() == 2);
    CHECK(storeFormatVersion(path) == 2);
    CHECK(identical(loadScene(path), v));
}

TEST_CASE("a store round trip equals the native .vdb round trip bit-exactly", "[store]")
{
    TempDir dir;
    const Volume v = multiBrickScene();
    writeStoreFile(v, dir.file("s.vdbclay"));
    saveVolume(v, dir.file("s.vdb"));
    const Volume fromStore = loadScene(dir.file("s.vdbclay"));
    const Volume fromVdb = loadScene(dir.file("s.vdb"));
    CHECK(checkInvariants(fromStore).empty());
    CHECK(identical(fromStore, v));
    CHECK(identical(fromStore, fromVdb));
    // Exported again, the store gives the very bytes of the .vdb.
    saveVolume(fromStore, dir.file("back.vdb"));
    CHECK(readBytes(dir.file("back.vdb")) == readBytes(dir.file("s.vdb")));

    {
        const SceneStore scene = SceneStore::open(dir.file("s.vdbclay"), StoreAccess::ReadOnly);
        const LevelSummary level0 = scene.summary(0);
        CHECK(level0.leaves == v.stats().leafCount);
        CHECK(level0.bricks > 8);
        bool uniformBrick = false;
        scene.bricks().scan(0, [&](const BrickKey&, const BrickSummary& b) { uniformBrick = uniformBrick || b.uniform.has_value(); });
        CHECK(uniformBrick);
    }
    // Replacing a store keeps no trace of the old one.
    writeStoreFile(Volume(0.5), dir.file("s.vdbclay"));
    CHECK(loadScene(dir.file("s.vdbclay")).stats().empty);
    CHECK(dir.entries() == std::vector<std::string>{"back.vdb", "s.vdb", "s.vdbclay"});
}

TEST_CASE("sculpting a store in place equals sculpting the .vdb", "[store]")
{
    TempDir dir;
    std::mt19937 rng(5);
    Volume reference = multiBrickScene();
    writeStoreFile(reference, dir.file("s.vdbclay"));
    for (int round = 0; round < 6; ++round) {
        const StrokeScript script = parseStrokeScript(randomScript(rng));
        runStrokeScript(reference, script);
        StoreSculptReport report;
        {
            SceneStore scene = SceneStore::open(dir.file("s.vdbclay"), StoreAccess::ReadWrite);
            report = sculptStore(scene, script);
        }
        INFO("round " << round);
        const Volume stored = loadScene(dir.file("s.vdbclay"));
        REQUIRE(identical(stored, reference));
        CHECK(report.bricksWritten <= report.bricksRead);
    }
    // Intersect reaches the whole scene.
    const StrokeScript intersect =
        parseStrokeScript(R"({"ops": [{"mode": "intersect", "brush": {"shape": "sphere", "radius": 30}, "at": [0, 0, 0]}]})");
    runStrokeScript(reference, intersect);
    {
        SceneStore scene = SceneStore::open(dir.file("s.vdbclay"), StoreAccess::ReadWrite);
        sculptStore(scene, intersect);
    }
    CHECK(identical(loadScene(dir.file("s.vdbclay")), reference));
}

TEST_CASE("a small edit reads and writes only the bricks it reaches", "[store]")
{
    TempDir dir;
    writeStoreFile(multiBrickScene(), dir.file("s.vdbclay"));
    SceneStore scene = SceneStore::open(dir.file("s.vdbclay"), StoreAccess::ReadWrite);
    const uint64_t total = scene.summary(0).bricks;
    const StrokeScript stamp =
        parseStrokeScript(R"({"ops": [{"mode": "remove", "brush": {"shape": "sphere", "radius": 3}, "at": [25.3, 0.2, 0.1]}]})");
    const StoreSculptReport report = sculptStore(scene, stamp);
    CHECK(report.bricksRead <= 8);
    CHECK(report.bricksWritten >= 1);
    CHECK(report.bricksRead < total);
}

TEST_CASE("stores that are damaged, truncated, foreign or newer are refused with one line", "[store]")
{
    TempDir dir;
    const std::string good = dir.file("good.vdbclay");
    writeStoreFile(multiBrickScene(), good);
    const auto refused = [](const std::string& path, const std::string& needle) {
        try {
            const Volume v = loadScene(path);
            FAIL("loaded " << path);
        } catch (const StoreError& e) {
            const std::string what = e.what();
            INFO(what);
            CHECK(what.find('\n') == std::string::npos);
            CHECK(what.find(needle) != std::string::npos);
        }
    };
    SECTION("not a database")
    {
        writeText(dir.file("text.vdbclay"), "hello, this is text");
        refused(dir.file("text.vdbclay"), "not an SQLite database");
        CHECK_THROWS_AS(SceneStore::open(dir.file("missing.vdbclay"), StoreAccess::ReadOnly), StoreError);
    }
    SECTION("another application's database")
    {
        execSql(dir.file("other.vdbclay"), "CREATE TABLE t (a INTEGER); INSERT INTO t VALUES (1);");
        refused(dir.file("other.vdbclay"), "not a VDBClay scene store");
    }
    SECTION("a newer format")
    {
        execSql(good, "PRAGMA user_version = 7;");
        refused(good, "format version 7");
    }
    SECTION("metadata gone")
    {
        execSql(good, "DELETE FROM meta WHERE key = 'voxel_size';");
        refused(good, "lacks 'voxel_size'");
    }
    SECTION("metadata values that are not what they claim, each named with its key")
    {
        // std::stod read "0x10" as 16 and blamed the bricks; "(stoi)" named no key; garbage flags passed.
        const std::vector<std::pair<std::string, std::string>> cases{
            {"voxel_size", "0x10"}, {"voxel_size", "inf"},    {"voxel_size", "1e-9"}, {"voxel_size", "0.5 "},
            {"lod_levels", "abc"},  {"lod_levels", "99"},     {"lod_levels", "-1"},   {"lod_stale", "yes"},
            {"lod_stale", ""},      {"materials", "[1, 2]"}};
        for (const auto& [key, value] : cases) {
            CAPTURE(key, value);
            std::filesystem::copy_file(good, dir.file("meta.vdbclay"), std::filesystem::copy_options::overwrite_existing);
            execSql(dir.file("meta.vdbclay"), "UPDATE meta SET value = '" + value + "' WHERE key = '" + key + "';");
            refused(dir.file("meta.vdbclay"), "its metadata '" + key + "'");
        }
        execSql(good, "INSERT OR REPLACE INTO meta (key, value) VALUES ('lod_levels', '1'), ('lod_densities', 'garbage');");
        CHECK_THROWS_WITH(lodFollowsEdits(SceneStore::open(good, StoreAccess::ReadOnly)), Catch::Contains("'lod_densities'"));
    }
    SECTION("a payload damaged inside the database")
    {
        execSql(good, "UPDATE bricks SET payload = substr(payload, 1, length(payload) / 2) || zeroblob(64) "
                      "WHERE uniform IS NULL;");
        refused(good, "damaged");
    }
    SECTION("brick rows whose coordinates or counts SQLite's loose typing let through")
    {
        // Each was skipped silently (export and mesh left voxels out, exit 0): now each is damage.
        for (const char* change : {"x = 1099511627776", "y = 1.5", "z = 'abc'", "x = -2147483649", "leaves = 'many'",
                                   "leaves = 100000", "uniform = 70000", "uniform = 2.5"}) {
            CAPTURE(change);
            std::filesystem::copy_file(good, dir.file("rows.vdbclay"), std::filesystem::copy_options::overwrite_existing);
            execSql(dir.file("rows.vdbclay"), std::string("UPDATE bricks SET ") + change +
                                                  " WHERE (level, x, y, z) = (SELECT level, x, y, z FROM bricks WHERE level = 0 "
                                                  "ORDER BY x, y, z LIMIT 1);");
            refused(dir.file("rows.vdbclay"), "is damaged: ");
        }
    }
    SECTION("truncated and overwritten files")
    {
        const std::vector<char> bytes = readBytes(good);
        std::mt19937 rng(9);
        for (int trial = 0; trial < 40; ++trial) {
            std::vector<char> damaged = bytes;
            if (trial % 2 == 0) {
                damaged.resize(std::size_t(rng() % bytes.size()));
            } else {
                for (int i = 0; i < 16; ++i) damaged[std::size_t(rng() % damaged.size())] ^= char(1 + rng() % 255);
            }
            const std::string path = dir.file("damaged" + std::to_string(trial) + ".vdbclay");
            writeBytes(path, damaged.data(), damaged.size());
            // Either refused with one line, or (damage in free pages) read as the scene it was.
            try {
                const Volume v = loadScene(path);
                CHECK(checkInvariants(v).empty());
            } catch (const std::exception& e) {
                const std::string what = e.what();
                CHECK(what.find('\n') == std::string::npos);
            }
        }
    }
}

TEST_CASE("a store open for writing refuses a second writer and lets readers read", "[store]")
{
    TempDir dir;
    const std::string path = dir.file("s.vdbclay");
    writeStoreFile(multiBrickScene(), path);
    SceneStore writer = SceneStore::open(path, StoreAccess::ReadWrite);
    try {
        SceneStore second = SceneStore::open(path, StoreAccess::ReadWrite);
        FAIL("a second writer opened the store");
    } catch (const StoreError& e) {
        CHECK(std::string(e.what()).find("open for writing by another process") != std::string::npos);
    }
    CHECK_THROWS_AS(writeStoreFile(Volume(0.5), path), StoreError);
    const SceneStore reader = SceneStore::open(path, StoreAccess::ReadOnly);
    CHECK(reader.summary(0).bricks == writer.summary(0).bricks);
}

TEST_CASE("a reader connection reads beside the writer and sees only what it commits", "[store]")
{
    TempDir dir;
    const std::string path = dir.file("s.vdbclay");
    writeStoreFile(multiBrickScene(), path);
    SceneStore writer = SceneStore::open(path, StoreAccess::ReadWrite);
    const std::vector<IndexCoord> bricks = writer.brickCoords(0);
    REQUIRE(bricks.size() > 1);
    const std::unique_ptr<BrickStore> reader = writer.bricks().openReader();
    const BrickKey key{0, bricks[0]};
    const std::optional<BrickRecord> before = writer.bricks().get(key);
    REQUIRE(before);
    CHECK(sameBrick(reader->get(key), before));
    // Through the reader, a brick decodes exactly as through the writer's own connection.
    uint64_t viaReader = 0, viaWriter = 0;
    Volume a(writer.voxelSize()), b(writer.voxelSize());
    pasteRegion(a, writer.readBrick(0, bricks[1], *reader, writer.materials().size(), &viaReader));
    pasteRegion(b, writer.readBrick(0, bricks[1], writer.bricks(), writer.materials().size(), &viaWriter));
    CHECK(viaReader == viaWriter);
    CHECK(identical(a, b));

    BrickRecord changed = *before;
    changed.uniform = MaterialId(1);
    changed.payload.clear();
    {
        StoreTransaction transaction(writer.bricks());
        writer.bricks().put(key, changed);
        CHECK(sameBrick(reader->get(key), before)); // not committed yet: the reader's snapshot is the old one
        transaction.commit();
    }
    CHECK(sameBrick(reader->get(key), changed));
    CHECK_THROWS_AS(reader->put(key, *before), StoreError); // it only reads
}

TEST_CASE("a store's bounds equal its volume's, kept by writers and found again after edits", "[store]")
{
    TempDir dir;
    const std::string path = dir.file("s.vdbclay");
    const Volume v = multiBrickScene();
    writeStoreFile(v, path);
    const auto expect = [](const SceneStore& scene, const Volume& volume) {
        const auto box = scene.bounds();
        REQUIRE(box);
        CHECK(box->first == volume.stats().bboxMin);
        CHECK(box->second == volume.stats().bboxMax);
    };
    expect(SceneStore::open(path, StoreAccess::ReadOnly), v);
    CHECK(SceneStore::open(path, StoreAccess::ReadOnly).bricks().meta("bbox").value_or("") != ""); // kept by the import
    // Edits that grow and shrink the scene, at random: the bounds follow (forgotten, then found from the bricks).
    std::mt19937 rng(3);
    for (int trial = 0; trial < 6; ++trial) {
        const int x = int(rng() % 200) - 100, r = 4 + int(rng() % 20);
        const std::string mode = trial % 2 ? "remove" : "add";
        const std::string script = R"({"ops": [{"mode": ")" + mode + R"(", "brush": {"shape": "sphere", "radius": )" +
                                   std::to_string(r) + R"(}, "at": [)" + std::to_string(x) + R"(, 3, -5]}]})";
        {
            SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
            sculptStore(scene, parseStrokeScript(script));
        }
        const SceneStore scene = SceneStore::open(path, StoreAccess::ReadOnly);
        expect(scene, scene.loadLevel(0));
    }
    execSql(path, "UPDATE meta SET value = '1 2 3' WHERE key = 'bbox';");
    CHECK_THROWS_WITH(SceneStore::open(path, StoreAccess::ReadOnly).bounds(), Catch::Contains("'bbox'"));
}

TEST_CASE("coarse bricks' errors: kept beside the bricks, refused when damaged, absent from older stores", "[store][lod]")
{
    TempDir dir;
    const std::string path = dir.file("e.vdbclay");
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(50.0), at(Vec3d(0.3, -0.2, 0.1)));
    writeStoreFile(v, path);
    {
        SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
        buildStoreLod(scene, 2);
        // Every coarse brick has one; a smooth sphere's lie under the level's voxel (each level's box filter
        // rounds the surface by about 0.3 of its voxel, and the levels' errors add up).
        for (int k = 1; k <= 2; ++k)
            for (const IndexCoord& b : scene.brickCoords(k)) {
                const std::optional<double> error = scene.bricks().lodError({k, b});
                REQUIRE(error);
                CHECK(*error >= 0.0);
                CHECK(*error < 0.75 * double(1 << k));
            }
        CHECK_FALSE(scene.bricks().lodError({0, scene.brickCoords(0).front()})); // level 0 is exact
        // Gone with its brick when a level goes.
        buildStoreLod(scene, 1);
        std::size_t level2 = 0;
        scene.bricks().scanLodErrors(2, [&](const IndexCoord&, double) { ++level2; });
        CHECK(level2 == 0);
        buildStoreLod(scene, 2);
    }
    SECTION("a damaged error row is refused with one line naming it")
    {
        for (const char* value : {"'abc'", "-1.0", "1e999", "X'00'"}) {
            CAPTURE(value);
            std::filesystem::copy_file(path, dir.file("bad.vdbclay"), std::filesystem::copy_options::overwrite_existing);
            execSql(dir.file("bad.vdbclay"), std::string("UPDATE lod_errors SET error = ") + value + " WHERE level = 1;");
            const SceneStore scene = SceneStore::open(dir.file("bad.vdbclay"), StoreAccess::ReadOnly);
            CHECK_THROWS_WITH(scene.bricks().scanLodErrors(1, [](const IndexCoord&, double) {}), Catch::Contains("is not a length"));
            CHECK_THROWS_AS(scene.bricks().lodError({1, scene.brickCoords(1).front()}), StoreError);
        }
    }
    SECTION("a store written before errors were kept: read without them, given the table when written")
    {
        execSql(path, "DROP TABLE lod_errors;");
        {
            const SceneStore scene = SceneStore::open(path, StoreAccess::ReadOnly);
            CHECK_FALSE(scene.bricks().lodError({1, scene.brickCoords(1).front()}));
            std::size_t rows = 0;
            scene.bricks().scanLodErrors(1, [&](const IndexCoord&, double) { ++rows; });
            CHECK(rows == 0);
        }
        SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
        buildStoreLod(scene, 2);
        CHECK(scene.bricks().lodError({1, scene.brickCoords(1).front()}));
    }
}
