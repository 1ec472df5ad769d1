// The files behind an editing session. A store is edited in place: autosaves commit into it. A .vdb is
// edited through a working store beside it (SCENE.vdb.edit.vdbclay, built on first open with its levels
// of detail) so that scenes of any size stream and autosave the same way; the .vdb itself is only
// replaced by an explicit, atomic save. Either way the store remembers how many edits the last save
// held, so the next session after a crash reports the edits it recovered.
#pragma once

#include "scene/SceneStore.h"
#include "scene/StreamingScene.h"

#include <cstdint>
#include <string>

namespace vdbclay {

/// The working store a .vdb is edited through.
std::string workingStorePath(const std::string& vdbPath);

struct PreparedScene {
    std::string storePath;   // what the session streams and autosaves into
    bool throughWorkingStore = false; // a .vdb: saves export the store to it
    uint64_t recoveredEdits = 0;      // edits autosaved after the last save (a session that crashed)
    bool createdWorkingStore = false;
};

/// Makes the scene ready to edit. For a .vdb: reuses its working store when one is there for this very
/// file (its recovered edits reported), builds it otherwise; `discardRecovery` drops a working store's
/// unsaved edits first. A working store whose .vdb changed since (another program wrote it) while it holds
/// unsaved edits is refused with std::runtime_error naming both files. Throws StoreError, VolumeIOError for
/// unreadable scenes; std::invalid_argument for discarding a store's own edits.
/// With `refuseUnsaved` (a replay, which starts from the scene as saved), edits autosaved after the last
/// save are refused instead of recovered (std::runtime_error saying how to keep or drop them), before any
/// file is touched.
PreparedScene prepareScene(const std::string& scenePath, bool discardRecovery, const Progress& progress = {}, bool refuseUnsaved = false);

/// Drops a .vdb's working store when it holds edits autosaved after the last save (what a headless replay
/// leaves: the replay never writes the .vdb, so its edits are not the scene's). Returns whether it did;
/// the next session builds the working store again from the .vdb.
bool dropUnsavedWorkingStore(const std::string& vdbPath);

/// Autosaves, then writes the scene to `target`: the opened scene (`scenePath`, marking its edits saved),
/// or another .vdb or store (a copy; the opened scene stays as it is). Atomic: a crash leaves the old
/// file or the new one.
void saveScene(StreamingScene& scene, const PreparedScene& prepared, const std::string& scenePath, const std::string& target);

} // namespace vdbclay
