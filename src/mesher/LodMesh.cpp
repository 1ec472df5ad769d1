#include "mesher/LodMesh.h"

#include <stdexcept>
#include <string>

namespace vdbclay {

void translateMesh(Mesh& mesh, const std::array<double, 3>& offset)
{
    for (auto& p : mesh.positions)
        for (int i = 0; i < 3; ++i) p[std::size_t(i)] = float(double(p[std::size_t(i)]) + offset[std::size_t(i)]);
}

Mesh meshLevel(const Volume& fine, const wavelet::LodPyramid& pyramid, int level, const MeshOptions& options)
{
    if (level < 0 || level > pyramid.levels())
        throw std::invalid_argument("level " + std::to_string(level) + " is outside 0 .. " +
                                    std::to_string(pyramid.levels()) + " (the pyramid's levels)");
    if (level == 0) return meshVolume(fine, options);
    return meshLevelVolume(pyramid.coarseVolume(fine, level), level, options);
}

Mesh meshLevelVolume(const Volume& levelVolume, int level, const MeshOptions& options)
{
    Mesh mesh = meshVolume(levelVolume, options);
    if (level == 0) return mesh;
    const double fineVoxel = levelVolume.voxelSize() / double(1 << level);
    const double shift = wavelet::LodPyramid::levelOffset(level) * fineVoxel;
    translateMesh(mesh, {shift, shift, shift});
    return mesh;
}

} // namespace vdbclay
