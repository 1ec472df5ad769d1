#include "mesher/CellOctree.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>

namespace vdbclay::mesher_detail {

namespace {

constexpr int kLattice = kLeafDim + 1; // voxels o .. o+8 per axis
constexpr int kNextAxis[3] = {1, 2, 0};

/// The spread of a set of unit normals: their sum, and the cosine of the largest angle between one of
/// them and the sum's direction. Merging bounds a parent's spread by its children's (the angle from the
/// parent's mean to a child's mean plus the child's own spread), so each normal is read once. Cells
/// stay whole only within less than a right angle, so every wider spread is held as cosine -1.
struct NormalCone {
    double sum[3] = {0.0, 0.0, 0.0};
    double cosSpread = 1.0;
    int count = 0;

    /// The cosine of the angle between two sums: -1 where either is zero.
    static double cosBetween(const double a[3], const double b[3])
    {
        const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        if (la == 0.0 || lb == 0.0) return -1.0;
        return std::clamp((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb), -1.0, 1.0);
    }

    /// cos(a + b) from cos a and cos b: -1 when either angle is wider than a right angle.
    static double cosOfSum(double cosA, double cosB)
    {
        if (cosA < 0.0 || cosB < 0.0) return -1.0;
        return cosA * cosB - std::sqrt((1.0 - cosA * cosA) * (1.0 - cosB * cosB));
    }
};

/// Bit k of kWindowsChangingTwice[level - 1][c]: the k-th window of 2^level consecutive bits of c
/// (a lattice line's material changes, bit t between points t and t + 1) holds more than one change.
constexpr std::array<std::array<uint8_t, 256>, 3> kWindowsChangingTwice = [] {
    std::array<std::array<uint8_t, 256>, 3> table{};
    for (int level = 1; level <= 3; ++level) {
        const int width = 1 << level;
        for (uint32_t changes = 0; changes < 256; ++changes)
            for (int k = 0; k < kLeafDim / width; ++k) {
                const uint32_t window = (changes >> (k * width)) & ((1u << width) - 1);
                if (window & (window - 1)) table[level - 1][changes] |= uint8_t(1u << k);
            }
    }
    return table;
}();

/// The cell of width 2^level at cell coordinates (x, y, z) is bit (x * count + y) * count + z of a
/// level's cell mask, with count = 8 >> level.
constexpr int cellBit(int level, int x, int y, int z)
{
    const int count = kLeafDim >> level;
    return (x * count + y) * count + z;
}

/// cellBit(1, x, y, z) = x * 16 + y * 4 + z.
constexpr int kTwoVoxelStride[3] = {(kLeafDim / 2) * (kLeafDim / 2), kLeafDim / 2, 1};

/// The two-voxel cells (cellBit(1, ...), less the part along the axis) that hold the lattice line
/// (u, v) along an axis: one or two across it in each other direction, two where the line lies on a
/// boundary between cells (a cell's range 2c .. 2c + 2 holds both ends).
struct LineCells {
    uint8_t count = 0;
    uint8_t cells[4] = {};
};
constexpr std::array<std::array<std::array<LineCells, kLattice>, kLattice>, 3> kLineCells = [] {
    constexpr uint8_t kCellsAcross[kLattice][2] = {{0, 0}, {0, 0}, {0, 1}, {1, 1}, {1, 2}, {2, 2}, {2, 3}, {3, 3}, {3, 3}};
    std::array<std::array<std::array<LineCells, kLattice>, kLattice>, 3> table{};
    for (int axis = 0; axis < 3; ++axis)
        for (int u = 0; u < kLattice; ++u)
            for (int v = 0; v < kLattice; ++v) {
                LineCells& line = table[axis][u][v];
                for (int cu = kCellsAcross[u][0]; cu <= kCellsAcross[u][1]; ++cu)
                    for (int cv = kCellsAcross[v][0]; cv <= kCellsAcross[v][1]; ++cv)
                        line.cells[line.count++] =
                            uint8_t(cu * kTwoVoxelStride[kNextAxis[axis]] + cv * kTwoVoxelStride[kNextAxis[kNextAxis[axis]]]);
            }
    return table;
}();

/// A leaf's voxel lattice (o .. o+8): which points are solid, seen along each axis, and its crossings
/// with their normals, read once per leaf.
class LeafLattice {
public:
    static constexpr int kTwoVoxelCells = (kLeafDim / 2) * (kLeafDim / 2) * (kLeafDim / 2);

