#include "query/ModelLibrary.h"

#include "query/ClusterD2Color.h"
#include "query/DescriptorIndex.h"
#include "query/HistogramDistance.h"
#include "query/LightFieldRecords.h"
#include "query/SceneModels.h"
#include "query/SurfaceSamples.h"
#include "render/ImageFile.h"
#include "render/ModelViews.h"

#include <tbb/parallel_for.h>

#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <unordered_map>

namespace vdbclay::query {

namespace {

/// 2: light fields stored at 8 bits per feature (version 1's, as floats, are read too).
constexpr int kFormatVersion = 2;
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
    /// Ready to run again, with new bindings.
    void reset()
    {
        sqlite3_reset(s_);
        sqlite3_clear_bindings(s_);
    }
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

/// Runs `sql` on `db`; throws LibraryError naming `what`.
void execOn(sqlite3* db, const char* sql, const std::string& what)
{
    char* message = nullptr;
    if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
        const std::string text = message ? message : "unknown error";
        sqlite3_free(message);
        throw LibraryError(what + ": " + text);
    }
}

std::vector<float> toFloats(const Histogram& h) { return std::vector<float>(h.begin(), h.end()); }

/// A model record from a row whose first columns are id, name, path, label, triangles, r, g, b.
ModelRecord recordOf(Statement& s)
{
    ModelRecord r;
    r.id = sqlite3_column_int64(s.get(), 0);
    r.name = s.column(1);
    r.path = s.column(2);
    r.label = s.column(3);
    r.triangles = uint64_t(sqlite3_column_int64(s.get(), 4));
    for (int k = 0; k < 3; ++k) r.colour[std::size_t(k)] = float(sqlite3_column_double(s.get(), 5 + k));
    return r;
}

/// A library's identity: random, so that files kept beside a library (FLANN's indexes, the light fields'
/// records) are not taken for those of another library made later at the same path, whose model ids
/// start again at 1.
std::string newLibraryIdentity()
{
    std::random_device device;
    std::ostringstream out;
    out << std::hex << std::setfill('0');
    for (int i = 0; i < 4; ++i) out << std::setw(8) << uint32_t(device());
    return out.str();
}

} // namespace

const char* descriptorName(Descriptor d)
{
    switch (d) {
    case Descriptor::ClusterD2: return "clusterd2";
    case Descriptor::D2: return "d2";
    case Descriptor::LightField: return "lightfield";
    case Descriptor::Combined: return "combined";
    }
    return "?";
}

std::optional<Descriptor> parseDescriptor(const std::string& name)
{
    for (const Descriptor d : {Descriptor::ClusterD2, Descriptor::D2, Descriptor::LightField, Descriptor::Combined})
        if (name == descriptorName(d)) return d;
    return std::nullopt;
}

const char* metricName(Metric m) { return m == Metric::ChiSquare ? "chi2" : "jsd"; }

void describeShape(const TriangleSoup& mesh, ModelDescription& description)
{
    description.d2 = smoothHistogram(d2Descriptor(mesh));
    description.clusterD2 = smoothHistogram(clusterD2ColorDescriptor(mesh));
}

void describeViews(render::ModelViews& views, const TriangleSoup& mesh, ModelDescription& description, int thumbnailSize)
{
    description.lightField = lightFieldDescriptor(views, mesh);
    MaterialTable materials;
    render::ThumbnailOptions options;
    options.size = thumbnailSize;
    description.thumbnailPng = render::encodePng(views.thumbnail(meshOfSoup(mesh, materials), materials, options));
}


namespace {

/// One stored descriptor's search structure: built on first use from the stored vectors (or loaded from
/// its file). For the light field it indexes the summaries; the whole vectors stay in the database.
struct SearchIndex {
    std::unique_ptr<DescriptorIndex> index;
    std::vector<ModelRecord> indexed;
    std::vector<std::vector<float>> vectors; // what the index holds, per indexed model
    std::unique_ptr<LightFieldRecords> lightFields; // the light field's whole vectors, per indexed model
    std::unordered_map<int64_t, std::size_t> positionOf; // a model id's place in `indexed`
    std::map<Metric, double> typicalDistance; // the mean distance between the library's models (Combined), per metric
};

double histogramDistance(const std::vector<float>& a, const std::vector<float>& b, Metric metric)
{
    const Histogram ha(a.begin(), a.end()), hb(b.begin(), b.end());
    return metric == Metric::ChiSquare ? chiSquareDistance(ha, hb) : jensenShannonDistance(ha, hb);
}

} // namespace

