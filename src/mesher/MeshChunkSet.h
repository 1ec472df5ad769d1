// Incremental meshing: the mesh of a volume kept as one chunk per leaf, re-meshed where an edit
// changed the volume. After update(), every chunk equals what a full re-mesh gives for its leaf.
#pragma once

#include "mesher/Mesher.h"

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

namespace vdbclay {

namespace mesher_detail {
struct LeafSurroundingsStore;
}

class MeshChunkSet {
public:
    using BlockOrigin = std::array<int32_t, 3>;

    explicit MeshChunkSet(const MeshOptions& options = {});
    ~MeshChunkSet();
    MeshChunkSet(MeshChunkSet&&) noexcept;
    MeshChunkSet& operator=(MeshChunkSet&&) noexcept;

    /// Meshes every leaf.
    void rebuild(const Volume& volume);

    /// Re-meshes the leaves an edit can change (EditStats::blockChanges): those that read a changed voxel
    /// and, with adaptive cells, which it subdivides again first, the face neighbours of leaves whose
    /// cells changed along their shared face. Chunks of leaves that no longer exist are dropped. Returns
    /// the number of chunks re-meshed.
    std::size_t update(const Volume& volume, const std::vector<BlockChange>& changes);
    /// The same from the changed blocks alone (EditStats::dirtyBlocks), taken as changed throughout.
    std::size_t update(const Volume& volume, const std::vector<BlockOrigin>& dirtyBlocks);

    const std::map<BlockOrigin, MeshChunk>& chunks() const { return chunks_; }
    /// The whole mesh, chunks welded in the order of their leaf origins.
    Mesh weld() const;

private:
    MeshOptions options_;
    std::map<BlockOrigin, MeshChunk> chunks_;
    // Adaptive CMS: each leaf's cells, kept so that an update subdivides only the leaves it can change.
    std::unique_ptr<mesher_detail::AdaptiveCellCache> cells_;
    // What an update's subdivision reads of each leaf, for its meshing (kept for the storage).
    std::unique_ptr<mesher_detail::LeafSurroundingsStore> surroundings_;
};

/// Whether two sets hold the same leaves with identical chunks (an update against a full rebuild).
bool identical(const MeshChunkSet& a, const MeshChunkSet& b);

} // namespace vdbclay
