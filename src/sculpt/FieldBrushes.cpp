#include "sculpt/FieldBrushes.h"

#include "sculpt/GridTool.h"
#include "sculpt/Symmetry.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeRegions.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

namespace vdbclay {

namespace {

/// Smooth blurs the old surface's distance capped at this many voxels. Blurring and thresholding a
/// capped distance moves the surface by its mean curvature as blurring the whole distance does (to
/// first order, as the MBO scheme does with an indicator), the distances are rebuilt only this near
/// the surface, and at a leaf's half-diagonal the capped field still tells a leaf's side.
constexpr double kSmoothBandVoxels = 8.0;

/// A box of a lattice grid's points, [lo, hi] per axis (indices into the grid).
struct PointRange {
    std::array<int32_t, 3> lo{}, hi{};

    /// Grown by `by` points on every side, clamped to a grid of these dims.
    PointRange grown(int32_t by, const std::array<int32_t, 3>& dims) const
    {
        PointRange out;
        for (std::size_t a = 0; a < 3; ++a) {
            out.lo[a] = std::max(0, lo[a] - by);
            out.hi[a] = std::min(dims[a] - 1, hi[a] + by);
        }
        return out;
    }
    bool empty() const { return lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]; }
};

/// fn(i, j) for every row (i, j) of the range, slabs of i in parallel.
template <typename Fn>
void forEachRow(const PointRange& range, const Fn& fn)
{
    if (range.empty()) return;
    tbb::parallel_for(tbb::blocked_range<int32_t>(range.lo[0], range.hi[0] + 1), [&](const tbb::blocked_range<int32_t>& slabs) {
        for (int32_t i = slabs.begin(); i < slabs.end(); ++i)
            for (int32_t j = range.lo[1]; j <= range.hi[1]; ++j) fn(i, j);
    });
}

/// fn(i, j, k) for every point of the range.
template <typename Fn>
void forEachPoint(const PointRange& range, const Fn& fn)
{
    forEachRow(range, [&](int32_t i, int32_t j) {
        for (int32_t k = range.lo[2]; k <= range.hi[2]; ++k) fn(i, j, k);
    });
}

/// A dense field on a box of the volume's lattice (world units), trilinear between its points.
struct LatticeGrid {
    std::array<int32_t, 3> origin{}, dims{};
    double voxelSize = 1.0;
    std::vector<float> values;

