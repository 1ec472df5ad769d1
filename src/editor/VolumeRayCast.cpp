#include "editor/VolumeRayCast.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/Quantize.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdbclay {

namespace {

/// Voxels of one grid.
struct GridLookup {
    const HermiteGrid& grid;
    HermiteGrid::ConstAccessor access{grid.getConstAccessor()};

    explicit GridLookup(const HermiteGrid& g) : grid(g) {}
    bool solid(const Coord& c) { return access.getValue(c).solid(); }
    const HermiteLeaf* leaf(const Coord& c) { return access.probeConstLeaf(c); }
    void addBounds(CoordBBox& bounds) const { addRootBounds(grid, bounds); }

    static void addRootBounds(const HermiteGrid& g, CoordBBox& bounds)
    {
        const auto& root = g.tree().root();
        for (auto child = root.cbeginChildOn(); child; ++child) bounds.expand(child->getNodeBoundingBox());
        for (auto tile = root.cbeginValueAll(); tile; ++tile)
            if (tile->solid()) bounds.expand(CoordBBox::createCube(tile.getCoord(), HermiteTree::RootNodeType::ChildNodeType::DIM));
    }
};

/// Voxels of `current`, except in the replaced leaves, read from `before`.
struct OverlaidLookup {
    GridLookup current, before;
    const std::set<std::array<int32_t, 3>>& replaced;

    OverlaidLookup(const OverlaidVolume& v) : current(*v.current.impl().grid), before(*v.before.impl().grid), replaced(v.replaced) {}
    bool fromBefore(const Coord& c) const
    {
        const Coord o = c & ~(kLeafDim - 1);
        return replaced.count({o[0], o[1], o[2]}) != 0;
    }
    bool solid(const Coord& c) { return fromBefore(c) ? before.solid(c) : current.solid(c); }
    const HermiteLeaf* leaf(const Coord& c) { return fromBefore(c) ? before.leaf(c) : current.leaf(c); }
    void addBounds(CoordBBox& bounds) const
    {
        current.addBounds(bounds);
        before.addBounds(bounds);
    }
};

template<typename Lookup>
std::optional<SurfaceHit> castRayIn(Lookup& lookup, double voxelSize, const std::array<double, 3>& origin,
                                    const std::array<double, 3>& direction, double maxDistance)
{
    const double length = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
    if (!(length > 0.0) || !std::isfinite(length) || !(maxDistance > 0.0)) return std::nullopt;
    const double h = voxelSize;
    std::array<double, 3> o{}, d{};
    for (int a = 0; a < 3; ++a) {
        o[std::size_t(a)] = origin[std::size_t(a)] / h;
        d[std::size_t(a)] = direction[std::size_t(a)] / length;
        if (!std::isfinite(o[std::size_t(a)]) || std::abs(o[std::size_t(a)]) > kMaxLatticeCoordinate) return std::nullopt;
    }
    double tStart = 0.0, tEnd = std::min(maxDistance / h, 4.0 * kMaxLatticeCoordinate);
    // Only the part of the ray inside the root's children and solid tiles (a few, 4096^3 voxels each) is
    // walked: a ray that misses everything costs nothing.
    {
        CoordBBox bounds;
        lookup.addBounds(bounds);
        if (bounds.empty()) return std::nullopt;
        for (int a = 0; a < 3; ++a) {
            const std::size_t i = std::size_t(a);
            const double lo = double(bounds.min()[a]) - 1.0, hi = double(bounds.max()[a]) + 1.0;
            if (d[i] == 0.0) {
                if (o[i] < lo || o[i] > hi) return std::nullopt;
                continue;
            }
            double t0 = (lo - o[i]) / d[i], t1 = (hi - o[i]) / d[i];
            if (t0 > t1) std::swap(t0, t1);
            tStart = std::max(tStart, t0);
            tEnd = std::min(tEnd, t1);
        }
        if (tStart > tEnd) return std::nullopt;
        for (std::size_t i = 0; i < 3; ++i) o[i] += d[i] * tStart; // start at the entry (distances add tStart back)
    }

    // Amanatides-Woo over the cells of lattice points (the cube of half a voxel around each): consecutive
    // cells share a face, so an empty point followed by a solid one spans exactly one lattice edge.
    Coord cell;
    std::array<int, 3> step{};
    std::array<double, 3> tMax{}, tDelta{};
    for (int a = 0; a < 3; ++a) {
        const std::size_t i = std::size_t(a);
        cell[a] = int32_t(std::floor(o[i] + 0.5));
        if (d[i] > 0) {
            step[i] = 1;
            tMax[i] = (double(cell[a]) + 0.5 - o[i]) / d[i];
            tDelta[i] = 1.0 / d[i];
        } else if (d[i] < 0) {
            step[i] = -1;
            tMax[i] = (double(cell[a]) - 0.5 - o[i]) / d[i];
            tDelta[i] = -1.0 / d[i];
        } else {
            tMax[i] = tDelta[i] = std::numeric_limits<double>::infinity();
        }
    }
    tEnd -= tStart;
    bool wasSolid = lookup.solid(cell);
    bool leftSolid = !wasSolid; // a ray starting inside looks for the next entry
    while (true) {
        const int axis = tMax[0] < tMax[1] ? (tMax[0] < tMax[2] ? 0 : 2) : (tMax[1] < tMax[2] ? 1 : 2);
        const double t = tMax[std::size_t(axis)];
        if (t > tEnd) return std::nullopt;
        const Coord previous = cell;
        cell[axis] += step[std::size_t(axis)];
        tMax[std::size_t(axis)] += tDelta[std::size_t(axis)];
        const bool solid = lookup.solid(cell);
        if (!solid) leftSolid = true;
        if (solid && !wasSolid && leftSolid) {
            // The crossing lies on the edge from the lower of the two points along `axis`.
            const Coord lower = step[std::size_t(axis)] > 0 ? previous : cell;
            SurfaceHit hit;
            std::array<double, 3> p{double(lower[0]), double(lower[1]), double(lower[2])};
            double offset = 0.5;
            std::array<double, 3> n{0, 0, 0};
            n[std::size_t(axis)] = -double(step[std::size_t(axis)]);
            if (const HermiteLeaf* leaf = lookup.leaf(lower))
                if (const PackedSample* s = leaf->sample(HermiteLeaf::coordToOffset(lower), axis)) {
                    const UnpackedSample u = unpackSample(*s);
                    offset = u.offset;
                    n = {u.normal[0], u.normal[1], u.normal[2]};
                }
            p[std::size_t(axis)] += offset;
            for (int a = 0; a < 3; ++a) hit.point[std::size_t(a)] = p[std::size_t(a)] * h;
            hit.normal = n;
            hit.distance = (t + tStart) * h;
            return hit;
        }
        wasSolid = solid;
    }
}

} // namespace

