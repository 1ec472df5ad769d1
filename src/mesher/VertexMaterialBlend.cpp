#include "mesher/VertexMaterialBlend.h"

#include "mesher/CellGrid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace vdbclay {

uint32_t MaterialBlend::pack(MaterialId other, double share)
{
    return uint32_t(other) | uint32_t(std::lround(std::clamp(share, 0.0, 1.0) * 255.0)) << 16;
}

std::vector<uint32_t> vertexMaterialBlend(const Volume& volume, const Mesh& mesh, std::size_t firstVertex)
{
    using namespace mesher_detail;
    firstVertex = std::min(firstVertex, mesh.positions.size());
    std::vector<uint32_t> out(mesh.positions.size() - firstVertex, 0);
    const HermiteTree& tree = volume.impl().grid->constTree();
    const double inv = 1.0 / volume.voxelSize();
    constexpr int kSide = 5;          // lattice points per axis around the vertex
    constexpr double kAlong = 2.5;    // voxels: the kernel's reach along the surface
    constexpr double kAcross = 1.0;   // voxels: its reach across it (material beneath the surface stays hidden)
    constexpr double kTrace = 0.15;   // shares below it count as none (above 1 - kTrace as all)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(firstVertex, mesh.positions.size(), 512), [&](const auto& range) {
        ConstAccessor acc(tree);
        // Per 8^3 block: its one solid material (0: none), or kMixed. Most vertices lie among blocks of
        // their own material alone and are settled by these, without reading voxels.
        constexpr MaterialId kMixed = 0xffff;
        std::unordered_map<Coord, MaterialId> blocks;
        const auto blockMaterial = [&](const Coord& origin) {
            const auto [it, fresh] = blocks.try_emplace(origin, kEmptyMaterial);
            if (!fresh) return it->second;
            if (const HermiteLeaf* leaf = acc.probeConstLeaf(origin)) {
                const MaterialValue* values = leaf->buffer().data();
                for (Index n = 0; n < Index(kLeafVoxels) && it->second != kMixed; ++n) {
                    const MaterialId m = values[n].id;
                    if (m == kEmptyMaterial || m == it->second) continue;
                    it->second = it->second == kEmptyMaterial ? m : kMixed;
                }
            } else {
                it->second = acc.getValue(origin).id;
            }
            return it->second;
        };
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            const MaterialId own = v < mesh.materials.size() ? mesh.materials[v] : kEmptyMaterial;
            {
                Coord lo, hi;
                for (int a = 0; a < 3; ++a) {
                    const int32_t c = int32_t(std::lround(mesh.positions[v][std::size_t(a)] * inv));
                    lo[a] = (c - kSide / 2) & ~int32_t(kLeafDim - 1);
                    hi[a] = (c + kSide / 2) & ~int32_t(kLeafDim - 1);
                }
                bool alone = true;
                for (int32_t x = lo.x(); x <= hi.x() && alone; x += kLeafDim)
                    for (int32_t y = lo.y(); y <= hi.y() && alone; y += kLeafDim)
                        for (int32_t z = lo.z(); z <= hi.z() && alone; z += kLeafDim) {
                            const MaterialId m = blockMaterial(Coord(x, y, z));
                            alone = m == kEmptyMaterial || m == own;
                        }
                if (alone) continue;
            }
            double p[3], n[3] = {0.0, 0.0, 0.0};
            int32_t first[3];
            for (int a = 0; a < 3; ++a) {
                p[a] = mesh.positions[v][std::size_t(a)] * inv;
                first[a] = int32_t(std::lround(p[a])) - kSide / 2;
                if (v < mesh.normals.size()) n[a] = mesh.normals[v][std::size_t(a)];
            }
            // A disc-shaped tent: full at the vertex, falling to zero kAlong away along the surface and
            // kAcross away across it.
            const auto weight = [&](int i, int j, int k) {
                const double d[3] = {first[0] + i - p[0], first[1] + j - p[1], first[2] + k - p[2]};
                const double across = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                const double along = std::sqrt(std::max(0.0, d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - across * across));
                return std::max(0.0, 1.0 - std::fabs(across) / kAcross) * std::max(0.0, 1.0 - along / kAlong);
            };
            MaterialId m[kSide][kSide][kSide];
            // Most vertices see their own material alone in the cube of 3 nearest them: nothing to blend.
            bool mixed = false;
            for (int i = 1; i < kSide - 1; ++i)
                for (int j = 1; j < kSide - 1; ++j)
                    for (int k = 1; k < kSide - 1; ++k) {
                        m[i][j][k] = acc.getValue(Coord(first[0] + i, first[1] + j, first[2] + k)).id;
                        mixed = mixed || (m[i][j][k] != own && m[i][j][k] != kEmptyMaterial);
                    }
            if (!mixed) continue;
            double ownWeight = 0.0;
            MaterialId others[kSide * kSide * kSide];
            double otherWeights[kSide * kSide * kSide];
            int count = 0;
            for (int i = 0; i < kSide; ++i)
                for (int j = 0; j < kSide; ++j)
                    for (int k = 0; k < kSide; ++k) {
                        const double w = weight(i, j, k);
                        if (w <= 0.0) continue;
                        const bool inner = i > 0 && j > 0 && k > 0 && i < kSide - 1 && j < kSide - 1 && k < kSide - 1;
                        const MaterialId id = inner ? m[i][j][k] : acc.getValue(Coord(first[0] + i, first[1] + j, first[2] + k)).id;
                        if (id == kEmptyMaterial) continue;
                        if (id == own) {
                            ownWeight += w;
                            continue;
                        }
                        int slot = 0;
                        while (slot < count && others[slot] != id) ++slot;
                        if (slot == count) {
                            others[count] = id;
                            otherWeights[count++] = 0.0;
                        }
                        otherWeights[slot] += w;
                    }
            if (count == 0) continue;
            const int heaviest = int(std::max_element(otherWeights, otherWeights + count) - otherWeights);
            // A trace of the other material leaves the vertex its own colour: a large triangle of a flat
            // face beside a boundary would otherwise carry the trace across its whole width.
            const double share = otherWeights[heaviest] / (ownWeight + otherWeights[heaviest]);
            // Linear between the traces: a smoothstep there steepened the middle, and along a hard paint
            // edge the voxels' staircase showed through (steps of 0.22 of the way between pixels half a
            // voxel apart, 0.15 linear).
            out[v - firstVertex] = MaterialBlend::pack(others[heaviest], std::clamp((share - kTrace) / (1.0 - 2.0 * kTrace), 0.0, 1.0));
        }
    });
    return out;
}

} // namespace vdbclay
