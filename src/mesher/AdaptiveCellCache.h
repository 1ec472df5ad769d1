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

class AdaptiveCellCache {
public:
    /// Subdivides those of `leaves` and of their face neighbours that have no cells yet (in parallel).
    void prepare(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves, const MeshOptions& options);

    /// The cell widths around `leaf`, whose face neighbours prepare() has seen.
    CellWidthField around(const HermiteLeaf& leaf) const;

    /// Subdivides again the leaves whose subdivision reads a changed voxel (kSubdivisionReach) and drops
    /// those that no longer exist. Returns the leaves next to a face along which a neighbour's cells
    /// changed, appeared or vanished (some more than once): only they can split their faces anew.
    /// `keep` (optional) receives the surroundings of the leaves subdivided, for meshing them next.
    std::vector<BlockOrigin> refreshAround(const HermiteTree& tree, const std::vector<BlockChange>& changes,
                                           const MeshOptions& options, LeafSurroundingsStore* keep = nullptr);

    void clear() { sizes_.clear(); }

private:
    const LeafCellSizes* find(const Coord& origin) const;

    std::unordered_map<Coord, LeafCellSizes> sizes_;
};

} // namespace vdbclay::mesher_detail
