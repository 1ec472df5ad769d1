// Internal to the mesher: the numbering of a cubical cell's corners, faces and edges, and the loops
// marching squares on its six faces make for each of the 256 corner cases. Plain constexpr data, no
// OpenVDB.
#pragma once

#include <array>
#include <cstdint>

namespace vdbclay::mesher_detail {

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

/// Face f has normal axis f / 2 and lies on the cell's low (f even) or high (f odd) side.
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

/// What marching squares on the six faces of a cell make of one solid-corner mask. Walking each face
/// counter-clockwise seen from outside, a segment runs from the crossing where the walk enters the
/// solid to the next crossing, where it leaves; the segments link into closed loops of cell edges.
/// On an ambiguous face (two solid corners on a diagonal) this separates the solid corners, which is
/// Marching Cubes' choice; Cubical Marching Squares lets the crossings' geometry decide there instead.
struct CellCase {
    bool ambiguousFace = false;
    uint8_t loopCount = 0;
    uint8_t loopEnd[4] = {};      // loop k is edges[loopEnd[k - 1] .. loopEnd[k]), loopEnd[-1] = 0
    uint8_t edges[12] = {};       // each loop's cell edges in walk order
    uint8_t segmentAxis[12] = {}; // the normal axis of the face whose segment runs from edges[i] to the next
    /// Per loop, the position to fan it from whose diagonals all cross the cell's inside, or -1 where
    /// every position has a diagonal between two crossings of one face (see fanApexOf).
    int8_t fanApex[4] = {};
};

/// Whether two cell edges lie on one face of the cell.
constexpr bool edgesShareFace(int e1, int e2)
{
    for (int axis = 0; axis < 3; ++axis) {
        if (e1 / 4 == axis || e2 / 4 == axis) continue;
        if (cornerBit(edgeLowCorner(e1), axis) == cornerBit(edgeLowCorner(e2), axis)) return true;
    }
    return false;
}

/// A diagonal of a fan between two crossings of one face (a loop that visits an ambiguous face twice)
/// lies in that face, where the cell beside it can fan the same edge: four triangles on one edge.
constexpr int8_t fanApexOf(const uint8_t* edges, int size)
{
    for (int k = 0; k < size; ++k) {
        bool clear = true;
        for (int j = 0; j < size && clear; ++j) {
            const int gap = (j - k + size) % size;
            if (gap > 1 && gap < size - 1) clear = !edgesShareFace(edges[k], edges[j]);
        }
        if (clear) return int8_t(k);
    }
    return -1;
}

/// Loops are listed as the face walk finds them: faces in order, each loop starting at the first
/// segment not yet in a loop.
constexpr CellCase makeCellCase(unsigned solidMask)
{
    CellCase cell;
    int next[12] = {}, axisOf[12] = {}, found[12] = {}, segmentCount = 0;
    for (int f = 0; f < 6; ++f) {
        int sides[4] = {}, count = 0;
        bool entering[4] = {};
        for (int i = 0; i < 4; ++i) {
            const int p = kFaces[f].corners[i], q = kFaces[f].corners[(i + 1) % 4];
            const bool solidP = (solidMask >> p) & 1u, solidQ = (solidMask >> q) & 1u;
            if (solidP == solidQ) continue;
            sides[count] = cellEdge(p, q);
            entering[count] = solidQ;
            ++count;
        }
        if (count == 4) cell.ambiguousFace = true;
        for (int i = 0; i < count; ++i) {
            if (!entering[i]) continue;
            next[sides[i]] = sides[(i + 1) % count];
            axisOf[sides[i]] = f / 2;
            found[segmentCount++] = sides[i];
        }
    }
    bool used[12] = {};
    int size = 0;
    for (int s = 0; s < segmentCount; ++s) {
        if (used[found[s]]) continue;
        for (int e = found[s]; !used[e]; e = next[e]) {
            used[e] = true;
            cell.edges[size] = uint8_t(e);
            cell.segmentAxis[size] = uint8_t(axisOf[e]);
            ++size;
        }
        const int begin = cell.loopCount ? cell.loopEnd[cell.loopCount - 1] : 0;
        cell.fanApex[cell.loopCount] = fanApexOf(cell.edges + begin, size - begin);
        cell.loopEnd[cell.loopCount++] = uint8_t(size);
    }
    return cell;
}

inline constexpr std::array<CellCase, 256> kCellCases = [] {
    std::array<CellCase, 256> cases{};
    for (unsigned mask = 0; mask < 256; ++mask) cases[mask] = makeCellCase(mask);
    return cases;
}();

} // namespace vdbclay::mesher_detail
