#include "sculpt/Brush.h"

#include "vdb_hermite/PrintableText.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <cstdint>
#include <stdexcept>
#include <utility>

namespace vdbclay {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct ShapeNameEntry {
    Shape shape;
    const char* name;
};
constexpr ShapeNameEntry kShapeNames[] = {
    {Shape::Sphere, "sphere"},   {Shape::Box, "box"},   {Shape::Cylinder, "cylinder"}, {Shape::Capsule, "capsule"},
    {Shape::Torus, "torus"},     {Shape::Cone, "cone"}, {Shape::HalfSpace, "half-space"},
};

double length2(double x, double y) { return std::sqrt(x * x + y * y); }

/// Polynomial smooth minimum; it lies at most k/4 below min(a, b).
double smoothMin(double a, double b, double k)
{
    if (k <= 0.0) return std::min(a, b);
    const double h = std::max(k - std::fabs(a - b), 0.0) / k;
    return std::min(a, b) - h * h * k * 0.25;
}

/// Cosine and sine of an angle in degrees, exact for multiples of 90: a box turned by 90 degrees keeps its
/// faces on the lattice planes it was on (cos(pi / 2) is 6e-17 in floating point, not 0).
std::pair<double, double> cosSinDegrees(double degrees)
{
    const double turns = degrees / 90.0;
    if (turns == std::floor(turns) && std::fabs(turns) < 1e15) {
        constexpr double kCos[4] = {1.0, 0.0, -1.0, 0.0}, kSin[4] = {0.0, 1.0, 0.0, -1.0};
        const int quarter = int(((int64_t(turns) % 4) + 4) % 4);
        return {kCos[quarter], kSin[quarter]};
    }
    const double r = degrees * (kPi / 180.0);
    return {std::cos(r), std::sin(r)};
}

} // namespace

Mat3d rotationFromEuler(const Vec3d& degrees)
{
    const auto [cx, sx] = cosSinDegrees(degrees.x());
    const auto [cy, sy] = cosSinDegrees(degrees.y());
    const auto [cz, sz] = cosSinDegrees(degrees.z());
    const Mat3d rx(1.0, 0.0, 0.0, 0.0, cx, -sx, 0.0, sx, cx);
    const Mat3d ry(cy, 0.0, sy, 0.0, 1.0, 0.0, -sy, 0.0, cy);
    const Mat3d rz(cz, -sz, 0.0, sz, cz, 0.0, 0.0, 0.0, 1.0);
    return rz * ry * rx; // column-vector convention: x first
}

Mat3d placementLinear(const Placement& p)
{
    const Vec3d& s = p.scale;
    return rotationFromEuler(p.rotationDegrees) * Mat3d(s.x(), 0.0, 0.0, 0.0, s.y(), 0.0, 0.0, 0.0, s.z());
}

void validatePlacement(const Placement& p)
{
    for (int i = 0; i < 3; ++i) {
        if (!(p.scale[i] > 0.0) || !std::isfinite(p.scale[i])) throw std::invalid_argument("scale factors must be positive");
        if (!std::isfinite(p.translation[i]) || !std::isfinite(p.rotationDegrees[i]))
            throw std::invalid_argument("positions and rotations must be finite numbers");
    }
}

