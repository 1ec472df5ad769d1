// A scene kept in a brick store (.vdbclay): the volume cut into bricks of 8^3 leaves (64^3 voxels) per
// level of detail, read and written brick by brick, so a command touches only the bricks it needs.
// Level 0 is the sculpted volume; level k >= 1 holds the coarse Hermite data of the LOD pyramid
// (wavelet/LodPyramid.h) at voxel size 2^k, cut into bricks the same way.
#pragma once

#include "scene/BrickStore.h"
#include "vdb_hermite/Materials.h"
#include "vdb_hermite/RegionCodec.h"
#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeRegions.h"
#include "vdb_hermite/VoxelMask.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace vdbclay {

/// Leaves per brick side, and voxels: chosen so that a brick's payload (tens of KB compressed for a
/// surface brick) amortizes a store read, while a small edit reads and writes few voxels it does not
/// change (docs/ARCHITECTURE.md, "The scene store").
constexpr int kBrickLeaves = 8;
constexpr int32_t kBrickEdge = kBrickLeaves * kLeafDim;

/// The index-space box of a brick (its coordinates times the brick edge).
inline LeafAlignedBox brickBox(const IndexCoord& brick)
{
    return {{brick[0] * kBrickEdge, brick[1] * kBrickEdge, brick[2] * kBrickEdge}, kBrickEdge};
}

/// Whether two bricks, of any levels, share level-0 voxels (a brick of level k spans kBrickEdge << k).
inline bool bricksOverlap(const BrickKey& a, const BrickKey& b)
{
    for (std::size_t i = 0; i < 3; ++i) {
        const int64_t aLo = int64_t(a.brick[i]) * (int64_t(kBrickEdge) << a.level), aHi = aLo + (int64_t(kBrickEdge) << a.level);
        const int64_t bLo = int64_t(b.brick[i]) * (int64_t(kBrickEdge) << b.level), bHi = bLo + (int64_t(kBrickEdge) << b.level);
        if (aHi <= bLo || bHi <= aLo) return false;
    }
    return true;
}

/// File extension of a store; every other extension is a native .vdb.
constexpr const char* kStoreExtension = ".vdbclay";
/// Whether a path names a store (by its extension, any case).
bool isStorePath(const std::string& path);
/// The end of the name of a .vdb's working store (SCENE.vdb.edit.vdbclay), where the editor autosaves the
/// edits made to it: no command's output replaces one.
constexpr const char* kWorkingStoreSuffix = ".edit.vdbclay";

struct LevelSummary {
    int level = 0;
    uint64_t bricks = 0;
    uint64_t leaves = 0;
    uint64_t bytes = 0;
};

/// The error for a damaged metadata value: names the store, the key, the value (printable) and what
/// was expected.
StoreError damagedMeta(const std::string& path, const std::string& key, const std::string& value, const std::string& expected);
/// A metadata flag: "1" true, "0" or absent false, anything else damage.
bool metaFlag(const BrickStore& store, const std::string& key);

/// Progress of long work: done out of total units.
using Progress = std::function<void(uint64_t done, uint64_t total)>;

class SceneStore {
public:
    /// A new store at `path` (which must not exist), empty, with the given voxel size and materials.
    static SceneStore create(const std::string& path, double voxelSize, const MaterialTable& materials);
    static SceneStore open(const std::string& path, StoreAccess access);

    SceneStore(SceneStore&&) noexcept;
    SceneStore& operator=(SceneStore&&) noexcept;
    ~SceneStore();

    const std::string& path() const;
    double voxelSize() const { return voxelSize_; }
    const MaterialTable& materials() const { return materials_; }
    /// Replaces the materials table (inside a transaction).
    void setMaterials(const MaterialTable& materials);
    /// The mask (VoxelMask.h) the store keeps beside level 0: empty when none was stored. StoreError for a
    /// damaged one.
    VoxelMask mask() const;
    /// Replaces it (inside a transaction).
    void setMask(const VoxelMask& mask);
    /// The coarse levels built and whether edits since left them behind; StoreError when the metadata
    /// holds anything but a whole number of 0 .. wavelet::kMaxLodLevels, or 0 or 1.
    int lodLevels() const;
    bool lodStale() const;
    void setLod(int levels, bool stale);

