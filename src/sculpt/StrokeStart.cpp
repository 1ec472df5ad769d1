#include "sculpt/StrokeStart.h"

#include <cmath>
#include <stdexcept>

namespace vdbclay {

void StrokeStart::keep(const Volume& current, const WorldBounds& bounds)
{
    if (!bounds.bounded()) throw std::invalid_argument("a stroke's start is kept over bounded regions only");
    if (current.voxelSize() != start_.voxelSize()) throw std::invalid_argument("a stroke's start is kept on its own lattice");
    const double h = current.voxelSize();
    IndexCoord lo, hi;
    for (int a = 0; a < 3; ++a) {
        // Boxes holding any voxel whose edges the bounds reach (a voxel's edges run to its +1 corner).
        const auto box = [](double voxel) { return int32_t(std::floor(voxel / kKeptBoxEdge)) * kKeptBoxEdge; };
        lo[std::size_t(a)] = box(std::floor(bounds.min[a] / h) - 1.0);
        hi[std::size_t(a)] = box(std::ceil(bounds.max[a] / h));
    }
    double boxes = 1.0;
    for (std::size_t a = 0; a < 3; ++a) boxes *= double(hi[a] - lo[a]) / kKeptBoxEdge + 1.0;
    if (!(boxes <= kMaxKeptBoxes)) throw std::invalid_argument("a stroke's op reaches too many boxes to keep its start");
    for (int32_t x = lo[0]; x <= hi[0]; x += kKeptBoxEdge)
        for (int32_t y = lo[1]; y <= hi[1]; y += kKeptBoxEdge)
            for (int32_t z = lo[2]; z <= hi[2]; z += kKeptBoxEdge) {
                const IndexCoord origin{x, y, z};
                if (kept_.insert(origin).second) pasteRegion(start_, current, {origin, kKeptBoxEdge});
            }
}

} // namespace vdbclay