    std::size_t index(int32_t i, int32_t j, int32_t k) const
    {
        return (std::size_t(i) * std::size_t(dims[1]) + std::size_t(j)) * std::size_t(dims[2]) + std::size_t(k);
    }
    float at(int32_t i, int32_t j, int32_t k) const
    {
        i = std::clamp(i, 0, dims[0] - 1);
        j = std::clamp(j, 0, dims[1] - 1);
        k = std::clamp(k, 0, dims[2] - 1);
        return values[index(i, j, k)];
    }
    Vec3d pointOf(int32_t i, int32_t j, int32_t k) const
    {
        return Vec3d(origin[0] + i, origin[1] + j, origin[2] + k) * voxelSize;
    }
    /// Trilinear at a world point (clamped to the box); exact at the lattice's points.
    double sample(const Vec3d& world) const
    {
        std::size_t at[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            const int32_t n = dims[std::size_t(a)];
            const double q = std::clamp(world[a] / voxelSize - origin[std::size_t(a)], 0.0, double(n - 1));
            const int32_t c = std::min(int32_t(q), std::max(n - 2, 0));
            at[a] = std::size_t(c);
            f[a] = q - c;
        }
        // Strides to the far corners; a grid one point thick along an axis reads its one point twice.
        const std::size_t sz = dims[2] > 1 ? 1 : 0, sy = dims[1] > 1 ? std::size_t(dims[2]) : 0,
                          sx = dims[0] > 1 ? std::size_t(dims[1]) * std::size_t(dims[2]) : 0;
        const float* p = &values[index(int32_t(at[0]), int32_t(at[1]), int32_t(at[2]))];
        const auto lerp = [](double a, double b, double t) { return a * (1.0 - t) + b * t; };
        const auto alongZ = [&](std::size_t o) { return lerp(p[o], p[o + sz], f[2]); };
        return lerp(lerp(alongZ(0), alongZ(sy), f[1]), lerp(alongZ(sx), alongZ(sx + sy), f[1]), f[0]);
    }
    /// The value at a lattice point, clamped to the box.
    double atPoint(const std::array<int32_t, 3>& ijk) const
    {
        return at(ijk[0] - origin[0], ijk[1] - origin[1], ijk[2] - origin[2]);
    }
    /// The largest change per world unit between neighbouring points of a range (bounds the
    /// interpolant's gradient there).
    double lipschitz(const PointRange& range) const
    {
        if (range.empty()) return 0.0;
        const double worst = tbb::parallel_reduce(
            tbb::blocked_range<int32_t>(range.lo[0], range.hi[0] + 1), 0.0,
            [&](const tbb::blocked_range<int32_t>& rows, double found) {
                for (int32_t i = rows.begin(); i < rows.end(); ++i)
                    for (int32_t j = range.lo[1]; j <= range.hi[1]; ++j)
                        for (int32_t k = range.lo[2]; k <= range.hi[2]; ++k) {
                            const float v = values[index(i, j, k)];
                            double g2 = 0.0;
                            for (const float n : {at(i + 1, j, k), at(i, j + 1, k), at(i, j, k + 1)}) g2 += double(n - v) * double(n - v);
                            found = std::max(found, g2);
                        }
                return found;
            },
            [](double a, double b) { return std::max(a, b); });
        return std::sqrt(worst) / voxelSize;
    }
    double lipschitz() const { return lipschitz(PointRange{{0, 0, 0}, {dims[0] - 1, dims[1] - 1, dims[2] - 1}}); }
};

bool holdsSolid(const SolidDistances& solid)
{
    return std::any_of(solid.material.begin(), solid.material.end(), [](MaterialId m) { return m != kEmptyMaterial; });
}

/// The old surface's signed distance in world units, on the lattice box solidDistances rebuilt it over
/// (taking its distances; its materials stay).
LatticeGrid worldDistances(SolidDistances& solid, const std::array<int32_t, 3>& origin, double voxelSize)
{
    LatticeGrid grid;
    grid.origin = origin;
    grid.dims = solid.dims;
    grid.voxelSize = voxelSize;
    grid.values = std::move(solid.distance);
    for (float& v : grid.values) v = float(double(v) * voxelSize);
    return grid;
}

/// max(a, b, ...) of a grid field and the brush (and optionally minus another grid): the CSG kernel's
/// view of "the new solid, inside the brush".
class ClippedGridField : public SdfField {
public:
    ClippedGridField(const LatticeGrid& grid, double sign, const SdfField& brush, const LatticeGrid* notInside, double lipschitz)
        : grid_(grid), sign_(sign), brush_(brush), notInside_(notInside), lipschitz_(lipschitz)
    {
    }
    double distance(const Vec3d& world) const override
    {
        double d = std::max(sign_ * grid_.sample(world), brush_.distance(world));
        if (notInside_) d = std::max(d, -notInside_->sample(world));
        return d;
    }
    /// The kernel's voxels lie on the grids' lattice: their values are read, not interpolated.
    void distances(const LatticePatch& patch, double* out) const override
    {
        if (patch.voxelSize != grid_.voxelSize || (notInside_ && notInside_->voxelSize != grid_.voxelSize))
            return SdfField::distances(patch, out);
        brush_.distances(patch, out);
        for (int32_t i = 0; i < patch.count; ++i)
            for (int32_t j = 0; j < patch.count; ++j)
                for (int32_t k = 0; k < patch.count; ++k, ++out) {
                    const std::array<int32_t, 3> ijk{patch.first[0] + patch.stride * i, patch.first[1] + patch.stride * j,
                                                     patch.first[2] + patch.stride * k};
                    double d = std::max(sign_ * grid_.atPoint(ijk), *out);
                    if (notInside_) d = std::max(d, -notInside_->atPoint(ijk));
                    *out = d;
                }
    }
    WorldBounds bounds() const override { return brush_.bounds(); }
    double innerRadius() const override { return brush_.innerRadius(); }
    double surfaceAreaBound() const override { return brush_.surfaceAreaBound(); }
    double lipschitz() const override { return lipschitz_; }
    double evaluationCost() const override { return brush_.evaluationCost() + 2.0; }

private:
    const LatticeGrid& grid_;
    double sign_;
    const SdfField& brush_;
    const LatticeGrid* notInside_;
    double lipschitz_;
};

/// The grid's points that world bounds hold (with the lattice points on their faces).
/// The region a move's brush sweeps from where it grabbed to where it lets go: the brush at samples
/// along the drag no farther apart than an eighth of its inner radius (the union's scallops between
/// them are under 1% of the radius deep). What a move may change: the dragged surface stretches along it.
class DraggedField : public SdfField {
public:
    DraggedField(const SdfField& brush, const Vec3d& offset) : brush_(brush), offset_(offset), sphere_(roundSphere(brush))
    {
        const double spacing = std::max(0.125 * brush.innerRadius(), 1e-9);
        steps_ = int(std::min(std::ceil(offset.length() / spacing), 4096.0));
    }
    double distance(const Vec3d& world) const override
    {
        if (sphere_) { // a round sphere swept along a segment: the capsule, exactly (it holds the samples' union)
            const Vec3d rel = world - sphere_->first;
            const double along = offset_.lengthSqr() > 0.0 ? std::clamp(rel.dot(offset_) / offset_.lengthSqr(), 0.0, 1.0) : 0.0;
            return (rel - offset_ * along).length() - sphere_->second;
        }
        double d = brush_.distance(world);
        for (int s = 1; s <= steps_; ++s) d = std::min(d, brush_.distance(world - offset_ * (double(s) / steps_)));
        return d;
    }
    WorldBounds bounds() const override
    {
        WorldBounds b = brush_.bounds();
        for (int a = 0; a < 3; ++a) {
            b.min[a] = std::min(b.min[a], b.min[a] + offset_[a]);
            b.max[a] = std::max(b.max[a], b.max[a] + offset_[a]);
        }
        return b;
    }
    double innerRadius() const override { return brush_.innerRadius(); }
    double lipschitz() const override { return brush_.lipschitz(); }
    double evaluationCost() const override { return sphere_ ? 1.0 : brush_.evaluationCost() * (steps_ + 1); }

private:
    /// The centre and radius of a brush that is one round sphere (as placed, or a symmetry's copy of one).
    static std::optional<std::pair<Vec3d, double>> roundSphere(const SdfField& field)
    {
        if (const auto* copy = dynamic_cast<const TransformedField*>(&field)) {
            const auto inner = roundSphere(copy->original());
            if (inner) return std::make_pair(copy->place(inner->first), inner->second);
            return std::nullopt;
        }
        if (const auto* placed = dynamic_cast<const PlaceableField*>(&field); placed && placed->roundSphereRadius() > 0.0)
            return std::make_pair(placed->translation(), placed->roundSphereRadius());
        return std::nullopt;
    }

