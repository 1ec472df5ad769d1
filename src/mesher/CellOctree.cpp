#include "mesher/CellOctree.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace vdbclay::mesher_detail {

namespace {

constexpr int kLattice = kLeafDim + 1; // voxels o .. o+8 per axis

/// The spread of a set of unit normals: their sum, and the largest angle between one of them and the
/// sum's direction. Merging bounds a parent's spread by its children's (the angle from the parent's
/// mean to a child's mean plus the child's own spread), so each normal is read once.
struct NormalCone {
    double sum[3] = {0.0, 0.0, 0.0};
    double halfAngle = 0.0; // radians
    int count = 0;

    static double angleBetween(const double a[3], const double b[3])
    {
        const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        if (la == 0.0 || lb == 0.0) return M_PI;
        const double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
        return std::acos(std::clamp(c, -1.0, 1.0));
    }
};

/// A leaf's voxel lattice (o .. o+8) with the normals of its crossings, read once per leaf.
class LeafLattice {
public:
    LeafLattice(const CornerGrid& grid, const Neighbourhood& hood) : grid_(grid)
    {
        // Solid bits along each axis: line (u, v) of axis a holds bit t for voxel t along a, where u and
        // v are the coordinates along (a + 1) % 3 and (a + 2) % 3.
        MaterialId solid = kEmptyMaterial;
        singleMaterial_ = true;
        std::fill(&solidLine_[0][0][0], &solidLine_[0][0][0] + 3 * kLattice * kLattice, 0u);
        for (int x = 0; x < kLattice; ++x)
            for (int y = 0; y < kLattice; ++y)
                for (int z = 0; z < kLattice; ++z) {
                    const MaterialId m = grid.at(x, y, z).id;
                    if (m == kEmptyMaterial) continue;
                    if (solid == kEmptyMaterial) solid = m;
                    else if (m != solid) singleMaterial_ = false;
                    solidLine_[0][y][z] |= 1u << x;
                    solidLine_[1][z][x] |= 1u << y;
                    solidLine_[2][x][y] |= 1u << z;
                }
        // The crossings' normals (a leaf's surface holds a few hundred).
        for (int axis = 0; axis < 3; ++axis)
            for (int u = 0; u < kLattice; ++u)
                for (int v = 0; v < kLattice; ++v) {
                    uint32_t changes = (solidLine_[axis][u][v] ^ (solidLine_[axis][u][v] >> 1)) & ((1u << kLeafDim) - 1);
                    while (changes) {
                        const int t = __builtin_ctz(changes);
                        changes &= changes - 1;
                        int c[3];
                        c[axis] = t;
                        c[(axis + 1) % 3] = u;
                        c[(axis + 2) % 3] = v;
                        const PackedSample* s = hood.sample(grid.origin.offsetBy(c[0], c[1], c[2]), axis);
                        if (!s) continue;
                        const UnpackedSample u = unpackSample(*s);
                        double p[3] = {double(c[0]), double(c[1]), double(c[2])};
                        p[axis] += u.offset;
                        crossings_.push_back({{c[0], c[1], c[2]}, axis, {u.normal[0], u.normal[1], u.normal[2]}, {p[0], p[1], p[2]}});
                    }
                }
        // Each two-voxel cell's crossings: a crossing counts in every such cell that holds its voxel
        // edge (up to four, where the edge lies on cell faces).
        std::fill(std::begin(memberStart_), std::end(memberStart_), 0);
        for (const Crossing& x : crossings_) forEachTwoVoxelCell(x, [&](int cell) { ++memberStart_[cell + 1]; });
        for (int cell = 0; cell < kTwoVoxelCells; ++cell) memberStart_[cell + 1] += memberStart_[cell];
        members_.resize(memberStart_[kTwoVoxelCells]);
        int next[kTwoVoxelCells];
        std::copy(memberStart_, memberStart_ + kTwoVoxelCells, next);
        for (std::size_t i = 0; i < crossings_.size(); ++i)
            forEachTwoVoxelCell(crossings_[i], [&](int cell) { members_[next[cell]++] = &crossings_[i]; });
    }

    /// Two-voxel cell (i, j, k) is number (i * 4 + j) * 4 + k.
    static constexpr int kTwoVoxelCells = (kLeafDim / 2) * (kLeafDim / 2) * (kLeafDim / 2);

