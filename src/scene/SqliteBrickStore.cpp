// The SQLite brick store: one table of bricks keyed by (level, x, y, z), one of metadata. WAL mode, so
// readers see the last committed state while a writer works; synchronous=FULL, so a commit survives a
// crash of the process or of the machine. One writer at a time, held by an flock on the file (SQLite's
// own locks are fcntl locks, which flock does not disturb).
#include "scene/BrickStore.h"

#include "scene/SceneStore.h" // the brick edge: what a row may hold
#include "vdb_hermite/FileStatus.h"

#include <sqlite3.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

constexpr int32_t kApplicationId = 0x56434C59; // "VCLY"
/// 2: brick payloads are RegionCodec records (1: .vdb streams of the brick, which 2 still reads).
constexpr int kStoreFormatVersion = 2;
/// The farthest brick from the origin the lattice can hold, and the leaves a brick can hold.
constexpr int64_t kMaxBrickCoordinate = int64_t(kMaxLatticeCoordinate) / kBrickEdge;
constexpr int64_t kMaxLeavesPerBrick = int64_t(kBrickEdge / 8) * (kBrickEdge / 8) * (kBrickEdge / 8);

/// Resets a statement when it goes out of scope: a statement left on a row holds a read transaction
/// open, which pins the reader's snapshot and stops checkpoints from emptying the WAL.
struct ResetOnExit {
    sqlite3_stmt* stmt;
    ~ResetOnExit() { sqlite3_reset(stmt); }
};

class Statement {
public:
    Statement(sqlite3* db, const char* sql, const std::string& path)
    {
        if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK)
            throw StoreError("'" + path + "' is not a usable VDBClay scene store (" + sqlite3_errmsg(db) + ")");
    }
    ~Statement() { sqlite3_finalize(stmt_); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;
    /// The statement with its bindings cleared; callers reset it after use (ResetOnExit).
    sqlite3_stmt* get() const
    {
        sqlite3_clear_bindings(stmt_);
        return stmt_;
    }

private:
    sqlite3_stmt* stmt_ = nullptr;
};

class SqliteBrickStore final : public BrickStore {
public:
    /// `sibling`: a reader of a store this process has open already, which needs no checks of the file
    /// (they open and close a descriptor of it, and closing any descriptor of a file drops the fcntl
    /// locks the process's other connections hold on it).
    SqliteBrickStore(const std::string& path, StoreAccess access, bool sibling = false) : path_(path)
    {
        if (!sibling) requireUsableFile(path, access);
        if (access != StoreAccess::ReadOnly) lockForWriting(access == StoreAccess::Create);
        // A reader opens a store it could write read-write (and then only queries), so that SQLite removes
        // the -wal and -shm files when the last connection closes instead of leaving them beside the store.
        // Where it cannot write the file or its folder (a shared or archived folder), it opens the file
        // read-only; with no -wal beside it no writer can be at work (one would have made it), so the
        // store is opened as immutable, which needs no -shm file in a folder it cannot write.
        std::string name = path;
        int flags = access == StoreAccess::Create ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READWRITE;
        if (access == StoreAccess::ReadOnly && !writable(path)) {
            flags = SQLITE_OPEN_READONLY;
            std::error_code ec;
            if (!fs::exists(path + "-wal", ec)) {
                name = immutableUri(path);
                flags |= SQLITE_OPEN_URI;
            }
        }
        if (sqlite3_open_v2(name.c_str(), &db_, flags | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK) {
            const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
            close();
            throw StoreError("cannot open '" + path + "': " + why);
        }
        try {
            sqlite3_busy_timeout(db_, 10000);
            sqlite3_extended_result_codes(db_, 1);
            if (access == StoreAccess::Create) createSchema();
            else checkSchema();
            if (access != StoreAccess::ReadOnly) {
                exec("PRAGMA journal_mode=WAL");
                exec("PRAGMA synchronous=FULL");
                createErrorTable();
                // Bricks written from now on are of this version's form, which older builds cannot read.
                if (pragmaInt("PRAGMA user_version") < kStoreFormatVersion)
                    exec(("PRAGMA user_version=" + std::to_string(kStoreFormatVersion)).c_str());
            } else {
                exec("PRAGMA query_only=1");
            }
            prepare();
        } catch (...) {
            close();
            throw;
        }
    }
    ~SqliteBrickStore() override
    {
        if (inTransaction_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
        close();
    }

    std::optional<BrickRecord> get(const BrickKey& key) const override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        sqlite3_stmt* s = select_->get();
        const ResetOnExit reset{s};
        bindKey(s, key);
        const int rc = sqlite3_step(s);
        if (rc == SQLITE_DONE) return std::nullopt;
        if (rc != SQLITE_ROW) fail("read a brick");
        BrickRecord record;
        const auto where = [&] { return "brick (" + std::to_string(key.brick[0]) + ", " + std::to_string(key.brick[1]) + ", " +
                                        std::to_string(key.brick[2]) + ") of level " + std::to_string(key.level); };
        if (sqlite3_column_type(s, 0) != SQLITE_NULL) record.uniform = MaterialId(checkedInteger(s, 0, 0, 65535, where, "uniform"));
        record.leaves = uint32_t(checkedInteger(s, 1, 0, kMaxLeavesPerBrick, where, "leaves"));
        const auto* bytes = static_cast<const char*>(sqlite3_column_blob(s, 2));
        record.payload.assign(bytes ? bytes : "", std::size_t(sqlite3_column_bytes(s, 2)));
        return record;
    }

    void put(const BrickKey& key, const BrickRecord& record) override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        sqlite3_stmt* s = insert_->get();
        const ResetOnExit reset{s};
        bindKey(s, key);
        if (record.uniform) sqlite3_bind_int(s, 5, int(*record.uniform));
        else sqlite3_bind_null(s, 5);
        sqlite3_bind_int64(s, 6, sqlite3_int64(record.leaves));
        sqlite3_bind_blob64(s, 7, record.payload.data(), sqlite3_uint64(record.payload.size()), SQLITE_STATIC);
        if (sqlite3_step(s) != SQLITE_DONE) fail("write a brick");
    }

