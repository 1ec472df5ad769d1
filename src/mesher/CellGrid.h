// Internal to the mesher: the cell geometry shared by Marching Cubes and Cubical Marching Squares,
// and the access to a leaf and its neighbours. OpenVDB-heavy: include only from mesher .cpp files.
#pragma once

#include "mesher/BlockSets.h"
#include "mesher/LodCut.h"
#include "mesher/CellTopology.h"
#include "mesher/Mesh.h"
#include "mesher/Mesher.h"
#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/tree/ValueAccessor.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vdbclay::mesher_detail {

using ConstAccessor = openvdb::tree::ValueAccessor<const HermiteTree, /*IsSafe=*/false>;

/// The voxels meshing a leaf reads: the corners of its cells (o-1 .. o+8) and the scans around sharp
/// features, which reach one voxel further. An edit outside them leaves the leaf's chunk as it was,
/// its neighbours' cell widths aside.
constexpr LeafReach kMeshingReach{-2, kLeafDim + 2};
/// The voxels subdividing a leaf into adaptive cells reads: its lattice o .. o+8.
constexpr LeafReach kSubdivisionReach{0, kLeafDim};

/// Bit z set where the voxel row[z] (z = 0 .. 7) is solid: one row of a leaf along z.
inline uint32_t solidBitsOfRow(const MaterialValue* row)
{
    static_assert(sizeof(MaterialValue) == 2 && kLeafDim == 8 && kEmptyMaterial == 0, "a leaf row: eight 16-bit ids, 0 empty");
#if defined(__SSE2__)
    const __m128i ids = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row));
    const __m128i empty = _mm_cmpeq_epi16(ids, _mm_setzero_si128());
    return ~uint32_t(_mm_movemask_epi8(_mm_packs_epi16(empty, empty))) & 0xffu;
#else
    uint32_t bits = 0;
    for (int z = 0; z < kLeafDim; ++z) bits |= uint32_t(row[z].solid()) << z;
    return bits;
#endif
}

/// Whether each of the voxels row[0 .. 7] is empty or holds `material`.
inline bool rowHoldsOnly(const MaterialValue* row, MaterialId material)
{
#if defined(__SSE2__)
    const __m128i ids = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row));
    const __m128i allowed = _mm_or_si128(_mm_cmpeq_epi16(ids, _mm_setzero_si128()),
                                         _mm_cmpeq_epi16(ids, _mm_set1_epi16(short(material))));
    return _mm_movemask_epi8(allowed) == 0xffff;
#else
    return std::all_of(row, row + kLeafDim, [&](MaterialValue m) { return !m.solid() || m.id == material; });
#endif
}

/// The leaves around one leaf, so cells at its borders find their corners and samples quickly.
class Neighbourhood {
public:
    Neighbourhood() {} // left unfilled: for arrays filled later
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

    /// The leaf (or null) and tile value of the block at (dx, dy, dz) from the centre, each -1 .. 1.
    const HermiteLeaf* leafAt(int dx, int dy, int dz) const { return leaves_[slot(dx, dy, dz)]; }
    MaterialValue tileAt(int dx, int dy, int dz) const { return tiles_[slot(dx, dy, dz)]; }

    MaterialValue material(const Coord& c) const
    {
        const int s = slotOf(c);
        return leaves_[s] ? leaves_[s]->getValue(HermiteLeaf::coordToOffset(c)) : tiles_[s];
    }

    const PackedSample* sample(const Coord& c, int axis) const
    {
        return localSample(c.x() - origin_.x(), c.y() - origin_.y(), c.z() - origin_.z(), axis);
    }

    /// sample() at leaf-local (x, y, z), each in -8 .. 15.
    const PackedSample* localSample(int x, int y, int z, int axis) const
    {
        const HermiteLeaf* leaf = leaves_[slot(blockOf(x), blockOf(y), blockOf(z))];
        constexpr int kMask = kLeafDim - 1;
        const Index offset = Index(x & kMask) << (2 * kLeafLog2Dim) | Index(y & kMask) << kLeafLog2Dim | Index(z & kMask);
        return leaf ? leaf->sample(offset, axis) : nullptr;
    }

