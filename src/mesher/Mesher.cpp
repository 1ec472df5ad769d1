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

std::vector<MeshChunk> meshVolumeChunks(const Volume& volume, const MeshOptions& options)
{
    using namespace mesher_detail;
    if (!(options.sharpAngleDegrees > 0.0 && options.sharpAngleDegrees < 180.0))
        throw std::invalid_argument("the sharp-feature angle must lie between 0 and 180 degrees");
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::vector<const HermiteLeaf*> leaves;
    leaves.reserve(tree.leafCount());
    for (auto it = tree.cbeginLeaf(); it; ++it) {
        const Coord& o = it->origin();
        if (std::max({std::abs(o.x()), std::abs(o.y()), std::abs(o.z())}) >= kMaxEdgeKeyCoordinate - kLeafDim)
            throw std::runtime_error("the volume reaches beyond the mesher's range of +-524,288 voxels from the origin");
        leaves.push_back(it.getLeaf());
    }
    std::vector<MeshChunk> chunks(leaves.size());
    const double voxelSize = volume.voxelSize();
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

Mesh meshVolume(const Volume& volume, const MeshOptions& options)
{
    return weldChunks(meshVolumeChunks(volume, options));
}

} // namespace vdbclay