    const SdfField& brush_;
    Vec3d offset_;
    std::optional<std::pair<Vec3d, double>> sphere_;
    int steps_ = 0;
};

PointRange pointsWithin(const LatticeGrid& g, const WorldBounds& bounds)
{
    PointRange out;
    for (std::size_t a = 0; a < 3; ++a) {
        const double lo = std::ceil(bounds.min[int(a)] / g.voxelSize) - g.origin[a];
        const double hi = std::floor(bounds.max[int(a)] / g.voxelSize) - g.origin[a];
        out.lo[a] = int32_t(std::clamp(lo, 0.0, double(g.dims[a])));
        out.hi[a] = int32_t(std::clamp(hi, -1.0, double(g.dims[a] - 1)));
    }
    return out;
}

/// A box filter of radius r along one axis, written at the range's points (`to`, read from `from`;
/// the ends of the grid clamp): running sums along the axis, a row of k at a time (the grid's
/// contiguous axis, so that every pass walks memory in order). The sums of floats in double are
/// exact, so a value does not depend on where the range starts.
void boxBlurAxis(const LatticeGrid& from, LatticeGrid& to, int axis, int r, const PointRange& range)
{
    if (range.empty()) return;
    const int32_t n = from.dims[std::size_t(axis)], k0 = range.lo[2], width = range.hi[2] - k0 + 1;
    const double scale = 1.0 / double(2 * r + 1);
    if (axis == 2) {
        forEachRow(range, [&](int32_t i, int32_t j) {
            const float* line = &from.values[from.index(i, j, 0)];
            float* out = &to.values[to.index(i, j, 0)];
            double sum = 0.0;
            for (int32_t t = k0 - r; t <= k0 + r; ++t) sum += double(line[std::clamp(t, 0, n - 1)]);
            for (int32_t t = k0; t <= range.hi[2]; ++t) {
                out[t] = float(sum * scale);
                sum += double(line[std::min(t + r + 1, n - 1)]) - double(line[std::max(t - r, 0)]);
            }
        });
        return;
    }
    // Along i or j: one row of sums per line across the other of the two, the rows of k side by side.
    const std::size_t across = axis == 0 ? 1 : 0;
    tbb::parallel_for(tbb::blocked_range<int32_t>(range.lo[across], range.hi[across] + 1), [&](const tbb::blocked_range<int32_t>& lines) {
        std::vector<double> sum(static_cast<std::size_t>(width));
        for (int32_t c = lines.begin(); c < lines.end(); ++c) {
            const auto row = [&](const LatticeGrid& g, int32_t t) {
                t = std::clamp(t, 0, n - 1);
                return axis == 0 ? g.index(t, c, k0) : g.index(c, t, k0);
            };
            std::fill(sum.begin(), sum.end(), 0.0);
            const int32_t lo = range.lo[std::size_t(axis)], hi = range.hi[std::size_t(axis)];
            for (int32_t t = lo - r; t <= lo + r; ++t) {
                const float* in = &from.values[row(from, t)];
                for (int32_t k = 0; k < width; ++k) sum[std::size_t(k)] += double(in[k]);
            }
            for (int32_t t = lo; t <= hi; ++t) {
                float* out = &to.values[row(to, t)];
                const float* enter = &from.values[row(from, t + r + 1)];
                const float* leave = &from.values[row(from, t - r)];
                for (int32_t k = 0; k < width; ++k) {
                    out[k] = float(sum[std::size_t(k)] * scale);
                    sum[std::size_t(k)] += double(enter[k]) - double(leave[k]);
                }
            }
        }
    });
}

} // namespace

