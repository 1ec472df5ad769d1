#include "query/ModelLibrary.h"

#include "query/DescriptorIndex.h"
#include "query/HistogramDistance.h"
#include "query/SurfaceSamples.h"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

namespace vdbclay::query {

namespace {

constexpr int kFormatVersion = 1;
constexpr const char* kFormatName = "vdbclay-model-library";

/// One prepared statement, finalized when it goes.
class Statement {
public:
    Statement(sqlite3* db, const char* sql)
    {
        if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK)
            throw LibraryError(std::string("the library's database refused a query: ") + sqlite3_errmsg(db));
    }
    ~Statement() { sqlite3_finalize(s_); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;
    sqlite3_stmt* get() { return s_; }
    void text(int i, const std::string& v) { sqlite3_bind_text(s_, i, v.c_str(), int(v.size()), SQLITE_TRANSIENT); }
    void integer(int i, int64_t v) { sqlite3_bind_int64(s_, i, v); }
    void blob(int i, const void* data, std::size_t bytes) { sqlite3_bind_blob(s_, i, data, int(bytes), SQLITE_TRANSIENT); }
    bool step()
    {
        const int r = sqlite3_step(s_);
        if (r == SQLITE_ROW) return true;
        if (r == SQLITE_DONE) return false;
        throw LibraryError(std::string("the library's database failed: ") + sqlite3_errmsg(sqlite3_db_handle(s_)));
    }
    std::string column(int i) const
    {
        const auto* t = sqlite3_column_text(s_, i);
        return t ? reinterpret_cast<const char*>(t) : "";
    }

private:
    sqlite3_stmt* s_ = nullptr;
};

std::vector<float> toFloats(const Histogram& h) { return std::vector<float>(h.begin(), h.end()); }

} // namespace

const char* descriptorName(Descriptor) { return "d2"; }
const char* metricName(Metric m) { return m == Metric::ChiSquare ? "chi2" : "jsd"; }

Histogram describeModel(const TriangleSoup& mesh, Descriptor)
{
    return smoothHistogram(d2Descriptor(mesh));
}

struct ModelLibrary::Impl {
    sqlite3* db = nullptr;
    // The search structure, built on first use from the stored vectors (or loaded from its file).
    mutable std::mutex indexMutex;
    mutable std::unique_ptr<DescriptorIndex> index;
    mutable std::vector<ModelRecord> indexed;
    mutable std::vector<Histogram> vectors;

    void exec(const char* sql) const
    {
        char* message = nullptr;
        if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
            const std::string text = message ? message : "unknown error";
            sqlite3_free(message);
            throw LibraryError("the library's database failed: " + text);
        }
    }
};

