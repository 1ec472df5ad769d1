#include "voxelize/VoxelizeToStore.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <optional>
#include <vector>

namespace vdbclay {

StoreVoxelizeReport voxelizeMeshToStore(const TriangleSoup& mesh, const VoxelizeOptions& options, const std::string& path,
                                        const Progress& progress)
{
    const MeshVoxelizer voxelizer(mesh, options);
    const std::vector<LeafAlignedBox> blocks = voxelizer.blocks(kBrickEdge);
    auto brickOf = [](const LeafAlignedBox& box) {
        return IndexCoord{box.min[0] / kBrickEdge, box.min[1] / kBrickEdge, box.min[2] / kBrickEdge};
    };
    StoreVoxelizeReport report;
    report.mesh = voxelizer.castReport();
    report.materials = voxelizer.materials();
    createStoreFile(path, voxelizer.voxelSize(), voxelizer.materials(), [&](SceneStore& scene) {
        // A batch keeps both cores busy while its bricks' volumes stay a few MB.
        constexpr std::size_t kBatch = 32;
        for (std::size_t first = 0; first < blocks.size(); first += kBatch) {
            const std::size_t count = std::min(kBatch, blocks.size() - first);
            std::vector<std::optional<BrickRecord>> records(count);
            std::vector<VoxelizeReport> counts(count);
            std::vector<VolumeStats> stats(count);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1), [&](const auto& range) {
                for (std::size_t i = range.begin(); i != range.end(); ++i) {
                    const LeafAlignedBox& box = blocks[first + i];
                    const Volume brick = voxelizer.voxelizeBlock(box, counts[i]);
                    stats[i] = brick.stats();
                    records[i] = encodeBrick(brick, brickOf(box));
                }
            });
            for (std::size_t i = 0; i < count; ++i) {
                report.mesh.votedPoints += counts[i].votedPoints;
                report.mesh.patchedCrossings += counts[i].patchedCrossings;
                report.mesh.crossings += counts[i].crossings;
                report.mesh.solidVoxels += counts[i].solidVoxels;
                report.mesh.materialInterfaces += counts[i].materialInterfaces;
                report.leaves += stats[i].leafCount;
                report.activeVoxels += stats[i].activeVoxels;
                if (!records[i]) continue;
                scene.bricks().put({0, brickOf(blocks[first + i])}, *records[i]);
                ++report.bricks;
            }
            // Commit as it goes: the WAL stays small, and the file is a temporary until complete.
            if ((first / kBatch) % 16 == 15) {
                scene.bricks().commit();
                scene.bricks().begin();
            }
            if (progress) progress(first + count, blocks.size());
        }
    });
    return report;
}

} // namespace vdbclay
