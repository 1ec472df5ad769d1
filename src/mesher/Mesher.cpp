#include "mesher/Mesher.h"

#include "mesher/CellGrid.h"
#include "mesher/AdaptiveCellCache.h"
#include "mesher/BlockSets.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>
#include <stdexcept>

namespace vdbclay {

const char* mesherName(MesherKind kind) { return kind == MesherKind::MarchingCubes ? "mc" : "cms"; }

MesherKind parseMesherKind(const std::string& s)
{
    if (s == "mc") return MesherKind::MarchingCubes;
    if (s == "cms") return MesherKind::CubicalMarchingSquares;
    throw std::invalid_argument("unknown mesher '" + s + "' (expected mc or cms)");
}

void validateMeshOptions(const MeshOptions& options)
{
    if (!(options.sharpAngleDegrees > 0.0 && options.sharpAngleDegrees < 180.0))
        throw std::invalid_argument("the sharp-feature angle must lie between 0 and 180 degrees");
    if (!(options.subdivisionAngleDegrees > 0.0 && options.subdivisionAngleDegrees < 180.0))
        throw std::invalid_argument("the subdivision angle must lie between 0 and 180 degrees");
    if (!(options.planeTolerance >= 0.0 && options.planeTolerance <= kLeafDim) ||
        !(options.coarseLevelPlaneTolerance >= 0.0 && options.coarseLevelPlaneTolerance <= kLeafDim))
        throw std::invalid_argument("a plane tolerance must lie between 0 and 8 voxels");
    if (!(options.coarseLevelSimplifyTolerance >= 0.0 && options.coarseLevelSimplifyTolerance <= kLeafDim))
        throw std::invalid_argument("a simplification tolerance must lie between 0 and 8 voxels");
    const int w = options.maxCellWidth;
    if (w != 1 && w != 2 && w != 4 && w != kLeafDim)
        throw std::invalid_argument("the widest cell must be 1, 2, 4 or 8 voxels");
}

bool meshesAdaptiveCells(const MeshOptions& options)
{
    return options.kind == MesherKind::CubicalMarchingSquares && (options.maxCellWidth > 1 || options.leafMaxCellWidth);
}

namespace {

void checkRange(const Coord& origin)
{
    using namespace mesher_detail;
    if (std::max({std::abs(origin.x()), std::abs(origin.y()), std::abs(origin.z())}) >= kMaxEdgeKeyCoordinate - kLeafDim)
        throw std::runtime_error("the volume reaches beyond the mesher's range of +-262,144 voxels from the origin");
}

} // namespace

namespace mesher_detail {

void meshLeavesInto(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                    const std::vector<MeshChunk*>& chunks, double voxelSize, const MeshOptions& options,
                    AdaptiveCellCache* cache, const LeafSurroundingsStore* surroundings)
{
    for (const HermiteLeaf* leaf : leaves) checkRange(leaf->origin());
    std::optional<AdaptiveCellCache> ownCache;
    AdaptiveCellCache* cells = nullptr;
    if (meshesAdaptiveCells(options)) {
        cells = cache ? cache : &ownCache.emplace();
        cells->prepare(tree, leaves, options);
    }
    // One mesher per thread: its buffers span a leaf's neighbourhood and are worth keeping.
    tbb::enumerable_thread_specific<std::unique_ptr<CubicalMarchingSquaresMesher>> meshers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 2), [&](const auto& range) {
        ConstAccessor acc(tree);
        if (options.kind == MesherKind::MarchingCubes) {
            for (std::size_t i = range.begin(); i != range.end(); ++i)
                *chunks[i] = meshLeafMarchingCubes(*leaves[i], acc, voxelSize);
            return;
        }
        std::unique_ptr<CubicalMarchingSquaresMesher>& local = meshers.local();
        if (!local) local = std::make_unique<CubicalMarchingSquaresMesher>(voxelSize, options.sharpAngleDegrees);
        CubicalMarchingSquaresMesher& cms = *local;
        const auto& b = options.lodBrickMin;
        cms.setLodBoundary(options.lodCut, options.lodLevel, Coord(b[0], b[1], b[2]), kLodBrickVoxels);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const HermiteLeaf& leaf = *leaves[i];
            const LeafSurroundings* read = surroundings ? surroundings->find(leaf.origin()) : nullptr;
            if (cells) {
                const CellWidthField widths = cells->around(leaf);
                cms.meshInto(leaf, acc, &widths, read, *chunks[i]);
            } else {
                cms.meshInto(leaf, acc, nullptr, read, *chunks[i]);
            }
        }
    });
}

} // namespace mesher_detail

