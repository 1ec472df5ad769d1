#include "mesher/Mesher.h"

#include "mesher/CellGrid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace vdbclay {

const char* mesherName(MesherKind kind) { return kind == MesherKind::MarchingCubes ? "mc" : "cms"; }

MesherKind parseMesherKind(const std::string& s)
{
    if (s == "mc") return MesherKind::MarchingCubes;
    if (s == "cms") return MesherKind::CubicalMarchingSquares;
    throw std::invalid_argument("unknown mesher '" + s + "' (expected mc or cms)");
}

namespace {

void checkOptions(const MeshOptions& options)
{
    if (!(options.sharpAngleDegrees > 0.0 && options.sharpAngleDegrees < 180.0))
        throw std::invalid_argument("the sharp-feature angle must lie between 0 and 180 degrees");
}

void checkRange(const Coord& origin)
{
    using namespace mesher_detail;
    if (std::max({std::abs(origin.x()), std::abs(origin.y()), std::abs(origin.z())}) >= kMaxEdgeKeyCoordinate - kLeafDim)
        throw std::runtime_error("the volume reaches beyond the mesher's range of +-262,144 voxels from the origin");
}

/// Meshes the given leaves in parallel, one chunk each.
std::vector<MeshChunk> meshLeaves(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                                  double voxelSize, const MeshOptions& options)
{
    using namespace mesher_detail;
    std::vector<MeshChunk> chunks(leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 8), [&](const auto& range) {
        ConstAccessor acc(tree);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            chunks[i] = options.kind == MesherKind::MarchingCubes
                            ? meshLeafMarchingCubes(*leaves[i], acc, voxelSize)
                            : meshLeafCubicalMarchingSquares(*leaves[i], acc, voxelSize, options.sharpAngleDegrees);
        }
    });
    return chunks;
}

} // namespace

std::vector<MeshChunk> meshVolumeChunks(const Volume& volume, const MeshOptions& options)
{
    checkOptions(options);
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::vector<const HermiteLeaf*> leaves;
    leaves.reserve(tree.leafCount());
    for (auto it = tree.cbeginLeaf(); it; ++it) {
        checkRange(it->origin());
        leaves.push_back(it.getLeaf());
    }
    return meshLeaves(tree, leaves, volume.voxelSize(), options);
}

std::vector<std::optional<MeshChunk>> meshLeafChunks(const Volume& volume,
                                                     const std::vector<std::array<int32_t, 3>>& leafOrigins,
                                                     const MeshOptions& options)
{
    checkOptions(options);
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::vector<const HermiteLeaf*> leaves;
    std::vector<std::size_t> slot;
    for (std::size_t i = 0; i < leafOrigins.size(); ++i) {
        const Coord origin(leafOrigins[i][0], leafOrigins[i][1], leafOrigins[i][2]);
        const HermiteLeaf* leaf = tree.probeConstLeaf(origin);
        if (!leaf || leaf->origin() != origin) continue;
        checkRange(origin);
        leaves.push_back(leaf);
        slot.push_back(i);
    }
    std::vector<MeshChunk> chunks = meshLeaves(tree, leaves, volume.voxelSize(), options);
    std::vector<std::optional<MeshChunk>> out(leafOrigins.size());
    for (std::size_t k = 0; k < chunks.size(); ++k) out[slot[k]] = std::move(chunks[k]);
    return out;
}

Mesh meshVolume(const Volume& volume, const MeshOptions& options)
{
    return weldChunks(meshVolumeChunks(volume, options));
}

} // namespace vdbclay