namespace {

/// Axis-aligned bounds of the primitive in its local frame (infinite for a half-space).
WorldBounds primitiveBounds(const Primitive& p)
{
    Vec3d h;
    switch (p.shape) {
    case Shape::Sphere: h = Vec3d(p.radius); break;
    case Shape::Box: h = p.size; break;
    case Shape::Cylinder: h = Vec3d(p.radius, 0.5 * p.height, p.radius); break;
    case Shape::Capsule: h = Vec3d(p.radius, 0.5 * p.length + p.radius, p.radius); break;
    case Shape::Torus: h = Vec3d(p.radius + p.minorRadius, p.minorRadius, p.radius + p.minorRadius); break;
    case Shape::Cone: h = Vec3d(p.radius, 0.5 * p.height, p.radius); break;
    case Shape::HalfSpace: return WorldBounds{};
    }
    return WorldBounds{-h, h};
}

double primitiveInnerRadius(const Primitive& p)
{
    switch (p.shape) {
    case Shape::Sphere: return p.radius;
    case Shape::Box: return std::min({p.size.x(), p.size.y(), p.size.z()});
    case Shape::Cylinder: return std::min(p.radius, 0.5 * p.height);
    case Shape::Capsule: return p.radius;
    case Shape::Torus: return p.minorRadius;
    case Shape::Cone: return p.radius * p.height / (p.radius + std::sqrt(p.radius * p.radius + p.height * p.height));
    case Shape::HalfSpace: return kInf;
    }
    return 0.0;
}

} // namespace

const char* shapeName(Shape shape)
{
    for (const auto& e : kShapeNames) {
        if (e.shape == shape) return e.name;
    }
    return "?";
}

Shape parseShape(const std::string& name)
{
    for (const auto& e : kShapeNames) {
        if (name == e.name) return e.shape;
    }
    throw std::invalid_argument("unknown shape '" + printableText(name, 80) +
                                "' (expected sphere, box, cylinder, capsule, torus, cone or half-space)");
}

Primitive primitiveOfSize(Shape shape, double s)
{
    Primitive p;
    p.shape = shape;
    switch (shape) {
    case Shape::Sphere: p.radius = s; break;
    case Shape::Box: p.size = Vec3d(s); break;
    case Shape::Cylinder:
    case Shape::Cone:
        p.radius = s;
        p.height = 2.0 * s;
        break;
    case Shape::Capsule:
        p.radius = s;
        p.length = s;
        break;
    case Shape::Torus:
        p.radius = s;
        p.minorRadius = s / 4.0;
        break;
    case Shape::HalfSpace: break;
    }
    return p;
}

bool WorldBounds::bounded() const
{
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(min[i]) || !std::isfinite(max[i])) return false;
    }
    return true;
}

void Primitive::validate() const
{
    auto positive = [](double v, const char* what) {
        if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string(what) + " must be a positive number");
    };
    switch (shape) {
    case Shape::Sphere: positive(radius, "radius"); break;
    case Shape::Box:
        positive(size.x(), "size");
        positive(size.y(), "size");
        positive(size.z(), "size");
        if (!(rounding >= 0.0) || rounding > std::min({size.x(), size.y(), size.z()}))
            throw std::invalid_argument("rounding must lie between 0 and the smallest half-extent");
        break;
    case Shape::Cylinder: positive(radius, "radius"); positive(height, "height"); break;
    case Shape::Capsule:
        positive(radius, "radius");
        if (!(length >= 0.0) || !std::isfinite(length)) throw std::invalid_argument("length must be zero or positive");
        break;
    case Shape::Torus:
        positive(radius, "radius");
        positive(minorRadius, "minor_radius");
        break;
    case Shape::Cone: positive(radius, "radius"); positive(height, "height"); break;
    case Shape::HalfSpace:
        if (!(normal.length() > 0.0) || !std::isfinite(normal.length())) throw std::invalid_argument("normal must be a non-zero vector");
        break;
    }
}

