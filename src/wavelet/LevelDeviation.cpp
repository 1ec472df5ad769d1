#include "wavelet/LevelDeviation.h"

#include "vdb_hermite/HermiteGrid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace vdbclay::wavelet {

namespace {

using ConstAccessor = openvdb::tree::ValueAccessor<const HermiteTree, /*IsSafe=*/false>;

struct SurfacePoint {
    std::array<double, 3> position; // world units
    std::array<float, 3> normal;
};

/// The solid/empty crossings of a volume whose points lie in the world box [lo, hi).
std::vector<SurfacePoint> crossingsIn(const Volume& volume, const std::array<double, 3>& lo, const std::array<double, 3>& hi)
{
    const double h = volume.voxelSize();
    const HermiteTree& tree = volume.impl().grid->constTree();
    ConstAccessor acc(tree);
    // The voxels whose positive edges may end inside the box.
    Coord first, last;
    for (int a = 0; a < 3; ++a) {
        first[a] = int32_t(std::floor(lo[std::size_t(a)] / h)) - 1;
        last[a] = int32_t(std::ceil(hi[std::size_t(a)] / h));
    }
    const CoordBBox voxels(first, last);
    std::vector<SurfacePoint> out;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        if (leaf->sampleCount() == 0 || !leaf->getNodeBoundingBox().hasOverlap(voxels)) continue;
        const Coord origin = leaf->origin();
        for (Index offset = 0; offset < Index(kLeafVoxels); ++offset) {
            const Coord ijk = leaf->offsetToGlobalCoord(offset);
            if (!voxels.isInside(ijk)) continue;
            const bool solid = leaf->getValue(offset).solid();
            for (int axis = 0; axis < 3; ++axis) {
                const PackedSample* sample = leaf->sample(offset, axis);
                if (!sample) continue;
                Coord next = ijk;
                next[axis] += 1;
                const bool inLeaf = next[axis] < origin[axis] + int32_t(kLeafDim);
                const bool nextSolid = inLeaf ? leaf->getValue(next).solid() : acc.getValue(next).solid();
                if (solid == nextSolid) continue; // a boundary between materials: no surface there
                const UnpackedSample s = unpackSample(*sample);
                SurfacePoint p{{double(ijk.x()) * h, double(ijk.y()) * h, double(ijk.z()) * h}, s.normal};
                p.position[std::size_t(axis)] += double(s.offset) * h;
                bool inside = true;
                for (std::size_t a = 0; a < 3; ++a) inside = inside && p.position[a] >= lo[a] && p.position[a] < hi[a];
                if (inside) out.push_back(p);
            }
        }
    }
    return out;
}

/// The crossings of a volume binned by the cells of its lattice over a box, for the crossings near a point.
class CrossingCells {
public:
    /// `points` must outlive it.
    CrossingCells(const std::vector<SurfacePoint>& points, double voxel, const std::array<double, 3>& lo, const std::array<double, 3>& hi)
        : points_(points), voxel_(voxel)
    {
        for (int a = 0; a < 3; ++a) {
            first_[std::size_t(a)] = int64_t(std::floor(lo[std::size_t(a)] / voxel)) - 1;
            dims_[std::size_t(a)] = int64_t(std::floor(hi[std::size_t(a)] / voxel)) + 2 - first_[std::size_t(a)];
        }
        head_.assign(std::size_t(dims_[0] * dims_[1] * dims_[2]), -1);
        next_.assign(points_.size(), -1);
        for (std::size_t i = 0; i < points_.size(); ++i) {
            const int64_t cell = cellOf(points_[i].position);
            if (cell < 0) continue;
            next_[i] = head_[std::size_t(cell)];
            head_[std::size_t(cell)] = int32_t(i);
        }
    }

