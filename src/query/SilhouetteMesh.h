// The triangles a model's silhouettes need, fewer than its file has: silhouettes are small pictures
// (kSilhouetteSize pixels across the model's bounding sphere), and a software rasterizer's time goes
// with the triangles it draws. Vertices are clustered on a grid of cells about a pixel wide (Rossignac
// and Borrel 1993), so the outline moves by at most a cell's diagonal; triangles whose corners meet in
// one cell are dropped. Clustering can pinch a thin curved part (a ring of vertices that leaves a cell
// and comes back into it folds its band of triangles): measured, a one-pixel crack along a table's leg
// in one view with cells of two pixels, none over the synthetic families' views with cells of one.
// A closed surface (every edge crossed as often one way as the other once clustered) is covered by its
// front faces alone in any view, so only those need drawing.
#pragma once

#include "mesher/Mesh.h"
#include "voxelize/TriangleMesh.h"

namespace vdbclay::query {

struct SilhouetteMesh {
    Mesh mesh;           // positions and triangles (normals and materials filled, unused)
    bool closed = false; // the triangles' edges cancel: front faces alone cover every silhouette
};

/// `soup`'s triangles with their corners welded, then clustered on a grid of `cell` (world units, > 0;
/// at least the model's extent / 2^21); where every triangle falls inside a cell, the welded triangles
/// unclustered. Throws std::invalid_argument for a cell that is not positive.
SilhouetteMesh silhouetteMesh(const TriangleSoup& soup, double cell);

} // namespace vdbclay::query