struct ModelLibrary::Impl {
    sqlite3* db = nullptr;
    std::string identity; // empty for a library made before identities that cannot be written (read-only)
    mutable std::mutex indexMutex;
    mutable std::map<Descriptor, SearchIndex> indexes;

    void exec(const char* sql) const { execOn(db, sql, "the library's database failed"); }

    /// The library's identity; one is given to a library made before identities were, where it can be written.
    std::string storedIdentity() const
    {
        const auto read = [&] {
            Statement s(db, "SELECT value FROM library WHERE key = 'identity'");
            return s.step() ? s.column(0) : std::string();
        };
        if (std::string known = read(); !known.empty()) return known;
        Statement put(db, "INSERT OR IGNORE INTO library(key, value) VALUES ('identity', ?1)");
        put.text(1, newLibraryIdentity());
        if (sqlite3_step(put.get()) != SQLITE_DONE) return {};
        return read();
    }

    /// The light field's search entries: the models holding one, their summaries, and their whole vectors
    /// as records (mapped from `recordsPath`, made again from the stored vectors when missing or stale,
    /// held in memory where the file cannot be written), all from one snapshot of the database.
    void loadLightFields(SearchIndex& si, const std::string& recordsPath, const std::string& path) const
    {
        constexpr const char* kRows = " FROM descriptors JOIN models ON models.id = descriptors.model WHERE kind = ?1 ORDER BY models.id";
        exec("BEGIN");
        try {
            std::vector<int64_t> ids;
            {
                Statement s(db, (std::string("SELECT models.id, name, path, label, triangles, r, g, b") + kRows).c_str());
                s.text(1, descriptorName(Descriptor::LightField));
                while (s.step()) {
                    ModelRecord r = recordOf(s);
                    ids.push_back(r.id);
                    si.positionOf[r.id] = si.indexed.size();
                    si.indexed.push_back(std::move(r));
                }
            }
            // Without an identity (an old library that cannot be written) a file beside it cannot be trusted.
            si.lightFields = identity.empty() ? nullptr : LightFieldRecords::map(recordsPath, identity, ids);
            const auto write = [&](const std::string& file) {
                LightFieldRecordsWriter writer(file, identity, ids);
                Statement s(db, (std::string("SELECT vector") + kRows).c_str());
                s.text(1, descriptorName(Descriptor::LightField));
                std::size_t rows = 0;
                for (; s.step(); ++rows) {
                    if (rows == ids.size()) break;
                    writer.append(storedLightField(sqlite3_column_blob(s.get(), 0), sqlite3_column_bytes(s.get(), 0), path));
                }
                if (rows != ids.size()) throw LibraryError("the library '" + path + "' changed while its light fields were read");
                return writer.finish();
            };
            if (!si.lightFields) {
                try {
                    si.lightFields = write(identity.empty() ? std::string() : recordsPath);
                } catch (const LibraryError&) {
                    throw;
                } catch (const std::runtime_error&) {
                    si.lightFields = write(""); // the file could not be completed: in memory
                }
            }
            exec("COMMIT");
        } catch (...) {
            sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
            throw;
        }
        for (std::size_t i = 0; i < si.indexed.size(); ++i) si.vectors.push_back(quantizedLightFieldSummary((*si.lightFields)[i]));
    }

    /// A stored light field: 8 bits per feature, or (version 1) floats, which are quantized as read.
    static QuantizedLightField storedLightField(const void* data, int bytes, const std::string& path)
    {
        if (bytes == int(kLightFieldLength)) {
            const auto* b = static_cast<const uint8_t*>(data);
            return QuantizedLightField(b, b + bytes);
        }
        if (bytes == int(kLightFieldLength * sizeof(float))) {
            const auto* f = static_cast<const float*>(data);
            return quantizeLightField(std::vector<float>(f, f + kLightFieldLength));
        }
        throw LibraryError("the library '" + path + "' is damaged: a light field of the wrong length");
    }
};

