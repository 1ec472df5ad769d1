// Marching Cubes over Hermite data, built from marching squares on the six faces of each cell: the
// face segments are linked into loops and each loop is fanned into triangles. Crossings sit at the
// stored offsets and carry the stored normals. Because a face's segments depend only on that face,
// the two cells sharing it agree on them and the welded mesh is watertight; the loops of each corner
// case come from that face walk, done once at compile time (CellTopology.h).
#include "mesher/CellGrid.h"

#include <unordered_map>

namespace vdbclay::mesher_detail {

MeshChunk meshLeafMarchingCubes(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize)
{
    const Neighbourhood hood(leaf, acc);
    MeshChunk chunk;
    chunk.leafOrigin = {leaf.origin().x(), leaf.origin().y(), leaf.origin().z()};
    std::unordered_map<uint64_t, uint32_t> local;
    const CornerGrid grid(leaf, hood);
    forEachOwnedSurfaceCell(grid, hood, OwnedCells::All, [&](const Coord& base, const MaterialValue mats[8], unsigned solid) {
        const CellCase& cell = kCellCases[solid];
        for (int l = 0, begin = 0; l < cell.loopCount; begin = cell.loopEnd[l++]) {
            const int size = cell.loopEnd[l] - begin;
            uint32_t ids[12];
            for (int v = 0; v < size; ++v) {
                const EdgeCrossing x = edgeCrossing(hood, base, mats, cell.edges[begin + v], voxelSize);
                auto [it, inserted] = local.emplace(x.key, uint32_t(chunk.mesh.positions.size()));
                if (inserted) {
                    chunk.mesh.positions.push_back(x.position);
                    chunk.mesh.normals.push_back(x.normal);
                    chunk.mesh.materials.push_back(x.material);
                    chunk.vertexKeys.push_back(x.key);
                }
                ids[v] = it->second;
            }
            for (int v = 1; v + 1 < size; ++v) {
                chunk.mesh.triangles.push_back({ids[0], ids[v], ids[v + 1]});
                chunk.mesh.triangleMaterials.push_back(chunk.mesh.materials[ids[0]]);
            }
        }
    });
    return chunk;
}

} // namespace vdbclay::mesher_detail