    /// Bit z + 8 set where the voxel at leaf-local (x, y, z) is solid, for z = -8 .. 15; x and y in -8 .. 15.
    uint32_t solidColumn(int x, int y) const
    {
        const int bx = blockOf(x), by = blockOf(y);
        constexpr int kMask = kLeafDim - 1;
        const Index rowStart = Index(x & kMask) << (2 * kLeafLog2Dim) | Index(y & kMask) << kLeafLog2Dim;
        uint32_t bits = 0;
        for (int bz = -1; bz <= 1; ++bz) {
            const HermiteLeaf* leaf = leaves_[slot(bx, by, bz)];
            const uint32_t row = leaf ? solidBitsOfRow(leaf->buffer().data() + rowStart)
                                      : (tiles_[slot(bx, by, bz)].solid() ? (1u << kLeafDim) - 1 : 0u);
            bits |= row << ((bz + 1) * kLeafDim);
        }
        return bits;
    }

private:
    static int slot(int dx, int dy, int dz) { return (dx + 1) * 9 + (dy + 1) * 3 + (dz + 1); }
    /// The block (-1, 0 or 1) of a leaf-local coordinate in -8 .. 15.
    static int blockOf(int local) { return ((local + kLeafDim) >> kLeafLog2Dim) - 1; }
    int slotOf(const Coord& c) const
    {
        return slot(blockOf(c.x() - origin_.x()), blockOf(c.y() - origin_.y()), blockOf(c.z() - origin_.z()));
    }

    Coord origin_;
    const HermiteLeaf* leaves_[27];
    MaterialValue tiles_[27];
};

/// The materials of the voxels o-1 .. o+8 per axis around a leaf at origin o: every corner a cell
/// owned by the leaf can have, gathered once per leaf, with a bit mask of the solid ones per row.
struct CornerGrid {
    static constexpr int kSpan = kLeafDim + 2;

    CornerGrid(const HermiteLeaf& leaf, const Neighbourhood& hood) { fill(leaf, hood); }
    CornerGrid() {} // left unfilled (not zeroed): for arrays filled later

    void fill(const HermiteLeaf& leaf, const Neighbourhood& hood)
    {
        origin = leaf.origin();
        // Each block's voxels, fetched once: a leaf buffer's element access checks for delayed loading
        // on every call.
        const MaterialValue* blockData[3][3][3];
        for (int bx = 0; bx < 3; ++bx)
            for (int by = 0; by < 3; ++by)
                for (int bz = 0; bz < 3; ++bz) {
                    const HermiteLeaf* blockLeaf = hood.leafAt(bx - 1, by - 1, bz - 1);
                    blockData[bx][by][bz] = blockLeaf ? blockLeaf->buffer().data() : nullptr;
                }
        // Row by row, one neighbourhood column of blocks (bx, by) at a time: rows x = 0 and 9 lie in the
        // blocks at -1 and +1, rows 1 .. 8 in the centre's column, and likewise for y.
        constexpr Index kMask = kLeafDim - 1;
        for (int bx = -1; bx <= 1; ++bx)
            for (int by = -1; by <= 1; ++by) {
                // The column's blocks below, at and above the leaf (null: a tile), held in locals so the
                // row loop keeps them in registers.
                const MaterialValue* const below = blockData[bx + 1][by + 1][0];
                const MaterialValue* const level = blockData[bx + 1][by + 1][1];
                const MaterialValue* const above = blockData[bx + 1][by + 1][2];
                const MaterialValue lowTile = hood.tileAt(bx, by, -1), midTile = hood.tileAt(bx, by, 0),
                                    highTile = hood.tileAt(bx, by, 1);
                const uint32_t midTileBits = midTile.solid() ? ((1u << kLeafDim) - 1) << 1 : 0u;
                const int xBegin = bx < 0 ? 0 : (bx == 0 ? 1 : kSpan - 1), xEnd = bx < 0 ? 1 : (bx == 0 ? kSpan - 1 : kSpan);
                const int yBegin = by < 0 ? 0 : (by == 0 ? 1 : kSpan - 1), yEnd = by < 0 ? 1 : (by == 0 ? kSpan - 1 : kSpan);
                for (int x = xBegin; x < xEnd; ++x)
                    for (int y = yBegin; y < yEnd; ++y) {
                        // A leaf's voxels are stored z fastest: a row's voxels in one block are consecutive.
                        const Index rowStart = (Index(x - 1) & kMask) << (2 * kLeafLog2Dim) | (Index(y - 1) & kMask) << kLeafLog2Dim;
                        MaterialValue* row = cells[x][y];
                        const MaterialValue first = below ? below[rowStart + kLeafDim - 1] : lowTile;
                        const MaterialValue last = above ? above[rowStart] : highTile;
                        row[0] = first;
                        row[kSpan - 1] = last;
                        uint32_t bits = uint32_t(first.solid()) | uint32_t(last.solid()) << (kSpan - 1);
                        if (level) {
                            std::copy_n(level + rowStart, kLeafDim, row + 1);
                            bits |= solidBitsOfRow(level + rowStart) << 1;
                        } else {
                            std::fill_n(row + 1, kLeafDim, midTile);
                            bits |= midTileBits;
                        }
                        solidRows[x][y] = bits;
                    }
            }
    }

