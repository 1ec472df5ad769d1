// Marching Cubes over Hermite data, built from marching squares on the six faces of each cell: the
// face segments are linked into loops and each loop is fanned into triangles. Crossings sit at the
// stored offsets and carry the stored normals. Because a face's segments depend only on that face,
// the two cells sharing it agree on them and the welded mesh is watertight without any table of cases.
#include "mesher/Mesher.h"

#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <unordered_map>

namespace vdbclay {

namespace {

using ConstAccessor = openvdb::tree::ValueAccessor<const HermiteTree, /*IsSafe=*/false>;

/// Corner c of a cell is at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1) from its minimum corner.
constexpr int cornerBit(int c, int axis) { return (c >> axis) & 1; }

struct CellFace {
    int corners[4]; // counter-clockwise seen from outside the cell
};

constexpr CellFace makeFace(int axis, int side)
{
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    // (b,c) = (0,0), (1,0), (1,1), (0,1) turns counter-clockwise about +axis.
    const int bc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    CellFace f{};
    for (int i = 0; i < 4; ++i) {
        const int k = side ? i : (4 - i) % 4; // reversed on the -axis face
        f.corners[i] = (side << axis) | (bc[k][0] << b) | (bc[k][1] << c);
    }
    return f;
}

constexpr CellFace kFaces[6] = {makeFace(0, 0), makeFace(0, 1), makeFace(1, 0),
                                makeFace(1, 1), makeFace(2, 0), makeFace(2, 1)};

/// Cell edge between two corners that differ in one coordinate: axis * 4 + position of the edge's low
/// corner in the other two coordinates.
constexpr int cellEdge(int c0, int c1)
{
    const int diff = c0 ^ c1;
    const int axis = diff == 1 ? 0 : (diff == 2 ? 1 : 2);
    const int low = c0 & c1;
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    return axis * 4 + (cornerBit(low, b) | (cornerBit(low, c) << 1));
}

constexpr int edgeLowCorner(int edge)
{
    const int axis = edge / 4, b = (axis + 1) % 3, c = (axis + 2) % 3;
    return ((edge & 1) << b) | (((edge >> 1) & 1) << c);
}

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

/// The leaves around one leaf, so cells at its borders find their corners and samples quickly.
class Neighbourhood {
public:
    Neighbourhood(const HermiteLeaf& centre, ConstAccessor& acc) : origin_(centre.origin())
    {
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const Coord o = origin_.offsetBy(dx * kLeafDim, dy * kLeafDim, dz * kLeafDim);
                    const int s = slot(dx, dy, dz);
                    leaves_[s] = acc.probeConstLeaf(o);
                    tiles_[s] = leaves_[s] ? MaterialValue{} : acc.getValue(o);
                }
    }

    const HermiteLeaf* leafOf(const Coord& c) const { return leaves_[slotOf(c)]; }

    MaterialValue material(const Coord& c) const
    {
        const int s = slotOf(c);
        return leaves_[s] ? leaves_[s]->getValue(HermiteLeaf::coordToOffset(c)) : tiles_[s];
    }

    const PackedSample* sample(const Coord& c, int axis) const
    {
        const HermiteLeaf* leaf = leaves_[slotOf(c)];
        return leaf ? leaf->sample(HermiteLeaf::coordToOffset(c), axis) : nullptr;
    }

private:
    static int slot(int dx, int dy, int dz) { return (dx + 1) * 9 + (dy + 1) * 3 + (dz + 1); }
    int slotOf(const Coord& c) const
    {
        auto block = [](int v, int o) { return v < o ? -1 : (v >= o + kLeafDim ? 1 : 0); };
        return slot(block(c.x(), origin_.x()), block(c.y(), origin_.y()), block(c.z(), origin_.z()));
    }

