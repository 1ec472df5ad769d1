#include "voxelize/VoxelizeToStore.h"

#include <tbb/combinable.h>

#include <functional>
#include <stdexcept>
#include <vector>

namespace vdbclay {

StoreVoxelizeReport voxelizeMeshToStore(const TriangleSoup& mesh, const VoxelizeOptions& options, const std::string& path,
                                        const Progress& progress)
{
    const MeshVoxelizer voxelizer(mesh, options);
    const std::vector<LeafAlignedBox> blocks = voxelizer.blocks(kBrickEdge);
    std::vector<IndexCoord> bricks;
    bricks.reserve(blocks.size());
    for (const LeafAlignedBox& box : blocks) bricks.push_back({box.min[0] / kBrickEdge, box.min[1] / kBrickEdge, box.min[2] / kBrickEdge});

    StoreVoxelizeReport report;
    report.mesh = voxelizer.castReport();
    report.materials = voxelizer.materials();
    tbb::combinable<VoxelizeReport> counts;
    tbb::combinable<uint64_t> activeVoxels;
    createStoreFile(path, voxelizer.voxelSize(), voxelizer.materials(), [&](SceneStore& scene) {
        const StoredBricks stored = putNewBricks(
            scene, 0, bricks,
            [&](std::size_t i) {
                const Volume brick = voxelizer.voxelizeBlock(blocks[i], counts.local());
                activeVoxels.local() += brick.stats().activeVoxels;
                return encodeBrick(brick, bricks[i]);
            },
            progress);
        // A store of nothing replaces no file: the caller hears why instead.
        if (stored.bricks == 0) throw MeshImportError(noSolidMessage(voxelizer.voxelSize()));
        report.bricks = stored.bricks;
        report.leaves = stored.leaves;
    });
    counts.combine_each([&](const VoxelizeReport& block) { addBlockCounts(report.mesh, block); });
    report.activeVoxels = activeVoxels.combine(std::plus<uint64_t>());
    return report;
}

} // namespace vdbclay
