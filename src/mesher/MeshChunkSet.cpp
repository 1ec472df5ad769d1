#include "mesher/MeshChunkSet.h"

#include "mesher/AdaptiveCellCache.h"

#include <algorithm>
#include <iterator>

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
        const std::vector<BlockOrigin> read = mesher_detail::leavesReaching(changes, mesher_detail::kMeshingReach);
        const std::vector<BlockOrigin> split = cells_->refreshAround(tree, changes, options_, surroundings_.get());
        origins.reserve(read.size() + split.size());
        std::set_union(read.begin(), read.end(), split.begin(), split.end(), std::back_inserter(origins));
    } else {
        origins = leavesAffectedBy(changes, options_);
    }
    // Each chunk is re-meshed in place, reusing its storage; those of leaves that are gone are dropped.
    mesher_detail::ConstAccessor acc(tree); // origins come sorted: neighbours share internal nodes
    std::vector<const HermiteLeaf*> leaves;
    std::vector<MeshChunk*> slots;
    for (const BlockOrigin& origin : origins) {
        const HermiteLeaf* leaf = acc.probeConstLeaf(Coord(origin[0], origin[1], origin[2]));
        if (!leaf) {
            chunks_.erase(origin);
            continue;
        }
        leaves.push_back(leaf);
        slots.push_back(&chunks_[origin]);
    }
    mesher_detail::meshLeavesInto(tree, leaves, slots, volume.voxelSize(), options_, cells_.get(),
                                  adaptive ? surroundings_.get() : nullptr);
    return leaves.size();
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