ModelLibrary::ModelLibrary(const std::string& path, bool create) : path_(path), impl_(std::make_unique<Impl>())
{
    namespace fs = std::filesystem;
    std::error_code ec;
    const bool exists = fs::exists(path, ec);
    if (!exists && !create) throw LibraryError("'" + path + "' does not exist (make one with 'vdbclay index add " + path + " MODELS...')");
    if (exists) {
        // A foreign file is refused before SQLite opens it (SQLite would take any file and fail later).
        std::ifstream in(path, std::ios::binary);
        char magic[16] = {};
        in.read(magic, sizeof magic);
        if (in.gcount() != 16 || std::memcmp(magic, "SQLite format 3", 16) != 0)
            throw LibraryError("'" + path + "' is not a VDBClay model library (not an SQLite database)");
    }
    const int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0);
    if (sqlite3_open_v2(path.c_str(), &impl_->db, flags, nullptr) != SQLITE_OK) {
        const std::string message = impl_->db ? sqlite3_errmsg(impl_->db) : "out of memory";
        sqlite3_close(impl_->db);
        impl_->db = nullptr;
        throw LibraryError("cannot open the library '" + path + "': " + message);
    }
    sqlite3_busy_timeout(impl_->db, 5000);
    try {
        impl_->exec("PRAGMA journal_mode=WAL");
        bool hasMeta = false;
        {
            Statement s(impl_->db, "SELECT name FROM sqlite_master WHERE type='table' AND name='library'");
            hasMeta = s.step();
        }
        if (!hasMeta) {
            Statement count(impl_->db, "SELECT count(*) FROM sqlite_master");
            count.step();
            if (sqlite3_column_int64(count.get(), 0) > 0) throw LibraryError("'" + path + "' is an SQLite database but not a VDBClay model library");
            impl_->exec("BEGIN");
            impl_->exec("CREATE TABLE library(key TEXT PRIMARY KEY, value TEXT NOT NULL)");
            impl_->exec("CREATE TABLE models(id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL UNIQUE, path TEXT NOT NULL, "
                        "label TEXT NOT NULL, triangles INTEGER NOT NULL, r REAL, g REAL, b REAL)");
            impl_->exec("CREATE TABLE descriptors(model INTEGER NOT NULL REFERENCES models(id) ON DELETE CASCADE, kind TEXT NOT NULL, "
                        "vector BLOB NOT NULL, PRIMARY KEY(model, kind))");
            Statement put(impl_->db, "INSERT INTO library(key, value) VALUES ('format', ?1), ('version', ?2)");
            put.text(1, kFormatName);
            put.text(2, std::to_string(kFormatVersion));
            put.step();
            impl_->exec("COMMIT");
        } else {
            Statement s(impl_->db, "SELECT key, value FROM library WHERE key IN ('format', 'version')");
            std::string format, version;
            while (s.step()) (s.column(0) == "format" ? format : version) = s.column(1);
            if (format != kFormatName) throw LibraryError("'" + path + "' is not a VDBClay model library");
            if (std::atoi(version.c_str()) > kFormatVersion)
                throw LibraryError("'" + path + "' was written by a newer VDBClay (library version " + version + "; this one reads " +
                                   std::to_string(kFormatVersion) + ")");
        }
        impl_->exec("PRAGMA foreign_keys=ON");
    } catch (...) {
        sqlite3_close(impl_->db);
        impl_->db = nullptr;
        throw;
    }
}

ModelLibrary::~ModelLibrary()
{
    if (impl_->db) sqlite3_close(impl_->db);
}

std::string ModelLibrary::indexPath(Descriptor d) const { return path_ + "." + descriptorName(d) + ".flann"; }

bool ModelLibrary::contains(const std::string& name) const
{
    Statement s(impl_->db, "SELECT 1 FROM models WHERE name = ?1");
    s.text(1, name);
    return s.step();
}

