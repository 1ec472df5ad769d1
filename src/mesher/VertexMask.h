// Which vertices of a mesh lie on masked surface (VoxelMask.h): what the renderer darkens.
#pragma once

#include "mesher/Mesh.h"
#include "vdb_hermite/VoxelMask.h"

#include <cstdint>
#include <vector>

namespace vdbclay {

/// Per vertex of `mesh` (world units, on a lattice of `voxelSize`), 1 where the mask keeps the voxel
/// nearest to it, else 0; empty when nothing is masked.
std::vector<uint8_t> maskedVertices(const VoxelMask& mask, const Mesh& mesh, double voxelSize);

} // namespace vdbclay