    /// The neighbourhood block grid index i lies in, per axis: -1 (i = 0), 0 (the leaf) or 1 (i = 9).
    static constexpr int blockOf(int i) { return i == 0 ? -1 : (i == kSpan - 1 ? 1 : 0); }

    /// The material at leaf-local voxel (x, y, z), each in -1 .. 8.
    MaterialValue at(int x, int y, int z) const { return cells[x + 1][y + 1][z + 1]; }

    Coord origin;
    MaterialValue cells[kSpan][kSpan][kSpan];
    uint32_t solidRows[kSpan][kSpan]; // bit z: cells[x][y][z] is solid
};

/// What reading a leaf and its neighbours gives: built once to subdivide the leaf, kept to mesh it.
struct LeafSurroundings {
    Neighbourhood hood;
    CornerGrid grid;
};

/// The surroundings of the leaves an update subdivided, for meshing them in the same update (the volume
/// must not change in between), in the order of their origins.
struct LeafSurroundingsStore {
    std::vector<Coord> origins; // sorted
    std::vector<LeafSurroundings> leaves;

    void resize(std::size_t count)
    {
        origins.resize(count);
        leaves.resize(count);
    }

    const LeafSurroundings* find(const Coord& origin) const
    {
        const auto it = std::lower_bound(origins.begin(), origins.end(), origin);
        return it != origins.end() && *it == origin ? &leaves[std::size_t(it - origins.begin())] : nullptr;
    }
};

/// Which of a leaf's owned cells forEachOwnedSurfaceCell visits: all of them, or only those whose
/// minimum corner lies outside the leaf (in a tile block beside it).
enum class OwnedCells { All, OutsideLeaf };