    LeafLattice(const CornerGrid& grid, const Neighbourhood& hood, NormalCone twoVoxelCones[kTwoVoxelCells]) : grid_(grid)
    {
        // Solid bits along each axis: line (u, v) of axis a holds bit t for lattice point t along a, where
        // u and v are the coordinates along (a + 1) % 3 and (a + 2) % 3. The corner grid's rows along z
        // cover points -1 .. 9.
        MaterialId firstSolid = kEmptyMaterial;
        for (int x = 0; x < kLattice; ++x)
            for (int y = 0; y < kLattice; ++y) {
                const uint32_t line = (grid.solidRows[x + 1][y + 1] >> 1) & ((1u << kLattice) - 1);
                solidLine_[2][x][y] = line;
                if (line && firstSolid == kEmptyMaterial) firstSolid = grid.at(x, y, __builtin_ctz(line)).id;
            }
        // The lines along x and y are the lines along z transposed, plane by plane.
        for (int i = 0; i < kLattice; ++i) {
            transposeLines([&](int x) { return solidLine_[2][x][i]; }, [&](int z, uint32_t xBits) { solidLine_[0][i][z] = xBits; });
            transposeLines([&](int y) { return solidLine_[2][i][y]; }, [&](int z, uint32_t yBits) { solidLine_[1][z][i] = yBits; });
        }
        bool mixed = false;
        for (int x = 0; x < kLattice; ++x)
            for (int y = 0; y < kLattice; ++y) {
                const MaterialValue last = grid.at(x, y, kLeafDim);
                mixed |= !rowHoldsOnly(&grid.cells[x + 1][y + 1][1], firstSolid) || (last.solid() && last.id != firstSolid);
            }
        singleMaterial_ = !mixed;
        for (int axis = 0; axis < 3; ++axis)
            for (int u = 0; u < kLattice; ++u)
                for (int v = 0; v < kLattice; ++v) {
                    const uint32_t line = solidLine_[axis][u][v];
                    const uint8_t changes = uint8_t((line ^ (line >> 1)) & ((1u << kLeafDim) - 1));
                    if (changes) changedLines_[changedLineCount_++] = {changes, uint8_t(axis), uint8_t(u), uint8_t(v)};
                    if (changes & (changes - 1))
                        linesChangingTwice_[lineChangingTwiceCount_++] = {changes, uint8_t(axis), uint8_t(u), uint8_t(v)};
                }
        // The crossings (a leaf's surface holds a few hundred), each added to the normal sums of the
        // two-voxel cells holding its voxel edge: the cell along the axis that holds the edge, and one or
        // two across it in each other direction (two where the line lies on a boundary between cells).
        for (int k = 0; k < changedLineCount_; ++k) {
            const ChangedLine& line = changedLines_[k];
            const int axis = line.axis;
            const LineCells& lineCells = kLineCells[axis][line.u][line.v];
            uint8_t at[3];
            at[kNextAxis[axis]] = line.u;
            at[kNextAxis[kNextAxis[axis]]] = line.v;
            for (uint32_t changes = line.changes; changes; changes &= changes - 1) {
                const int t = __builtin_ctz(changes);
                at[axis] = uint8_t(t);
                const PackedSample* s = hood.localSample(at[0], at[1], at[2], axis);
                if (!s) continue;
                Crossing& x = crossings_[crossingCount_++];
                std::copy(at, at + 3, x.at);
                x.axis = uint8_t(axis);
                const UnpackedSample sample = unpackSample(*s);
                std::copy(sample.normal.begin(), sample.normal.end(), x.normal);
                x.offset = sample.offset;
                x.cellCount = lineCells.count;
                const int along = (t >> 1) * kTwoVoxelStride[axis];
                for (int i = 0; i < lineCells.count; ++i) {
                    const int cell = lineCells.cells[i] + along;
                    x.cells[i] = uint8_t(cell);
                    NormalCone& cone = twoVoxelCones[cell];
                    for (int a = 0; a < 3; ++a) cone.sum[a] += x.normal[a];
                    ++cone.count;
                }
            }
        }
        // Each cone's spread: the cosine of the widest angle between one of its normals and its sum.
        double length[kTwoVoxelCells], minCos[kTwoVoxelCells];
        for (int cell = 0; cell < kTwoVoxelCells; ++cell) {
            const double* sum = twoVoxelCones[cell].sum;
            length[cell] = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
            minCos[cell] = 1.0;
        }
        for (const Crossing* x = crossings_; x != crossings_ + crossingCount_; ++x)
            for (int i = 0; i < x->cellCount; ++i) {
                const int cell = x->cells[i];
                const double* sum = twoVoxelCones[cell].sum;
                const double cosine = length[cell] > 0.0
                                          ? (x->normal[0] * sum[0] + x->normal[1] * sum[1] + x->normal[2] * sum[2]) / length[cell]
                                          : -1.0;
                minCos[cell] = std::min(minCos[cell], cosine);
            }
        for (int cell = 0; cell < kTwoVoxelCells; ++cell) twoVoxelCones[cell].cosSpread = std::clamp(minCos[cell], -1.0, 1.0);
    }

