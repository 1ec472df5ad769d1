#include "mesher/LodMesh.h"

#include "mesher/MeshSimplify.h"

#include <stdexcept>
#include <string>

namespace vdbclay {

Mesh meshLevel(const Volume& fine, const wavelet::LodPyramid& pyramid, int level, const MeshOptions& options)
{
    if (level < 0 || level > pyramid.levels())
        throw std::invalid_argument("level " + std::to_string(level) + " is outside 0 .. " +
                                    std::to_string(pyramid.levels()) + " (the pyramid's levels)");
    if (level == 0) return meshVolume(fine, options);
    return meshVolume(pyramid.coarseVolume(fine, level), options);
}

bool simplifyLodBrickMesh(Mesh& mesh, int level, double levelVoxel, const MeshOptions& options, std::vector<uint32_t>* kept)
{
    const double tolerance = options.coarseLevelSimplifyTolerance;
    if (level == 0 || !(tolerance > 0.0)) return false;
    simplifyMesh(mesh, tolerance * levelVoxel, kept);
    return true;
}

} // namespace vdbclay
