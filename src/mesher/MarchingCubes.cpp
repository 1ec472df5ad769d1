// Marching Cubes over Hermite data, built from marching squares on the six faces of each cell: the
// face segments are linked into loops and each loop is fanned into triangles. Crossings sit at the
// stored offsets and carry the stored normals. Because a face's segments depend only on that face,
// the two cells sharing it agree on them and the welded mesh is watertight without any table of cases.
#include "mesher/CellGrid.h"

#include <unordered_map>

namespace vdbclay::mesher_detail {

namespace {

/// Polygon loops of one cell as lists of cell edges, from the occupancy of its corners.
int cellLoops(unsigned solidMask, int loops[4][12], int loopSizes[4])
{
    int next[12] = {};
    bool crossed[12] = {};
    for (const CellFace& f : kFaces) {
        int edges[4] = {}, count = 0;
        bool entering[4] = {};
        for (int i = 0; i < 4; ++i) {
            const int p = f.corners[i], q = f.corners[(i + 1) % 4];
            const bool sp = (solidMask >> p) & 1u, sq = (solidMask >> q) & 1u;
            if (sp == sq) continue;
            edges[count] = cellEdge(p, q);
            entering[count] = sq; // walking counter-clockwise, this crossing enters the solid
            ++count;
        }
        // Each entering crossing runs to the leaving crossing that follows it counter-clockwise: a segment
        // cuts off one run of solid corners, so on an ambiguous face the two solid corners stay apart.
        for (int i = 0; i < count; ++i) {
            if (!entering[i]) continue;
            next[edges[i]] = edges[(i + 1) % count];
            crossed[edges[i]] = true;
        }
    }
    int loopCount = 0;
    bool used[12] = {};
    for (int start = 0; start < 12; ++start) {
        if (!crossed[start] || used[start]) continue;
        int size = 0;
        for (int e = start; !used[e] && size < 12; e = next[e]) {
            used[e] = true;
            loops[loopCount][size++] = e;
        }
        loopSizes[loopCount++] = size;
        if (loopCount == 4) break;
    }
    return loopCount;
}

} // namespace

MeshChunk meshLeafMarchingCubes(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize)
{
    const Neighbourhood hood(leaf, acc);
    MeshChunk chunk;
    chunk.leafOrigin = {leaf.origin().x(), leaf.origin().y(), leaf.origin().z()};
    std::unordered_map<uint64_t, uint32_t> local;
    const CornerGrid grid(leaf, hood);
    forEachOwnedSurfaceCell(grid, hood, OwnedCells::All, [&](const Coord& base, const MaterialValue mats[8], unsigned solid) {
        int loops[4][12], sizes[4];
        const int nLoops = cellLoops(solid, loops, sizes);
        for (int l = 0; l < nLoops; ++l) {
            uint32_t ids[12];
            for (int v = 0; v < sizes[l]; ++v) {
                const EdgeCrossing x = edgeCrossing(hood, base, mats, loops[l][v], voxelSize);
                auto [it, inserted] = local.emplace(x.key, uint32_t(chunk.mesh.positions.size()));
                if (inserted) {
                    chunk.mesh.positions.push_back(x.position);
                    chunk.mesh.normals.push_back(x.normal);
                    chunk.mesh.materials.push_back(x.material);
                    chunk.vertexKeys.push_back(x.key);
                }
                ids[v] = it->second;
            }
            for (int v = 1; v + 1 < sizes[l]; ++v) {
                chunk.mesh.triangles.push_back({ids[0], ids[v], ids[v + 1]});
                chunk.mesh.triangleMaterials.push_back(chunk.mesh.materials[ids[0]]);
            }
        }
    });
    return chunk;
}

} // namespace vdbclay::mesher_detail
