// Mesh properties the tests and the CLI report: closedness, manifoldness, components and enclosed volume.
//
// Closedness is geometric, not a comparison of vertex indices: vertices closer than a merge distance are
// one point first, so two walls that coincide in space, or two vertices that pinch the surface at one
// position, count as the defects they are.
#pragma once

#include "mesher/Mesh.h"

#include <cstddef>

namespace vdbclay {

/// Vertices closer than this many voxels are one point for analyzeTopology.
constexpr double kMergeDistanceVoxels = 1e-5;

struct MeshTopology {
    std::size_t mergedVertices = 0;      // distinct positions after merging
    std::size_t boundaryEdges = 0;       // edges used by one triangle only
    std::size_t nonManifoldEdges = 0;    // edges used by more than two triangles
    std::size_t misorientedEdges = 0;    // edges whose two triangles traverse them the same way
    std::size_t degenerateTriangles = 0; // triangles with two corners at one point, or of zero area
    std::size_t pinchedVertices = 0;     // vertices whose triangles form more than one fan
    std::size_t components = 0;          // edge-connected pieces of surface
    /// A closed, oriented 2-manifold: every edge in two triangles that traverse it in opposite
    /// directions, every vertex's triangles one fan, no zero-area triangle.
    bool watertight() const
    {
        return boundaryEdges == 0 && nonManifoldEdges == 0 && misorientedEdges == 0 && degenerateTriangles == 0 &&
               pinchedVertices == 0;
    }
};

/// Merges vertices closer than `mergeDistance` (world units; pass kMergeDistanceVoxels * voxel size) and
/// reports the topology of the result. A triangle of zero area is one whose doubled area is below
/// mergeDistance squared.
MeshTopology analyzeTopology(const Mesh& mesh, double mergeDistance);

/// Total area of the triangles, world units squared.
double surfaceArea(const Mesh& mesh);

/// Signed volume enclosed by a closed, outward-oriented mesh (divergence theorem), world units cubed.
double enclosedVolume(const Mesh& mesh);

} // namespace vdbclay
