#include "mesher/MeshChunkSet.h"

#include "mesher/AdaptiveCellCache.h"

#include <algorithm>
#include <iterator>
#include <optional>

namespace vdbclay {

MeshChunkSet::MeshChunkSet(const MeshOptions& options)
    : options_(options), cells_(std::make_unique<mesher_detail::AdaptiveCellCache>()),
      surroundings_(std::make_unique<mesher_detail::LeafSurroundingsStore>())
{
}

MeshChunkSet::~MeshChunkSet() = default;
MeshChunkSet::MeshChunkSet(MeshChunkSet&&) noexcept = default;
MeshChunkSet& MeshChunkSet::operator=(MeshChunkSet&&) noexcept = default;

void MeshChunkSet::rebuild(const Volume& volume)
{
    chunks_.clear();
    cells_->clear();
    for (MeshChunk& chunk : meshVolumeChunks(volume, options_, cells_.get())) {
        const BlockOrigin origin = chunk.leafOrigin;
        chunks_[origin] = std::move(chunk);
    }
}

std::size_t MeshChunkSet::update(const Volume& volume, const std::vector<BlockOrigin>& dirtyBlocks)
{
    return update(volume, wholeBlockChanges(dirtyBlocks));
}

std::size_t MeshChunkSet::update(const Volume& volume, const std::vector<BlockChange>& changes)
{
    std::vector<BlockOrigin> origins;
    const bool adaptive = meshesAdaptiveCells(options_);
    if (adaptive) {
        // Subdividing first shows whose cells changed along which faces: only the leaves across those
        // faces may split theirs anew. What it reads of each leaf serves meshing too.
        const HermiteTree& tree = volume.impl().grid->constTree();
        const std::vector<BlockOrigin> read = mesher_detail::leavesReaching(changes, mesher_detail::kMeshingReach);
        const std::vector<BlockOrigin> split = cells_->refreshAround(tree, changes, options_, surroundings_.get());
        origins.reserve(read.size() + split.size());
        std::set_union(read.begin(), read.end(), split.begin(), split.end(), std::back_inserter(origins));
    } else {
        origins = leavesAffectedBy(changes, options_);
    }
    std::vector<std::optional<MeshChunk>> fresh =
        meshLeafChunks(volume, origins, options_, cells_.get(), adaptive ? surroundings_.get() : nullptr);
    std::size_t remeshed = 0;
    for (std::size_t i = 0; i < origins.size(); ++i) {
        if (fresh[i]) {
            chunks_[origins[i]] = std::move(*fresh[i]);
            ++remeshed;
        } else {
            chunks_.erase(origins[i]);
        }
    }
    return remeshed;
}

bool identical(const MeshChunkSet& a, const MeshChunkSet& b)
{
    return std::equal(a.chunks().begin(), a.chunks().end(), b.chunks().begin(), b.chunks().end(),
                      [](const auto& x, const auto& y) { return x.first == y.first && identical(x.second, y.second); });
}

Mesh MeshChunkSet::weld() const
{
    std::vector<const MeshChunk*> ordered;
    ordered.reserve(chunks_.size());
    for (const auto& [origin, chunk] : chunks_) ordered.push_back(&chunk);
    return weldChunks(ordered);
}

} // namespace vdbclay