namespace {

/// Makes an empty library at `path` atomically: its tables are written under a temporary name, which
/// is renamed to `path` once they are committed, so a stopped `index add` never leaves a file that is
/// not a library (SQLite makes its file empty at open, and writes it at the first commit).
void createLibrary(const std::string& path)
{
    namespace fs = std::filesystem;
    const std::string temporary = path + ".new-" + std::to_string(::getpid());
    std::error_code ec;
    fs::remove(temporary, ec);
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(temporary.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
        const std::string message = db ? sqlite3_errmsg(db) : "out of memory";
        sqlite3_close(db);
        throw LibraryError("cannot make the library '" + path + "': " + message);
    }
    try {
        const std::string what = "cannot make the library '" + path + "'";
        // A light field (18 KB) then reads from one page, not a chain of five overflow pages: a combined
        // query's ~110 of them in 20 % less time.
        execOn(db, "PRAGMA page_size=32768", what);
        execOn(db, "BEGIN", what);
        execOn(db, "CREATE TABLE library(key TEXT PRIMARY KEY, value TEXT NOT NULL)", what);
        execOn(db, "CREATE TABLE models(id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL UNIQUE, path TEXT NOT NULL, "
                   "label TEXT NOT NULL, triangles INTEGER NOT NULL, r REAL, g REAL, b REAL)", what);
        execOn(db, "CREATE TABLE descriptors(model INTEGER NOT NULL REFERENCES models(id) ON DELETE CASCADE, kind TEXT NOT NULL, "
                   "vector BLOB NOT NULL, PRIMARY KEY(model, kind))", what);
        execOn(db, "CREATE TABLE thumbnails(model INTEGER PRIMARY KEY REFERENCES models(id) ON DELETE CASCADE, png BLOB NOT NULL)", what);
        {
            Statement put(db, "INSERT INTO library(key, value) VALUES ('format', ?1), ('version', ?2), ('identity', ?3)");
            put.text(1, kFormatName);
            put.text(2, std::to_string(kFormatVersion));
            put.text(3, newLibraryIdentity());
            put.step();
        }
        execOn(db, "COMMIT", what);
    } catch (...) {
        sqlite3_close(db);
        fs::remove(temporary, ec);
        throw;
    }
    sqlite3_close(db);
    fs::rename(temporary, path, ec);
    if (ec) {
        fs::remove(temporary, ec);
        throw LibraryError("cannot make the library '" + path + "': " + ec.message());
    }
}

} // namespace