    void erase(const BrickKey& key) override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        sqlite3_stmt* s = remove_->get();
        const ResetOnExit reset{s};
        bindKey(s, key);
        if (sqlite3_step(s) != SQLITE_DONE) fail("erase a brick");
    }

    void scan(int level, const std::function<void(const BrickKey&, const BrickSummary&)>& fn) const override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        Statement stmt(db_, "SELECT x, y, z, uniform, leaves, length(payload) FROM bricks WHERE level = ?1 ORDER BY x, y, z", path_);
        sqlite3_stmt* s = stmt.get();
        sqlite3_bind_int(s, 1, level);
        int rc;
        while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
            // A row SQLite's loose typing let through (a coordinate of 2^40 or 1.5, a text count) is damage:
            // skipping it would lose its voxels without a word.
            const auto where = [&] { return "a brick row of level " + std::to_string(level); };
            BrickKey key{level, {}};
            for (int a = 0; a < 3; ++a)
                key.brick[std::size_t(a)] = int32_t(checkedInteger(s, a, -kMaxBrickCoordinate, kMaxBrickCoordinate, where, "xyz" + a));
            BrickSummary summary;
            if (sqlite3_column_type(s, 3) != SQLITE_NULL) summary.uniform = MaterialId(checkedInteger(s, 3, 0, 65535, where, "uniform"));
            summary.leaves = uint32_t(checkedInteger(s, 4, 0, kMaxLeavesPerBrick, where, "leaves"));
            summary.bytes = uint64_t(sqlite3_column_int64(s, 5));
            fn(key, summary);
        }
        if (rc != SQLITE_DONE) fail("list the bricks");
    }

    std::optional<std::string> meta(const std::string& key) const override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        sqlite3_stmt* s = metaSelect_->get();
        const ResetOnExit reset{s};
        sqlite3_bind_text(s, 1, key.c_str(), int(key.size()), SQLITE_TRANSIENT);
        const int rc = sqlite3_step(s);
        if (rc == SQLITE_DONE) return std::nullopt;
        if (rc != SQLITE_ROW) fail("read the scene's metadata");
        // Values may hold any bytes (a mask), so they are read by length, not up to a NUL.
        const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
        return text ? std::string(text, std::size_t(sqlite3_column_bytes(s, 0))) : std::string();
    }

    void putMeta(const std::string& key, const std::string& value) override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        sqlite3_stmt* s = metaInsert_->get();
        const ResetOnExit reset{s};
        sqlite3_bind_text(s, 1, key.c_str(), int(key.size()), SQLITE_TRANSIENT);
        sqlite3_bind_text(s, 2, value.c_str(), int(value.size()), SQLITE_TRANSIENT);
        if (sqlite3_step(s) != SQLITE_DONE) fail("write the scene's metadata");
    }

    std::optional<double> lodError(const BrickKey& key) const override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!errorSelect_) return std::nullopt;
        sqlite3_stmt* s = errorSelect_->get();
        const ResetOnExit reset{s};
        bindKey(s, key);
        const int rc = sqlite3_step(s);
        if (rc == SQLITE_DONE) return std::nullopt;
        if (rc != SQLITE_ROW) fail("read a brick's error");
        return checkedError(s, 0, [&] { return "the error of brick " + describeKey(key); });
    }

    void putLodError(const BrickKey& key, double error) override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!errorInsert_) throw std::logic_error("a read-only store keeps no errors");
        sqlite3_stmt* s = errorInsert_->get();
        const ResetOnExit reset{s};
        bindKey(s, key);
        sqlite3_bind_double(s, 5, error);
        if (sqlite3_step(s) != SQLITE_DONE) fail("write a brick's error");
    }

    void eraseLodError(const BrickKey& key) override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!errorRemove_) throw std::logic_error("a read-only store keeps no errors");
        sqlite3_stmt* s = errorRemove_->get();
        const ResetOnExit reset{s};
        bindKey(s, key);
        if (sqlite3_step(s) != SQLITE_DONE) fail("erase a brick's error");
    }

    void scanLodErrors(int level, const std::function<void(const IndexCoord&, double)>& fn) const override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!errorSelect_) return;
        Statement stmt(db_, "SELECT x, y, z, error FROM lod_errors WHERE level = ?1 ORDER BY x, y, z", path_);
        sqlite3_stmt* s = stmt.get();
        sqlite3_bind_int(s, 1, level);
        int rc;
        while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
            const auto where = [&] { return "an error row of level " + std::to_string(level); };
            IndexCoord brick{};
            for (int a = 0; a < 3; ++a)
                brick[std::size_t(a)] = int32_t(checkedInteger(s, a, -kMaxBrickCoordinate, kMaxBrickCoordinate, where, "xyz" + a));
            fn(brick, checkedError(s, 3, where));
        }
        if (rc != SQLITE_DONE) fail("list the bricks' errors");
    }

    void begin() override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        exec("BEGIN IMMEDIATE");
        inTransaction_ = true;
    }
    void commit() override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        exec("COMMIT");
        inTransaction_ = false;
    }
    void rollback() override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        exec("ROLLBACK");
        inTransaction_ = false;
    }

    std::unique_ptr<BrickStore> openReader() const override
    {
        return std::make_unique<SqliteBrickStore>(path_, StoreAccess::ReadOnly, true);
    }

    const std::string& path() const override { return path_; }
    int formatVersion() const override
    {
        std::lock_guard<std::mutex> lock(mutex_);
        return int(pragmaInt("PRAGMA user_version"));
    }

