// Internal to the mesher: the cell geometry shared by Marching Cubes and Cubical Marching Squares,
// and the access to a leaf and its neighbours. OpenVDB-heavy: include only from mesher .cpp files.
#pragma once

#include "mesher/Mesh.h"
#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/tree/ValueAccessor.h>

namespace vdbclay::mesher_detail {

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

/// The corner an edge starts from (its lower end).
constexpr int edgeLowCorner(int edge)
{
    const int axis = edge / 4, b = (axis + 1) % 3, c = (axis + 2) % 3;
    return ((edge & 1) << b) | (((edge >> 1) & 1) << c);
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

/// Every cell whose corners are not all solid or all empty and that `leaf` owns: a cell belongs to
/// the leaf holding its first corner that lies in a leaf, so the leaves' cells tile space exactly.
template<typename CellFn>
void forEachOwnedSurfaceCell(const HermiteLeaf& leaf, const Neighbourhood& hood, CellFn&& fn)
{
    const Coord o = leaf.origin();
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
                const Coord ownerCorner = base.offsetBy(cornerBit(owner, 0), cornerBit(owner, 1), cornerBit(owner, 2));
                if (hood.leafOf(ownerCorner) != &leaf) continue;
                fn(base, mats, solid);
            }
        }
    }
}

/// The crossing on cell edge `e` of the cell at `base`: its grid key, world position, normal and the
/// material of its solid side.
struct EdgeCrossing {
    uint64_t key;
    std::array<float, 3> position;
    std::array<float, 3> normal;
    MaterialId material;
};

inline EdgeCrossing edgeCrossing(const Neighbourhood& hood, const Coord& base, const MaterialValue mats[8], int e,
                                 double voxelSize)
{
    const int axis = e / 4;
    const int lowCorner = edgeLowCorner(e);
    const Coord start = base.offsetBy(cornerBit(lowCorner, 0), cornerBit(lowCorner, 1), cornerBit(lowCorner, 2));
    const PackedSample* s = hood.sample(start, axis);
    const UnpackedSample u = s ? unpackSample(*s) : UnpackedSample{0.5f, {0.f, 0.f, 0.f}};
    std::array<float, 3> pos{float(start.x()), float(start.y()), float(start.z())};
    pos[axis] += u.offset;
    for (float& p : pos) p = float(p * voxelSize);
    const int highCorner = lowCorner | (1 << axis);
    const MaterialValue m = mats[lowCorner].solid() ? mats[lowCorner] : mats[highCorner];
    return {edgeKey(start.x(), start.y(), start.z(), axis), pos, u.normal, m.id};
}

MeshChunk meshLeafMarchingCubes(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize);
MeshChunk meshLeafCubicalMarchingSquares(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize,
                                         double sharpAngleDegrees);

} // namespace vdbclay::mesher_detail
