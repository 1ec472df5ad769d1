#include "mesher/CellOctree.h"

#include <cmath>

namespace vdbclay::mesher_detail {

namespace {

constexpr int kLattice = kLeafDim + 1; // voxels o .. o+8 per axis

/// A leaf's voxel lattice (o .. o+8) with the normals of its crossings, read once per leaf.
class LeafLattice {
public:
    LeafLattice(const CornerGrid& grid, const Neighbourhood& hood)
    {
        for (int x = 0; x < kLattice; ++x)
            for (int y = 0; y < kLattice; ++y)
                for (int z = 0; z < kLattice; ++z) material_[x][y][z] = grid.at(x, y, z).id;
        for (int axis = 0; axis < 3; ++axis)
            for (int x = 0; x < kLattice; ++x)
                for (int y = 0; y < kLattice; ++y)
                    for (int z = 0; z < kLattice; ++z) {
                        int v[3] = {x, y, z};
                        crossed_[axis][x][y][z] = false;
                        if (v[axis] == kLeafDim) continue;
                        const bool low = material_[x][y][z] != kEmptyMaterial;
                        ++v[axis];
                        const bool high = material_[v[0]][v[1]][v[2]] != kEmptyMaterial;
                        if (low == high) continue;
                        const PackedSample* s = hood.sample(grid.origin.offsetBy(x, y, z), axis);
                        if (!s) continue;
                        const auto n = unpackSample(*s).normal;
                        crossed_[axis][x][y][z] = true;
                        for (int k = 0; k < 3; ++k) normal_[axis][x][y][z][k] = n[k];
                    }
    }

    /// Whether the cell of `width` at leaf-local `b` can stay whole (see subdivideLeaf).
    bool simple(const int b[3], int width, double cosHalfSpread) const
    {
        return singleChangeLines(b, width) && unambiguousFaces(b, width) && narrowNormals(b, width, cosHalfSpread);
    }

private:
    MaterialId material(const int v[3]) const { return material_[v[0]][v[1]][v[2]]; }

    bool singleChangeLines(const int b[3], int width) const
    {
        MaterialId solid = kEmptyMaterial;
        for (int axis = 0; axis < 3; ++axis) {
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            for (int i = 0; i <= width; ++i) {
                for (int j = 0; j <= width; ++j) {
                    int v[3];
                    v[axis] = b[axis];
                    v[u] = b[u] + i;
                    v[w] = b[w] + j;
                    MaterialId previous = material(v);
                    int changes = 0;
                    for (int t = 1; t <= width; ++t) {
                        ++v[axis];
                        const MaterialId m = material(v);
                        if (m != kEmptyMaterial) {
                            if (solid == kEmptyMaterial) solid = m;
                            else if (m != solid) return false;
                        }
                        if (m != previous && ++changes > 1) return false;
                        previous = m;
                    }
                }
            }
        }
        return true;
    }

    bool unambiguousFaces(const int b[3], int width) const
    {
        for (int f = 0; f < 6; ++f) {
            bool solid[4];
            for (int i = 0; i < 4; ++i) {
                const int c = kFaces[f].corners[i];
                const int v[3] = {b[0] + width * cornerBit(c, 0), b[1] + width * cornerBit(c, 1),
                                  b[2] + width * cornerBit(c, 2)};
                solid[i] = material(v) != kEmptyMaterial;
            }
            if (solid[0] == solid[2] && solid[1] == solid[3] && solid[0] != solid[1]) return false;
        }
        return true;
    }

    template<typename Fn>
    void forEachNormal(const int b[3], int width, Fn&& fn) const
    {
        for (int axis = 0; axis < 3; ++axis) {
            int hi[3] = {b[0] + width, b[1] + width, b[2] + width};
            hi[axis] -= 1; // edges along `axis` start before the far face
            for (int x = b[0]; x <= hi[0]; ++x)
                for (int y = b[1]; y <= hi[1]; ++y)
                    for (int z = b[2]; z <= hi[2]; ++z)
                        if (crossed_[axis][x][y][z]) fn(normal_[axis][x][y][z]);
        }
    }

    bool narrowNormals(const int b[3], int width, double cosHalfSpread) const
    {
        double sum[3] = {0.0, 0.0, 0.0};
        forEachNormal(b, width, [&](const float* n) {
            for (int k = 0; k < 3; ++k) sum[k] += n[k];
        });
        const double length = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
        if (length == 0.0) return true; // no crossings, or normals that cancel (caught by the lines)
        bool narrow = true;
        forEachNormal(b, width, [&](const float* n) {
            if ((n[0] * sum[0] + n[1] * sum[1] + n[2] * sum[2]) < cosHalfSpread * length) narrow = false;
        });
        return narrow;
    }

    MaterialId material_[kLattice][kLattice][kLattice];
    bool crossed_[3][kLattice][kLattice][kLattice];
    float normal_[3][kLattice][kLattice][kLattice][3];
};

} // namespace

LeafCellSizes subdivideLeaf(const CornerGrid& grid, const Neighbourhood& hood, const SubdivisionCriteria& criteria)
{
    LeafCellSizes sizes{};
    if (criteria.maxCellSize <= 1) return sizes;
    const LeafLattice lattice(grid, hood);
    // whole[level][x][y][z]: whether the cell of width 2^level at (x, y, z) * 2^level stays whole.
    bool whole[4][kLeafDim][kLeafDim][kLeafDim] = {};
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
                    bool children = true;
                    for (int c = 0; c < 8 && children; ++c)
                        children = whole[level - 1][2 * x + cornerBit(c, 0)][2 * y + cornerBit(c, 1)][2 * z + cornerBit(c, 2)];
                    const int b[3] = {x * width, y * width, z * width};
                    whole[level][x][y][z] = children && lattice.simple(b, width, criteria.cosHalfSpread);
                    any = any || whole[level][x][y][z];
                }
        if (!any) break;
        finest = level;
    }
    // Each voxel cell takes the widest whole cell containing it.
    for (int x = 0; x < kLeafDim; ++x)
        for (int y = 0; y < kLeafDim; ++y)
            for (int z = 0; z < kLeafDim; ++z) {
                int level = finest;
                while (level > 0 && !whole[level][x >> level][y >> level][z >> level]) --level;
                sizes.log2Width[x][y][z] = uint8_t(level);
            }
    return sizes;
}

} // namespace vdbclay::mesher_detail