std::vector<MeshChunk> meshVolumeChunks(const Volume& volume, const MeshOptions& options,
                                        mesher_detail::AdaptiveCellCache* cells)
{
    using namespace mesher_detail;
    validateMeshOptions(options);
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::vector<const HermiteLeaf*> leaves;
    leaves.reserve(tree.leafCount());
    for (auto it = tree.cbeginLeaf(); it; ++it) leaves.push_back(it.getLeaf());
    std::vector<MeshChunk> chunks(leaves.size());
    std::vector<MeshChunk*> into(chunks.size());
    for (std::size_t i = 0; i < chunks.size(); ++i) into[i] = &chunks[i];
    meshLeavesInto(tree, leaves, into, volume.voxelSize(), options, cells);
    return chunks;
}

std::vector<MeshChunk> meshRegionChunks(const Volume& volume, const std::array<int32_t, 3>& min, int32_t edge,
                                        const MeshOptions& options, const std::vector<std::array<int32_t, 3>>* onlyLeaves)
{
    using namespace mesher_detail;
    validateMeshOptions(options);
    const HermiteTree& tree = volume.impl().grid->constTree();
    if (edge <= 0 || edge % kLeafDim != 0) throw std::invalid_argument("a meshed region must be whole leaves wide");
    // Probes the box's leaf origins, so a brick of a large level costs its own leaves.
    std::vector<const HermiteLeaf*> leaves;
    ConstAccessor acc(tree);
    // A brick of a level-of-detail cut meshes the cells whose minimum corner it holds, whoever owns them:
    // a cell at its far faces whose other corners lie in the next brick's leaves (its own corners in
    // tile blocks) belongs to one of those leaves, which are visited too, for those cells only.
    // An empty region beside the cut holds no leaf, so the cells there that this brick meshes
    // (LodCut::cellOwner) belong to its own leaves.
    const int32_t reach = options.lodCut ? edge + kLeafDim : edge;
    for (int32_t x = min[0]; x < min[0] + reach; x += kLeafDim)
        for (int32_t y = min[1]; y < min[1] + reach; y += kLeafDim)
            for (int32_t z = min[2]; z < min[2] + reach; z += kLeafDim)
                if (const HermiteLeaf* leaf = acc.probeConstLeaf(Coord(x, y, z)))
                    if (!onlyLeaves || std::binary_search(onlyLeaves->begin(), onlyLeaves->end(), std::array<int32_t, 3>{x, y, z}))
                        leaves.push_back(leaf);
    std::vector<MeshChunk> chunks(leaves.size());
    std::vector<MeshChunk*> into(chunks.size());
    for (std::size_t i = 0; i < chunks.size(); ++i) into[i] = &chunks[i];
    meshLeavesInto(tree, leaves, into, volume.voxelSize(), options, nullptr);
    return chunks;
}

std::vector<std::array<int32_t, 3>> leavesAffectedBy(const std::vector<std::array<int32_t, 3>>& dirtyBlocks,
                                                     const MeshOptions& options)
{
    return leavesAffectedBy(wholeBlockChanges(dirtyBlocks), options);
}

std::vector<std::array<int32_t, 3>> leavesAffectedBy(const std::vector<BlockChange>& changes, const MeshOptions& options)
{
    using namespace mesher_detail;
    if (!meshesAdaptiveCells(options)) return leavesReaching(changes, kMeshingReach);
    // Without subdividing first, any leaf whose subdivision reads a change may split its faces anew.
    std::vector<BlockOrigin> faces;
    for (int f = 0; f < 6; ++f) {
        const Coord c = faceNeighbour(Coord(0), f);
        faces.push_back({c.x(), c.y(), c.z()});
    }
    return leavesReaching(changes, kMeshingReach, blocksAround(leavesReaching(changes, kSubdivisionReach), faces));
}

Mesh meshVolume(const Volume& volume, const MeshOptions& options)
{
    return weldChunks(meshVolumeChunks(volume, options));
}

} // namespace vdbclay