    /// The index-space box of level 0's solid and surface voxels (as VolumeStats has it), nullopt for
    /// an empty scene. Read from the metadata where a writer kept it; else found from the bricks on the
    /// six sides of the brick grid (the only ones that can hold an extreme voxel).
    std::optional<std::pair<IndexCoord, IndexCoord>> bounds() const;
    /// Writes bounds() into the metadata, found from the bricks (call inside a transaction).
    void storeBounds();
    /// Marks the kept bounds unknown: edits call it when they change level 0.
    void forgetBounds();

    BrickStore& bricks() { return *store_; }
    const BrickStore& bricks() const { return *store_; }

    /// The brick coordinates of a level, sorted.
    std::vector<IndexCoord> brickCoords(int level) const;
    LevelSummary summary(int level) const;
    /// Reads bricks of a level into `into` (a volume of that level's voxel size); missing bricks are empty.
    /// `records` (optional) receives what was stored for each brick (nullopt: nothing).
    void loadBricks(int level, const std::vector<IndexCoord>& bricks, Volume& into, const Progress& progress = {},
                    std::vector<std::optional<BrickRecord>>* records = nullptr) const;
    /// One brick of a level, decoded outside any volume (safe on several threads at once): empty space
    /// where nothing is stored. It is read through `from`: bricks(), or a reader of this store
    /// (bricks().openReader()) with which a thread reads beside the others instead of waiting for this
    /// store's connection. The brick may use material ids up to `materialCount`, which the caller read
    /// where setMaterials cannot run at the same time (the thread that commits may replace this store's
    /// table meanwhile). `payloadBytes` (optional) receives the size of the record read.
    DecodedRegion readBrick(int level, const IndexCoord& brick, const BrickStore& from, std::size_t materialCount,
                            uint64_t* payloadBytes = nullptr) const;
    /// A whole level as one volume (level 0 with the mask).
    Volume loadLevel(int level, const Progress& progress = {}) const;
    /// Stores the given bricks of `volume` (a level): a payload, a uniform record, or nothing for empty
    /// space. Call between bricks().begin() and commit().
    void writeBricks(int level, const Volume& volume, const std::vector<IndexCoord>& bricks, const Progress& progress = {});
    /// Replaces a whole level by `volume`'s content (bricks it does not occupy are erased).
    void writeLevel(int level, const Volume& volume, const Progress& progress = {});

private:
    SceneStore(std::unique_ptr<BrickStore> store);
    DecodedRegion decodeBrick(int level, const IndexCoord& brick, const std::optional<BrickRecord>& record,
                              std::size_t materialCount) const;
    std::optional<std::pair<IndexCoord, IndexCoord>> boundsFromBricks() const;
    void readMeta();

    std::unique_ptr<BrickStore> store_;
    double voxelSize_ = 1.0;
    MaterialTable materials_;
};

/// What a store holds for one brick of `volume`: a payload, a uniform record, or nullopt (empty space).
/// The same content always gives the same bytes.
std::optional<BrickRecord> encodeBrick(const Volume& volume, const IndexCoord& brick);

/// Makes a new store at `path`: `fill` writes it inside one transaction (begun and committed here), and
/// the file replaces an existing store only once complete (a crash leaves the old one or none).
/// Refuses to replace a store another process has open for writing, or a file that is not a store.
void createStoreFile(const std::string& path, double voxelSize, const MaterialTable& materials,
                     const std::function<void(SceneStore&)>& fill);

/// What putNewBricks stored.
struct StoredBricks {
    uint64_t bricks = 0; // payloads and uniform records
    uint64_t leaves = 0;
    uint64_t bytes = 0;  // payload bytes
};

/// Fills a level of a new store brick by brick: `make` builds the record of bricks[i] (called in parallel,
/// a batch at a time; nullopt: empty space, nothing stored), and the records are put in order, committing
/// every few batches so the write-ahead log stays small. Call inside createStoreFile's `fill`.
StoredBricks putNewBricks(SceneStore& scene, int level, const std::vector<IndexCoord>& bricks,
                          const std::function<std::optional<BrickRecord>(std::size_t)>& make, const Progress& progress = {});

/// Writes `volume` as a new store at `path`, replacing an existing store there only once the new one is
/// complete (a crash leaves the old one or none). Refuses a store another process has open for writing.
void writeStoreFile(const Volume& volume, const std::string& path, const Progress& progress = {});

/// Loads a scene in either form: a native .vdb, or level 0 of a store.
Volume loadScene(const std::string& path, const Progress& progress = {});

} // namespace vdbclay
