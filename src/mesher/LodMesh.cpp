#include "mesher/LodMesh.h"

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

} // namespace vdbclay