const char* fieldModeName(FieldMode mode)
{
    switch (mode) {
    case FieldMode::Smooth: return "smooth";
    case FieldMode::Flatten: return "flatten";
    case FieldMode::Inflate: return "inflate";
    case FieldMode::Deflate: return "deflate";
    case FieldMode::Move: return "move";
    }
    return "?";
}

std::optional<FieldMode> parseFieldMode(const std::string& name)
{
    for (FieldMode m : {FieldMode::Smooth, FieldMode::Flatten, FieldMode::Inflate, FieldMode::Deflate, FieldMode::Move})
        if (name == fieldModeName(m)) return m;
    return std::nullopt;
}

const char* falloffName(Falloff falloff)
{
    switch (falloff) {
    case Falloff::Smooth: return "smooth";
    case Falloff::Linear: return "linear";
    case Falloff::Constant: return "constant";
    case Falloff::Curve: return "curve";
    }
    return "?";
}

Falloff parseFalloff(const std::string& name)
{
    for (Falloff f : {Falloff::Smooth, Falloff::Linear, Falloff::Constant})
        if (name == falloffName(f)) return f;
    throw std::invalid_argument("unknown falloff '" + printableText(name, 80) + "' (smooth, linear or constant)");
}

double falloffWeight(Falloff falloff, double depth, double innerRadius, const FalloffCurve& curve)
{
    if (!(depth >= 0.0)) return 0.0;
    if (falloff == Falloff::Constant) return 1.0;
    const double t = innerRadius > 0.0 ? std::min(1.0, depth / innerRadius) : 1.0;
    if (falloff == Falloff::Curve && curve.size() >= 2) {
        const double at = t * double(curve.size() - 1);
        const std::size_t i = std::min(std::size_t(at), curve.size() - 2);
        return curve[i] + (curve[i + 1] - curve[i]) * (at - double(i));
    }
    return falloff == Falloff::Linear ? t : t * t * (3.0 - 2.0 * t);
}

void checkFalloffCurve(const FalloffCurve& curve)
{
    if (curve.size() < 2 || curve.size() > kMaxFalloffPoints)
        throw std::invalid_argument("a falloff curve holds 2 to " + std::to_string(kMaxFalloffPoints) + " weights");
    for (double w : curve)
        if (!(w >= 0.0 && w <= 1.0)) throw std::invalid_argument("a falloff curve's weights lie in [0, 1]");
}

namespace {

/// The most a falloff's weight changes per world unit of depth (infinite for the constant falloff's
/// step at the rim).
double falloffSlope(Falloff falloff, double innerRadius, const FalloffCurve& curve)
{
    if (!(innerRadius > 0.0) || falloff == Falloff::Constant) return std::numeric_limits<double>::infinity();
    if (falloff == Falloff::Linear) return 1.0 / innerRadius;
    if (falloff == Falloff::Curve && curve.size() >= 2) {
        double steepest = 0.0;
        for (std::size_t i = 0; i + 1 < curve.size(); ++i) steepest = std::max(steepest, std::fabs(curve[i + 1] - curve[i]));
        return steepest * double(curve.size() - 1) / innerRadius;
    }
    return 1.5 / innerRadius; // smoothstep's steepest, at half depth
}

/// The root in [0, 1] of a strictly falling g with g(0) >= 0 >= g(1), by regula falsi (the Illinois
/// variant, which keeps both ends moving).
template <typename G>
double fallingRoot(const G& g)
{
    double lo = 0.0, hi = 1.0, glo = g(lo), ghi = g(hi);
    if (glo <= 0.0) return lo;
    if (ghi >= 0.0) return hi;
    int side = 0;
    for (int it = 0; it < 60 && hi - lo > 1e-9; ++it) {
        const double t = std::clamp((lo * ghi - hi * glo) / (ghi - glo), lo, hi);
        const double gt = g(t);
        if (gt == 0.0) return t;
        if (gt > 0.0) {
            lo = t, glo = gt;
            if (side == 1) ghi *= 0.5;
            side = 1;
        } else {
            hi = t, ghi = gt;
            if (side == -1) glo *= 0.5;
            side = -1;
        }
    }
    return 0.5 * (lo + hi);
}

} // namespace

int smoothingRadiusVoxels(const SdfField& brush, double voxelSize)
{
    return std::clamp(int(std::lround(brush.innerRadius() / (2.0 * voxelSize))), 1, 12);
}

double fieldBrushReach(const SdfField& brush, const FieldBrushOp& op, double voxelSize)
{
    // The rebuilt field is right within its box; a few voxels more keep the box's walls away.
    double reach = 4.0 * voxelSize;
    switch (op.mode) {
    case FieldMode::Smooth: reach += 2.0 * smoothingRadiusVoxels(brush, voxelSize) * voxelSize; break; // two passes
    case FieldMode::Flatten: reach += brush.innerRadius(); break; // the plane may lie that far off the surface
    case FieldMode::Inflate:
    case FieldMode::Deflate: reach += std::fabs(op.distance); break;
    case FieldMode::Move: reach += op.offset.length(); break;
    }
    return reach;
}

