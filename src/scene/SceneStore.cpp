#include "scene/SceneStore.h"

#include "interop/StandardVdb.h"

#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/FileExtension.h"
#include "vdb_hermite/NumberText.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeIO.h"
#include "vdb_hermite/VolumeRegions.h"
#include "wavelet/LodPyramid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <set>
#include <sstream>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

constexpr const char* kFormatKey = "format";
constexpr const char* kFormatValue = "vdbclay-scene";
constexpr const char* kVoxelSizeKey = "voxel_size";
constexpr const char* kMaterialsKey = "materials";
constexpr const char* kMaskKey = "mask"; // VoxelMask::encode(); absent or empty: nothing masked
constexpr const char* kBrickLeavesKey = "brick_leaves";
constexpr const char* kLodLevelsKey = "lod_levels";
constexpr const char* kLodStaleKey = "lod_stale";
constexpr const char* kBoundsKey = "bbox"; // "x0 y0 z0 x1 y1 z1", "empty", or "" (unknown: edited since)

std::string exactNumber(double v)
{
    char text[32];
    std::snprintf(text, sizeof(text), "%.17g", v);
    return text;
}

double levelVoxelSize(double voxelSize, int level) { return voxelSize * double(1 << level); }

} // namespace

bool isStorePath(const std::string& path)
{
    return lowerCaseExtension(path) == kStoreExtension;
}

SceneStore::SceneStore(std::unique_ptr<BrickStore> store) : store_(std::move(store)) {}
SceneStore::SceneStore(SceneStore&&) noexcept = default;
SceneStore& SceneStore::operator=(SceneStore&&) noexcept = default;
SceneStore::~SceneStore() = default;

SceneStore SceneStore::create(const std::string& path, double voxelSize, const MaterialTable& materials)
{
    Volume probe(voxelSize); // checks the voxel size
    SceneStore scene(openSqliteStore(path, StoreAccess::Create));
    StoreTransaction transaction(*scene.store_);
    scene.store_->putMeta(kFormatKey, kFormatValue);
    scene.store_->putMeta(kVoxelSizeKey, exactNumber(voxelSize));
    scene.store_->putMeta(kMaterialsKey, materials.toJson());
    scene.store_->putMeta(kBrickLeavesKey, std::to_string(kBrickLeaves));
    scene.store_->putMeta(kLodLevelsKey, "0");
    scene.store_->putMeta(kLodStaleKey, "0");
    transaction.commit();
    scene.readMeta();
    return scene;
}

SceneStore SceneStore::open(const std::string& path, StoreAccess access)
{
    SceneStore scene(openSqliteStore(path, access));
    scene.readMeta();
    return scene;
}

StoreError damagedMeta(const std::string& path, const std::string& key, const std::string& value, const std::string& expected)
{
    return StoreError("'" + path + "' is damaged: its metadata '" + key + "' is '" + printableText(value, 40) + "', not " + expected);
}

bool metaFlag(const BrickStore& store, const std::string& key)
{
    const std::string text = store.meta(key).value_or("0");
    if (text != "0" && text != "1") throw damagedMeta(store.path(), key, text, "0 or 1");
    return text == "1";
}

void SceneStore::readMeta()
{
    const std::string& path = store_->path();
    const auto require = [&](const char* key) {
        const std::optional<std::string> value = store_->meta(key);
        if (!value) throw StoreError("'" + path + "' is damaged: its metadata lacks '" + key + "'");
        return *value;
    };
    if (require(kFormatKey) != kFormatValue) throw StoreError("'" + path + "' is not a VDBClay scene store");
    const std::string voxelText = require(kVoxelSizeKey);
    voxelSize_ = parseDecimal(voxelText).value_or(0.0);
    if (!(voxelSize_ >= kMinVoxelSize && voxelSize_ <= kMaxVoxelSize))
        throw damagedMeta(path, kVoxelSizeKey, voxelText, "a decimal number from " + formatNumber(kMinVoxelSize) + " to " + formatNumber(kMaxVoxelSize));
    if (require(kBrickLeavesKey) != std::to_string(kBrickLeaves))
        throw StoreError("'" + path + "' has bricks of " + printableText(require(kBrickLeavesKey), 40) + " leaves; this build reads " +
                         std::to_string(kBrickLeaves));
    try {
        materials_ = MaterialTable::fromJson(require(kMaterialsKey));
    } catch (const std::exception& e) {
        throw StoreError("'" + path + "' is damaged: its metadata 'materials' is not valid (" + printableText(e.what(), 200) + ")");
    }
    (void)lodLevels();
    (void)lodStale();
}

