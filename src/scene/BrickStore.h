// The scene store's narrow interface: bricks by (level, brick coordinate) and the scene's metadata,
// written in transactions. SQLite (SqliteBrickStore.cpp) is the working store; a server backend for
// scenes shared between machines can be added behind the same interface.
#pragma once

#include "vdb_hermite/VolumeRegions.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace vdbclay {

/// Every failure to open, read or write a store; what() is one line meant for the user.
class StoreError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct BrickKey {
    int level = 0;
    IndexCoord brick{0, 0, 0}; // the brick's origin divided by the brick edge
    friend bool operator<(const BrickKey& a, const BrickKey& b)
    {
        return a.level != b.level ? a.level < b.level : a.brick < b.brick;
    }
    friend bool operator==(const BrickKey& a, const BrickKey& b) { return a.level == b.level && a.brick == b.brick; }
};

/// For hashed containers of bricks (a view touches thousands each frame).
struct BrickKeyHash {
    std::size_t operator()(const BrickKey& k) const
    {
        uint64_t h = uint64_t(uint32_t(k.level)) * 0x9E3779B97F4A7C15ull;
        for (const int32_t c : k.brick) h = (h ^ uint32_t(c)) * 0x100000001B3ull + (h >> 29);
        return std::size_t(h ^ (h >> 32));
    }
};

/// One stored brick: either uniform (one material throughout, no payload) or a payload, the brick's part
/// of the volume as RegionCodec writes it (its leaves OpenVDB-serialized, Blosc-compressed).
struct BrickRecord {
    std::optional<MaterialId> uniform;
    std::string payload;
    uint32_t leaves = 0;
};

/// Whether two stored states of a brick (nullopt: not stored, i.e. empty) hold the same bytes.
inline bool sameBrick(const std::optional<BrickRecord>& a, const std::optional<BrickRecord>& b)
{
    if (!a || !b) return !a && !b;
    return a->uniform == b->uniform && a->payload == b->payload;
}

/// What scan() tells about a brick without reading its payload.
struct BrickSummary {
    std::optional<MaterialId> uniform;
    uint32_t leaves = 0;
    uint64_t bytes = 0;
};

enum class StoreAccess {
    ReadOnly,  // any number of readers, beside at most one writer
    ReadWrite, // one writer at a time: a second is refused
    Create,    // a new, empty store (the file must not exist), opened for writing
};

class BrickStore {
public:
    virtual ~BrickStore() = default;

    virtual std::optional<BrickRecord> get(const BrickKey& key) const = 0;
    virtual void put(const BrickKey& key, const BrickRecord& record) = 0;
    virtual void erase(const BrickKey& key) = 0;
    /// Calls fn for every brick of a level, in key order.
    virtual void scan(int level, const std::function<void(const BrickKey&, const BrickSummary&)>& fn) const = 0;

    virtual std::optional<std::string> meta(const std::string& key) const = 0;
    virtual void putMeta(const std::string& key, const std::string& value) = 0;
    /// A coarse brick's geometric error (StoreLod.h: how far its surface may lie from level 0's, world
    /// units), kept beside the bricks. Stores written before errors were kept have none.
    virtual std::optional<double> lodError(const BrickKey& key) const = 0;
    virtual void putLodError(const BrickKey& key, double error) = 0;
    virtual void eraseLodError(const BrickKey& key) = 0;
    /// Calls fn for every brick of a level that has an error, in key order.
    virtual void scanLodErrors(int level, const std::function<void(const IndexCoord&, double)>& fn) const = 0;

    /// Puts and erases between begin() and commit() land together or not at all; commit() returns
    /// once they are on disk.
    virtual void begin() = 0;
    virtual void commit() = 0;
    virtual void rollback() = 0;

    /// Another connection to the same store, for reads on one other thread: its reads run beside this
    /// connection's (which serializes its callers), and it sees what this one commits. It only reads.
    virtual std::unique_ptr<BrickStore> openReader() const = 0;

    virtual const std::string& path() const = 0;
    /// The store's format version (1: bricks as .vdb streams; 2: as region records, RegionCodec.h).
    virtual int formatVersion() const = 0;
};

/// One transaction: begun on construction, rolled back on destruction unless committed.
class StoreTransaction {
public:
    explicit StoreTransaction(BrickStore& store) : store_(store) { store_.begin(); }
    ~StoreTransaction()
    {
        if (!done_) {
            try {
                store_.rollback();
            } catch (...) {
            }
        }
    }
    StoreTransaction(const StoreTransaction&) = delete;
    StoreTransaction& operator=(const StoreTransaction&) = delete;
    void commit()
    {
        store_.commit();
        done_ = true;
    }

private:
    BrickStore& store_;
    bool done_ = false;
};

/// Opens an SQLite store (WAL mode). Refuses, with one line, a file that is not an SQLite database,
/// not a VDBClay store, of a newer format, damaged, or (for writing) open for writing elsewhere.
std::unique_ptr<BrickStore> openSqliteStore(const std::string& path, StoreAccess access);

/// Whether the file starts like an SQLite database (the form of a .vdbclay store).
bool looksLikeSqliteFile(const std::string& path);

} // namespace vdbclay