double Primitive::distance(const Vec3d& p) const
{
    switch (shape) {
    case Shape::Sphere: return p.length() - radius;
    case Shape::Box: {
        const Vec3d q(std::fabs(p.x()) - size.x() + rounding, std::fabs(p.y()) - size.y() + rounding,
                      std::fabs(p.z()) - size.z() + rounding);
        const Vec3d outside(std::max(q.x(), 0.0), std::max(q.y(), 0.0), std::max(q.z(), 0.0));
        return outside.length() + std::min(std::max({q.x(), q.y(), q.z()}), 0.0) - rounding;
    }
    case Shape::Cylinder: {
        const double dx = length2(p.x(), p.z()) - radius;
        const double dy = std::fabs(p.y()) - 0.5 * height;
        return std::min(std::max(dx, dy), 0.0) + length2(std::max(dx, 0.0), std::max(dy, 0.0));
    }
    case Shape::Capsule: {
        const double half = 0.5 * length;
        const double y = p.y() - std::clamp(p.y(), -half, half);
        return std::sqrt(p.x() * p.x() + y * y + p.z() * p.z()) - radius;
    }
    case Shape::Torus: return length2(length2(p.x(), p.z()) - radius, p.y()) - minorRadius;
    case Shape::Cone: {
        // Cone with base radius `radius` at y = -h and apex at y = +h, h = height / 2: the distance to
        // the 2D profile (radial distance q, height y) is the nearer of the cap and the slanted side.
        const double h = 0.5 * height;
        const double qx = length2(p.x(), p.z());
        const double qy = p.y();
        const double capX = qx - std::min(qx, qy < 0.0 ? radius : 0.0);
        const double capY = std::fabs(qy) - h;
        // Side segment from (radius, -h) to (0, h).
        const double ex = -radius, ey = 2.0 * h;
        const double t = std::clamp(((qx - radius) * ex + (qy + h) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
        const double sideX = qx - radius - ex * t;
        const double sideY = qy + h - ey * t;
        const bool inside = sideX < 0.0 && capY < 0.0;
        const double d2 = std::min(capX * capX + capY * capY, sideX * sideX + sideY * sideY);
        return (inside ? -1.0 : 1.0) * std::sqrt(d2);
    }
    case Shape::HalfSpace: return normal.dot(p) / normal.length();
    }
    return kInf;
}

Brush::Brush(const Primitive& primitive, const Placement& placement)
{
    compile({BrushPart{primitive, Placement{}, PartOp::Add}}, placement);
}

Brush::Brush(std::vector<BrushPart> parts, double smoothness, const Placement& placement)
{
    if (parts.empty()) throw std::invalid_argument("a composite brush needs at least one part");
    if (!(smoothness >= 0.0) || !std::isfinite(smoothness)) throw std::invalid_argument("smoothness must be zero or positive");
    if (parts.front().op != PartOp::Add) throw std::invalid_argument("the first part of a composite brush must add");
    smoothness_ = smoothness;
    compile(parts, placement);
}

void Brush::compile(const std::vector<BrushPart>& parts, const Placement& placement)
{
    validatePlacement(placement);
    translation_ = placement.translation;
    const Mat3d brushLinear = placementLinear(placement);
    const double brushMinScale = std::min({placement.scale.x(), placement.scale.y(), placement.scale.z()});

    parts_.clear();
    localBounds_ = WorldBounds{Vec3d(kInf), Vec3d(-kInf)};
    innerRadius_ = 0.0;
    bool unbounded = false;
    for (const auto& part : parts) {
        part.primitive.validate();
        validatePlacement(part.placement);
        const Mat3d partLinear = placementLinear(part.placement);
        const Mat3d localToWorld = brushLinear * partLinear;
        CompiledPart compiled;
        compiled.primitive = part.primitive;
        const Mat3d inverse = localToWorld.inverse();
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) compiled.worldToLocal[r * 3 + c] = inverse(r, c);
        compiled.offset = brushLinear * part.placement.translation;
        compiled.minScale =
            brushMinScale * std::min({part.placement.scale.x(), part.placement.scale.y(), part.placement.scale.z()});
        compiled.op = part.op;
        parts_.push_back(compiled);
        if (part.op != PartOp::Add) continue;

        innerRadius_ = std::max(innerRadius_, primitiveInnerRadius(part.primitive) * compiled.minScale);
        const WorldBounds local = primitiveBounds(part.primitive);
        if (!local.bounded()) {
            unbounded = true;
            continue;
        }
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3d c((corner & 1) ? local.max.x() : local.min.x(), (corner & 2) ? local.max.y() : local.min.y(),
                          (corner & 4) ? local.max.z() : local.min.z());
            const Vec3d w = localToWorld * c + compiled.offset;
            for (int i = 0; i < 3; ++i) {
                localBounds_.min[i] = std::min(localBounds_.min[i], w[i]);
                localBounds_.max[i] = std::max(localBounds_.max[i], w[i]);
            }
        }
    }
    singlePart_ = parts_.size() == 1;
    singleSphere_ = singlePart_ && parts_.front().primitive.shape == Shape::Sphere;
    if (unbounded) {
        localBounds_ = WorldBounds{};
    } else {
        localBounds_.min -= Vec3d(0.25 * smoothness_);
        localBounds_.max += Vec3d(0.25 * smoothness_);
    }
}