/// Every cell whose corners are not all solid or all empty and that `leaf` owns: a cell belongs to
/// the leaf holding its first corner that lies in a leaf, so the leaves' cells tile space exactly.
/// Surface cells are found a row of ten corners at a time from bit masks of the solid corners.
template<typename CellFn>
void forEachOwnedSurfaceCell(const CornerGrid& grid, const Neighbourhood& hood, OwnedCells which, CellFn&& fn)
{
    constexpr int kSpan = CornerGrid::kSpan;
    const Coord o = grid.origin;
    auto block = CornerGrid::blockOf;
    bool isLeaf[3][3][3];
    for (int bx = -1; bx <= 1; ++bx)
        for (int by = -1; by <= 1; ++by)
            for (int bz = -1; bz <= 1; ++bz)
                isLeaf[bx + 1][by + 1][bz + 1] = hood.leafAt(bx, by, bz) != nullptr;

    constexpr uint32_t kCellBits = (1u << (kSpan - 1)) - 1; // cells z = 0 .. 8
    // A cell whose minimum corner lies in another leaf is that leaf's: only cells whose minimum corner
    // lies in this leaf or in a tile block can be this leaf's. Per column of blocks (x = 0 or y = 0 lie
    // in the blocks below), the cells z = 0 .. 8 that can be.
    uint32_t candidatesIn[2][2];
    for (int bx = -1; bx <= 0; ++bx)
        for (int by = -1; by <= 0; ++by) {
            const bool centreColumn = bx == 0 && by == 0;
            uint32_t& candidates = candidatesIn[bx + 1][by + 1];
            candidates = isLeaf[bx + 1][by + 1][0] ? 0u : 1u; // z = 0: the block below
            if (!isLeaf[bx + 1][by + 1][1] || (centreColumn && which == OwnedCells::All)) candidates |= kCellBits & ~1u;
        }
    if (!(candidatesIn[0][0] | candidatesIn[0][1] | candidatesIn[1][0] | candidatesIn[1][1])) return;
    for (int x = 0; x < kSpan - 1; ++x) {
        for (int y = 0; y < kSpan - 1; ++y) {
            const uint32_t candidates = candidatesIn[x > 0][y > 0];
            if (!candidates) continue;
            // The four corner rows of the cells (x, y, *), in corner order.
            const uint32_t rows[4] = {grid.solidRows[x][y], grid.solidRows[x + 1][y], grid.solidRows[x][y + 1],
                                      grid.solidRows[x + 1][y + 1]};
            const MaterialValue* rowMats[4] = {grid.cells[x][y], grid.cells[x + 1][y], grid.cells[x][y + 1], grid.cells[x + 1][y + 1]};
            const uint32_t all = rows[0] & rows[1] & rows[2] & rows[3], any = rows[0] | rows[1] | rows[2] | rows[3];
            uint32_t mixed = ((any | (any >> 1)) & ~(all & (all >> 1))) & candidates;
            while (mixed) {
                const int z = __builtin_ctz(mixed);
                mixed &= mixed - 1;
                // A cell whose minimum corner lies in the leaf is the leaf's; others go to the first
                // of their corners that lies in a leaf.
                if (x == 0 || y == 0 || z == 0) {
                    int owner = 0;
                    while (!isLeaf[block(x + cornerBit(owner, 0)) + 1][block(y + cornerBit(owner, 1)) + 1]
                                  [block(z + cornerBit(owner, 2)) + 1])
                        ++owner; // stops: on each axis one of the cell's two corner indices lies in this leaf
                    const int ox = x + cornerBit(owner, 0), oy = y + cornerBit(owner, 1), oz = z + cornerBit(owner, 2);
                    if (block(ox) != 0 || block(oy) != 0 || block(oz) != 0) continue; // owned by a neighbour
                }
                MaterialValue mats[8];
                unsigned solid = 0;
                for (int corner = 0; corner < 8; ++corner) {
                    const int row = corner & 3, dz = corner >> 2;
                    mats[corner] = rowMats[row][z + dz];
                    solid |= ((rows[row] >> (z + dz)) & 1u) << corner;
                }
                fn(o.offsetBy(x - 1, y - 1, z - 1), mats, solid);
            }
        }
    }
}

/// The crossing on cell edge `e` of the cell at `base`: its grid key, world position, normal and the
/// material of its solid side.
struct EdgeCrossing {
    uint64_t key;
    Coord start; // the voxel edge's lower end
    int axis;
    std::array<float, 3> position;
    std::array<float, 3> normal;
    MaterialId material;
};

/// The crossing on the voxel edge from `start` along `axis`, whose ends hold `low` and `high`.
inline EdgeCrossing voxelEdgeCrossing(const Neighbourhood& hood, const Coord& start, int axis, MaterialValue low,
                                      MaterialValue high, double voxelSize)
{
    const PackedSample* s = hood.sample(start, axis);
    const UnpackedSample u = s ? unpackSample(*s) : UnpackedSample{0.5f, {0.f, 0.f, 0.f}};
    std::array<float, 3> pos{float(start.x()), float(start.y()), float(start.z())};
    pos[axis] += u.offset;
    for (float& p : pos) p = float(p * voxelSize);
    const MaterialValue m = low.solid() ? low : high;
    return {edgeKey(start.x(), start.y(), start.z(), axis), start, axis, pos, u.normal, m.id};
}

inline EdgeCrossing edgeCrossing(const Neighbourhood& hood, const Coord& base, const MaterialValue mats[8], int e,
                                 double voxelSize)
{
    const int axis = e / 4;
    const int lowCorner = edgeLowCorner(e);
    const Coord start = base.offsetBy(cornerBit(lowCorner, 0), cornerBit(lowCorner, 1), cornerBit(lowCorner, 2));
    return voxelEdgeCrossing(hood, start, axis, mats[lowCorner], mats[lowCorner | (1 << axis)], voxelSize);
}