WorldBounds fieldBrushRegion(const SdfField& brush, const FieldBrushOp& op, double voxelSize)
{
    WorldBounds b = brush.bounds();
    if (!b.bounded()) return b;
    if (op.mode == FieldMode::Move) {
        for (int a = 0; a < 3; ++a) {
            b.min[a] = std::min(b.min[a], b.min[a] + op.offset[a]) - 4.0 * voxelSize;
            b.max[a] = std::max(b.max[a], b.max[a] + op.offset[a]) + 4.0 * voxelSize;
        }
        return b;
    }
    const double reach = fieldBrushReach(brush, op, voxelSize);
    b.min -= Vec3d(reach);
    b.max += Vec3d(reach);
    return b;
}

void checkFieldBrush(const Volume& volume, const SdfField& brush, const FieldBrushOp& op)
{
    if (!(op.strength >= 0.0 && op.strength <= 1.0)) throw std::invalid_argument("strength must lie in [0,1]");
    if (!std::isfinite(op.distance)) throw std::invalid_argument("distance must be a finite number");
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(op.offset[a])) throw std::invalid_argument("offset must be finite");
    const WorldBounds b = brush.bounds();
    if (!b.bounded()) throw std::invalid_argument(std::string(fieldModeName(op.mode)) + " needs a bounded brush");
    const double h = volume.voxelSize();
    const WorldBounds region = fieldBrushRegion(brush, op, h);
    for (int a = 0; a < 3; ++a) {
        if (!(std::fabs(region.min[a]) <= kMaxReachVoxels * h && std::fabs(region.max[a]) <= kMaxReachVoxels * h))
            throw std::invalid_argument("the brush reaches beyond " + std::to_string(int64_t(kMaxReachVoxels)) + " voxels from the origin");
        const double voxels = (region.max[a] - region.min[a]) / h;
        if (!(voxels <= double(kMaxFieldBrushVoxels)))
            throw std::invalid_argument(std::string(fieldModeName(op.mode)) + " rebuilds the surface within " +
                                        std::to_string(kMaxFieldBrushVoxels) + " voxels of a side; this brush, with its reach, spans " +
                                        std::to_string(int64_t(std::min(voxels, 1e15))));
    }
    if (op.material && (*op.material == kEmptyMaterial || *op.material > volume.materials().size()))
        throw std::invalid_argument("unknown material id " + std::to_string(*op.material));
}

namespace {

/// What a prepared field brush writes back from: the old field, the new one, and a move's swept brush.
struct FieldBrushState {
    LatticeGrid old, next;
    std::optional<DraggedField> dragged;
};

} // namespace

EditStats applyFieldBrush(Volume& volume, const SdfField& brush, const FieldBrushOp& op, const Volume* strokeStart)
{
    return prepareFieldBrush(volume, brush, op, strokeStart)(volume);
}