double Brush::sphereDistance(const CompiledPart& part, const Vec3d& relative)
{
    const double* m = part.worldToLocal;
    const double x = relative.x() - part.offset.x(), y = relative.y() - part.offset.y(), z = relative.z() - part.offset.z();
    const double lx = m[0] * x + m[1] * y + m[2] * z, ly = m[3] * x + m[4] * y + m[5] * z,
                 lz = m[6] * x + m[7] * y + m[8] * z;
    return (std::sqrt(lx * lx + ly * ly + lz * lz) - part.primitive.radius) * part.minScale;
}

double Brush::distanceAtOrigin(const Vec3d& relative) const
{
    auto partDistance = [&relative](const CompiledPart& part) {
        const double* m = part.worldToLocal;
        const double x = relative.x() - part.offset.x(), y = relative.y() - part.offset.y(),
                     z = relative.z() - part.offset.z();
        const Vec3d local(m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
                          m[6] * x + m[7] * y + m[8] * z);
        return part.primitive.distance(local) * part.minScale;
    };
    if (singleSphere_) return sphereDistance(parts_.front(), relative);
    if (singlePart_) return partDistance(parts_.front());
    double d = kInf;
    for (const auto& part : parts_) {
        const double dp = partDistance(part);
        if (part.op == PartOp::Add) d = smoothMin(d, dp, smoothness_);
        else d = -smoothMin(-d, dp, smoothness_);
    }
    return d;
}

void SdfField::distances(const LatticePatch& patch, double* out) const
{
    for (int32_t i = 0; i < patch.count; ++i)
        for (int32_t j = 0; j < patch.count; ++j)
            for (int32_t k = 0; k < patch.count; ++k) *out++ = distance(patch.point(i, j, k));
}

void Brush::distances(const LatticePatch& patch, double* out) const
{
    for (int32_t i = 0; i < patch.count; ++i)
        for (int32_t j = 0; j < patch.count; ++j)
            for (int32_t k = 0; k < patch.count; ++k) {
                const Vec3d local = patch.point(i, j, k) - translation_;
                *out++ = singleSphere_ ? sphereDistance(parts_.front(), local) : distanceAtOrigin(local);
            }
}

double SdfField::surfaceAreaBound() const
{
    const WorldBounds b = bounds();
    if (!b.bounded()) return kInf;
    const Vec3d d = b.max - b.min;
    return 2.0 * (d.x() * d.y() + d.y() * d.z() + d.z() * d.x());
}

Vec3d SweptBrush::gradient(const Vec3d& world, double step) const
{
    if (capsuleRadius_ > 0.0 && path_.size() > 1) {
        // A swept sphere's gradient points away from the nearest point of its path: one search, not six.
        const PieceGrid& g = grid();
        const Near near = piecesNear(g, world);
        if (near.ids) {
            Vec3d nearest;
            const double length = std::sqrt(nearestOnPieces(g, *near.ids, world, nearest));
            if (length - capsuleRadius_ < near.farther && length > 0.0 && std::isfinite(length)) return (world - nearest) / length;
        }
    }
    return SdfField::gradient(world, capsuleRadius_ > 0.0 ? step : std::max(step, 1e-3 * reach_));
}