MeshChunk meshLeafMarchingCubes(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize);
class CellWidthField;

/// Meshes `leaves` in parallel, leaf i into *chunks[i] (its storage reused). `cells` (optional): the
/// adaptive cells kept from earlier calls, filled in where missing; `surroundings` (optional): what
/// subdividing some of the leaves read since the volume last changed. Throws std::runtime_error for a
/// leaf beyond the range of edge keys.
void meshLeavesInto(const HermiteTree& tree, const std::vector<const HermiteLeaf*>& leaves,
                    const std::vector<MeshChunk*>& chunks, double voxelSize, const MeshOptions& options,
                    AdaptiveCellCache* cells = nullptr, const LeafSurroundingsStore* surroundings = nullptr);

/// Cubical Marching Squares, one leaf at a time; keeps its buffers from one leaf to the next, so use
/// one per thread.
/// The brick of a level-of-detail cut being meshed (LodCut.h): its unit cells that touch a finer brick
/// are left to the transition mesher, and the faces beside them are meshed plainly.
struct LodBoundary {
    const LodCut* cut;
    int level;
    Coord brickMin, brickMax; // the brick's cells: [brickMin, brickMax)

    /// Whether a cell or face at `c` lies within `margin` cells of the brick's box (only those can touch
    /// another brick or a transition cell).
    /// Whether this brick meshes the cell at `base` (LodCut::cellOwner): its own cells, and the cells
    /// of an empty region beside it whose first corner in a shown brick is in this one.
    bool owns(const Coord& base) const
    {
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside = inside && base[a] >= brickMin[a] && base[a] < brickMax[a];
        if (inside) return true;
        const std::optional<LodBrick> owner = cut->cellOwner(level, {base.x(), base.y(), base.z()});
        if (!owner || owner->level != level) return false;
        for (int a = 0; a < 3; ++a)
            if (int64_t(owner->brick[std::size_t(a)]) * kLodBrickVoxels != brickMin[a]) return false;
        return true;
    }
    bool nearBoundary(const Coord& c, int margin) const
    {
        for (int a = 0; a < 3; ++a)
            if (c[a] < brickMin[a] + margin || c[a] >= brickMax[a] - margin) return true;
        return false;
    }
};

class CubicalMarchingSquaresMesher {
public:
    /// `walkEveryCell` turns off the shortcut for smooth voxel cells, for tests that check it changes
    /// nothing.
    CubicalMarchingSquaresMesher(double voxelSize, double sharpAngleDegrees, bool walkEveryCell = false);
    ~CubicalMarchingSquaresMesher();
    CubicalMarchingSquaresMesher(const CubicalMarchingSquaresMesher&) = delete;
    CubicalMarchingSquaresMesher& operator=(const CubicalMarchingSquaresMesher&) = delete;

    /// `widths`: the adaptive cells around the leaf (CellOctree.h); null meshes voxel cells.
    /// `surroundings`: the leaf's neighbourhood and corner grid if they were built already (null: built here).
    MeshChunk mesh(const HermiteLeaf& leaf, ConstAccessor& acc, const CellWidthField* widths,
                   const LeafSurroundings* surroundings = nullptr);
    /// The same, written into `out` (its storage reused: a chunk set re-meshes in place).
    void meshInto(const HermiteLeaf& leaf, ConstAccessor& acc, const CellWidthField* widths,
                  const LeafSurroundings* surroundings, MeshChunk& out);

    /// Meshing one brick of a level-of-detail cut at `level` (null: an ordinary volume).
    void setLodBoundary(const LodCut* cut, int level, const Coord& brickMin, int brickEdge);

    /// Cells meshed so far: all of them, and those the smooth-cell shortcut took.
    std::size_t cellsMeshed() const { return cellsMeshed_; }
    std::size_t cellsFromCaseTable() const { return cellsFromCaseTable_; }

    struct Buffers;

private:
    double voxelSize_;
    double cosSharp_;
    bool walkEveryCell_;
    std::optional<LodBoundary> lod_;
    std::size_t cellsMeshed_ = 0, cellsFromCaseTable_ = 0;
    std::unique_ptr<Buffers> buffers_;
};

} // namespace vdbclay::mesher_detail
