#include "mesher/VertexMask.h"

#include <cmath>

namespace vdbclay {

std::vector<uint8_t> maskedVertices(const VoxelMask& mask, const Mesh& mesh, double voxelSize)
{
    if (!mask.any()) return {};
    std::vector<uint8_t> out(mesh.vertexCount(), 0);
    for (std::size_t i = 0; i < out.size(); ++i) {
        IndexCoord voxel;
        for (std::size_t a = 0; a < 3; ++a) voxel[a] = int32_t(std::lround(mesh.positions[i][a] / voxelSize));
        out[i] = mask.masked(voxel) ? 1 : 0;
    }
    return out;
}

} // namespace vdbclay