double SweptBrush::surfaceAreaBound() const
{
    const double tube = 2.0 * kPi * reach_ * pathLength_ + 4.0 * kPi * reach_ * reach_;
    return std::min(tube, SdfField::surfaceAreaBound());
}

Vec3d SdfField::gradient(const Vec3d& p, double h) const
{
    // Central differences along each axis: a mirror maps this stencil onto itself (p + h e_x and p - h e_x
    // trade places), so a mirrored field's gradient is the field's own turned, bit for bit. A tetrahedral
    // stencil, one evaluation cheaper, turns into another tetrahedron and differs at edges and corners.
    Vec3d g;
    for (int a = 0; a < 3; ++a) {
        Vec3d step(0.0);
        step[a] = h;
        g[a] = distance(p + step) - distance(p - step);
    }
    const double len = g.length();
    return len > 0.0 && std::isfinite(len) ? g / len : Vec3d(0.0);
}

Vec3d Brush::gradient(const Vec3d& world, double step) const
{
    if (!singleSphere_) return SdfField::gradient(world, step);
    // A sphere's gradient is radial in its local frame; the chain rule carries it back to world space.
    const CompiledPart& part = parts_.front();
    const Vec3d r = world - translation_ - part.offset;
    const double* m = part.worldToLocal;
    const Vec3d local(m[0] * r.x() + m[1] * r.y() + m[2] * r.z(), m[3] * r.x() + m[4] * r.y() + m[5] * r.z(),
                      m[6] * r.x() + m[7] * r.y() + m[8] * r.z());
    const Vec3d g(m[0] * local.x() + m[3] * local.y() + m[6] * local.z(),
                  m[1] * local.x() + m[4] * local.y() + m[7] * local.z(),
                  m[2] * local.x() + m[5] * local.y() + m[8] * local.z());
    const double len = g.length();
    return len > 0.0 && std::isfinite(len) ? g / len : Vec3d(0.0);
}

WorldBounds Brush::bounds() const
{
    if (!localBounds_.bounded()) return localBounds_;
    return WorldBounds{localBounds_.min + translation_, localBounds_.max + translation_};
}

double Brush::innerRadius() const { return innerRadius_; }

double Brush::boundingRadius() const
{
    if (!localBounds_.bounded()) return kInf;
    double r2 = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3d c((corner & 1) ? localBounds_.max.x() : localBounds_.min.x(),
                      (corner & 2) ? localBounds_.max.y() : localBounds_.min.y(),
                      (corner & 4) ? localBounds_.max.z() : localBounds_.min.z());
        r2 = std::max(r2, c.lengthSqr());
    }
    return std::sqrt(r2);
}

double Brush::roundSphereRadius() const
{
    if (!singleSphere_) return 0.0;
    const CompiledPart& part = parts_.front();
    const double* m = part.worldToLocal;
    // Uniform scale: the rows of worldToLocal are orthogonal with equal lengths.
    const double r0 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
    const double r1 = m[3] * m[3] + m[4] * m[4] + m[5] * m[5];
    const double r2 = m[6] * m[6] + m[7] * m[7] + m[8] * m[8];
    const double d01 = m[0] * m[3] + m[1] * m[4] + m[2] * m[5];
    const double d02 = m[0] * m[6] + m[1] * m[7] + m[2] * m[8];
    const double d12 = m[3] * m[6] + m[4] * m[7] + m[5] * m[8];
    const double tol = 1e-12 * r0;
    const bool round = part.offset.lengthSqr() == 0.0 && std::fabs(r1 - r0) < tol && std::fabs(r2 - r0) < tol &&
                       std::fabs(d01) < tol && std::fabs(d02) < tol && std::fabs(d12) < tol;
    return round ? part.primitive.radius * part.minScale : 0.0;
}

