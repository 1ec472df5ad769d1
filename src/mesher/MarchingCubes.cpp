// Marching Cubes over Hermite data, built from marching squares on the six faces of each cell: the
// face segments are linked into loops and each loop is fanned into triangles. Crossings sit at the
// stored offsets and carry the stored normals. Because a face's segments depend only on that face,
// the two cells sharing it agree on them and the welded mesh is watertight; the loops of each corner
// case come from that face walk, done once at compile time (CellTopology.h).
#include "mesher/CellGrid.h"

#include <array>
#include <cmath>
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
            const int apex = cell.fanApex[l];
            if (apex >= 0) {
                for (int v = 1; v + 1 < size; ++v) {
                    const uint32_t a = ids[apex], b = ids[(apex + v) % size], c = ids[(apex + v + 1) % size];
                    chunk.mesh.triangles.push_back({a, b, c});
                    chunk.mesh.triangleMaterials.push_back(chunk.mesh.materials[a]);
                }
                continue;
            }
            // No such position: fan from the loop's mean point, a vertex of this cell alone.
            std::array<float, 3> centre{0.0f, 0.0f, 0.0f}, normal{0.0f, 0.0f, 0.0f};
            for (int v = 0; v < size; ++v)
                for (int a = 0; a < 3; ++a) {
                    centre[a] += chunk.mesh.positions[ids[v]][a] / float(size);
                    normal[a] += chunk.mesh.normals[ids[v]][a];
                }
            const float length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
            for (float& n : normal) n = length > 0.0f ? n / length : 0.0f;
            const uint32_t c = uint32_t(chunk.mesh.positions.size());
            chunk.mesh.positions.push_back(centre);
            chunk.mesh.normals.push_back(normal);
            chunk.mesh.materials.push_back(chunk.mesh.materials[ids[0]]);
            chunk.vertexKeys.push_back(kUnsharedVertex);
            for (int v = 0; v < size; ++v) {
                chunk.mesh.triangles.push_back({c, ids[v], ids[(v + 1) % size]});
                chunk.mesh.triangleMaterials.push_back(chunk.mesh.materials[ids[v]]);
            }
        }
    });
    return chunk;
}

} // namespace vdbclay::mesher_detail