ModelRecord ModelLibrary::add(const std::string& name, const std::string& sourcePath, const std::string& label, const TriangleSoup& mesh,
                              const Histogram& d2)
{
    if (contains(name)) throw LibraryError("a model named '" + name + "' is in the library already");
    ModelRecord r;
    r.name = name;
    r.path = sourcePath;
    r.label = label;
    r.triangles = mesh.triangles.size();
    r.colour = meanColour(mesh);
    const std::vector<float> vector = toFloats(d2);
    impl_->exec("BEGIN IMMEDIATE");
    try {
        Statement put(impl_->db, "INSERT INTO models(name, path, label, triangles, r, g, b) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
        put.text(1, name);
        put.text(2, sourcePath);
        put.text(3, label);
        put.integer(4, int64_t(r.triangles));
        for (int k = 0; k < 3; ++k) sqlite3_bind_double(put.get(), 5 + k, r.colour[std::size_t(k)]);
        put.step();
        r.id = sqlite3_last_insert_rowid(impl_->db);
        Statement d(impl_->db, "INSERT INTO descriptors(model, kind, vector) VALUES (?1, ?2, ?3)");
        d.integer(1, r.id);
        d.text(2, descriptorName(Descriptor::D2));
        d.blob(3, vector.data(), vector.size() * sizeof(float));
        d.step();
        impl_->exec("COMMIT");
    } catch (...) {
        sqlite3_exec(impl_->db, "ROLLBACK", nullptr, nullptr, nullptr);
        throw;
    }
    std::lock_guard<std::mutex> lock(impl_->indexMutex);
    impl_->index.reset();
    return r;
}

bool ModelLibrary::remove(const std::string& name)
{
    Statement s(impl_->db, "DELETE FROM models WHERE name = ?1");
    s.text(1, name);
    s.step();
    const bool removed = sqlite3_changes(impl_->db) > 0;
    if (removed) {
        std::lock_guard<std::mutex> lock(impl_->indexMutex);
        impl_->index.reset();
    }
    return removed;
}

std::vector<ModelRecord> ModelLibrary::models() const
{
    std::vector<ModelRecord> out;
    Statement s(impl_->db, "SELECT id, name, path, label, triangles, r, g, b FROM models ORDER BY id");
    while (s.step()) {
        ModelRecord r;
        r.id = sqlite3_column_int64(s.get(), 0);
        r.name = s.column(1);
        r.path = s.column(2);
        r.label = s.column(3);
        r.triangles = uint64_t(sqlite3_column_int64(s.get(), 4));
        for (int k = 0; k < 3; ++k) r.colour[std::size_t(k)] = float(sqlite3_column_double(s.get(), 5 + k));
        out.push_back(r);
    }
    return out;
}

std::vector<QueryHit> ModelLibrary::query(const Histogram& query, std::size_t k, Metric metric) const
{
    std::lock_guard<std::mutex> lock(impl_->indexMutex);
    if (!impl_->index) {
        // The stored vectors, in the records' order; the saved index when it was made for exactly these.
        impl_->indexed = models();
        impl_->vectors.clear();
        std::vector<std::vector<float>> rows;
        Statement s(impl_->db, "SELECT vector FROM descriptors JOIN models ON models.id = descriptors.model WHERE kind = ?1 ORDER BY models.id");
        s.text(1, descriptorName(Descriptor::D2));
        while (s.step()) {
            const auto* data = static_cast<const float*>(sqlite3_column_blob(s.get(), 0));
            const int bytes = sqlite3_column_bytes(s.get(), 0);
            std::vector<float> v(data, data + bytes / int(sizeof(float)));
            impl_->vectors.emplace_back(v.begin(), v.end());
            rows.push_back(std::move(v));
        }
        if (rows.size() != impl_->indexed.size()) throw LibraryError("the library '" + path_ + "' is damaged: models without descriptors");
        std::string stamp = std::to_string(rows.size());
        for (const ModelRecord& r : impl_->indexed) stamp += "," + std::to_string(r.id);
        const std::string file = indexPath(Descriptor::D2), stampFile = file + ".models";
        std::string saved;
        {
            std::ifstream in(stampFile);
            std::getline(in, saved);
        }
        try {
            if (saved == stamp && std::filesystem::exists(file)) impl_->index = std::make_unique<DescriptorIndex>(rows, file);
        } catch (const std::exception&) {
            impl_->index.reset(); // damaged or stale: built again below
        }
        if (!impl_->index) {
            impl_->index = std::make_unique<DescriptorIndex>(rows);
            try {
                // Saved beside the library (a cache: failing to write it costs only the next rebuild).
                const std::string temporary = file + ".tmp";
                impl_->index->save(temporary);
                std::filesystem::rename(temporary, file);
                std::ofstream(stampFile) << stamp << "\n";
            } catch (const std::exception&) {
            }
        }
    }
    const std::size_t shortlist = std::min(impl_->indexed.size(), std::max<std::size_t>(4 * k, 64));
    std::vector<QueryHit> hits;
    for (std::size_t i : impl_->index->nearest(toFloats(query), shortlist)) {
        const Histogram& h = impl_->vectors[i];
        hits.push_back({impl_->indexed[i], metric == Metric::ChiSquare ? chiSquareDistance(query, h) : jensenShannonDistance(query, h)});
    }
    std::sort(hits.begin(), hits.end(), [](const QueryHit& a, const QueryHit& b) { return a.distance < b.distance || (a.distance == b.distance && a.model.id < b.model.id); });
    if (hits.size() > k) hits.resize(k);
    return hits;
}

} // namespace vdbclay::query
