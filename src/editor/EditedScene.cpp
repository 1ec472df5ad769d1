#include "editor/EditedScene.h"

#include "scene/StoreLod.h"
#include "vdb_hermite/VolumeIO.h"

#include <filesystem>
#include <stdexcept>

namespace vdbclay {

namespace {

constexpr const char* kSourceKey = "editor_source";     // the .vdb a working store was built from: size and time
constexpr const char* kSavedEditsKey = "editor_saved_edits"; // the edit count the last save held

std::string signatureOf(const std::string& path)
{
    namespace fs = std::filesystem;
    const auto size = fs::file_size(path);
    const auto time = fs::last_write_time(path).time_since_epoch().count();
    return std::to_string(size) + ":" + std::to_string(time);
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

std::string workingStorePath(const std::string& vdbPath) { return vdbPath + ".edit" + kStoreExtension; }

PreparedScene prepareScene(const std::string& scenePath, bool discardRecovery, const Progress& progress)
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
    const std::string signature = signatureOf(scenePath);
    if (fs::exists(out.storePath)) {
        bool reuse = false;
        {
            SceneStore store = SceneStore::open(out.storePath, StoreAccess::ReadOnly);
            const uint64_t edits = StreamingScene::committedEdits(store);
            const uint64_t unsaved = edits - std::min(edits, savedEdits(store.bricks()));
            reuse = store.bricks().meta(kSourceKey) == signature;
            if (!reuse && unsaved > 0 && !discardRecovery)
                throw std::runtime_error("'" + out.storePath + "' holds " + std::to_string(unsaved) + " edits autosaved from an earlier version of '" +
                                         scenePath + "', which was changed since: open the working store itself to keep them, or run again with "
                                         "--discard-recovery to drop them");
            if (reuse && !discardRecovery) out.recoveredEdits = unsaved;
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

void saveScene(StreamingScene& scene, const PreparedScene& prepared, const std::string& scenePath, const std::string& target)
{
    scene.autosave();
    const bool own = target == scenePath;
    if (own && !prepared.throughWorkingStore) {
        scene.commitMeta(kSavedEditsKey, std::to_string(scene.edits()));
        return;
    }
    Volume volume = scene.store().loadLevel(0);
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
