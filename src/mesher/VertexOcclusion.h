// Ambient occlusion per vertex, read from the volume the mesh came from: how much of the space just
// outside each vertex is solid. Computed once when a chunk is meshed, so shading costs nothing per frame
// and every view of the chunk agrees.
#pragma once

#include "mesher/Mesh.h"
#include "vdb_hermite/Volume.h"

#include <cstdint>
#include <vector>

namespace vdbclay {

/// Per vertex, 0 (enclosed) .. 255 (open): the share of sample points on the hemisphere around the
/// vertex's normal, 1.5 and 3.5 voxels out, that lie in empty voxels. `mesh` is in the volume's world
/// units (before any translation applied to show it).
/// `firstVertex`: only the vertices from it on (the values of those).
std::vector<uint8_t> vertexOcclusion(const Volume& volume, const Mesh& mesh, std::size_t firstVertex = 0);

} // namespace vdbclay