    /// The cells of width 2^level (cellBit order) that some lattice line through them crosses the
    /// surface more than once in: their edges hide surface, or a face or the inside does. Only the lines
    /// that change more than once anywhere can mark a cell, and a smooth leaf has few or none.
    uint64_t cellsWithLinesChangingTwice(int level) const
    {
        const int width = 1 << level, count = kLeafDim >> level;
        const std::array<uint8_t, 256>& windows = kWindowsChangingTwice[level - 1];
        // The cells along one lattice coordinate holding index i: one, or two where i is on a boundary.
        auto cellsAt = [&](int i, int& first, int& last) {
            last = std::min(count - 1, i >> level);
            first = (i & (width - 1)) == 0 && i > 0 ? (i >> level) - 1 : last;
        };
        uint64_t cells = 0;
        for (int k = 0; k < lineChangingTwiceCount_; ++k) {
            const ChangedLine& line = linesChangingTwice_[k];
            const uint32_t twice = windows[line.changes]; // bit c: the c-th cell along the axis
            if (!twice) continue;
            const int axis = line.axis, u = kNextAxis[axis], v = kNextAxis[u];
            int firstU, lastU, firstV, lastV;
            cellsAt(line.u, firstU, lastU);
            cellsAt(line.v, firstV, lastV);
            for (int cu = firstU; cu <= lastU; ++cu)
                for (int cv = firstV; cv <= lastV; ++cv)
                    for (uint32_t rest = twice; rest; rest &= rest - 1) {
                        int c[3];
                        c[axis] = __builtin_ctz(rest);
                        c[u] = cu;
                        c[v] = cv;
                        cells |= uint64_t(1) << cellBit(level, c[0], c[1], c[2]);
                    }
        }
        return cells;
    }

    /// The cells of width 2^level (cellBit order) with an ambiguous face: two solid corners on a
    /// diagonal, two empty on the other. Found a column of cells along z at a time, from the four lines
    /// along z through the column's edges.
    uint64_t cellsWithAmbiguousFaces(int level) const
    {
        const int width = 1 << level, count = kLeafDim >> level;
        // Bit z: the face from z to z + width between lines p and q (corners p[z], p[z + w], q[z + w],
        // q[z] in turn) alternates.
        auto alternates = [width](uint32_t p, uint32_t q) {
            const uint32_t pUp = p >> width, qUp = q >> width;
            return ~(p ^ qUp) & ~(pUp ^ q) & (p ^ pUp);
        };
        uint64_t cells = 0;
        for (int cx = 0; cx < count; ++cx)
            for (int cy = 0; cy < count; ++cy) {
                const int x0 = cx * width, y0 = cy * width;
                const uint32_t l00 = solidLine_[2][x0][y0], l10 = solidLine_[2][x0 + width][y0];
                const uint32_t l01 = solidLine_[2][x0][y0 + width], l11 = solidLine_[2][x0 + width][y0 + width];
                // Bit z: the face across the column at z alternates (l00, l10, l11, l01 in turn).
                const uint32_t across = ~(l00 ^ l11) & ~(l01 ^ l10) & (l00 ^ l01);
                const uint32_t ambiguous = across | (across >> width) | alternates(l00, l01) | alternates(l10, l11) |
                                           alternates(l00, l10) | alternates(l01, l11);
                for (int cz = 0; cz < count; ++cz)
                    if ((ambiguous >> (cz * width)) & 1u) cells |= uint64_t(1) << cellBit(level, cx, cy, cz);
            }
        return cells;
    }

