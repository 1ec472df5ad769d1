// Simplifying a welded mesh by edge collapses within an error bound, its open boundary kept exactly.
#pragma once

#include "mesher/Mesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vdbclay {

struct SimplifyReport {
    std::size_t trianglesBefore = 0, trianglesAfter = 0;
    double largestError = 0.0; // of the collapses made: the farthest a kept vertex lies from a plane it absorbed
};

/// Collapses vertices of a welded mesh onto neighbours (half-edge collapses: the vertices kept keep their
/// positions, normals and materials), cheapest first by the quadric error of the planes the removed
/// vertex carries (Garland and Heckbert 1997, each original triangle's plane at its corners, unweighted),
/// while that error's square root stays within `maxError` (world units): then every original plane a kept
/// vertex absorbed lies within `maxError` of it. Never collapsed: a vertex on an open or non-manifold
/// edge (meshes that meet along their open edges, as a cut's bricks do, still meet), a vertex where
/// materials meet; never made: a collapse that breaks the link condition (the mesh stays a manifold of
/// the same topology), a triangle turned by more than 60 degrees or of no area, a vertex of more than 12
/// neighbours. `maxError` <= 0 leaves
/// the mesh as it is. `kept` (optional): for each vertex of the result, its index before.
SimplifyReport simplifyMesh(Mesh& mesh, double maxError, std::vector<uint32_t>* kept = nullptr);

} // namespace vdbclay