const std::string& SceneStore::path() const { return store_->path(); }

void SceneStore::setMaterials(const MaterialTable& materials)
{
    store_->putMeta(kMaterialsKey, materials.toJson());
    materials_ = materials;
}

VoxelMask SceneStore::mask() const
{
    const std::optional<std::string> bytes = store_->meta(kMaskKey);
    if (!bytes || bytes->empty()) return {};
    try {
        return VoxelMask::decode(*bytes);
    } catch (const MaskFormatError& e) {
        throw StoreError("'" + path() + "': " + e.what());
    }
}

void SceneStore::setMask(const VoxelMask& mask) { store_->putMeta(kMaskKey, mask.any() ? mask.encode() : std::string()); }

std::optional<std::pair<IndexCoord, IndexCoord>> SceneStore::bounds() const
{
    const std::string kept = store_->meta(kBoundsKey).value_or("");
    if (kept.empty()) return boundsFromBricks();
    if (kept == "empty") return std::nullopt;
    std::istringstream in(kept);
    std::array<long long, 6> v{};
    for (long long& x : v) in >> x;
    std::string rest;
    const bool valid = in && !(in >> rest) && std::all_of(v.begin(), v.end(), [](long long x) { return std::llabs(x) <= (1ll << 31) - 1; }) &&
                       v[0] <= v[3] && v[1] <= v[4] && v[2] <= v[5];
    if (!valid) throw damagedMeta(path(), kBoundsKey, kept, "six integers x0 y0 z0 x1 y1 z1 with x0 <= x1, y0 <= y1, z0 <= z1");
    return std::make_pair(IndexCoord{int32_t(v[0]), int32_t(v[1]), int32_t(v[2])}, IndexCoord{int32_t(v[3]), int32_t(v[4]), int32_t(v[5])});
}

std::optional<std::pair<IndexCoord, IndexCoord>> SceneStore::boundsFromBricks() const
{
    const std::vector<IndexCoord> all = brickCoords(0);
    if (all.empty()) return std::nullopt;
    IndexCoord lo = all.front(), hi = all.front();
    for (const IndexCoord& b : all)
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b[a]), hi[a] = std::max(hi[a], b[a]);
    std::vector<IndexCoord> sides;
    for (const IndexCoord& b : all)
        if (b[0] == lo[0] || b[0] == hi[0] || b[1] == lo[1] || b[1] == hi[1] || b[2] == lo[2] || b[2] == hi[2]) sides.push_back(b);
    // One brick at a time: the sides of a wide flat scene (a terrain) may hold most of its bricks.
    std::optional<std::pair<IndexCoord, IndexCoord>> box;
    for (const IndexCoord& b : sides) {
        Volume one(voxelSize_);
        one.materials() = materials_;
        loadBricks(0, {b}, one);
        const VolumeStats stats = one.stats();
        if (stats.empty) continue;
        if (!box) box = std::make_pair(stats.bboxMin, stats.bboxMax);
        for (int a = 0; a < 3; ++a)
            box->first[a] = std::min(box->first[a], stats.bboxMin[a]), box->second[a] = std::max(box->second[a], stats.bboxMax[a]);
    }
    return box;
}

void SceneStore::storeBounds()
{
    const auto box = boundsFromBricks();
    std::string text = "empty";
    if (box) {
        text.clear();
        for (const IndexCoord* c : {&box->first, &box->second})
            for (int a = 0; a < 3; ++a) text += (text.empty() ? "" : " ") + std::to_string((*c)[a]);
    }
    store_->putMeta(kBoundsKey, text);
}

void SceneStore::forgetBounds() { store_->putMeta(kBoundsKey, ""); }

int SceneStore::lodLevels() const
{
    const std::string text = store_->meta(kLodLevelsKey).value_or("0");
    const bool digits = !text.empty() && text.size() <= 2 && text.find_first_not_of("0123456789") == std::string::npos;
    if (!digits || std::stoi(text) > wavelet::kMaxLodLevels)
        throw damagedMeta(store_->path(), kLodLevelsKey, text, "a whole number from 0 to " + std::to_string(wavelet::kMaxLodLevels));
    return std::stoi(text);
}

bool SceneStore::lodStale() const { return metaFlag(*store_, kLodStaleKey); }
void SceneStore::setLod(int levels, bool stale)
{
    store_->putMeta(kLodLevelsKey, std::to_string(levels));
    store_->putMeta(kLodStaleKey, stale ? "1" : "0");
}

