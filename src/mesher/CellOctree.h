// Internal to the mesher: the adaptive cells of Cubical Marching Squares (seed 000 §5). Each leaf is
// an octree of cells 8, 4, 2 and 1 voxels wide; a cell stays whole only while the surface inside it is
// simple enough for one cell to carry it. OpenVDB-heavy: include only from mesher .cpp files.
#pragma once

#include "mesher/CellGrid.h"

#include <cstdint>

namespace vdbclay::mesher_detail {

struct SubdivisionCriteria {
    int maxCellSize = 8;        // 1, 2, 4 or 8 voxels
    double cosHalfSpread = 1.0; // a cell splits when a crossing normal lies further than half the
                                // spread angle from the cell's mean normal
    double planeTolerance = 0.0; // voxels; > 0: a cell whose normals spread wider stays whole when
                                 // its crossings lie this close to one plane (see subdivideLeaf)
};

/// The cells of one leaf, aligned to their width. A cell wider than a voxel covers whole two-voxel
/// blocks and voxel cells come eight to a block, so the widths are kept per two-voxel block (128 bytes
/// a leaf, which keeps a large scene's cells in cache).
struct LeafCellSizes {
    static constexpr int kBlocks = kLeafDim / 2;
    uint8_t blockLog2Width[kBlocks][kBlocks][kBlocks]; // log2 of the width of the cells in each block
    uint8_t cellStarts[kLeafDim][kLeafDim];            // bit z: a cell has its minimum corner at (x, y, z)

    /// The width of the cell containing the voxel cell at leaf-local (x, y, z).
    int widthAt(int x, int y, int z) const { return 1 << blockLog2Width[x >> 1][y >> 1][z >> 1]; }
};

/// Merges cells bottom-up: a cell wider than one voxel stays whole when its eight children stayed
/// whole and
///  - every grid line through it (along x, y or z) changes material at most once, so each of its
///    edges has at most one crossing and no face or interior hides surface its corners do not show;
///  - it holds at most one solid material (material boundaries are meshed at voxel resolution);
///  - none of its faces is ambiguous (two solid corners on a diagonal);
///  - its crossings' normals lie within half the criteria's angle of their mean (bounded from its
///    children's cones above two voxels, so a cell may split where an exact test would not), or, for
///    a two-voxel cell, they form two such groups whose planes meet in a line through the cell: one
///    straight sharp edge, which the cell's vertex reproduces; or, with a plane tolerance, its
///    crossings lie within that distance of the plane through their centroid across their mean
///    normal and their normals within a right angle of it (a height field over that plane: ripples
///    that tilt the normals without moving the surface, as coarse levels of detail carry).
LeafCellSizes subdivideLeaf(const CornerGrid& grid, const Neighbourhood& hood, const SubdivisionCriteria& criteria);

/// The cell widths around one leaf: its own cells and those of its six face neighbours, which is
/// all a cell face of the leaf can touch. Blocks without subdivision (tiles) hold one-voxel cells.
class CellWidthField {
public:
    /// `blocks`: the leaf's own cells, then the -x, +x, -y, +y, -z, +z neighbours' (null: one-voxel cells).
    CellWidthField(const Coord& origin, const LeafCellSizes* const blocks[7]) : origin_(origin)
    {
        for (int i = 0; i < 7; ++i) blocks_[i] = blocks[i];
    }

    /// The width of the cell containing the voxel cell at `c`, which lies in the leaf or a face neighbour.
    int widthAt(const Coord& c) const
    {
        int local[3], slot = 0;
        for (int a = 0; a < 3; ++a) {
            const int d = c[a] - origin_[a];
            const int block = d < 0 ? -1 : (d >= kLeafDim ? 1 : 0);
            local[a] = d - block * kLeafDim;
            if (block != 0) slot = 1 + 2 * a + (block > 0);
        }
        const LeafCellSizes* sizes = blocks_[slot];
        return sizes ? sizes->widthAt(local[0], local[1], local[2]) : 1;
    }

    const LeafCellSizes* own() const { return blocks_[0]; }

private:
    Coord origin_;
    const LeafCellSizes* blocks_[7];
};

} // namespace vdbclay::mesher_detail
