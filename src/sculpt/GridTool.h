// Sculptures used as tools (seed 001 §3): any Hermite volume carves, adds and paints like a brush.
//
// A GridTool holds the volume in its own frame and, rebuilt once from its Hermite data, signed distances
// on its lattice: one field for the whole solid and one for each material's region. A PlacedTool puts it
// in the world (at, rotate, scale) and samples those fields by inverse mapping with trilinear
// interpolation (seed 001 §3.1.3, §3.2), so any rotation fills every voxel it covers, without holes and
// with sub-voxel crossings. A placement that maps the tool's lattice onto the volume's (the same voxel
// size, whole-voxel positions, quarter turns, unit scale) copies the tool's crossings and normals
// exactly instead (SdfField::latticeCrossing). Every placement and every stroke shares one GridTool.
#pragma once

#include "sculpt/Brush.h"
#include "vdb_hermite/Materials.h"
#include "vdb_hermite/Quantize.h"
#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace vdbclay {

/// Tools larger than this many lattice points (their solid's box and a margin) are refused: each
/// field holds a float per point.
constexpr double kMaxToolPoints = double(1u << 24);

/// A scene, or the part of it inside a world box, as a tool: the scene intersected with the box (the voxels
/// whose centres lie in it, cut faces sharp and flat). Throws std::invalid_argument on an empty or
/// inverted box, or when nothing solid is left.
Volume toolFromScene(Volume scene, const std::optional<WorldBounds>& box);

/// One signed distance field on the tool's lattice, in voxels of the tool, negative inside.
struct ToolField {
    MaterialId region = kEmptyMaterial; // the material whose region it bounds; empty: the whole solid
    std::vector<float> distance;        // dense, over GridTool::origin() + dims()
    float outerValue = 0.0f;            // the value on the box's outer layer (one value all round)
    double lipschitz = 1.0;             // the largest gradient of its trilinear interpolant
    double deepest = 0.0;               // the depth of its deepest inside point (voxels)
};

/// The signed distance to a volume's solid (voxels, negative inside) at the lattice points of a box, built
/// as a tool's fields are: the points near a Hermite crossing take their distance to it, and a vector
/// propagation carries the nearest crossing through the box (Euclidean to any depth; crossings outside the
/// box are not seen). With the material at each point. Points indexed (x * dims[1] + y) * dims[2] + z.
/// `band` (voxels): magnitudes are capped at it, and the work spent on points beyond it is skipped.
/// `innerBand` (voxels): the same inside the solid, for brushes that read only a thin layer of it (the
/// distances outside do not change).
struct SolidDistances {
    std::array<int32_t, 3> origin{0, 0, 0}, dims{0, 0, 0};
    std::vector<float> distance;
    std::vector<MaterialId> material;
};
SolidDistances solidDistances(const Volume& volume, const std::array<int32_t, 3>& origin, const std::array<int32_t, 3>& dims,
                              float band = std::numeric_limits<float>::infinity(), float innerBand = std::numeric_limits<float>::infinity());

/// Where the solid's boundary crosses the lattice edges inside a box (Hermite crossings between solid
/// and empty), index space.
struct SurfaceSample {
    Vec3d point;
    Vec3d normal; // unit, out of the solid
};
std::vector<SurfaceSample> surfaceSamples(const Volume& volume, const std::array<int32_t, 3>& origin, const std::array<int32_t, 3>& dims);

class GridTool {
public:
    /// Rebuilds the fields of `volume`. The tool's pivot, where a placement's `at` puts it, is the
    /// lattice point at the centre of its solid's bounding box (rounded down). Throws
    /// std::invalid_argument for a volume without solid voxels or one over kMaxToolPoints.
    explicit GridTool(Volume volume);
    ~GridTool();
    GridTool(const GridTool&) = delete;
    GridTool& operator=(const GridTool&) = delete;

    /// Loads a native .vdb (VolumeIOError when it cannot) and builds the tool.
    static std::shared_ptr<const GridTool> load(const std::string& path);