    /// Whether every grid line through the cell of `width` at leaf-local `b` changes material at most
    /// once, the cell holds at most one solid material, and none of its faces is ambiguous.
    bool simpleTopology(const int b[3], int width) const
    {
        if (!singleMaterial_ && !singleMaterialIn(b, width)) return false;
        if (uniform(b, width)) return true; // most cells of a surface leaf hold no surface
        const uint32_t span = (1u << width) - 1;
        for (int axis = 0; axis < 3; ++axis) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            for (int i = 0; i <= width; ++i)
                for (int j = 0; j <= width; ++j) {
                    const uint32_t bits = solidLine_[axis][b[u] + i][b[v] + j] >> b[axis];
                    const uint32_t changes = (bits ^ (bits >> 1)) & span;
                    if (changes & (changes - 1)) return false; // more than one change
                }
        }
        return unambiguousFaces(b, width);
    }

    /// The normal cones of the two-voxel cells.
    void twoVoxelCones(NormalCone cones[kTwoVoxelCells]) const
    {
        for (int cell = 0; cell < kTwoVoxelCells; ++cell) {
            NormalCone& c = cones[cell];
            for (int m = memberStart_[cell]; m < memberStart_[cell + 1]; ++m) {
                for (int a = 0; a < 3; ++a) c.sum[a] += members_[m]->normal[a];
                ++c.count;
            }
            if (c.count == 0) continue;
            const double length = std::sqrt(c.sum[0] * c.sum[0] + c.sum[1] * c.sum[1] + c.sum[2] * c.sum[2]);
            double minCos = 1.0;
            for (int m = memberStart_[cell]; m < memberStart_[cell + 1]; ++m) {
                const double* n = members_[m]->normal;
                minCos = std::min(minCos, length > 0.0 ? (n[0] * c.sum[0] + n[1] * c.sum[1] + n[2] * c.sum[2]) / length : -1.0);
            }
            c.halfAngle = std::acos(std::clamp(minCos, -1.0, 1.0));
        }
    }

    /// Whether the two-voxel cell (i, j, k) holds one straight sharp edge: its crossings' normals fall
    /// into two groups, each within `cosHalfSpread` of its own mean, and the two groups' planes meet
    /// in a line through the cell. CMS puts that cell's vertex on the edge, so it needs no splitting.
    bool holdsOneSharpEdge(int i, int j, int k, double cosHalfSpread) const
    {
        const int b[3] = {2 * i, 2 * j, 2 * k};
        constexpr int kCells = kLeafDim / 2;
        const int cell = (i * kCells + j) * kCells + k;
        const Crossing* const* members = members_.data() + memberStart_[cell];
        const int count = memberStart_[cell + 1] - memberStart_[cell];
        if (count < 2) return false;
        auto dot = [](const double* a, const double* c) { return a[0] * c[0] + a[1] * c[1] + a[2] * c[2]; };
        const double* seed[2] = {members[0]->normal, members[0]->normal};
        for (int m = 1; m < count; ++m)
            if (dot(members[m]->normal, seed[0]) < dot(seed[1], seed[0])) seed[1] = members[m]->normal;
        double mean[2][3] = {};
        // A two-voxel cell holds at most 54 voxel edges (18 per axis).
        std::array<uint8_t, 54> group;
        if (count > int(group.size())) return false;
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
            const Eigen::Vector3d p(members[m]->position[0], members[m]->position[1], members[m]->position[2]);
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

private:
    struct Crossing {
        int at[3];
        int axis;
        double normal[3];
        double position[3]; // leaf-local voxel units
    };

    MaterialId material(const int v[3]) const { return grid_.at(v[0], v[1], v[2]).id; }

    /// Calls fn(cell) for each two-voxel cell that holds the crossing's voxel edge.
    template<typename Fn>
    static void forEachTwoVoxelCell(const Crossing& x, Fn&& fn)
    {
        constexpr int kCells = kLeafDim / 2;
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const int at = x.at[a];
            if (a == x.axis || at % 2 == 1) {
                lo[a] = hi[a] = std::min(kCells - 1, at / 2);
            } else { // on the boundary between two cells (or on the leaf's face)
                lo[a] = std::max(0, at / 2 - 1);
                hi[a] = std::min(kCells - 1, at / 2);
            }
        }
        for (int i = lo[0]; i <= hi[0]; ++i)
            for (int j = lo[1]; j <= hi[1]; ++j)
                for (int k = lo[2]; k <= hi[2]; ++k) fn((i * kCells + j) * kCells + k);
    }