EditWriteBack prepareFieldBrush(const Volume& volume, const SdfField& brush, const FieldBrushOp& op, const Volume* strokeStart)
{
    const auto nothing = [](Volume&) { return EditStats{}; };
    checkFieldBrush(volume, brush, op);
    const double h = volume.voxelSize();
    const WorldBounds bounds = brush.bounds();
    const double inner = brush.innerRadius();
    // A move carries a core of full weight, a voxel and a half deep (at most half the brush): dragged
    // several radii, the surface about the grabbed point still spans a voxel, so the point the pointer
    // holds stays under it instead of thinning to a needle the lattice cannot hold.
    const double core = op.mode == FieldMode::Move ? std::min(1.5 * h, 0.5 * inner) : 0.0;
    const auto weightAt = [&](const Vec3d& world) { return op.strength * falloffWeight(op.falloff, core - brush.distance(world), inner, op.curve); };
    const auto latticeBox = [&](double grow, std::array<int32_t, 3>& lo, std::array<int32_t, 3>& dims) {
        for (int a = 0; a < 3; ++a) {
            lo[std::size_t(a)] = int32_t(std::floor((bounds.min[a] - grow) / h));
            dims[std::size_t(a)] = int32_t(std::ceil((bounds.max[a] + grow) / h)) - lo[std::size_t(a)] + 1;
        }
    };
    // The old field must be right as far from the surface as the surface may move and the new field
    // reads it (the band); farther, its magnitude is capped. The region is what opBounds promises a store
    // pages in (fieldBrushRegion), so a streamed scene and a whole volume read the same voxels. A move
    // only carries values along: their signs, and exact distances near the surface it drags.
    double band = op.mode == FieldMode::Move     ? 6.0 * h
                  : op.mode == FieldMode::Smooth ? std::min(fieldBrushReach(brush, op, h), kSmoothBandVoxels * h)
                                                 : fieldBrushReach(brush, op, h);
    const WorldBounds region = fieldBrushRegion(brush, op, h);
    Vec3d centroid(0.0), normal(0.0); // flatten's plane
    if (op.mode == FieldMode::Flatten) {
        // The plane under the brush, fitted to the surface's crossings there weighted by the falloff.
        // The surface moves at most as far as it lies from the plane.
        std::array<int32_t, 3> lo{}, dims{};
        latticeBox(0.0, lo, dims);
        const std::vector<SurfaceSample> samples = surfaceSamples(volume, lo, dims);
        double total = 0.0;
        std::vector<std::pair<Vec3d, double>> weighted;
        for (const SurfaceSample& sample : samples) {
            const Vec3d p = sample.point * h;
            const double w = weightAt(p);
            if (w <= 0.0) continue;
            weighted.push_back({p, w});
            centroid += p * w;
            normal += sample.normal * w;
            total += w;
        }
        if (total <= 0.0 || normal.length() < 1e-9) return nothing; // no surface under the brush
        centroid /= total;
        normal.normalize();
        double gap = 0.0;
        for (const auto& [p, w] : weighted) gap = std::max(gap, std::fabs((p - centroid).dot(normal)));
        band = std::min(band, gap + 4.0 * h);
    }
    std::array<int32_t, 3> lo{}, dims{};
    for (int a = 0; a < 3; ++a) {
        // Flatten's band may be narrower than its reach (the plane lies near): the box shrinks with it.
        const double grow = op.mode == FieldMode::Flatten ? band : 0.0;
        const double from = op.mode == FieldMode::Flatten ? bounds.min[a] - grow : region.min[a];
        const double to = op.mode == FieldMode::Flatten ? bounds.max[a] + grow : region.max[a];
        lo[std::size_t(a)] = int32_t(std::floor(from / h));
        dims[std::size_t(a)] = int32_t(std::ceil(to / h)) - lo[std::size_t(a)] + 1;
    }
    // The old field, rebuilt from the Hermite data in the region, and the materials there.
    SolidDistances solid = solidDistances(volume, lo, dims, float(band / h));
    if (!holdsSolid(solid)) return nothing; // nothing solid to reshape
    const auto state = std::make_shared<FieldBrushState>();
    state->old = worldDistances(solid, lo, h);
    const LatticeGrid& old = state->old;
    // Only points inside the brush change (the weight is zero elsewhere, and the written-back field is
    // clipped by the brush): the work below is done on the brush's points, not on the whole band. A move
    // changes the region its brush sweeps along the drag.
    std::optional<DraggedField>& dragged = state->dragged;
    if (op.mode == FieldMode::Move) dragged.emplace(brush, op.offset);
    const SdfField& changed = dragged ? static_cast<const SdfField&>(*dragged) : brush;
    const PointRange inBrush = pointsWithin(old, changed.bounds());

    // The material of new voxels: the op's, else the most common solid one inside the brush.
    MaterialId material = op.material.value_or(kEmptyMaterial);
    if (material == kEmptyMaterial) {
        const std::size_t ids = volume.materials().size() + 1;
        tbb::enumerable_thread_specific<std::vector<uint64_t>> counts([&] { return std::vector<uint64_t>(ids, 0); });
        forEachRow(inBrush, [&](int32_t i, int32_t j) {
            std::vector<uint64_t>& local = counts.local();
            for (int32_t k = inBrush.lo[2]; k <= inBrush.hi[2]; ++k) {
                const MaterialId m = solid.material[old.index(i, j, k)];
                if (m != kEmptyMaterial && m < ids && brush.distance(old.pointOf(i, j, k)) <= 0.0) ++local[m];
            }
        });
        std::vector<uint64_t> total(ids, 0);
        for (const std::vector<uint64_t>& local : counts)
            for (std::size_t m = 0; m < ids; ++m) total[m] += local[m];
        material = MaterialId(1);
        for (std::size_t m = 1; m < ids; ++m)
            if (total[m] > total[material]) material = MaterialId(m);
    }

    // Weights, once per point.
    std::vector<float> weight(old.values.size(), 0.0f);
    forEachPoint(inBrush, [&](int32_t i, int32_t j, int32_t k) { weight[old.index(i, j, k)] = float(weightAt(old.pointOf(i, j, k))); });

    state->next = old;
    LatticeGrid& next = state->next;
    switch (op.mode) {
    case FieldMode::Inflate:
    case FieldMode::Deflate: {
        const double d = op.mode == FieldMode::Inflate ? op.distance : -op.distance;
        if (!strokeStart) {
            forEachPoint(inBrush, [&](int32_t i, int32_t j, int32_t k) {
                const std::size_t n = old.index(i, j, k);
                next.values[n] = float(old.values[n] - weight[n] * d);
            });
            break;
        }
        // Moved from where the stroke began, never back past where its earlier stamps put the surface.
        SolidDistances start = solidDistances(*strokeStart, lo, dims, float(band / h));
        const LatticeGrid began = worldDistances(start, lo, h);
        forEachPoint(inBrush, [&](int32_t i, int32_t j, int32_t k) {
            const std::size_t n = old.index(i, j, k);
            const float moved = float(began.values[n] - weight[n] * d);
            next.values[n] = d > 0.0 ? std::min(old.values[n], moved) : std::max(old.values[n], moved);
        });
        break;
    }
    case FieldMode::Smooth: {
        // Two box passes per axis (a smooth, symmetric kernel), each written where a later pass reads
        // it for a point of the brush: within the brush grown by the passes' reach.
        const int r = smoothingRadiusVoxels(brush, h); // fieldBrushReach reads 2 r around the brush
        const PointRange read = inBrush.grown(2 * r, old.dims);
        LatticeGrid blurred = old, scratch = old;
        for (int pass = 0; pass < 2; ++pass)
            for (int a = 0; a < 3; ++a) {
                boxBlurAxis(blurred, scratch, a, r, read);
                std::swap(blurred, scratch);
            }
        forEachPoint(inBrush, [&](int32_t i, int32_t j, int32_t k) {
            const std::size_t n = old.index(i, j, k);
            next.values[n] = float(old.values[n] + weight[n] * (blurred.values[n] - old.values[n]));
        });
        break;
    }
    case FieldMode::Flatten: {
        forEachPoint(inBrush, [&](int32_t i, int32_t j, int32_t k) {
            const std::size_t n = old.index(i, j, k);
            const double plane = (old.pointOf(i, j, k) - centroid).dot(normal);
            next.values[n] = float(old.values[n] + weight[n] * (plane - old.values[n]));
        });
        break;
    }
    case FieldMode::Move: {
        // Each point p moves to p + w(p) offset (w where the brush grabbed it). A lattice point x takes
        // the old field where it came from: p = x - t offset with t = w(p), a root of
        // g(t) = w(x - t offset) - t on [0, 1] (g(0) >= 0 >= g(1), so there is one). A long drag folds
        // the trailing side over itself and x then has several sources: x is solid if any of them is
        // (the smallest of their fields), so the dragged bump stays whole however far it goes.
        // A point moves at most `moved`, so a lattice point's new value lies within that of its old
        // one. Farther from the surface than that and the reach of the cells the surface crosses, the
        // old value less `moved` keeps its side and bounds its distance; only the points nearer search
        // for their sources.
        // When w changes by less than 1 over the drag (w's slope times the drag under 1), g falls
        // strictly and its one root is found by regula falsi; otherwise g is sampled for every root.
        constexpr int kSamples = 16, kBisections = 24;
        const double moved = op.strength * op.offset.length(), searched = moved + 3.0 * h;
        const bool oneSource = moved * falloffSlope(op.falloff, inner, op.curve) < 0.999;
        forEachPoint(inBrush, [&](int32_t i, int32_t j, int32_t k) {
            const double here = old.values[old.index(i, j, k)];
            if (std::fabs(here) > searched) {
                next.values[old.index(i, j, k)] = float(here > 0.0 ? here - moved : here + moved);
                return;
            }
            const Vec3d x = old.pointOf(i, j, k);
            const auto g = [&](double t) { return weightAt(x - op.offset * t) - t; };
            if (oneSource) {
                next.values[old.index(i, j, k)] = float(old.sample(x - op.offset * fallingRoot(g)));
                return;
            }
            double best = std::numeric_limits<double>::infinity();
            double t0 = 0.0, g0 = g(0.0);
            if (g0 == 0.0) best = old.sample(x);
            for (int s = 1; s <= kSamples; ++s) {
                const double t1 = double(s) / kSamples, g1 = g(t1);
                if (g1 == 0.0) best = std::min(best, old.sample(x - op.offset * t1));
                else if ((g0 > 0.0) != (g1 > 0.0) && g0 != 0.0) {
                    double lo = t0, hi = t1;
                    const bool negativeAtLo = g0 < 0.0;
                    for (int b = 0; b < kBisections; ++b) {
                        const double mid = 0.5 * (lo + hi);
                        ((g(mid) < 0.0) == negativeAtLo ? lo : hi) = mid;
                    }
                    best = std::min(best, old.sample(x - op.offset * (0.5 * (lo + hi))));
                }
                t0 = t1;
                g0 = g1;
            }
            next.values[old.index(i, j, k)] = float(best);
        });
        break;
    }
    }

    // Write back inside the brush: add what the new field holds and the old did not, then remove what the
    // new field leaves. Outside the brush nothing changes. The grids' values (at most the band in size)
    // decide the clipped fields only within the band of the brush's box; beyond it, the brush's distance.
    const int32_t bandPoints = int32_t(std::ceil(band / h)) + 2;
    const double lipschitz = std::max({1.0, next.lipschitz(inBrush.grown(1, next.dims)), old.lipschitz(inBrush.grown(bandPoints, old.dims))});
    return [state, &brush, material, lipschitz](Volume& target) {
        const SdfField& changed = state->dragged ? static_cast<const SdfField&>(*state->dragged) : brush;
        EditStats stats = applyCsg(target, ClippedGridField(state->next, 1.0, changed, &state->old, lipschitz), CsgOp{CsgMode::Add, material, 1.0, {}});
        stats.append(applyCsg(target, ClippedGridField(state->next, -1.0, changed, nullptr, lipschitz), CsgOp{CsgMode::Remove, material, 1.0, {}}));
        return stats;
    };
}

