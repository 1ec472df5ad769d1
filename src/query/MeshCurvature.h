// Curvature on a triangle mesh for the ClusterD2+Color descriptor (seed 004 §4.1.3): the mesh welded into
// vertices and their neighbours, the integral of absolute Gaussian curvature (angle defects) and
// Taubin's per-vertex mean curvature.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay::query {

/// A soup's vertices joined where their positions are equal to a billionth of the mesh's extent (files
/// repeat a corner per face, or with rounding noise along a seam).
struct WeldedMesh {
    std::vector<std::array<double, 3>> positions;
    std::vector<std::array<uint32_t, 3>> triangles; // into positions, one per soup triangle (same order)
    std::vector<uint32_t> neighbourStart;           // CSR: vertex v's neighbours are neighbours[start[v] .. start[v + 1])
    std::vector<uint32_t> neighbours;
    std::vector<bool> boundary; // on an edge that only one triangle uses
};

WeldedMesh weldMesh(const TriangleSoup& soup);

/// The weld alone: each soup vertex's index among the joined positions.
struct VertexWeld {
    std::vector<std::array<double, 3>> positions;
    std::vector<uint32_t> index; // per soup vertex
};
VertexWeld weldVertices(const TriangleSoup& soup);

/// The integral of |K| over the surface: the sum of the vertices' angle defects (2 pi less their
/// triangles' angles; pi on a boundary). 4 pi for any convex closed surface.
double absoluteGaussianCurvature(const WeldedMesh& mesh);

/// Taubin's estimate of the mean curvature per vertex (1995): the normal curvatures along the vertex's
/// edges, 2 N.(v - w) / |v - w|^2, averaged with weights of the triangles' areas beside each edge.
/// Positive where the surface is convex (1 / R on a sphere of radius R with outward triangles).
std::vector<double> meanCurvature(const WeldedMesh& mesh);

} // namespace vdbclay::query