ModelLibrary::ModelLibrary(const std::string& path, bool create) : path_(path), impl_(std::make_unique<Impl>())
{
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::exists(path, ec)) {
        if (!create) throw LibraryError("'" + path + "' does not exist (make one with 'vdbclay index add " + path + " MODELS...')");
        createLibrary(path);
    }
    {
        // A foreign file is refused before SQLite opens it (SQLite would take any file and fail later).
        std::ifstream in(path, std::ios::binary);
        char magic[16] = {};
        in.read(magic, sizeof magic);
        if (in.gcount() != 16 || std::memcmp(magic, "SQLite format 3", 16) != 0)
            throw LibraryError("'" + path + "' is not a VDBClay model library (not an SQLite database)");
    }
    if (sqlite3_open_v2(path.c_str(), &impl_->db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
        const std::string message = impl_->db ? sqlite3_errmsg(impl_->db) : "out of memory";
        sqlite3_close(impl_->db);
        impl_->db = nullptr;
        throw LibraryError("cannot open the library '" + path + "': " + message);
    }
    sqlite3_busy_timeout(impl_->db, 5000);
    try {
        impl_->exec("PRAGMA journal_mode=WAL");
        std::string format, version;
        {
            Statement meta(impl_->db, "SELECT name FROM sqlite_master WHERE type='table' AND name='library'");
            if (!meta.step()) throw LibraryError("'" + path + "' is an SQLite database but not a VDBClay model library");
            Statement s(impl_->db, "SELECT key, value FROM library WHERE key IN ('format', 'version')");
            while (s.step()) (s.column(0) == "format" ? format : version) = s.column(1);
        }
        if (format != kFormatName) throw LibraryError("'" + path + "' is not a VDBClay model library");
        if (std::atoi(version.c_str()) > kFormatVersion)
            throw LibraryError("'" + path + "' was written by a newer VDBClay (library version " + version + "; this one reads " +
                               std::to_string(kFormatVersion) + ")");
        Statement tables(impl_->db, "SELECT count(*) FROM sqlite_master WHERE type='table' AND name IN ('models', 'descriptors', 'thumbnails')");
        tables.step();
        if (sqlite3_column_int64(tables.get(), 0) != 3) throw LibraryError("the library '" + path + "' is damaged: tables are missing");
        impl_->exec("PRAGMA foreign_keys=ON");
        impl_->identity = impl_->storedIdentity();
        // Descriptors read through the mapped file instead of a read() per page, and a cache that holds a
        // query's pages.
        impl_->exec("PRAGMA mmap_size=4294967296");
        impl_->exec("PRAGMA cache_size=-65536");
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
                              const ModelDescription& description)
{
    return addAll({{name, sourcePath, label, &mesh, &description}}).front();
}

std::vector<ModelRecord> ModelLibrary::addAll(const std::vector<NewModel>& models)
{
    for (const NewModel& m : models)
        if (m.description->d2.empty() || m.description->clusterD2.empty()) throw LibraryError("the model '" + m.name + "' was not described");
    std::vector<ModelRecord> out;
    bool storedQuantized = false;
    impl_->exec("BEGIN IMMEDIATE");
    try {
        Statement put(impl_->db, "INSERT INTO models(name, path, label, triangles, r, g, b) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
        Statement descriptor(impl_->db, "INSERT INTO descriptors(model, kind, vector) VALUES (?1, ?2, ?3)");
        Statement thumbnail(impl_->db, "INSERT INTO thumbnails(model, png) VALUES (?1, ?2)");
        for (const NewModel& m : models) {
            if (contains(m.name)) throw LibraryError("a model named '" + m.name + "' is in the library already");
            ModelRecord r;
            r.name = m.name;
            r.path = m.sourcePath;
            r.label = m.label;
            r.triangles = m.mesh->triangles.size();
            r.colour = meanColour(*m.mesh);
            put.reset();
            put.text(1, r.name);
            put.text(2, r.path);
            put.text(3, r.label);
            put.integer(4, int64_t(r.triangles));
            for (int k = 0; k < 3; ++k) sqlite3_bind_double(put.get(), 5 + k, r.colour[std::size_t(k)]);
            put.step();
            r.id = sqlite3_last_insert_rowid(impl_->db);
            const auto store = [&](Descriptor kind, const void* data, std::size_t bytes) {
                descriptor.reset();
                descriptor.integer(1, r.id);
                descriptor.text(2, descriptorName(kind));
                descriptor.blob(3, data, bytes);
                descriptor.step();
            };
            const ModelDescription& d = *m.description;
            for (const auto& [kind, histogram] : {std::pair<Descriptor, const Histogram*>{Descriptor::D2, &d.d2}, {Descriptor::ClusterD2, &d.clusterD2}}) {
                const std::vector<float> floats = toFloats(*histogram);
                store(kind, floats.data(), floats.size() * sizeof(float));
            }
            if (!d.lightField.empty()) {
                const QuantizedLightField q = quantizeLightField(d.lightField);
                store(Descriptor::LightField, q.data(), q.size());
                storedQuantized = true;
            }
            if (!d.thumbnailPng.empty()) {
                thumbnail.reset();
                thumbnail.integer(1, r.id);
                thumbnail.blob(2, d.thumbnailPng.data(), d.thumbnailPng.size());
                thumbnail.step();
            }
            out.push_back(std::move(r));
        }
        // A library of version 1 holding a light field of 8 bits is of version 2 (older readers refuse it
        // as newer, rather than as damaged).
        if (storedQuantized) impl_->exec("UPDATE library SET value = '2' WHERE key = 'version' AND CAST(value AS INTEGER) < 2");
        impl_->exec("COMMIT");
    } catch (...) {
        sqlite3_exec(impl_->db, "ROLLBACK", nullptr, nullptr, nullptr);
        throw;
    }
    std::lock_guard<std::mutex> lock(impl_->indexMutex);
    impl_->indexes.clear();
    return out;
}

bool ModelLibrary::remove(const std::string& name)
{
    Statement s(impl_->db, "DELETE FROM models WHERE name = ?1");
    s.text(1, name);
    s.step();
    const bool removed = sqlite3_changes(impl_->db) > 0;
    if (removed) {
        std::lock_guard<std::mutex> lock(impl_->indexMutex);
        impl_->indexes.clear();
    }
    return removed;
}

std::vector<ModelRecord> ModelLibrary::models() const
{
    std::vector<ModelRecord> out;
    Statement s(impl_->db, "SELECT id, name, path, label, triangles, r, g, b FROM models ORDER BY id");
    while (s.step()) out.push_back(recordOf(s));
    return out;
}

std::size_t ModelLibrary::count(Descriptor d) const
{
    Statement s(impl_->db, "SELECT count(*) FROM descriptors WHERE kind = ?1");
    s.text(1, descriptorName(d));
    s.step();
    return std::size_t(sqlite3_column_int64(s.get(), 0));
}

std::string ModelLibrary::thumbnail(int64_t model) const
{
    Statement s(impl_->db, "SELECT png FROM thumbnails WHERE model = ?1");
    s.integer(1, model);
    if (!s.step()) return {};
    const auto* data = static_cast<const char*>(sqlite3_column_blob(s.get(), 0));
    return std::string(data, data + sqlite3_column_bytes(s.get(), 0));
}

namespace {

/// The part of a description a stored descriptor's index compares.
std::vector<float> indexedPart(const ModelDescription& d, Descriptor kind)
{
    switch (kind) {
    case Descriptor::D2: return toFloats(d.d2);
    case Descriptor::ClusterD2: return toFloats(d.clusterD2);
    case Descriptor::LightField: return d.lightField.empty() ? std::vector<float>() : lightFieldSummary(d.lightField);
    case Descriptor::Combined: break;
    }
    return {};
}

} // namespace

std::vector<QueryHit> ModelLibrary::query(const ModelDescription& query, std::size_t k, Descriptor descriptor, Metric metric) const
{
    std::lock_guard<std::mutex> lock(impl_->indexMutex);
    // The index of a stored descriptor, built (or loaded) on first use.
    const auto searchIndex = [&](Descriptor kind) -> SearchIndex& {
        SearchIndex& si = impl_->indexes[kind];
        if (si.index) return si;
        si.indexed.clear();
        si.vectors.clear();
        si.positionOf.clear();
        si.lightFields.reset();
        if (kind == Descriptor::LightField) {
            impl_->loadLightFields(si, lightFieldRecordsPath(), path_);
        } else {
            Statement s(impl_->db, "SELECT models.id, name, path, label, triangles, r, g, b, vector FROM descriptors JOIN models ON models.id = "
                                   "descriptors.model WHERE kind = ?1 ORDER BY models.id");
            s.text(1, descriptorName(kind));
            while (s.step()) {
                const ModelRecord r = recordOf(s);
                const auto* data = static_cast<const float*>(sqlite3_column_blob(s.get(), 8));
                si.positionOf[r.id] = si.indexed.size();
                si.indexed.push_back(r);
                si.vectors.emplace_back(data, data + sqlite3_column_bytes(s.get(), 8) / int(sizeof(float)));
            }
        }
        std::string stamp = impl_->identity + "," + std::to_string(si.vectors.size());
        for (const ModelRecord& r : si.indexed) stamp += "," + std::to_string(r.id);
        const std::string file = indexPath(kind), stampFile = file + ".models";
        std::string saved;
        {
            std::ifstream in(stampFile);
            std::getline(in, saved);
        }
        try {
            if (!impl_->identity.empty() && saved == stamp && std::filesystem::exists(file)) si.index = std::make_unique<DescriptorIndex>(si.vectors, file);
        } catch (const std::exception&) {
            si.index.reset(); // damaged or stale: built again below
        }
        if (!si.index) {
            try {
                si.index = std::make_unique<DescriptorIndex>(si.vectors);
            } catch (const std::invalid_argument&) {
                throw LibraryError("the library '" + path_ + "' is damaged: " + descriptorName(kind) + " vectors of different lengths");
            }
            try {
                // Saved beside the library (a cache: failing to write it costs only the next rebuild).
                const std::string temporary = file + ".tmp";
                si.index->save(temporary);
                std::filesystem::rename(temporary, file);
                std::ofstream(stampFile) << stamp << "\n";
            } catch (const std::exception&) {
            }
        }
        return si;
    };
    // The query's light field at the stored precision, made once.
    std::optional<QuantizedLightField> quantized;
    const auto quantizedQuery = [&]() -> const QuantizedLightField& {
        if (!quantized) quantized = quantizeLightField(query.lightField);
        return *quantized;
    };
    // The exact distances of the query to some models of a descriptor's index (positions in it).
    const auto exact = [&](Descriptor kind, const SearchIndex& si, const std::vector<std::size_t>& positions) {
        std::vector<double> out;
        if (kind != Descriptor::LightField) {
            const std::vector<float> q = indexedPart(query, kind);
            for (std::size_t i : positions) out.push_back(histogramDistance(q, si.vectors[i], metric));
            return out;
        }
        // 600 turns of ten views each, on bytes read in place: a combined query's up to 192 share the cores.
        out.resize(positions.size());
        const QuantizedLightField& q = quantizedQuery();
        tbb::parallel_for(std::size_t(0), positions.size(), [&](std::size_t i) { out[i] = lightFieldDistance(q.data(), (*si.lightFields)[positions[i]]); });
        return out;
    };
    const auto shortlistOf = [&](Descriptor kind, const SearchIndex& si) {
        const std::size_t shortlist = std::min(si.indexed.size(), std::max<std::size_t>(4 * k, 64));
        return si.index->size() ? si.index->nearest(indexedPart(query, kind), shortlist) : std::vector<std::size_t>();
    };
    // A descriptor's typical distance in this library: the mean over up to 64 pairs of its models a fixed
    // stride apart (the same figure for the same library), kept per metric.
    const auto typicalDistance = [&](Descriptor kind, SearchIndex& si) {
        const Metric used = kind == Descriptor::LightField ? Metric::ChiSquare : metric; // the light field's is L1 either way
        if (const auto known = si.typicalDistance.find(used); known != si.typicalDistance.end()) return known->second;
        const std::size_t n = si.indexed.size();
        std::vector<std::pair<std::size_t, std::size_t>> pairs;
        for (std::size_t p = 0; n > 2 && p < std::min<std::size_t>(64, n - 1); ++p) {
            const std::size_t a = p * n / std::min<std::size_t>(64, n - 1);
            pairs.emplace_back(a, (a + n / 2 + 1) % n);
        }
        double sum = 0.0;
        for (const auto& pair : pairs)
            sum += kind == Descriptor::LightField ? lightFieldDistance((*si.lightFields)[pair.first], (*si.lightFields)[pair.second])
                                                  : histogramDistance(si.vectors[pair.first], si.vectors[pair.second], metric);
        const double typical = sum > 0.0 ? sum / double(pairs.size()) : 1.0;
        si.typicalDistance[used] = typical;
        return typical;
    };
    std::vector<QueryHit> hits;
    if (descriptor != Descriptor::Combined) {
        if (indexedPart(query, descriptor).empty())
            throw LibraryError(std::string("the query has no ") + descriptorName(descriptor) + " descriptor (it needs a renderer)");
        SearchIndex& si = searchIndex(descriptor);
        const std::vector<std::size_t> shortlist = shortlistOf(descriptor, si);
        const std::vector<double> distances = exact(descriptor, si, shortlist);
        for (std::size_t j = 0; j < shortlist.size(); ++j) hits.push_back({si.indexed[shortlist[j]], distances[j]});
    } else {
        // Each stored descriptor's shortlist; every candidate ranked by the mean of its distances, each
        // over that descriptor's typical distance between the library's models (so none outweighs).
        std::vector<Descriptor> kinds;
        for (Descriptor kind : kStoredDescriptors)
            if (!indexedPart(query, kind).empty() && !searchIndex(kind).indexed.empty()) kinds.push_back(kind);
        std::map<int64_t, std::pair<ModelRecord, std::vector<double>>> candidates;
        for (Descriptor kind : kinds) {
            SearchIndex& si = searchIndex(kind);
            for (std::size_t i : shortlistOf(kind, si)) candidates.emplace(si.indexed[i].id, std::make_pair(si.indexed[i], std::vector<double>()));
        }
        for (Descriptor kind : kinds) {
            SearchIndex& si = searchIndex(kind);
            std::vector<std::size_t> positions;
            std::vector<int64_t> ids;
            for (const auto& entry : candidates)
                if (const auto at = si.positionOf.find(entry.first); at != si.positionOf.end()) positions.push_back(at->second), ids.push_back(entry.first);
            const std::vector<double> distances = exact(kind, si, positions);
            const double typical = typicalDistance(kind, si);
            for (std::size_t j = 0; j < ids.size(); ++j) candidates.at(ids[j]).second.push_back(distances[j] / typical);
        }
        for (auto& [id, candidate] : candidates) {
            if (candidate.second.empty()) continue;
            double sum = 0.0;
            for (double d : candidate.second) sum += d;
            hits.push_back({candidate.first, sum / double(candidate.second.size())});
        }
    }
    std::sort(hits.begin(), hits.end(), [](const QueryHit& a, const QueryHit& b) { return a.distance < b.distance || (a.distance == b.distance && a.model.id < b.model.id); });
    if (hits.size() > k) hits.resize(k);
    return hits;
}

} // namespace vdbclay::query