    /// The distance from p to the tangent plane of the nearest crossing within `reach` cells of p's cell,
    /// or nullopt where there is none.
    std::optional<double> distanceNear(const std::array<double, 3>& p, int reach) const
    {
        int64_t c[3];
        for (int a = 0; a < 3; ++a) c[a] = int64_t(std::floor(p[std::size_t(a)] / voxel_)) - first_[std::size_t(a)];
        double nearest = std::numeric_limits<double>::infinity(), plane = 0.0;
        for (int64_t x = c[0] - reach; x <= c[0] + reach; ++x)
            for (int64_t y = c[1] - reach; y <= c[1] + reach; ++y)
                for (int64_t z = c[2] - reach; z <= c[2] + reach; ++z) {
                    if (x < 0 || y < 0 || z < 0 || x >= dims_[0] || y >= dims_[1] || z >= dims_[2]) continue;
                    for (int32_t i = head_[std::size_t((x * dims_[1] + y) * dims_[2] + z)]; i >= 0; i = next_[std::size_t(i)]) {
                        const SurfacePoint& q = points_[std::size_t(i)];
                        double d2 = 0.0, along = 0.0;
                        for (std::size_t a = 0; a < 3; ++a) {
                            const double d = p[a] - q.position[a];
                            d2 += d * d;
                            along += d * double(q.normal[a]);
                        }
                        if (d2 < nearest) nearest = d2, plane = std::fabs(along);
                    }
                }
        if (!std::isfinite(nearest)) return std::nullopt;
        return plane;
    }

private:
    int64_t cellOf(const std::array<double, 3>& p) const
    {
        int64_t c[3];
        for (int a = 0; a < 3; ++a) {
            c[a] = int64_t(std::floor(p[std::size_t(a)] / voxel_)) - first_[std::size_t(a)];
            if (c[a] < 0 || c[a] >= dims_[std::size_t(a)]) return -1;
        }
        return (c[0] * dims_[1] + c[1]) * dims_[2] + c[2];
    }

    const std::vector<SurfacePoint>& points_;
    double voxel_;
    std::array<int64_t, 3> first_{}, dims_{};
    std::vector<int32_t> head_, next_;
};

/// The largest distance from `from`'s points to the surface `to` holds within `reach` of its cells
/// (`unmatched` where it holds none there). Points within `margin` of the box's faces are left out: their
/// nearest match may lie beyond the faces, where `to` holds nothing.
double oneSided(const std::vector<SurfacePoint>& from, const CrossingCells& to, int reach, double unmatched,
                const std::array<double, 3>& lo, const std::array<double, 3>& hi, double margin)
{
    const auto nearFace = [&](const std::array<double, 3>& p) {
        for (std::size_t a = 0; a < 3; ++a)
            if (p[a] < lo[a] + margin || p[a] >= hi[a] - margin) return true;
        return false;
    };
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, from.size(), 1024), 0.0,
        [&](const tbb::blocked_range<std::size_t>& range, double worst) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                if (nearFace(from[i].position)) continue;
                const std::optional<double> d = to.distanceNear(from[i].position, reach);
                worst = std::max(worst, d ? *d : unmatched);
            }
            return worst;
        },
        [](double a, double b) { return std::max(a, b); });
}

} // namespace

double levelDeviation(const Volume& coarse, const Volume& fine, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                      double unmatched)
{
    // Both sides search as far as a coarse cell around a crossing: a coarse surface a coarse voxel off
    // the fine one is still matched.
    const double hc = coarse.voxelSize(), hf = fine.voxelSize();
    const int fineReach = std::max(1, int(std::ceil(hc / hf)));
    const std::vector<SurfacePoint> coarsePoints = crossingsIn(coarse, lo, hi), finePoints = crossingsIn(fine, lo, hi);
    const CrossingCells coarseCells(coarsePoints, hc, lo, hi), fineCells(finePoints, hf, lo, hi);
    const double fineToCoarse = oneSided(finePoints, coarseCells, 1, unmatched, lo, hi, hc);
    const double coarseToFine = oneSided(coarsePoints, fineCells, fineReach, unmatched, lo, hi, hc);
    return std::max(fineToCoarse, coarseToFine);
}

} // namespace vdbclay::wavelet