    /// Whether the cell of `width` at leaf-local `b` holds at most one solid material.
    bool holdsOneMaterial(const int b[3], int width) const { return singleMaterial_ || singleMaterialIn(b, width); }

    /// Whether the two-voxel cell (i, j, k) holds one straight sharp edge: its crossings' normals fall
    /// into two groups, each within `cosHalfSpread` of its own mean, and the two groups' planes meet
    /// in a line through the cell. CMS puts that cell's vertex on the edge, so it needs no splitting.
    bool holdsOneSharpEdge(int i, int j, int k, double cosHalfSpread) const
    {
        const int b[3] = {2 * i, 2 * j, 2 * k};
        const int cell = cellBit(1, i, j, k);
        // A two-voxel cell holds at most 54 voxel edges (18 per axis).
        std::array<const Crossing*, 54> members;
        int count = 0;
        for (const Crossing* x = crossings_; x != crossings_ + crossingCount_; ++x)
            if (std::find(x->cells, x->cells + x->cellCount, cell) != x->cells + x->cellCount && count < int(members.size()))
                members[count++] = x;
        if (count < 2) return false;
        auto dot = [](const auto* a, const auto* c) { return double(a[0]) * c[0] + double(a[1]) * c[1] + double(a[2]) * c[2]; };
        const float* seed[2] = {members[0]->normal, members[0]->normal};
        for (int m = 1; m < count; ++m)
            if (dot(members[m]->normal, seed[0]) < dot(seed[1], seed[0])) seed[1] = members[m]->normal;
        double mean[2][3] = {};
        std::array<uint8_t, 54> group;
        for (int m = 0; m < count; ++m) {
            group[m] = dot(members[m]->normal, seed[1]) > dot(members[m]->normal, seed[0]) ? 1 : 0;
            for (int a = 0; a < 3; ++a) mean[group[m]][a] += members[m]->normal[a];
        }
        for (auto& g : mean) {
            const double length = std::sqrt(dot(g, g));
            if (length == 0.0) return false;
            for (double& v : g) v /= length;
        }
        for (int m = 0; m < count; ++m)
            if (dot(members[m]->normal, mean[group[m]]) < cosHalfSpread) return false;
        // The edge: the point nearest the cell's centre on both groups' mean planes.
        const Eigen::Vector3d n0(mean[0][0], mean[0][1], mean[0][2]), n1(mean[1][0], mean[1][1], mean[1][2]);
        const Eigen::Vector3d direction = n0.cross(n1);
        if (direction.norm() < 1e-3) return false;
        double offset[2] = {0.0, 0.0};
        int sizes[2] = {0, 0};
        for (int m = 0; m < count; ++m) {
            Eigen::Vector3d p(members[m]->at[0], members[m]->at[1], members[m]->at[2]);
            p[members[m]->axis] += members[m]->offset;
            offset[group[m]] += (group[m] ? n1 : n0).dot(p);
            ++sizes[group[m]];
        }
        const Eigen::Vector3d centre(b[0] + 1.0, b[1] + 1.0, b[2] + 1.0);
        Eigen::Matrix3d system;
        system.row(0) = n0;
        system.row(1) = n1;
        system.row(2) = direction;
        const Eigen::Vector3d rhs(offset[0] / sizes[0], offset[1] / sizes[1], direction.dot(centre));
        const Eigen::Vector3d onEdge = system.partialPivLu().solve(rhs);
        for (int a = 0; a < 3; ++a)
            if (onEdge[a] < b[a] || onEdge[a] > b[a] + 2) return false;
        return true;
    }