double blendReach(double width, double voxelSize) { return width + 4.0 * voxelSize; }

WorldBounds blendedAddRegion(WorldBounds brushBounds, double width, double voxelSize)
{
    if (!brushBounds.bounded()) return brushBounds;
    const double reach = blendReach(width, voxelSize);
    brushBounds.min -= Vec3d(reach);
    brushBounds.max += Vec3d(reach);
    return brushBounds;
}

namespace {

/// Voxels of the old solid's depth a blended add reads: its fillet only adds, so only the lattice points
/// on edges that cross the old surface (within sqrt 3 of it) take part in a new crossing.
constexpr float kBlendInnerBand = 3.0f;

/// A field grown by `by` world units: where a blended add's fillet may reach.
class GrownField : public SdfField {
public:
    GrownField(const SdfField& field, double by) : field_(field), by_(by) {}
    double distance(const Vec3d& world) const override { return field_.distance(world) - by_; }
    WorldBounds bounds() const override
    {
        WorldBounds b = field_.bounds();
        b.min -= Vec3d(by_);
        b.max += Vec3d(by_);
        return b;
    }
    double innerRadius() const override { return field_.innerRadius() + by_; }
    double lipschitz() const override { return field_.lipschitz(); }
    double evaluationCost() const override { return field_.evaluationCost(); }

private:
    const SdfField& field_;
    double by_;
};

} // namespace