std::vector<IndexCoord> SceneStore::brickCoords(int level) const
{
    std::vector<IndexCoord> out;
    store_->scan(level, [&](const BrickKey& key, const BrickSummary&) { out.push_back(key.brick); });
    return out;
}

LevelSummary SceneStore::summary(int level) const
{
    LevelSummary s;
    s.level = level;
    store_->scan(level, [&](const BrickKey&, const BrickSummary& b) {
        ++s.bricks;
        s.leaves += b.leaves;
        s.bytes += b.bytes;
    });
    return s;
}

DecodedRegion SceneStore::decodeBrick(int level, const IndexCoord& brick, const std::optional<BrickRecord>& record,
                                      std::size_t materialCount) const
{
    const LeafAlignedBox box = brickBox(brick);
    if (!record) return DecodedRegion(box, kEmptyMaterial);
    const std::string name = store_->path() + " brick " + std::to_string(level) + "/" + std::to_string(brick[0]) + "," +
                             std::to_string(brick[1]) + "," + std::to_string(brick[2]);
    if (record->uniform) {
        if (*record->uniform > materialCount) throw StoreError("'" + name + "' is damaged: it uses an undefined material");
        return DecodedRegion(box, *record->uniform);
    }
    try {
        return decodeRegion(record->payload, box, levelVoxelSize(voxelSize_, level), materialCount, name);
    } catch (const VolumeIOError& e) {
        throw StoreError(e.what());
    }
}

DecodedRegion SceneStore::readBrick(int level, const IndexCoord& brick, const BrickStore& from, std::size_t materialCount,
                                    uint64_t* payloadBytes) const
{
    const std::optional<BrickRecord> record = from.get({level, brick});
    if (payloadBytes) *payloadBytes = record ? record->payload.size() : 0;
    return decodeBrick(level, brick, record, materialCount);
}

void SceneStore::loadBricks(int level, const std::vector<IndexCoord>& bricks, Volume& into, const Progress& progress,
                            std::vector<std::optional<BrickRecord>>* raw) const
{
    if (raw) raw->clear();
    if (into.voxelSize() != levelVoxelSize(voxelSize_, level))
        throw std::invalid_argument("loadBricks: the volume has another voxel size");
    constexpr std::size_t kBatch = 64; // decoded in parallel, pasted in order
    for (std::size_t first = 0; first < bricks.size(); first += kBatch) {
        const std::size_t count = std::min(kBatch, bricks.size() - first);
        std::vector<std::optional<BrickRecord>> records(count);
        for (std::size_t i = 0; i < count; ++i) records[i] = store_->get({level, bricks[first + i]});
        std::vector<std::optional<DecodedRegion>> parts(count);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i)
                if (records[i]) parts[i] = decodeBrick(level, bricks[first + i], records[i], materials_.size());
        });
        for (std::optional<DecodedRegion>& part : parts)
            if (part) pasteRegion(into, std::move(*part));
        if (raw) std::move(records.begin(), records.end(), std::back_inserter(*raw));
        if (progress) progress(first + count, bricks.size());
    }
}

Volume SceneStore::loadLevel(int level, const Progress& progress) const
{
    Volume volume(levelVoxelSize(voxelSize_, level));
    volume.materials() = materials_;
    loadBricks(level, brickCoords(level), volume, progress);
    if (level == 0) volume.mask() = mask();
    return volume;
}

void SceneStore::writeBricks(int level, const Volume& volume, const std::vector<IndexCoord>& bricks, const Progress& progress)
{
    constexpr std::size_t kBatch = 256;
    for (std::size_t first = 0; first < bricks.size(); first += kBatch) {
        const std::size_t count = std::min(kBatch, bricks.size() - first);
        std::vector<std::optional<BrickRecord>> records(count);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) records[i] = encodeBrick(volume, bricks[first + i]);
        });
        for (std::size_t i = 0; i < count; ++i) {
            const BrickKey key{level, bricks[first + i]};
            if (records[i]) store_->put(key, *records[i]);
            else store_->erase(key);
        }
        if (progress) progress(first + count, bricks.size());
    }
}

void SceneStore::writeLevel(int level, const Volume& volume, const Progress& progress)
{
    const std::vector<IndexCoord> occupied = occupiedBoxes(volume, kBrickEdge);
    std::vector<IndexCoord> bricks;
    for (const IndexCoord& o : occupied) bricks.push_back({o[0] / kBrickEdge, o[1] / kBrickEdge, o[2] / kBrickEdge});
    const std::set<IndexCoord> keep(bricks.begin(), bricks.end());
    for (const IndexCoord& old : brickCoords(level))
        if (!keep.count(old)) store_->erase({level, old});
    writeBricks(level, volume, bricks, progress);
}

