// The state a stroke began from, kept box by box where its ops reach (copy on first touch),
// so that a stroke can be measured against where it started: inflate and deflate move the surface at
// most distance x strength per stroke however often their stamps overlap (Blender's draw brushes), and
// a stroke exported as a script or replayed does exactly what the editor did.
#pragma once

#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeRegions.h"

#include "sculpt/Brush.h"

#include <set>

namespace vdbclay {

/// The boxes kept whole, in voxels a side: four leaves (a stroke's next stamps mostly fall in boxes kept
/// already, and one copy of a larger box costs less than its leaves copied one by one).
constexpr int32_t kKeptBoxEdge = 4 * kLeafDim;
/// The most boxes one keep() visits (a field brush's region, kMaxFieldBrushVoxels a side, is far less).
constexpr double kMaxKeptBoxes = 1e6;

class StrokeStart {
public:
    explicit StrokeStart(double voxelSize) : start_(voxelSize) {}

    /// Keeps what `current` holds in each box (kKeptBoxEdge) `bounds` touches that is not kept yet. Called before
    /// each op of the stroke changes anything there, so that every box is kept as the stroke found it.
    /// Throws std::invalid_argument for unbounded bounds.
    void keep(const Volume& current, const WorldBounds& bounds);

    /// The stroke's starting state: right in every box kept so far (empty elsewhere).
    const Volume& volume() const { return start_; }

private:
    Volume start_;
    std::set<IndexCoord> kept_;
};

} // namespace vdbclay