SweptBrush::SweptBrush(Brush brush, std::vector<Vec3d> path)
    : SweptBrush(std::make_shared<const Brush>(std::move(brush)), std::move(path))
{
}

SweptBrush::SweptBrush(std::shared_ptr<const PlaceableField> brush, std::vector<Vec3d> path)
    : brush_(std::move(brush)), path_(std::move(path))
{
    if (path_.empty()) throw std::invalid_argument("a stroke path needs at least one point");
    reach_ = brush_->boundingRadius();
    if (!std::isfinite(reach_)) throw std::invalid_argument("an unbounded brush (half-space) cannot follow a path");
    step_ = std::max(0.25 * brush_->innerRadius(), 1e-6);
    capsuleRadius_ = brush_->roundSphereRadius();

    // Pieces at most one reach long; cells two reaches wide (built in grid()).
    const double pieceLength = std::max(reach_, 1e-9);
    cell_ = 2.0 * pieceLength;
    double pieces = 0.0;
    for (std::size_t i = 0; i + 1 < path_.size(); ++i) {
        const double len = (path_[i + 1] - path_[i]).length();
        pathLength_ += len;
        pieces += std::max(1.0, std::ceil(len / pieceLength));
    }
    if (!(pieces <= kMaxPieces))
        throw std::invalid_argument("the stroke is " + std::to_string(int64_t(std::min(pieces, 1e18))) +
                                    " brush reaches long, more than the 1000000 allowed (use a larger brush or a "
                                    "shorter path)");
}

const SweptBrush::PieceGrid& SweptBrush::grid() const
{
    // A piece is listed in every cell within reach + half a cell of it, so a point in a cell sees every
    // piece whose brush reaches within half a cell of it: the pieces it does not see are farther away.
    std::call_once(grid_->built, [this] {
        PieceGrid& g = *grid_;
        const double pieceLength = 0.5 * cell_;
        for (std::size_t i = 0; i + 1 < path_.size(); ++i) {
            const Vec3d a = path_[i], b = path_[i + 1];
            const double len = (b - a).length();
            const int count = std::max(1, int(std::ceil(len / pieceLength)));
            const Vec3d dir = len > 1e-12 ? (b - a) / len : Vec3d(0.0);
            for (int k = 0; k < count; ++k) {
                const double t0 = len * k / count, t1 = len * (k + 1) / count;
                g.pieces.push_back({a + dir * t0, dir, t1 - t0, uint32_t(i), t0});
            }
        }
        const double grow = reach_ + 0.5 * cell_;
        for (uint32_t id = 0; id < g.pieces.size(); ++id) {
            const Piece& piece = g.pieces[id];
            const Vec3d end = piece.start + piece.direction * piece.length;
            int64_t lo[3], hi[3];
            for (int a = 0; a < 3; ++a) {
                lo[a] = int64_t(std::floor((std::min(piece.start[a], end[a]) - grow) / cell_));
                hi[a] = int64_t(std::floor((std::max(piece.start[a], end[a]) + grow) / cell_));
            }
            for (int64_t i = lo[0]; i <= hi[0]; ++i)
                for (int64_t j = lo[1]; j <= hi[1]; ++j)
                    for (int64_t k = lo[2]; k <= hi[2]; ++k) {
                        g.cells[{i, j, k}].pieces.push_back(id);
                    }
        }
    });
    return *grid_;
}

std::size_t SweptBrush::CellHash::operator()(const std::array<int64_t, 3>& c) const
{
    // Each coordinate mixed in turn (splitmix64's finalizer): cells a few apart, with either sign, spread.
    uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int64_t v : c) {
        h ^= uint64_t(v) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
        h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
        h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
        h ^= h >> 31;
    }
    return std::size_t(h);
}

