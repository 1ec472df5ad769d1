// A store whose metadata and brick rows were changed through SQLite (whose loose typing lets any value
// into any column), not only its bytes: the input is a list of edits to a copy of a small store with
// levels of detail. Every reader must then read the store or refuse it with one printable line.
//
// An edit: one byte picks its kind and target, one byte a value's type (integer, real, text, blob,
// null), then up to 8 bytes of value (a length byte first for text and blobs).
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "support/Sculpt.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeIO.h"

#include <sqlite3.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace {

const char* const kMetaKeys[] = {"format",    "voxel_size",    "materials",  "brick_leaves", "lod_levels",
                                 "lod_stale", "lod_densities", "edit_count", "bbox",         "no_such_key"};
const char* const kColumns[] = {"level", "x", "y", "z", "uniform", "leaves", "payload"};

std::string seedStore()
{
    static const std::string path = [] {
        const std::string p = "/tmp/vdbclay-fuzz-store-seed-" + std::to_string(::getpid()) + ".vdbclay";
        std::filesystem::remove(p);
        using namespace vdbclay::test;
        vdbclay::Volume v(0.5); // a sphere and a box of another material across several bricks
        const vdbclay::MaterialId red = v.materials().define(vdbclay::Material{"red"});
        apply(v, vdbclay::CsgMode::Add, sphere(20.0), at({0.0, 0.0, 0.0}), 1);
        apply(v, vdbclay::CsgMode::Add, box({12.0, 12.0, 12.0}), at({30.0, 0.0, 0.0}), red);
        vdbclay::writeStoreFile(v, p);
        vdbclay::SceneStore scene = vdbclay::SceneStore::open(p, vdbclay::StoreAccess::ReadWrite);
        vdbclay::buildStoreLod(scene, 2);
        return p;
    }();
    return path;
}

struct Reader {
    const uint8_t* data;
    size_t size, at = 0;
    bool more() const { return at < size; }
    uint8_t byte() { return at < size ? data[at++] : 0; }
    int64_t integer()
    {
        uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v = (v << 8) | byte();
        return int64_t(v);
    }
    std::string bytes()
    {
        const size_t n = std::min<size_t>(byte(), size - std::min(at, size));
        std::string s(reinterpret_cast<const char*>(data + at), n);
        at += n;
        return s;
    }
};

/// Binds a value of the type the input picks.
void bindValue(sqlite3_stmt* s, int index, Reader& in)
{
    switch (in.byte() % 6) {
    case 0: sqlite3_bind_int64(s, index, in.integer()); break;
    case 1: sqlite3_bind_int64(s, index, int64_t(int8_t(in.byte()))); break; // small integers: near valid values
    case 2: {
        double d = 0.0;
        const int64_t bits = in.integer();
        std::memcpy(&d, &bits, sizeof d);
        sqlite3_bind_double(s, index, d);
        break;
    }
    case 3: {
        const std::string t = in.bytes();
        sqlite3_bind_text(s, index, t.data(), int(t.size()), SQLITE_TRANSIENT);
        break;
    }
    case 4: {
        const std::string b = in.bytes();
        sqlite3_bind_blob(s, index, b.data(), int(b.size()), SQLITE_TRANSIENT);
        break;
    }
    default: sqlite3_bind_null(s, index);
    }
}

void run(sqlite3* db, const std::string& sql, Reader& in, int values)
{
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) return;
    for (int i = 1; i <= values; ++i) bindValue(s, i, in);
    (void)sqlite3_step(s); // a constraint refused (a repeated key, NULL in NOT NULL) leaves the row as it was
    sqlite3_finalize(s);
}

void requirePrintable(const char* message)
{
    if (!vdbclay::isPrintableName(message, std::string::npos)) std::abort(); // raw bytes or several lines
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string path = "/tmp/vdbclay-fuzz-store-" + std::to_string(::getpid()) + ".vdbclay";
    std::filesystem::copy_file(seedStore(), path, std::filesystem::copy_options::overwrite_existing);
    {
        sqlite3* db = nullptr;
        if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) std::abort();
        Reader in{data, size};
        for (int edits = 0; in.more() && edits < 16; ++edits) {
            const uint8_t what = in.byte();
            const uint8_t target = in.byte();
            switch (what % 4) {
            case 0:
                run(db, std::string("INSERT OR REPLACE INTO meta (key, value) VALUES ('") + kMetaKeys[target % 10] + "', ?1)", in, 1);
                break;
            case 1: // one column of the n-th brick row
                run(db, std::string("UPDATE bricks SET ") + kColumns[target % 7] +
                            " = ?1 WHERE (level, x, y, z) = (SELECT level, x, y, z FROM bricks ORDER BY level, x, y, z LIMIT 1 OFFSET " +
                            std::to_string(in.byte() % 32) + ")",
                    in, 1);
                break;
            case 2: run(db, "INSERT OR REPLACE INTO bricks (level, x, y, z, uniform, leaves, payload) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)", in, 7); break;
            default: run(db, std::string("DELETE FROM meta WHERE key = '") + kMetaKeys[target % 10] + "'", in, 0);
            }
        }
        sqlite3_close(db);
    }
    try {
        const vdbclay::SceneStore scene = vdbclay::SceneStore::open(path, vdbclay::StoreAccess::ReadOnly);
        (void)scene.bounds();
        (void)vdbclay::lodFollowsEdits(scene);
        for (int k = 0; k <= scene.lodLevels(); ++k) {
            (void)scene.summary(k);
            const vdbclay::Volume level = scene.loadLevel(k);
            (void)level.stats();
        }
    } catch (const vdbclay::StoreError& e) {
        requirePrintable(e.what());
    } catch (const vdbclay::VolumeIOError& e) {
        requirePrintable(e.what());
    } catch (const std::invalid_argument& e) {
        requirePrintable(e.what());
    }
    std::filesystem::remove(path);
    return 0;
}