std::optional<SurfaceHit> castRay(const Volume& volume, const std::array<double, 3>& origin,
                                  const std::array<double, 3>& direction, double maxDistance)
{
    GridLookup lookup(*volume.impl().grid);
    return castRayIn(lookup, volume.voxelSize(), origin, direction, maxDistance);
}

std::optional<SurfaceHit> castRay(const OverlaidVolume& volume, const std::array<double, 3>& origin,
                                  const std::array<double, 3>& direction, double maxDistance)
{
    OverlaidLookup lookup(volume);
    return castRayIn(lookup, volume.current.voxelSize(), origin, direction, maxDistance);
}

std::optional<SurfaceHit> castRayAcrossLevels(const std::vector<const Volume*>& levels, const std::array<double, 3>& origin,
                                              const std::array<double, 3>& direction, double maxDistance,
                                              const std::function<bool(const std::array<double, 3>&)>& finestResidentAt)
{
    std::optional<SurfaceHit> best;
    for (std::size_t k = 0; k < levels.size(); ++k) {
        if (!levels[k]) continue;
        std::optional<SurfaceHit> hit = castRay(*levels[k], origin, direction, maxDistance);
        if (!hit) continue;
        if (k > 0 && finestResidentAt && finestResidentAt(hit->point)) continue;
        hit->level = int(k);
        if (!best || hit->distance < best->distance - 2.0 * levels[k]->voxelSize()) best = hit;
    }
    return best;
}

} // namespace vdbclay