double SweptBrush::distance(const Vec3d& x) const
{
    if (path_.size() == 1) return brush_->distanceAt(x, path_.front());
    const PieceGrid& g = grid();
    const Near near = piecesNear(g, x);
    double best = near.farther; // every piece not listed lies farther away
    if (!near.ids) return best;
    if (capsuleRadius_ > 0.0) {
        Vec3d nearest;
        return std::min(best, std::sqrt(nearestOnPieces(g, *near.ids, x, nearest)) - capsuleRadius_);
    }
    for (uint32_t id : *near.ids) best = std::min(best, pieceDistance(g.pieces[id], x, best));
    return best;
}

double SweptBrush::nearestOnPieces(const PieceGrid& g, const std::vector<uint32_t>& ids, const Vec3d& x, Vec3d& nearest) const
{
    // By squared distance, one square root at the end (a dense stroke lists hundreds of pieces in a
    // cell; the root per piece was most of its cost). Consecutive pieces of one path segment listed
    // together are one longer segment (a cell holds a run of several): one test for the run.
    double nearestSq = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < ids.size();) {
        const Piece& first = g.pieces[ids[k]];
        std::size_t last = k;
        while (last + 1 < ids.size() && ids[last + 1] == ids[last] + 1 && g.pieces[ids[last + 1]].segment == first.segment) ++last;
        const Piece& end = g.pieces[ids[last]];
        const double length = end.along + end.length - first.along;
        const double along = std::clamp((x - first.start).dot(first.direction), 0.0, length);
        const Vec3d point = first.start + first.direction * along;
        const double sq = (x - point).lengthSqr();
        if (sq < nearestSq) nearestSq = sq, nearest = point;
        k = last + 1;
    }
    return nearestSq;
}

uint64_t SweptBrush::nextGridId()
{
    static std::atomic<uint64_t> next{1};
    return next.fetch_add(1, std::memory_order_relaxed);
}

SweptBrush::Near SweptBrush::piecesNear(const PieceGrid& g, const Vec3d& x) const
{
    struct Remembered {
        uint64_t grid = 0;
        Vec3d lo, hi; // the cell or sub-cell looked up last
        Near near;
    };
    thread_local Remembered last;
    if (last.grid == g.id && x.x() >= last.lo.x() && x.y() >= last.lo.y() && x.z() >= last.lo.z() && x.x() < last.hi.x() &&
        x.y() < last.hi.y() && x.z() < last.hi.z())
        return last.near;
    const std::array<int64_t, 3> at{int64_t(std::floor(x.x() / cell_)), int64_t(std::floor(x.y() / cell_)), int64_t(std::floor(x.z() / cell_))};
    const Vec3d origin = Vec3d(double(at[0]), double(at[1]), double(at[2])) * cell_;
    last.grid = g.id;
    last.lo = origin;
    last.hi = origin + Vec3d(cell_);
    const auto found = g.cells.find(at);
    if (found == g.cells.end()) return last.near = {nullptr, 0.5 * cell_};
    const Cell& cell = found->second;
    if (cell.pieces.size() <= kDenseCell) return last.near = {&cell.pieces, 0.5 * cell_};
    const double sub = cell_ / kSubCells;
    std::call_once(cell.subCellsBuilt, [&] {
        // A piece is listed in a sub-cell when it passes within the reach and half a sub-cell of some point
        // of it: within that and the half-diagonal of the sub-cell's centre (its segment, not its box, so
        // a long diagonal piece is listed along its line only).
        cell.subCells.resize(std::size_t(kSubCells * kSubCells * kSubCells));
        const double within = reach_ + 0.5 * sub + 0.5 * std::sqrt(3.0) * sub;
        for (int k = 0; k < kSubCells; ++k)
            for (int j = 0; j < kSubCells; ++j)
                for (int i = 0; i < kSubCells; ++i) {
                    const Vec3d centre = origin + Vec3d(i + 0.5, j + 0.5, k + 0.5) * sub;
                    std::vector<uint32_t>& listed = cell.subCells[std::size_t((k * kSubCells + j) * kSubCells + i)];
                    for (uint32_t id : cell.pieces) {
                        const Piece& piece = g.pieces[id];
                        const double along = std::clamp((centre - piece.start).dot(piece.direction), 0.0, piece.length);
                        if ((centre - (piece.start + piece.direction * along)).lengthSqr() <= within * within) listed.push_back(id);
                    }
                }
    });
    int index[3];
    for (int a = 0; a < 3; ++a) {
        index[a] = std::clamp(int(std::floor((x[a] - origin[a]) / sub)), 0, kSubCells - 1);
        last.lo[a] = origin[a] + index[a] * sub;
        last.hi[a] = index[a] == kSubCells - 1 ? origin[a] + cell_ : origin[a] + (index[a] + 1) * sub;
    }
    return last.near = {&cell.subCells[std::size_t((index[2] * kSubCells + index[1]) * kSubCells + index[0])], 0.5 * sub};
}

