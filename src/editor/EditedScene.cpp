#include "editor/EditedScene.h"

#include "scene/OutputCheck.h"
#include "scene/StoreLod.h"
#include "vdb_hermite/VolumeIO.h"

#include <xxhash.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <new>
#include <stdexcept>
#include <vector>

namespace vdbclay {

namespace {

constexpr const char* kSourceKey = "editor_source";     // the .vdb a working store was built from: size and content hash
constexpr const char* kSavedEditsKey = "editor_saved_edits"; // the edit count the last save held

/// The .vdb's size and a hash of its bytes: a file replaced by another of the same size with its time
/// restored still differs, and `touch` alone changes nothing.
std::string signatureOf(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read '" + path + "'");
    XXH3_state_t* state = XXH3_createState();
    if (!state) throw std::bad_alloc();
    XXH3_64bits_reset(state);
    std::vector<char> buffer(1 << 20);
    uint64_t size = 0;
    while (in) {
        in.read(buffer.data(), std::streamsize(buffer.size()));
        const auto got = std::size_t(in.gcount());
        XXH3_64bits_update(state, buffer.data(), got);
        size += got;
    }
    const bool failed = in.bad();
    const XXH64_hash_t hash = XXH3_64bits_digest(state);
    XXH3_freeState(state);
    if (failed) throw std::runtime_error("cannot read '" + path + "'");
    char text[64];
    std::snprintf(text, sizeof text, "xxh3:%llu:%016llx", static_cast<unsigned long long>(size), static_cast<unsigned long long>(hash));
    return text;
}

/// Whether a working store's recorded signature is that of the .vdb now: the bytes are hashed only when
/// the size matches. Stores built before the hash recorded size and modification time; they are still
/// recognised by those.
bool sameSource(const std::optional<std::string>& recorded, const std::string& vdbPath)
{
    namespace fs = std::filesystem;
    if (!recorded) return false;
    const std::string size = std::to_string(fs::file_size(vdbPath));
    if (recorded->rfind("xxh3:", 0) == 0)
        return recorded->compare(5, size.size() + 1, size + ":") == 0 && *recorded == signatureOf(vdbPath);
    const auto time = fs::last_write_time(vdbPath).time_since_epoch().count();
    return *recorded == size + ":" + std::to_string(time);
}

uint64_t savedEdits(const BrickStore& store)
{
    const std::optional<std::string> text = store.meta(kSavedEditsKey);
    if (!text) return 0;
    if (text->empty() || text->size() > 19 || text->find_first_not_of("0123456789") != std::string::npos)
        throw StoreError("'" + store.path() + "' is damaged: its saved edit count is not a number");
    return std::stoull(*text);
}

void markSaved(SceneStore& store, const std::string& source)
{
    StoreTransaction transaction(store.bricks());
    store.bricks().putMeta(kSavedEditsKey, std::to_string(StreamingScene::committedEdits(store)));
    if (!source.empty()) store.bricks().putMeta(kSourceKey, signatureOf(source));
    transaction.commit();
}

} // namespace

std::string workingStorePath(const std::string& vdbPath) { return vdbPath + kWorkingStoreSuffix; }

PreparedScene prepareScene(const std::string& scenePath, bool discardRecovery, const Progress& progress, bool refuseUnsaved)
{
    namespace fs = std::filesystem;
    PreparedScene out;
    if (isStorePath(scenePath)) {
        if (discardRecovery) throw std::invalid_argument("a store's autosaved edits are part of it and cannot be discarded");
        SceneStore store = SceneStore::open(scenePath, StoreAccess::ReadWrite);
        const uint64_t edits = StreamingScene::committedEdits(store);
        if (!store.bricks().meta(kSavedEditsKey)) markSaved(store, "");
        else out.recoveredEdits = edits - std::min(edits, savedEdits(store.bricks()));
        out.storePath = scenePath;
        return out;
    }
    out.throughWorkingStore = true;
    out.storePath = workingStorePath(scenePath);
    if (!fs::exists(scenePath)) throw std::runtime_error("cannot open '" + scenePath + "': no such file");
    if (fs::exists(out.storePath)) {
        bool reuse = false;
        {
            SceneStore store = SceneStore::open(out.storePath, StoreAccess::ReadOnly);
            const uint64_t edits = StreamingScene::committedEdits(store);
            const uint64_t unsaved = edits - std::min(edits, savedEdits(store.bricks()));
            reuse = sameSource(store.bricks().meta(kSourceKey), scenePath);
            if (!reuse && unsaved > 0 && !discardRecovery)
                throw std::runtime_error("'" + out.storePath + "' holds " + std::to_string(unsaved) + " edits autosaved from an earlier version of '" +
                                         scenePath + "', which was changed since: open the working store itself to keep them, or run again with "
                                         "--discard-recovery to drop them");
            if (reuse && !discardRecovery) out.recoveredEdits = unsaved;
            if (reuse && unsaved > 0 && !discardRecovery && refuseUnsaved)
                throw std::runtime_error("'" + out.storePath + "' holds " + std::to_string(unsaved) + (unsaved == 1 ? " edit" : " edits") +
                                         " autosaved after the last save of '" + scenePath + "', and a replay starts from the scene as saved: "
                                         "open the scene and save to keep them, or run again with --discard-recovery to drop them");
        }
        if (reuse && !discardRecovery) return out;
        fs::remove(out.storePath);
    }
    Volume volume = loadVolume(scenePath);
    writeStoreFile(volume, out.storePath, progress);
    SceneStore store = SceneStore::open(out.storePath, StoreAccess::ReadWrite);
    buildStoreLod(store, 0);
    markSaved(store, scenePath);
    out.createdWorkingStore = true;
    return out;
}

bool dropUnsavedWorkingStore(const std::string& vdbPath)
{
    namespace fs = std::filesystem;
    const std::string path = workingStorePath(vdbPath);
    std::error_code ec;
    if (isStorePath(vdbPath) || !fs::exists(path, ec)) return false;
    {
        SceneStore store = SceneStore::open(path, StoreAccess::ReadOnly);
        const uint64_t edits = StreamingScene::committedEdits(store);
        if (edits <= savedEdits(store.bricks())) return false;
    }
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix, ec);
    return true;
}

void saveScene(StreamingScene& scene, const PreparedScene& prepared, const std::string& scenePath, const std::string& target)
{
    // The scene's own file however it is spelled (another path, a link); any other target goes through the
    // output check every command makes: never the working store, never a file of another kind.
    const bool own = samePlace(target, scenePath);
    if (!own) checkOutput(target, isStorePath(target) ? OutputForm::Store : OutputForm::NativeVolume, {scenePath, prepared.storePath});
    scene.autosave();
    if (own && !prepared.throughWorkingStore) {
        scene.commitMeta(kSavedEditsKey, std::to_string(scene.edits()));
        return;
    }
    Volume volume = scene.storedLevel0();
    if (isStorePath(target)) {
        writeStoreFile(volume, target);
        return;
    }
    saveVolume(volume, target);
    if (own) {
        scene.commitMeta(kSavedEditsKey, std::to_string(scene.edits()));
        scene.commitMeta(kSourceKey, signatureOf(scenePath));
    }
}

} // namespace vdbclay