    /// Whether the crossings of the cell of `width` at leaf-local `b` lie within `tolerance` voxels of
    /// the plane through their centroid across `normalSum` (their normals' sum), with every normal
    /// within a right angle of it.
    bool liesNearPlane(const int b[3], int width, const double normalSum[3], double tolerance) const
    {
        const double length = std::sqrt(normalSum[0] * normalSum[0] + normalSum[1] * normalSum[1] + normalSum[2] * normalSum[2]);
        if (length == 0.0) return false;
        const double n[3] = {normalSum[0] / length, normalSum[1] / length, normalSum[2] / length};
        // A voxel edge lies in the cell when it starts inside the cell along its axis and lies within
        // the cell's closed box across it.
        const auto inCell = [&](const Crossing& x) {
            for (int a = 0; a < 3; ++a) {
                const int t = x.at[a];
                if (t < b[a] || t > b[a] + width || (a == x.axis && t == b[a] + width)) return false;
            }
            return true;
        };
        double centre = 0.0;
        int count = 0;
        for (const Crossing* x = crossings_; x != crossings_ + crossingCount_; ++x) {
            if (!inCell(*x)) continue;
            if (x->normal[0] * n[0] + x->normal[1] * n[1] + x->normal[2] * n[2] <= 0.0) return false;
            centre += heightOf(*x, n);
            ++count;
        }
        if (count == 0) return false;
        centre /= count;
        for (const Crossing* x = crossings_; x != crossings_ + crossingCount_; ++x)
            if (inCell(*x) && std::fabs(heightOf(*x, n) - centre) > tolerance) return false;
        return true;
    }

private:
    struct Crossing {
        float normal[3];
        float offset; // along the axis from `at`
        uint8_t at[3];
        uint8_t axis;
        uint8_t cells[4]; // the two-voxel cells holding the voxel edge
        uint8_t cellCount;
    };

    /// A crossing's position along `n`.
    static double heightOf(const Crossing& x, const double n[3])
    {
        double h = x.offset * n[x.axis];
        for (int a = 0; a < 3; ++a) h += double(x.at[a]) * n[a];
        return h;
    }

    /// Transposes a 9 x 9 bit matrix: row(r) gives bit c of row r, put(c, bits) takes bit r of column c.
    template<typename Row, typename Put>
    static void transposeLines(Row&& row, Put&& put)
    {
        // Rows and columns 0 .. 7 as an 8 x 8 byte matrix, transposed by swapping ever smaller blocks
        // across the diagonal; the ninth row and column separately.
        uint64_t m = 0;
        uint32_t lastColumn = 0;
        for (int r = 0; r < 8; ++r) {
            const uint32_t bits = row(r);
            m |= uint64_t(bits & 0xFFu) << (8 * r);
            lastColumn |= ((bits >> 8) & 1u) << r;
        }
        uint64_t t = (m ^ (m >> 7)) & 0x00AA00AA00AA00AAull;
        m ^= t ^ (t << 7);
        t = (m ^ (m >> 14)) & 0x0000CCCC0000CCCCull;
        m ^= t ^ (t << 14);
        t = (m ^ (m >> 28)) & 0x00000000F0F0F0F0ull;
        m ^= t ^ (t << 28);
        const uint32_t lastRow = row(8);
        for (int c = 0; c < 8; ++c) put(c, uint32_t((m >> (8 * c)) & 0xFFu) | ((lastRow >> c) & 1u) << 8);
        put(8, lastColumn | ((lastRow >> 8) & 1u) << 8);
    }

    bool singleMaterialIn(const int b[3], int width) const
    {
        MaterialId solid = kEmptyMaterial;
        for (int x = b[0]; x <= b[0] + width; ++x)
            for (int y = b[1]; y <= b[1] + width; ++y)
                for (int z = b[2]; z <= b[2] + width; ++z) {
                    const MaterialId m = grid_.at(x, y, z).id;
                    if (m == kEmptyMaterial) continue;
                    if (solid == kEmptyMaterial) solid = m;
                    else if (m != solid) return false;
                }
        return true;
    }

