// Internal to the mesher: the adaptive cells of a volume's leaves, subdivided on demand and kept
// between incremental updates, so that an update subdivides again only the leaves an edit can change
// instead of every re-meshed leaf and its face neighbours. OpenVDB-heavy: include only from mesher
// .cpp files.
#pragma once

#include "mesher/CellOctree.h"
#include "mesher/Mesher.h"

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace vdbclay::mesher_detail {

/// The origin of a leaf's face neighbour f, in the order -x, +x, -y, +y, -z, +z.
inline Coord faceNeighbour(const Coord& origin, int f)
{
    Coord c = origin;
    c[f / 2] += (f % 2 ? 1 : -1) * kLeafDim;
    return c;
}

/// Calls fn(origin) for each leaf whose subdivision reads the leaf-sized block at `block`: a leaf's
/// octree reads its voxel lattice o .. o+8, that is the blocks at +0 and +1 along each axis.
template<typename Fn>
void forEachLeafSubdividingWith(const Coord& block, Fn&& fn)
{
    for (int dx = -1; dx <= 0; ++dx)
        for (int dy = -1; dy <= 0; ++dy)
            for (int dz = -1; dz <= 0; ++dz) fn(block.offsetBy(dx * kLeafDim, dy * kLeafDim, dz * kLeafDim));
}

class AdaptiveCellCache {
public:
    /// Subdivides those of `leaves` and of their face neighbours that have no cells yet (in parallel).
    void prepare(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves, const MeshOptions& options);

    /// The cell widths around `leaf`, whose face neighbours prepare() has seen.
    CellWidthField around(const HermiteLeaf& leaf) const;

    /// Subdivides again the leaves whose subdivision reads the given leaf-sized blocks
    /// (forEachLeafSubdividingWith) and drops those that no longer exist. Returns the origins of the
    /// leaves whose cells changed, appeared or vanished: only their face neighbours can split a face
    /// differently.
    /// `keep` (optional) receives the surroundings of the leaves subdivided, for meshing them next.
    std::vector<std::array<int32_t, 3>> refreshAround(const HermiteTree& tree,
                                                      const std::vector<std::array<int32_t, 3>>& dirtyBlocks,
                                                      const MeshOptions& options, LeafSurroundingsStore* keep = nullptr);

    void clear() { sizes_.clear(); }

private:
    const LeafCellSizes* find(const Coord& origin) const;

    std::unordered_map<Coord, LeafCellSizes> sizes_;
};

} // namespace vdbclay::mesher_detail