    /// Whether the cell's lattice points are all solid or all empty, from its lines along z.
    bool uniform(const int b[3], int width) const
    {
        const uint32_t points = (1u << (width + 1)) - 1;
        const uint32_t first = (solidLine_[2][b[0]][b[1]] >> b[2]) & points;
        if (first != 0 && first != points) return false;
        for (int i = 0; i <= width; ++i)
            for (int j = 0; j <= width; ++j)
                if (((solidLine_[2][b[0] + i][b[1] + j] >> b[2]) & points) != first) return false;
        return true;
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

    bool unambiguousFaces(const int b[3], int width) const
    {
        unsigned solidCorners = 0;
        for (int c = 0; c < 8; ++c) {
            const int v[3] = {b[0] + width * cornerBit(c, 0), b[1] + width * cornerBit(c, 1), b[2] + width * cornerBit(c, 2)};
            if (material(v) != kEmptyMaterial) solidCorners |= 1u << c;
        }
        return !kCellCases[solidCorners].ambiguousFace;
    }

    const CornerGrid& grid_; // the lattice's materials are the corner grid's o .. o+8
    bool singleMaterial_;
    uint32_t solidLine_[3][kLattice][kLattice];
    std::vector<Crossing> crossings_;
    std::vector<const Crossing*> members_;
    int memberStart_[kTwoVoxelCells + 1];
};

} // namespace

LeafCellSizes subdivideLeaf(const CornerGrid& grid, const Neighbourhood& hood, const SubdivisionCriteria& criteria)
{
    LeafCellSizes sizes{};
    if (criteria.maxCellSize <= 1) return sizes;
    const LeafLattice lattice(grid, hood);
    const double halfSpread = std::acos(std::clamp(criteria.cosHalfSpread, -1.0, 1.0));
    // whole[level][x][y][z]: whether the cell of width 2^level at (x, y, z) * 2^level stays whole,
    // with its normals' cone.
    bool whole[4][kLeafDim][kLeafDim][kLeafDim] = {};
    // Normal cones of the cells of width 2, 4 and 8, at (x * count + y) * count + z with count = 8 >> level.
    NormalCone twoVoxel[64], fourVoxel[8], eightVoxel[1];
    NormalCone* const cones[4] = {nullptr, twoVoxel, fourVoxel, eightVoxel};
    lattice.twoVoxelCones(twoVoxel);
    for (int x = 0; x < kLeafDim; ++x)
        for (int y = 0; y < kLeafDim; ++y)
            for (int z = 0; z < kLeafDim; ++z) whole[0][x][y][z] = true;
    int finest = 0;
    for (int level = 1; (1 << level) <= criteria.maxCellSize && level <= 3; ++level) {
        const int width = 1 << level, count = kLeafDim >> level;
        bool any = false;
        for (int x = 0; x < count; ++x)
            for (int y = 0; y < count; ++y)
                for (int z = 0; z < count; ++z) {
                    bool& keep = whole[level][x][y][z];
                    keep = true;
                    for (int c = 0; c < 8 && keep && level > 1; ++c) // every voxel cell is whole
                        keep = whole[level - 1][2 * x + cornerBit(c, 0)][2 * y + cornerBit(c, 1)][2 * z + cornerBit(c, 2)];
                    const int b[3] = {x * width, y * width, z * width};
                    if (!keep || !lattice.simpleTopology(b, width)) {
                        keep = false;
                        continue;
                    }
                    NormalCone& cone = cones[level][(x * count + y) * count + z];
                    if (level > 1) {
                        auto childCone = [&](int c) -> const NormalCone& {
                            const int childCount = 2 * count;
                            const int cx = 2 * x + cornerBit(c, 0), cy = 2 * y + cornerBit(c, 1), cz = 2 * z + cornerBit(c, 2);
                            return cones[level - 1][(cx * childCount + cy) * childCount + cz];
                        };
                        for (int c = 0; c < 8; ++c) {
                            for (int k = 0; k < 3; ++k) cone.sum[k] += childCone(c).sum[k];
                            cone.count += childCone(c).count;
                        }
                        for (int c = 0; c < 8; ++c) {
                            const NormalCone& child = childCone(c);
                            if (child.count == 0) continue;
                            cone.halfAngle = std::max(cone.halfAngle, NormalCone::angleBetween(child.sum, cone.sum) + child.halfAngle);
                        }
                    }
                    keep = cone.halfAngle <= halfSpread ||
                           (level == 1 && lattice.holdsOneSharpEdge(x, y, z, criteria.cosHalfSpread));
                    any = any || keep;
                }
        if (!any) break;
        finest = level;
    }
    // Each voxel cell takes the widest whole cell containing it; the eight voxel cells of a two-voxel
    // cell share every cell wider than one voxel.
    for (int x = 0; x < kLeafDim; x += 2)
        for (int y = 0; y < kLeafDim; y += 2)
            for (int z = 0; z < kLeafDim; z += 2) {
                int level = finest;
                while (level > 0 && !whole[level][x >> level][y >> level][z >> level]) --level;
                for (int c = 0; c < 8; ++c)
                    sizes.log2Width[x + cornerBit(c, 0)][y + cornerBit(c, 1)][z + cornerBit(c, 2)] = uint8_t(level);
            }
    return sizes;
}

} // namespace vdbclay::mesher_detail