std::optional<BrickRecord> encodeBrick(const Volume& volume, const IndexCoord& brick)
{
    const LeafAlignedBox box = brickBox(brick);
    if (const std::optional<MaterialId> uniform = uniformMaterial(volume, box)) {
        if (*uniform == kEmptyMaterial) return std::nullopt;
        return BrickRecord{uniform, {}, 0};
    }
    uint32_t leaves = 0;
    std::string payload = encodeRegion(volume, box, &leaves);
    return BrickRecord{std::nullopt, std::move(payload), leaves};
}

StoredBricks putNewBricks(SceneStore& scene, int level, const std::vector<IndexCoord>& bricks,
                          const std::function<std::optional<BrickRecord>(std::size_t)>& make, const Progress& progress)
{
    // A batch keeps the cores busy while its records stay a few MB.
    constexpr std::size_t kBatch = 64;
    StoredBricks stored;
    for (std::size_t first = 0; first < bricks.size(); first += kBatch) {
        const std::size_t count = std::min(kBatch, bricks.size() - first);
        std::vector<std::optional<BrickRecord>> records(count);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) records[i] = make(first + i);
        });
        for (std::size_t i = 0; i < count; ++i) {
            if (!records[i]) continue;
            scene.bricks().put({level, bricks[first + i]}, *records[i]);
            ++stored.bricks;
            stored.leaves += records[i]->leaves;
            stored.bytes += records[i]->payload.size();
        }
        if ((first / kBatch) % 16 == 15) {
            scene.bricks().commit();
            scene.bricks().begin();
        }
        if (progress) progress(first + count, bricks.size());
    }
    return stored;
}

void createStoreFile(const std::string& path, double voxelSize, const MaterialTable& materials,
                     const std::function<void(SceneStore&)>& fill)
{
    std::error_code ec;
    if (fs::exists(path, ec)) {
        if (!fs::is_regular_file(path, ec)) throw StoreError("'" + path + "' exists and is not a regular file");
        // Opening for writing refuses a store another process writes; the lock ends with this scope.
        if (looksLikeSqliteFile(path)) openSqliteStore(path, StoreAccess::ReadWrite);
        else throw StoreError("'" + path + "' exists and is not a VDBClay scene store; not replacing it");
    }
    const fs::path target(path);
    removeStaleTemporaries(path);
    const fs::path temp = temporaryPathFor(path);
    try {
        {
            SceneStore scene = SceneStore::create(temp.string(), voxelSize, materials);
            scene.bricks().begin();
            fill(scene);
            scene.storeBounds();
            scene.bricks().commit();
        } // closing checkpoints the WAL into the file
        syncFileToDisk(temp.string());
        for (const char* suffix : {"-wal", "-shm"}) fs::remove(path + suffix, ec);
        fs::rename(temp, target);
        const int dir = ::open(target.parent_path().empty() ? "." : target.parent_path().c_str(), O_RDONLY | O_DIRECTORY);
        if (dir >= 0) ::fsync(dir), ::close(dir);
    } catch (...) {
        for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(temp.string() + suffix, ec);
        throw;
    }
}

void writeStoreFile(const Volume& volume, const std::string& path, const Progress& progress)
{
    createStoreFile(path, volume.voxelSize(), volume.materials(),
                    [&](SceneStore& scene) {
                        scene.writeLevel(0, volume, progress);
                        if (volume.mask().any()) scene.setMask(volume.mask());
                    });
}

Volume loadScene(const std::string& path, const Progress& progress)
{
    if (!isStorePath(path)) {
        if (classifyVdbFile(path) == VdbFileKind::Other) {
            // Another tool's file: say what it holds and how to bring it in, instead of a bare refusal.
            std::string holds;
            try {
                holds = "; it holds " + listGrids(describeStandardVdb(path));
            } catch (const VolumeIOError& e) {
                throw VolumeIOError(std::string(e.what()) + " (it is not a VDBClay volume)");
            }
            throw VolumeIOError("'" + path + "' is a .vdb file of another tool, not a VDBClay volume" + holds +
                                "; 'vdbclay import " + path + " -o scene.vdb' brings it in");
        }
        return loadVolume(path);
    }
    return SceneStore::open(path, StoreAccess::ReadOnly).loadLevel(0, progress);
}

} // namespace vdbclay
