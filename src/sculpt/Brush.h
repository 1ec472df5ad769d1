// Signed distance brushes: primitives with a full transform, composite (smoothly blended) brushes and
// swept brushes for strokes. Distances are in world units, negative inside, and never overestimate
// the true distance by more than the blend allows (they are Lipschitz-1 bounds), which the CSG kernel
// relies on for block classification and for the adaptive crossing search.
#pragma once

#include <openvdb/math/Mat3.h>
#include <openvdb/math/Vec3.h>

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace vdbclay {

using Vec3d = openvdb::math::Vec3d;
using Mat3d = openvdb::math::Mat3d;

enum class Shape { Sphere, Box, Cylinder, Capsule, Torus, Cone, HalfSpace };

/// Shape name as used in scripts and on the command line ("sphere", "box", "half-space", ...).
const char* shapeName(Shape shape);
/// Throws std::invalid_argument listing the valid names.
Shape parseShape(const std::string& name);

/// A primitive in its local frame. Cylinder, capsule, torus and cone have their axis along local Y.
struct Primitive {
    Shape shape = Shape::Sphere;
    double radius = 1.0;      // sphere, cylinder, capsule, cone (base radius), torus (major radius)
    Vec3d size{1.0, 1.0, 1.0}; // box half-extents
    double rounding = 0.0;    // box edge/corner radius, inside the half-extents
    double height = 2.0;      // cylinder and cone: full height
    double length = 2.0;      // capsule: distance between the centres of its two caps
    double minorRadius = 0.5; // torus: tube radius
    Vec3d normal{0.0, 1.0, 0.0}; // half-space: solid where dot(normal, p) < 0

    double distance(const Vec3d& p) const;
    /// Throws std::invalid_argument on non-positive or inconsistent sizes.
    void validate() const;
};

/// The primitive `vdbclay new --size S` makes: a sphere of radius S, a box of half-extent S, a cylinder or
/// cone of radius S and height 2S, a capsule of radius S and length S, a torus of radii S and S/4.
Primitive primitiveOfSize(Shape shape, double size);

/// Translation, rotation (Euler degrees about world axes, x first: R = Rz*Ry*Rx) and per-axis scale.
struct Placement {
    Vec3d translation{0.0, 0.0, 0.0};
    Vec3d rotationDegrees{0.0, 0.0, 0.0};
    Vec3d scale{1.0, 1.0, 1.0};
};

/// The rotation of Euler angles in degrees (R = Rz*Ry*Rx), exact for multiples of 90.
Mat3d rotationFromEuler(const Vec3d& degrees);
/// Rotation times scale: local to world, less the translation.
Mat3d placementLinear(const Placement& placement);
/// Throws std::invalid_argument on a non-positive or non-finite scale, or a non-finite position or angle.
void validatePlacement(const Placement& placement);

struct WorldBounds {
    Vec3d min{-std::numeric_limits<double>::infinity()};
    Vec3d max{std::numeric_limits<double>::infinity()};
    bool bounded() const;
};

/// Where a field's surface crosses one lattice edge: the offset along the edge (0..1) and the unit
/// normal there, pointing out of the field's solid.
struct EdgeCrossing {
    double offset = 0.5;
    Vec3d normal{0.0, 0.0, 1.0};
};

/// A cube of lattice points: (first + stride * (i, j, k)) * voxelSize for i, j, k in [0, count), i slowest
/// and k fastest. The block kernel asks for distances a patch at a time, so that a sampled field can step
/// through its own lattice instead of transforming every point.
struct LatticePatch {
    std::array<int32_t, 3> first{};
    int32_t stride = 1;
    int32_t count = 1;
    double voxelSize = 1.0;

    std::size_t size() const { return std::size_t(count) * std::size_t(count) * std::size_t(count); }
    Vec3d point(int32_t i, int32_t j, int32_t k) const
    {
        return Vec3d(first[0] + stride * i, first[1] + stride * j, first[2] + stride * k) * voxelSize;
    }
};

/// Anything the CSG kernel can carve with.
class SdfField {
public:
    virtual ~SdfField() = default;
    virtual double distance(const Vec3d& world) const = 0;
    /// Distances at a patch's points (patch.size() of them, in its order) with one virtual call.
    virtual void distances(const LatticePatch& patch, double* out) const;
    /// Unit gradient of the distance (pointing out of the brush), or zero where it is undefined.
    /// The default is a central difference along each axis with the given step (mirror-exact).
    virtual Vec3d gradient(const Vec3d& world, double step) const;
    virtual WorldBounds bounds() const = 0;
    /// Depth of the deepest inside point (world units): erosion scales with it.
    virtual double innerRadius() const = 0;
    /// An upper bound of the brush's surface area (world units squared): edits cost about that many
    /// voxels. The default is the area of the bounds' box (infinite when unbounded).
    virtual double surfaceAreaBound() const;
    /// Primitive distances one distance() evaluates (a blend evaluates each of its parts).
    virtual double evaluationCost() const { return 1.0; }
    /// The most the distance changes per world unit moved. Analytic brushes are Lipschitz-1 bounds; a
    /// sampled field (a grid tool) can change faster between its samples, and the kernel widens every
    /// "this region lies on one side" test, and the steps of its crossing search, by this factor.
    virtual double lipschitz() const { return 1.0; }
    /// The exact crossing of the lattice edge from `start` one voxel (`voxelSize`) along +`axis`, for a
    /// field built from Hermite data and placed on the volume's lattice (a grid tool stamped at whole
    /// voxels and quarter turns), so that such a stamp copies the tool's samples instead of resampling
    /// them. Nullopt where the field has no such crossing; the kernel then searches the distance's zero.
    virtual std::optional<EdgeCrossing> latticeCrossing(const Vec3d& /*start*/, int /*axis*/, double /*voxelSize*/) const
    {
        return std::nullopt;
    }
};

/// A field with an origin that strokes move along their path: an analytic Brush or a placed grid tool.
class PlaceableField : public SdfField {
public:
    /// The distance with the field's origin moved to `origin`.
    virtual double distanceAt(const Vec3d& world, const Vec3d& origin) const = 0;
    /// Where the field's origin is.
    virtual const Vec3d& translation() const = 0;
    /// Radius of a sphere about the origin that holds the whole (bounded) field: beyond it, the distance
    /// is at least the distance to that sphere.
    virtual double boundingRadius() const = 0;
    /// World radius of a lone sphere centred on the origin, or 0 for any other field: sweeping such a
    /// sphere has a closed form.
    virtual double roundSphereRadius() const { return 0.0; }
};

enum class PartOp { Add, Remove };

struct BrushPart {
    Primitive primitive;
    Placement placement;
    PartOp op = PartOp::Add;
};

/// One primitive, or several blended with smooth min/max (polynomial, radius `smoothness`).
class Brush : public PlaceableField {
public:
    Brush() = default;
    Brush(const Primitive& primitive, const Placement& placement);
    Brush(std::vector<BrushPart> parts, double smoothness, const Placement& placement);

    double distance(const Vec3d& world) const override { return distanceAtOrigin(world - translation_); }
    void distances(const LatticePatch& patch, double* out) const override;
    Vec3d gradient(const Vec3d& world, double step) const override;
    WorldBounds bounds() const override;
    double innerRadius() const override;
    double evaluationCost() const override { return double(parts_.size()); }

    double distanceAt(const Vec3d& world, const Vec3d& origin) const override { return distanceAtOrigin(world - origin); }
    const Vec3d& translation() const override { return translation_; }
    double boundingRadius() const override;
    /// Non-zero for a lone sphere with a uniform scale.
    double roundSphereRadius() const override;

private:
    struct CompiledPart {
        Primitive primitive;
        double worldToLocal[9]; // inverse of (rotation * scale), brush and part combined, row-major
        Vec3d offset;        // part origin relative to the brush origin, world frame
        double minScale;     // rescales local distances into world (lower) bounds
        PartOp op;
    };
    double distanceAtOrigin(const Vec3d& relative) const;
    /// The most common brush, a lone sphere, evaluated without the per-shape dispatch.
    static double sphereDistance(const CompiledPart& part, const Vec3d& relative);
    void compile(const std::vector<BrushPart>& parts, const Placement& placement);

    std::vector<CompiledPart> parts_;
    bool singlePart_ = false;
    bool singleSphere_ = false;
    double smoothness_ = 0.0;
    Vec3d translation_{0.0, 0.0, 0.0};
    WorldBounds localBounds_; // relative to the brush origin
    double innerRadius_ = 0.0;
};

/// A brush (or any placeable field) swept along a polyline of origins: the union of the brush at every
/// point of the path.
///
/// A distance looks only at the pieces of the path near the point: the path is cut into pieces no
/// longer than the brush is wide, kept in a hash grid by the cells their reach overlaps, so a stroke
/// costs about the voxels it covers whatever its number of points. Where no piece is near, the distance
/// is the bound the grid guarantees (half a cell), which is positive and never above the true distance.
/// The grid is built on the first distance, so a stroke refused by the limits costs nothing; copies
/// share it.
class SweptBrush : public SdfField {
public:
    /// A stroke may be at most this many brush reaches long (pieces of the path).
    static constexpr double kMaxPieces = 1e6;
    /// Throws std::invalid_argument on an empty path, an unbounded brush or a path over kMaxPieces.
    SweptBrush(Brush brush, std::vector<Vec3d> path);
    SweptBrush(std::shared_ptr<const PlaceableField> brush, std::vector<Vec3d> path);
    double distance(const Vec3d& world) const override;
    WorldBounds bounds() const override;
    double innerRadius() const override { return brush_->innerRadius(); }
    double lipschitz() const override { return brush_->lipschitz(); }
    /// A swept sphere's exact gradient (away from the nearest point of the path); for other brushes
    /// finite differences no finer than the window search's precision (a thousandth of the reach).
    Vec3d gradient(const Vec3d& world, double step) const override;
    /// The tube around the path the brush's reach sweeps, or the bounds' box where that is smaller.
    double surfaceAreaBound() const override;
    /// The brush evaluated along the pieces near a point (about four, with a window search each).
    double evaluationCost() const override { return brush_->evaluationCost() * (capsuleRadius_ > 0.0 ? 4.0 : 200.0); }
    /// Length of the path (world units).
    double pathLength() const { return pathLength_; }
    /// Radius of a sphere about the brush origin that holds the brush (world units).
    double reach() const { return reach_; }

private:
    struct Piece {
        Vec3d start, direction;
        double length;
        uint32_t segment; // of the path: consecutive pieces of one segment continue each other
        double along;     // where the piece starts on its segment
    };
    /// The pieces within reach (and half a cell) of one cell. A cell a tangled stroke crosses many times
    /// is split into sub-cells of a third of its width, each listing the pieces within reach (and half a
    /// sub-cell) of it: a point there looks at the pieces near it, not at the hundreds the cell holds.
    struct Cell {
        std::vector<uint32_t> pieces;
        mutable std::once_flag subCellsBuilt; // built on first use, by whichever thread asks first
        mutable std::vector<std::vector<uint32_t>> subCells; // kSubCells^3, x fastest
    };
    struct CellHash {
        std::size_t operator()(const std::array<int64_t, 3>& c) const;
    };
    static constexpr int kSubCells = 3;
    static constexpr std::size_t kDenseCell = 16; // pieces above which a cell is split
    struct PieceGrid {
        uint64_t id = nextGridId(); // names it in the threads' lookup caches (an address may be reused)
        std::once_flag built;
        std::vector<Piece> pieces;
        std::unordered_map<std::array<int64_t, 3>, Cell, CellHash> cells; // cell -> pieces within reach of it
    };
    double pieceDistance(const Piece& piece, const Vec3d& x, double best) const;
    /// A swept sphere: the squared distance from x to the nearest of the pieces `ids` (runs of one
    /// segment taken as one), and that nearest point.
    double nearestOnPieces(const PieceGrid& g, const std::vector<uint32_t>& ids, const Vec3d& x, Vec3d& nearest) const;
    const PieceGrid& grid() const;
    static uint64_t nextGridId();
    /// The pieces a point must look at (none: an empty cell), and the distance beyond which the ones left
    /// out lie (half the width of the cell or sub-cell listing them). Each thread remembers the last
    /// cell or sub-cell it looked up: the kernel's points come in blocks, mostly in the same one.
    struct Near {
        const std::vector<uint32_t>* ids = nullptr;
        double farther = 0.0;
    };
    Near piecesNear(const PieceGrid& g, const Vec3d& x) const;

    std::shared_ptr<const PlaceableField> brush_;
    std::vector<Vec3d> path_;
    double reach_;  // bounding radius of the brush
    double step_;   // sampling step along the path
    double capsuleRadius_; // > 0: a round sphere swept along segments, exact capsule distances
    double pathLength_ = 0.0;
    double cell_ = 1.0; // grid spacing, world units
    std::shared_ptr<PieceGrid> grid_ = std::make_shared<PieceGrid>();
};

} // namespace vdbclay
