#include "scene/StoreLod.h"

#include "wavelet/LodPyramid.h"

#include <stdexcept>
#include <string>

namespace vdbclay {

int buildStoreLod(SceneStore& scene, int levels, const Progress& progress)
{
    const Volume fine = scene.loadLevel(0);
    if (levels == 0) levels = wavelet::LodPyramid::levelsFor(fine);
    if (scene.voxelSize() * double(1 << levels) > kMaxVoxelSize)
        throw std::invalid_argument("a voxel size of " + std::to_string(scene.voxelSize()) + " leaves room for fewer than " +
                                    std::to_string(levels) + " levels");
    wavelet::LodPyramid pyramid(levels);
    pyramid.build(fine);
    StoreTransaction transaction(scene.bricks());
    for (int k = 1; k <= levels; ++k) {
        scene.writeLevel(k, pyramid.coarseVolume(fine, k));
        if (progress) progress(uint64_t(k), uint64_t(levels));
    }
    for (int k = levels + 1; k <= scene.lodLevels(); ++k)
        for (const IndexCoord& b : scene.brickCoords(k)) scene.bricks().erase({k, b});
    scene.setLod(levels, false);
    transaction.commit();
    return levels;
}

} // namespace vdbclay
