// A scene as a model to describe: a volume (a .vdb, a store's level) meshed, its triangles taking their
// materials' colours, so the descriptors read a sculpture as they read an imported mesh.
#pragma once

#include "mesher/Mesh.h"
#include "voxelize/TriangleMesh.h"

namespace vdbclay::query {

/// The mesh as a triangle soup: each triangle's material named and coloured as `materials` says (a
/// material the table lacks: grey).
TriangleSoup soupOfMesh(const Mesh& mesh, const MaterialTable& materials);

/// A sculpture's mesh as the descriptors should read it: welded and smoothed by Taubin's lambda|mu
/// filter (lambda 0.5, mu -0.53, `passes` pairs of steps), which takes out the voxel lattice's facets
/// (a few voxels wide, read as features by ClusterD2+Color's curvature maps) and keeps the shape and its
/// size. Materials stay per triangle.
TriangleSoup smoothedSculpture(const TriangleSoup& soup, int passes = 10);

/// A model as the renderer draws it (thumbnails, silhouettes): each triangle with its own three corners
/// and its face's normal, its material defined in `materials` with the soup material's colour.
Mesh meshOfSoup(const TriangleSoup& soup, MaterialTable& materials);

} // namespace vdbclay::query
