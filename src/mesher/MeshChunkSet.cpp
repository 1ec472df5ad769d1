#include "mesher/MeshChunkSet.h"

#include "mesher/AdaptiveCellCache.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

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
    validateMeshOptions(options_);
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::vector<BlockOrigin> origins;
    const bool adaptive = meshesAdaptiveCells(options_);
    if (adaptive) {
        // Subdividing first shows whose cells changed along which faces: only the leaves across those
        // faces may split theirs anew. What it reads of each leaf serves meshing too.
        const std::vector<BlockOrigin> split = cells_->refreshAround(tree, changes, options_, surroundings_.get());
        origins = mesher_detail::leavesReaching(changes, mesher_detail::kMeshingReach, split);
    } else {
        origins = mesher_detail::leavesReaching(changes, mesher_detail::kMeshingReach);
    }
    // Each chunk is re-meshed in place, reusing its storage. The leaves and chunks are looked up in
    // parallel; chunks of leaves that appeared are added, and those of leaves that are gone dropped, after.
    std::vector<const HermiteLeaf*> leaves(origins.size(), nullptr);
    std::vector<MeshChunk*> slots(origins.size(), nullptr);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 64), [&](const auto& range) {
        mesher_detail::ConstAccessor acc(tree);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            leaves[i] = acc.probeConstLeaf(Coord(origins[i][0], origins[i][1], origins[i][2]));
            const auto it = chunks_.find(origins[i]);
            if (it != chunks_.end()) slots[i] = &it->second;
        }
    });
    std::size_t meshed = 0;
    for (std::size_t i = 0; i < origins.size(); ++i) {
        if (!leaves[i]) {
            if (slots[i]) chunks_.erase(origins[i]);
            continue;
        }
        leaves[meshed] = leaves[i];
        slots[meshed++] = slots[i] ? slots[i] : &chunks_[origins[i]];
    }
    leaves.resize(meshed);
    slots.resize(meshed);
    mesher_detail::meshLeavesInto(tree, leaves, slots, volume.voxelSize(), options_, cells_.get(),
                                  adaptive ? surroundings_.get() : nullptr);
    return meshed;
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