double SweptBrush::pieceDistance(const Piece& piece, const Vec3d& x, double best) const
{
    const Vec3d& a = piece.start;
    const Vec3d& dir = piece.direction;
    const double len = piece.length;
    if (len < 1e-12) return brush_->distanceAt(x, a);
    const double along = std::clamp((x - a).dot(dir), 0.0, len);
    const double toSegment = (x - (a + dir * along)).length();
    if (capsuleRadius_ > 0.0) return toSegment - capsuleRadius_; // a swept round sphere is a capsule
    const double lowerBound = toSegment - reach_;
    if (lowerBound >= best) return best;
    // The brush cannot reach x from this piece: a safe bound, used only when it is clearly positive, as a
    // point on the surface counts as inside (a bound of 0 where the brush's farthest corner just fails to
    // reach x would put x in the stroke).
    if (lowerBound > 1e-6 * reach_) return lowerBound;
    // The brush can touch x only for origins within `reach_` of the closest point: sample that window
    // on a fixed grid along the piece, then refine the best sample by golden-section search (exact for
    // convex brushes, whose distance is convex along the path).
    const double lo = std::max(0.0, along - reach_);
    const double hi = std::min(len, along + reach_);
    auto eval = [&](double s) { return brush_->distanceAt(x, a + dir * s); };
    double bestS = lo, bestD = eval(lo);
    for (double s = std::ceil(lo / step_) * step_; s < hi; s += step_) {
        const double d = eval(s);
        if (d < bestD) bestD = d, bestS = s;
    }
    if (const double d = eval(hi); d < bestD) bestD = d, bestS = hi;
    double left = std::max(lo, bestS - step_), right = std::min(hi, bestS + step_);
    constexpr double kGolden = 0.6180339887498949;
    double m1 = right - kGolden * (right - left), m2 = left + kGolden * (right - left);
    double f1 = eval(m1), f2 = eval(m2);
    for (int it = 0; it < 24; ++it) {
        if (f1 < f2) {
            right = m2, m2 = m1, f2 = f1;
            m1 = right - kGolden * (right - left), f1 = eval(m1);
        } else {
            left = m1, m1 = m2, f1 = f2;
            m2 = left + kGolden * (right - left), f2 = eval(m2);
        }
    }
    return std::min({bestD, f1, f2});
}

WorldBounds SweptBrush::bounds() const
{
    WorldBounds b{Vec3d(kInf), Vec3d(-kInf)};
    for (const auto& p : path_) {
        const WorldBounds one = brush_->bounds();
        for (int i = 0; i < 3; ++i) {
            b.min[i] = std::min(b.min[i], one.min[i] - brush_->translation()[i] + p[i]);
            b.max[i] = std::max(b.max[i], one.max[i] - brush_->translation()[i] + p[i]);
        }
    }
    return b;
}

} // namespace vdbclay
