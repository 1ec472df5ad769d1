// How close a mesh is to the surface it approximates: two-sided distances (Hausdorff and mean), normal
// deviation, the smallest triangle angle and closedness. The exact surface is given either as a signed
// distance function (negative inside) or as a reference mesh; this module does not depend on
// src/sculpt, so a brush is passed in as a std::function.
#pragma once

#include "mesher/Mesh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace vdbclay {

using Point3d = std::array<double, 3>;
/// Signed distance in world units, negative inside, a Lipschitz-1 bound at least. Called from several
/// threads at once, so it must be thread-safe.
using SignedDistanceFn = std::function<double(const Point3d&)>;
/// Gradient of the signed distance (need not be unit length). Also called from several threads.
using SdfGradientFn = std::function<Point3d(const Point3d&)>;

struct SurfaceSampling {
    /// Spacing of the regular grid from which points on the exact surface are projected (world units).
    /// 0 picks the mean edge length of the mesh.
    double spacing = 0.0;
    /// Largest distance between neighbouring samples inside a mesh triangle (barycentric samples; the
    /// vertices and edge points are included). 0 means half of `spacing`.
    double triangleSpacing = 0.0;
    /// No triangle is split into more than this many segments per edge (caps sliver cost).
    int maxTriangleSubdivisions = 64;
    /// The surface grid covers the mesh's bounding box grown by this much; parts of the exact surface
    /// outside it are not sampled. Negative picks the larger of 2 * spacing and 10% of the box diagonal.
    double margin = -1.0;
    /// Newton steps p -= sdf(p) * grad(p) / |grad(p)|^2 when projecting a grid point onto the zero set.
    int newtonSteps = 6;
    /// Projected points are kept when |sdf| is below this; 0 picks 1e-6 * spacing.
    double projectionTolerance = 0.0;
    /// Step of the central differences used when no gradient function is given; 0 picks 1e-4 * spacing.
    double gradientStep = 0.0;
    /// Vertices closer than this are one point for the closedness test (analyzeTopology); 0 picks
    /// kMergeDistanceVoxels of `spacing` (or of the mean edge length).
    double mergeDistance = 0.0;
};

struct MeshQuality {
    double meanDistance = 0.0;            // mean of the two one-sided means below
    double maxDistance = 0.0;             // two-sided Hausdorff distance
    double meanDistanceToSurface = 0.0;   // mesh -> surface, over mesh samples
    double maxDistanceToSurface = 0.0;
    double meanDistanceFromSurface = 0.0; // surface -> mesh, over samples on the exact surface
    double maxDistanceFromSurface = 0.0;
    double meanNormalDeviationDeg = 0.0;  // per non-degenerate triangle, unweighted mean
    double maxNormalDeviationDeg = 0.0;
    double minTriangleAngleDeg = 0.0;     // over non-degenerate triangles; 0 when there are none
    std::size_t triangles = 0;
    std::size_t meshSamples = 0;          // samples taken on the mesh
    std::size_t surfaceSamples = 0;       // samples taken on the exact surface (or the reference mesh)
    bool watertight = false;              // analyzeTopology(mesh).watertight()
    bool manifold = false;                // no edge is shared by more than two triangles
};

/// Compares a mesh with the zero set of `sdf`. Mesh -> surface distances are |sdf| at the vertices and
/// at barycentric points inside every triangle; surface -> mesh distances are the exact distances from
/// points projected onto the zero set to the nearest triangle. Normal deviation is the angle between a
/// triangle's geometric normal and the gradient at its centroid. Without `gradient`, central
/// differences are used. When one side has no samples its distances are +infinity.
MeshQuality measureAgainstSdf(const Mesh& mesh, const SignedDistanceFn& sdf, const SurfaceSampling& sampling = {},
                              const SdfGradientFn& gradient = {});

/// Compares a mesh with a reference mesh: both are sampled (vertices and barycentric points, spacing
/// from `sampling`; 0 picks the mean edge length of the reference) and each side's samples are
/// measured against the other mesh. Normal deviation is the angle between each triangle's normal and
/// the normal of the reference triangle nearest its centroid.
MeshQuality measureAgainstMesh(const Mesh& mesh, const Mesh& reference, const SurfaceSampling& sampling = {});

/// The largest distance from samples of `from` (vertices and barycentric points at most `spacing` apart)
/// to `to`: one side of the Hausdorff distance. 0 when `from` is empty, infinite when only `to` is.
double maxDistanceToMesh(const Mesh& from, const Mesh& to, double spacing);

/// Closest point to p on the triangle abc (region-based: vertex, edge or face region).
Point3d closestPointOnTriangle(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c);

/// Nearest-triangle queries against a fixed mesh, accelerated with a uniform grid of triangle buckets.
/// Queries are const and may run concurrently. Keeps a reference to the mesh, which must outlive it.
class TriangleLocator {
public:
    explicit TriangleLocator(const Mesh& mesh);

    struct Hit {
        double distance = 0.0;   // +infinity when the mesh has no triangles
        uint32_t triangle = 0;   // index into mesh.triangles
        Point3d point{0, 0, 0};  // closest point on that triangle
    };
    Hit nearest(const Point3d& p) const;
    bool empty() const { return triangleCount_ == 0; }

private:
    const Mesh* mesh_;
    std::size_t triangleCount_ = 0;
    Point3d origin_{0, 0, 0};
    double cell_ = 1.0;
    std::array<int, 3> dims_{1, 1, 1};
    std::vector<uint32_t> cellStart_; // CSR: triangles of cell i are items_[cellStart_[i] .. cellStart_[i+1])
    std::vector<uint32_t> items_;
};

} // namespace vdbclay