    const Volume& volume() const { return volume_; }
    double voxelSize() const { return volume_.voxelSize(); }
    const MaterialTable& materials() const { return volume_.materials(); }
    /// The lattice point the placement's origin maps to.
    const std::array<int32_t, 3>& pivot() const { return pivot_; }
    /// The first lattice point of the fields' box and its size in points.
    const std::array<int32_t, 3>& origin() const { return origin_; }
    const std::array<int32_t, 3>& dims() const { return dims_; }
    /// The whole solid (fields().front()), then one field per material present, by ascending id.
    const std::vector<ToolField>& fields() const { return fields_; }
    /// The field of a material's region, or of the whole solid for kEmptyMaterial; nullptr when the
    /// tool holds no voxel of that material.
    const ToolField* field(MaterialId region) const;
    /// The materials present, by ascending id.
    std::vector<MaterialId> regions() const;
    /// The material of a tool voxel (empty outside the fields' box).
    MaterialId materialAt(const std::array<int32_t, 3>& ijk) const;
    /// The sample of the positive `axis` edge of a tool voxel, or nullopt when that edge does not cross.
    std::optional<PackedSample> sampleAt(const std::array<int32_t, 3>& ijk, int axis) const;

private:
    std::size_t index(const std::array<int32_t, 3>& ijk) const;

    Volume volume_;
    std::array<int32_t, 3> pivot_{}, origin_{}, dims_{};
    std::vector<MaterialId> material_; // dense, over the fields' box
    std::vector<ToolField> fields_;
};

/// A tool placed in the world: its region's field seen through the placement.
class PlacedTool : public PlaceableField {
public:
    /// `region`: kEmptyMaterial for the whole solid, or a material of the tool. Throws
    /// std::invalid_argument on a bad placement or a material the tool does not hold.
    PlacedTool(std::shared_ptr<const GridTool> tool, const Placement& placement, MaterialId region = kEmptyMaterial);

    double distance(const Vec3d& world) const override { return distanceAt(world, placement_.translation); }
    void distances(const LatticePatch& patch, double* out) const override;
    double distanceAt(const Vec3d& world, const Vec3d& origin) const override;
    /// The gradient of the interpolant, carried back to world space.
    Vec3d gradient(const Vec3d& world, double step) const override;
    WorldBounds bounds() const override;
    double innerRadius() const override;
    double lipschitz() const override { return std::max(1.0, field_->lipschitz); }
    double evaluationCost() const override { return 1.0; }
    std::optional<EdgeCrossing> latticeCrossing(const Vec3d& start, int axis, double voxelSize) const override;
    const Vec3d& translation() const override { return placement_.translation; }
    double boundingRadius() const override { return boundingRadius_; }

    const GridTool& tool() const { return *tool_; }
    MaterialId region() const { return field_->region; }
    /// Whether the placement maps the tool's lattice onto a lattice of its voxel size (see the header).
    bool onLattice() const { return onLattice_; }

private:
    /// The tool-lattice position of a world point with the origin at `origin`.
    Vec3d toLattice(const Vec3d& world, const Vec3d& origin) const;
    /// A tool-lattice position relative to the fields' first point, and whether such a position lies in
    /// their box.
    Vec3d relative(const Vec3d& q) const;
    bool insideFields(const Vec3d& rel) const;
    /// The field at a tool-lattice position, or at a relative one, in tool voxels.
    double sample(const Vec3d& q) const;
    double sampleRelative(const Vec3d& rel) const;

    std::shared_ptr<const GridTool> tool_;
    const ToolField* field_;
    Placement placement_;
    Mat3d worldToLattice_; // (rotation * scale)^-1 / voxel size
    Mat3d latticeToWorld_; // rotation * scale * voxel size
    double toWorldDistance_; // tool voxels to world units: voxel size * the least scale
    double boundingRadius_ = 0.0;
    WorldBounds bounds_;
    bool onLattice_ = false;
    std::array<std::array<int, 3>, 3> quarterTurn_{}; // onLattice_: the rotation's integer entries
};

} // namespace vdbclay