    const CornerGrid& grid_; // the lattice's materials are the corner grid's o .. o+8
    bool singleMaterial_;
    uint32_t solidLine_[3][kLattice][kLattice];
    struct ChangedLine {
        uint8_t changes; // bit t: the line changes material between points t and t + 1
        uint8_t axis, u, v;
    };
    ChangedLine changedLines_[3 * kLattice * kLattice];   // lines that change material, in order
    ChangedLine linesChangingTwice_[3 * kLattice * kLattice]; // those that change more than once
    int changedLineCount_ = 0, lineChangingTwiceCount_ = 0;
    // At most one per voxel edge of the lattice: 3 * 9 * 9 * 8. On the stack, so a leaf allocates nothing.
    static constexpr int kMaxCrossings = 3 * kLattice * kLattice * kLeafDim;
    Crossing crossings_[kMaxCrossings];
    int crossingCount_ = 0;
};

} // namespace

LeafCellSizes subdivideLeaf(const CornerGrid& grid, const Neighbourhood& hood, const SubdivisionCriteria& criteria)
{
    LeafCellSizes sizes{};
    if (criteria.maxCellSize <= 1) {
        std::fill(&sizes.cellStarts[0][0], &sizes.cellStarts[0][0] + kLeafDim * kLeafDim, uint8_t(0xFF));
        return sizes;
    }
    // Normal cones of the cells of width 2, 4 and 8, in cellBit order.
    NormalCone twoVoxel[LeafLattice::kTwoVoxelCells], fourVoxel[8], eightVoxel[1];
    NormalCone* const cones[4] = {nullptr, twoVoxel, fourVoxel, eightVoxel};
    LeafLattice lattice(grid, hood, twoVoxel);
    // whole[level], bit cellBit(level, x, y, z): the cell of width 2^level at (x, y, z) * 2^level stays
    // whole (voxel cells always do).
    uint64_t whole[4] = {0, 0, 0, 0};
    auto isWhole = [&](int level, int x, int y, int z) { return (whole[level] >> cellBit(level, x, y, z)) & 1u; };
    int finest = 0;
    for (int level = 1; (1 << level) <= criteria.maxCellSize && level <= 3; ++level) {
        const int width = 1 << level, count = kLeafDim >> level;
        const uint64_t linesChangingTwice = lattice.cellsWithLinesChangingTwice(level);
        const uint64_t ambiguousFaces = lattice.cellsWithAmbiguousFaces(level);
        for (int x = 0; x < count; ++x)
            for (int y = 0; y < count; ++y)
                for (int z = 0; z < count; ++z) {
                    const int bit = cellBit(level, x, y, z);
                    if (((linesChangingTwice | ambiguousFaces) >> bit) & 1u) continue;
                    bool childrenWhole = true;
                    for (int c = 0; c < 8 && childrenWhole && level > 1; ++c)
                        childrenWhole = isWhole(level - 1, 2 * x + cornerBit(c, 0), 2 * y + cornerBit(c, 1), 2 * z + cornerBit(c, 2));
                    const int b[3] = {x * width, y * width, z * width};
                    if (!childrenWhole || !lattice.holdsOneMaterial(b, width)) continue;
                    NormalCone& cone = cones[level][bit];
                    if (level > 1) {
                        auto childCone = [&](int c) -> const NormalCone& {
                            return cones[level - 1][cellBit(level - 1, 2 * x + cornerBit(c, 0), 2 * y + cornerBit(c, 1),
                                                            2 * z + cornerBit(c, 2))];
                        };
                        for (int c = 0; c < 8; ++c) {
                            for (int k = 0; k < 3; ++k) cone.sum[k] += childCone(c).sum[k];
                            cone.count += childCone(c).count;
                        }
                        for (int c = 0; c < 8; ++c) {
                            const NormalCone& child = childCone(c);
                            if (child.count == 0) continue;
                            cone.cosSpread = std::min(
                                cone.cosSpread, NormalCone::cosOfSum(NormalCone::cosBetween(child.sum, cone.sum), child.cosSpread));
                        }
                    }
                    if (cone.cosSpread >= criteria.cosHalfSpread ||
                        (level == 1 && lattice.holdsOneSharpEdge(x, y, z, criteria.cosHalfSpread)) ||
                        (criteria.planeTolerance > 0.0 && lattice.liesNearPlane(b, width, cone.sum, criteria.planeTolerance)))
                        whole[level] |= uint64_t(1) << bit;
                }
        if (!whole[level]) break;
        finest = level;
    }
    // Each two-voxel block takes the widest whole cell containing it (its eight voxel cells share every
    // cell wider than one voxel), and marks where its cells start.
    for (int x = 0; x < kLeafDim / 2; ++x)
        for (int y = 0; y < kLeafDim / 2; ++y)
            for (int z = 0; z < kLeafDim / 2; ++z) {
                int level = finest;
                while (level > 0 && !isWhole(level, (2 * x) >> level, (2 * y) >> level, (2 * z) >> level)) --level;
                sizes.blockLog2Width[x][y][z] = uint8_t(level);
                if (level == 0) {
                    for (int i = 0; i < 2; ++i)
                        for (int j = 0; j < 2; ++j) sizes.cellStarts[2 * x + i][2 * y + j] |= uint8_t(3u << (2 * z));
                } else if (((2 * (x | y | z)) & ((1 << level) - 1)) == 0) {
                    sizes.cellStarts[2 * x][2 * y] |= uint8_t(1u << (2 * z));
                }
            }
    return sizes;
}

} // namespace vdbclay::mesher_detail