private:
    /// What can be told from the file before SQLite opens it: it exists (or, to create, does not) and
    /// starts like an SQLite database.
    /// Whether this process may write the store and create files beside it (SQLite's -wal and -shm).
    static bool writable(const std::string& path)
    {
        const fs::path dir = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
        return ::access(path.c_str(), W_OK) == 0 && ::access(dir.c_str(), W_OK | X_OK) == 0;
    }

    /// "file:PATH?immutable=1", the path percent-encoded where SQLite's URI syntax needs it.
    static std::string immutableUri(const std::string& path)
    {
        std::string uri = "file:";
        for (const char c : path) {
            if (c == '%' || c == '?' || c == '#') {
                static const char kHex[] = "0123456789ABCDEF";
                uri += '%';
                uri += kHex[(unsigned char)c >> 4];
                uri += kHex[(unsigned char)c & 15];
            } else {
                uri += c;
            }
        }
        return uri + "?immutable=1";
    }

    static void requireUsableFile(const std::string& path, StoreAccess access)
    {
        std::error_code ec;
        const bool exists = fs::exists(path, ec);
        if (access == StoreAccess::Create) {
            if (exists) throw StoreError("'" + path + "' already exists");
            return;
        }
        if (const auto why = unreachableFile(path)) throw StoreError(*why);
        if (!fs::is_regular_file(path, ec)) throw StoreError("'" + path + "' is not a regular file");
        if (!looksLikeSqliteFile(path)) throw StoreError("'" + path + "' is not a VDBClay scene store (not an SQLite database)");
    }

    void lockForWriting(bool create)
    {
        lockFd_ = ::open(path_.c_str(), O_RDWR | O_CLOEXEC | (create ? O_CREAT | O_EXCL : 0), 0644);
        if (lockFd_ < 0) {
            if (errno == EEXIST) throw StoreError("'" + path_ + "' already exists");
            throw StoreError("cannot open '" + path_ + "' for writing: " + std::strerror(errno));
        }
        if (::flock(lockFd_, LOCK_EX | LOCK_NB) != 0) {
            const int err = errno;
            ::close(lockFd_);
            lockFd_ = -1;
            if (err == EWOULDBLOCK)
                throw StoreError("'" + path_ + "' is open for writing by another process (close it there, or read it only)");
            throw StoreError("cannot lock '" + path_ + "': " + std::strerror(err));
        }
    }

    void close()
    {
        if (db_) sqlite3_close_v2(db_);
        db_ = nullptr;
        // After SQLite let go of the file: closing another descriptor of it drops the process's fcntl locks.
        if (lockFd_ >= 0) ::close(lockFd_);
        lockFd_ = -1;
    }

    void exec(const char* sql) const
    {
        char* message = nullptr;
        if (sqlite3_exec(db_, sql, nullptr, nullptr, &message) != SQLITE_OK) {
            const std::string why = message ? message : sqlite3_errmsg(db_);
            sqlite3_free(message);
            throw StoreError(describe(why));
        }
    }

    std::string describe(const std::string& why) const
    {
        const int code = sqlite3_errcode(db_) & 0xff;
        if (code == SQLITE_NOTADB) return "'" + path_ + "' is not a VDBClay scene store (not an SQLite database)";
        if (code == SQLITE_CORRUPT) return "'" + path_ + "' is damaged (" + why + ")";
        if (code == SQLITE_FULL) return "cannot write '" + path_ + "' (disk full)";
        if (code == SQLITE_BUSY) return "'" + path_ + "' is busy in another process (" + why + ")";
        return "'" + path_ + "': " + why;
    }

    [[noreturn]] void fail(const char* what) const
    {
        throw StoreError(describe(std::string("cannot ") + what + ": " + sqlite3_errmsg(db_)));
    }

    /// Column `col` of the current row as an integer in lo .. hi; anything else (a real, text, a blob, a
    /// value out of range) is a damaged row, named by `where` and the column.
    template <typename Where>
    int64_t checkedInteger(sqlite3_stmt* s, int col, int64_t lo, int64_t hi, const Where& where, const char* column) const
    {
        const int64_t value = sqlite3_column_int64(s, col);
        if (sqlite3_column_type(s, col) != SQLITE_INTEGER || value < lo || value > hi)
            throw StoreError("'" + path_ + "' is damaged: " + where() + " has a '" + column + "' of " +
                             (sqlite3_column_type(s, col) == SQLITE_INTEGER ? std::to_string(value) : std::string("another type than an integer")) +
                             " (" + std::to_string(lo) + " .. " + std::to_string(hi) + " expected)");
        return value;
    }

    int64_t pragmaInt(const char* sql) const
    {
        Statement stmt(db_, sql, path_);
        sqlite3_stmt* s = stmt.get();
        const int rc = sqlite3_step(s);
        if (rc != SQLITE_ROW) throw StoreError(describe(sqlite3_errmsg(db_)));
        return sqlite3_column_int64(s, 0);
    }

    void createSchema()
    {
        exec("PRAGMA journal_mode=WAL");
        exec("PRAGMA application_id=1447251033"); // kApplicationId
        exec(("PRAGMA user_version=" + std::to_string(kStoreFormatVersion)).c_str());
        exec("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL) WITHOUT ROWID");
        exec("CREATE TABLE bricks (level INTEGER NOT NULL, x INTEGER NOT NULL, y INTEGER NOT NULL, z INTEGER NOT NULL, "
             "uniform INTEGER, leaves INTEGER NOT NULL, payload BLOB NOT NULL, PRIMARY KEY (level, x, y, z)) WITHOUT ROWID");
        createErrorTable();
    }

    /// The coarse bricks' errors: a table of its own, added to stores written before it (older builds
    /// read such a store as before and leave the table alone).
    void createErrorTable()
    {
        exec("CREATE TABLE IF NOT EXISTS lod_errors (level INTEGER NOT NULL, x INTEGER NOT NULL, y INTEGER NOT NULL, "
             "z INTEGER NOT NULL, error REAL NOT NULL, PRIMARY KEY (level, x, y, z)) WITHOUT ROWID");
    }

    std::string describeKey(const BrickKey& key) const
    {
        return "(" + std::to_string(key.brick[0]) + ", " + std::to_string(key.brick[1]) + ", " + std::to_string(key.brick[2]) +
               ") of level " + std::to_string(key.level);
    }

    /// Column `col` of the current row as an error: a finite number, 0 or more.
    template <typename Where>
    double checkedError(sqlite3_stmt* s, int col, const Where& where) const
    {
        const double value = sqlite3_column_double(s, col);
        const int type = sqlite3_column_type(s, col);
        if ((type != SQLITE_FLOAT && type != SQLITE_INTEGER) || !std::isfinite(value) || value < 0.0)
            throw StoreError("'" + path_ + "' is damaged: " + where() + " is not a length (a finite number, 0 or more)");
        return value;
    }

    void checkSchema()
    {
        if (pragmaInt("PRAGMA application_id") != kApplicationId)
            throw StoreError("'" + path_ + "' is an SQLite database but not a VDBClay scene store");
        const int64_t version = pragmaInt("PRAGMA user_version");
        if (version > kStoreFormatVersion || version < 1)
            throw StoreError("'" + path_ + "' is a VDBClay scene store of format version " + std::to_string(version) +
                             "; this build reads versions 1 to " + std::to_string(kStoreFormatVersion));
        if (pragmaInt("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN ('meta', 'bricks')") != 2)
            throw StoreError("'" + path_ + "' is damaged (its tables are missing)");
    }

    void prepare()
    {
        select_ = std::make_unique<Statement>(
            db_, "SELECT uniform, leaves, payload FROM bricks WHERE level = ?1 AND x = ?2 AND y = ?3 AND z = ?4", path_);
        insert_ = std::make_unique<Statement>(
            db_, "INSERT OR REPLACE INTO bricks (level, x, y, z, uniform, leaves, payload) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)", path_);
        remove_ = std::make_unique<Statement>(db_, "DELETE FROM bricks WHERE level = ?1 AND x = ?2 AND y = ?3 AND z = ?4", path_);
        metaSelect_ = std::make_unique<Statement>(db_, "SELECT value FROM meta WHERE key = ?1", path_);
        metaInsert_ = std::make_unique<Statement>(db_, "INSERT OR REPLACE INTO meta (key, value) VALUES (?1, ?2)", path_);
        if (pragmaInt("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'lod_errors'") == 0) return;
        errorSelect_ = std::make_unique<Statement>(db_, "SELECT error FROM lod_errors WHERE level = ?1 AND x = ?2 AND y = ?3 AND z = ?4", path_);
        if (pragmaInt("PRAGMA query_only") != 0) return;
        errorInsert_ = std::make_unique<Statement>(
            db_, "INSERT OR REPLACE INTO lod_errors (level, x, y, z, error) VALUES (?1, ?2, ?3, ?4, ?5)", path_);
        errorRemove_ = std::make_unique<Statement>(db_, "DELETE FROM lod_errors WHERE level = ?1 AND x = ?2 AND y = ?3 AND z = ?4", path_);
    }

    static void bindKey(sqlite3_stmt* s, const BrickKey& key)
    {
        sqlite3_bind_int(s, 1, key.level);
        for (int i = 0; i < 3; ++i) sqlite3_bind_int(s, 2 + i, key.brick[std::size_t(i)]);
    }

    std::string path_;
    sqlite3* db_ = nullptr;
    int lockFd_ = -1;
    bool inTransaction_ = false;
    mutable std::mutex mutex_; // one connection, used from the loader threads too
    std::unique_ptr<Statement> select_, insert_, remove_, metaSelect_, metaInsert_;
    std::unique_ptr<Statement> errorSelect_, errorInsert_, errorRemove_; // null where the store has no error table
};

} // namespace

std::unique_ptr<BrickStore> openSqliteStore(const std::string& path, StoreAccess access)
{
    return std::make_unique<SqliteBrickStore>(path, access);
}

bool looksLikeSqliteFile(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    char header[16] = {};
    in.read(header, sizeof(header));
    return in && std::memcmp(header, "SQLite format 3\0", 16) == 0;
}

} // namespace vdbclay