    Coord origin_;
    const HermiteLeaf* leaves_[27];
    MaterialValue tiles_[27];
};

MeshChunk meshLeafMarchingCubes(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize)
{
    const Neighbourhood hood(leaf, acc);
    const Coord o = leaf.origin();
    MeshChunk chunk;
    chunk.leafOrigin = {o.x(), o.y(), o.z()};
    std::unordered_map<uint64_t, uint32_t> local;

    for (int x = -1; x < kLeafDim; ++x) {
        for (int y = -1; y < kLeafDim; ++y) {
            for (int z = -1; z < kLeafDim; ++z) {
                const Coord base = o.offsetBy(x, y, z);
                MaterialValue mats[8];
                unsigned solid = 0;
                int owner = -1;
                for (int c = 0; c < 8; ++c) {
                    const Coord p = base.offsetBy(cornerBit(c, 0), cornerBit(c, 1), cornerBit(c, 2));
                    mats[c] = hood.material(p);
                    if (mats[c].solid()) solid |= 1u << c;
                    if (owner < 0 && hood.leafOf(p)) owner = c;
                }
                if (solid == 0 || solid == 0xFF) continue;
                // A cell belongs to the leaf holding its first corner that lies in a leaf.
                const Coord ownerCorner = base.offsetBy(cornerBit(owner, 0), cornerBit(owner, 1), cornerBit(owner, 2));
                if (hood.leafOf(ownerCorner) != &leaf) continue;

                int loops[4][12], sizes[4];
                const int nLoops = cellLoops(solid, loops, sizes);
                for (int l = 0; l < nLoops; ++l) {
                    uint32_t ids[12];
                    for (int v = 0; v < sizes[l]; ++v) {
                        const int e = loops[l][v];
                        const int axis = e / 4;
                        const int lowCorner = edgeLowCorner(e);
                        const Coord start =
                            base.offsetBy(cornerBit(lowCorner, 0), cornerBit(lowCorner, 1), cornerBit(lowCorner, 2));
                        const uint64_t key = edgeKey(start.x(), start.y(), start.z(), axis);
                        auto [it, inserted] = local.emplace(key, uint32_t(chunk.mesh.positions.size()));
                        if (inserted) {
                            const PackedSample* s = hood.sample(start, axis);
                            const UnpackedSample u = s ? unpackSample(*s) : UnpackedSample{0.5f, {0.f, 0.f, 0.f}};
                            std::array<float, 3> pos{float(start.x()), float(start.y()), float(start.z())};
                            pos[axis] += u.offset;
                            for (float& p : pos) p = float(p * voxelSize);
                            const int highCorner = lowCorner | (1 << axis);
                            const MaterialValue m = mats[lowCorner].solid() ? mats[lowCorner] : mats[highCorner];
                            chunk.mesh.positions.push_back(pos);
                            chunk.mesh.normals.push_back(u.normal);
                            chunk.mesh.materials.push_back(m.id);
                            chunk.vertexKeys.push_back(key);
                        }
                        ids[v] = it->second;
                    }
                    for (int v = 1; v + 1 < sizes[l]; ++v) chunk.mesh.triangles.push_back({ids[0], ids[v], ids[v + 1]});
                }
            }
        }
    }
    return chunk;
}

} // namespace

const char* mesherName(MesherKind kind) { return kind == MesherKind::MarchingCubes ? "mc" : "cms"; }

MesherKind parseMesherKind(const std::string& s)
{
    if (s == "mc") return MesherKind::MarchingCubes;
    if (s == "cms") return MesherKind::CubicalMarchingSquares;
    throw std::invalid_argument("unknown mesher '" + s + "' (expected mc or cms)");
}

std::vector<MeshChunk> meshVolumeChunks(const Volume& volume, const MeshOptions& options)
{
    if (options.kind == MesherKind::CubicalMarchingSquares)
        throw MesherUnavailable("the Cubical Marching Squares mesher is not built yet; use --mesher mc");
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
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            chunks[i] = meshLeafMarchingCubes(*leaves[i], acc, voxelSize);
    });
    return chunks;
}

Mesh meshVolume(const Volume& volume, const MeshOptions& options)
{
    return weldChunks(meshVolumeChunks(volume, options));
}

} // namespace vdbclay
