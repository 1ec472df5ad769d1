#include "scene/LevelSetToStore.h"

#include "vdb_hermite/PrintableText.h"

#include <tbb/combinable.h>

#include <functional>
#include <stdexcept>

namespace vdbclay {

StoreLevelSetReport importLevelSetToStore(const std::string& input, const LevelSetImportOptions& options, const std::string& output,
                                          const Progress& progress)
{
    const LevelSetImporter importer(input, options);
    const std::vector<IndexCoord> bricks = importer.occupiedBoxes(kBrickEdge);
    tbb::combinable<uint64_t> crossings, activeVoxels;
    StoreLevelSetReport report;
    createStoreFile(output, importer.voxelSize(), importer.materials(), [&](SceneStore& scene) {
        const StoredBricks stored = putNewBricks(
            scene, 0, bricks,
            [&](std::size_t i) {
                const Volume brick = importer.region(brickBox(bricks[i]), &crossings.local());
                activeVoxels.local() += brick.stats().activeVoxels;
                return encodeBrick(brick, bricks[i]);
            },
            progress);
        // A store of nothing replaces no file: the caller hears why instead.
        if (stored.bricks == 0)
            throw std::runtime_error("grid '" + printableText(importer.report().grid, 64) + "' of '" + input +
                                     "' holds no solid voxel at this reading: nothing to import");
        report.bricks = stored.bricks;
        report.leaves = stored.leaves;
    });
    report.levelSet = importer.report();
    report.levelSet.crossings = crossings.combine(std::plus<uint64_t>());
    report.activeVoxels = activeVoxels.combine(std::plus<uint64_t>());
    return report;
}

} // namespace vdbclay
