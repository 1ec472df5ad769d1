// The editor's undo history: per edit (a whole stroke), the level-0 leaf boxes it changed, before and
// after, encoded as the store encodes bricks (copy on write: only changed leaves are kept). Entries
// beyond the memory cap are spilled, oldest first, to an anonymous temporary file and read back when
// undone, so undo works however far the camera has flown (restoring pages the bricks in again).
#pragma once

#include "scene/StreamingScene.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

struct HistoryLimits {
    uint64_t memoryBytes = 256ull << 20; // entries kept in memory
    uint64_t spillBytes = 8ull << 30;    // the spill file; beyond it the oldest entries are forgotten
};

/// A change of the mask (VoxelMask::encode() before and after).
struct MaskChange {
    std::string before, after;
};

/// What undo or redo puts back: leaf images, and the mask where the edit changed it.
struct HistoryStep {
    std::vector<LeafImage> leaves;
    std::optional<std::string> mask; // VoxelMask::encode()
};

class History {
public:
    explicit History(const HistoryLimits& limits = {});
    ~History();
    History(const History&) = delete;
    History& operator=(const History&) = delete;

    /// Records an edit and the stroke-script ops that made it (changes with equal before and after are
    /// dropped; nothing is recorded when none remain and the mask did not change) and forgets what could
    /// be redone.
    void push(std::vector<LeafChange> changes, nlohmann::json ops = nlohmann::json::array(), std::optional<MaskChange> mask = std::nullopt);
    /// What takes the scene back before the latest edit; the edit moves to the redo side.
    std::optional<HistoryStep> undo();
    /// What applies the latest undone edit again.
    std::optional<HistoryStep> redo();

    std::size_t undoDepth() const { return undo_.size(); }
    std::size_t redoDepth() const { return redo_.size(); }
    uint64_t memoryBytes() const { return memoryBytes_; }
    uint64_t spilledBytes() const { return spilledBytes_; }
    uint64_t forgotten() const { return forgotten_; } // oldest edits dropped past the spill limit
    /// The ops of the edits in effect, oldest first: those forgotten (no longer undoable) and those on
    /// the undo side; undone ones are left out.
    nlohmann::json opsInEffect() const;

private:
    struct Entry {
        std::vector<LeafChange> changes; // empty while spilled
        nlohmann::json ops;              // kept in memory: small beside the changes
        std::optional<MaskChange> mask;  // kept in memory too
        uint64_t bytes = 0;              // encoded size
        bool spilled = false;
        uint64_t fileOffset = 0;
    };
    /// Moves the latest entry of `from` to `to`, returning its images before (undo) or after (redo).
    std::optional<HistoryStep> step(std::vector<Entry>& from, std::vector<Entry>& to, bool before);
    void spillOver();
    void load(Entry& entry);
    void release(Entry& entry);

    HistoryLimits limits_;
    std::vector<Entry> undo_, redo_;
    uint64_t memoryBytes_ = 0, spilledBytes_ = 0, forgotten_ = 0;
    nlohmann::json forgottenOps_ = nlohmann::json::array();
    uint64_t fileEnd_ = 0;
    std::FILE* spill_ = nullptr;
};

} // namespace vdbclay