EditStats applyBlendedAdd(Volume& volume, const SdfField& brush, const CsgOp& op, double width)
{
    return prepareBlendedAdd(volume, brush, op, width)(volume);
}

EditWriteBack prepareBlendedAdd(const Volume& volume, const SdfField& brush, const CsgOp& op, double width)
{
    const auto exact = [&brush, op](Volume& target) { return applyCsg(target, brush, op); };
    checkCsgLimits(volume.voxelSize(), volume.materials(), brush, op);
    if (!(width > 0.0) || !std::isfinite(width)) throw std::invalid_argument("a blend's width must be positive");
    const double h = volume.voxelSize(), band = blendReach(width, h);
    const WorldBounds region = blendedAddRegion(brush.bounds(), width, h);
    std::array<int32_t, 3> lo{}, dims{};
    bool fits = region.bounded();
    for (int a = 0; a < 3 && fits; ++a) {
        lo[std::size_t(a)] = int32_t(std::floor(region.min[a] / h));
        dims[std::size_t(a)] = int32_t(std::ceil(region.max[a] / h)) - lo[std::size_t(a)] + 1;
        fits = dims[std::size_t(a)] <= kMaxFieldBrushVoxels;
    }
    if (!fits) return exact;
    // The old surface's distance, before the brush changes it.
    SolidDistances solid = solidDistances(volume, lo, dims, float(band / h), kBlendInnerBand);
    if (!holdsSolid(solid)) return exact; // nothing to blend into
    const auto state = std::make_shared<FieldBrushState>();
    state->old = worldDistances(solid, lo, h);
    const LatticeGrid& old = state->old;
    const GrownField reach(brush, width);
    const PointRange inReach = pointsWithin(old, reach.bounds());
    state->next = old;
    LatticeGrid& next = state->next;
    // Where the old distance is capped outside (the surface lies beyond the band), the fillet adds nothing
    // the exact add has not: the point keeps its old value and the brush need not be evaluated there.
    // Inside, the fillet's value goes on from the capped distance (the field stays continuous; it is
    // solid there either way).
    const float capped = float(band * (1.0 - 1e-6));
    forEachPoint(inReach, [&](int32_t i, int32_t j, int32_t k) {
        const std::size_t n = old.index(i, j, k);
        if (old.values[n] >= capped) return;
        const double a = old.values[n], b = brush.distance(old.pointOf(i, j, k));
        const double t = std::max(width - std::fabs(a - b), 0.0) / width;
        next.values[n] = float(std::min(a, b) - 0.25 * width * t * t);
    });
    const double lipschitz = std::max({1.0, next.lipschitz(inReach.grown(1, next.dims)), old.lipschitz()});
    // The brush exactly, then the fillet where it meets the old surface.
    return [state, &brush, op, width, lipschitz](Volume& target) {
        EditStats stats = applyCsg(target, brush, op);
        stats.append(applyCsg(target, ClippedGridField(state->next, 1.0, GrownField(brush, width), &state->old, lipschitz), op));
        return stats;
    };
}

} // namespace vdbclay
