// Cubical Marching Squares (Ho et al., seed 000; seed 004 §2.6 and §4.2.2) over Hermite data, on
// voxel cells or on the adaptive cells of CellOctree.h.
//
// Each face of a cell is meshed on its own by marching squares. A face segment whose two crossings'
// normals span more than the sharp angle gets a 2D sharp feature: the point where the crossings'
// tangent lines meet, when it lies on the face. The only segment of a face may instead follow a wedge
// that pokes out through a side of the face between that side's corners (tipChain). On an ambiguous
// face (two solid corners on a diagonal) the segments that cut off each solid corner are used unless
// their sharp features make them cross, or unless they join crossings whose normals disagree with no
// sharp feature on the face while the other pairing's do not; then the other pairing is. Segments are
// linked into components; each component gets one inner vertex, the least-squares point of its
// crossing planes (truncated SVD, clamped to the cell grown to the component's face points) when its
// normals span the sharp angle, else the mean of its vertices, and is fanned from it (a corner that
// planes read around the cell make is taken only on the cell's own edge line). A fan with a triangle
// that folds back against the surface's normals at both of its loop points, or against the sheet nearer
// its centroid (a concave crease's planes can put the point where) gets a centre nearer the mean point,
// or else the loop is triangulated without one, its diagonals chosen so that none folds (never between
// points that may share a cell face, so neighbouring cells cannot both draw one). A concave crease's
// sharp fan that leans back past either loop point's normal is triangulated that way too (LoopFan.h).
// A face's segments and sharp points depend on the face alone, so neighbouring cells agree on them
// and the welded mesh is watertight.
//
// Adaptive cells: a cell face is meshed as the squares of the finer of the two cells sharing it (a
// wide face beside narrower cells is split into their faces), so both cells walk the same squares and
// no crack opens between cells of different widths. A wide cell's edge has at most one crossing, which
// is the crossing of the voxel edge where its material changes: the same point, with the same key, at
// every width.
#include "mesher/CellGrid.h"
#include "mesher/LoopFan.h"
#include "mesher/CellOctree.h"
#include "mesher/MeshMetrics.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>
#include <utility>
#include <unordered_map>

namespace vdbclay::mesher_detail {

namespace {

struct Vec2 {
    double x, y;
};

double cross2(const Vec2& a, const Vec2& b) { return a.x * b.y - a.y * b.x; }
Vec2 sub2(const Vec2& a, const Vec2& b) { return {a.x - b.x, a.y - b.y}; }

/// Whether segments ab and cd properly intersect (touching end points do not count).
bool segmentsCross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d)
{
    const double d1 = cross2(sub2(b, a), sub2(c, a)), d2 = cross2(sub2(b, a), sub2(d, a));
    const double d3 = cross2(sub2(d, c), sub2(a, c)), d4 = cross2(sub2(d, c), sub2(b, c));
    return ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0));
}

double pointSegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b)
{
    const Vec2 ab = sub2(b, a), ap = sub2(p, a);
    const double length2 = ab.x * ab.x + ab.y * ab.y;
    const double t = length2 > 0.0 ? std::clamp((ap.x * ab.x + ap.y * ab.y) / length2, 0.0, 1.0) : 0.0;
    return std::hypot(ap.x - t * ab.x, ap.y - t * ab.y);
}

/// A vertex inside a face segment: its 2D sharp feature, or a material transition (where the
/// tangent line of a material interface on the face meets the segment, seed 004 Algorithm 2).
struct FacePoint {
    Vec2 onFace;
    std::array<double, 3> position;
    uint64_t key;
    bool transition;
    MaterialId materialBefore;             // transitions: the material up to here, in walk order
    MaterialId materialAfter;              // transitions: the material from here on
    std::array<float, 3> interfaceNormal;  // transitions: the material interface's normal
};

/// The points inside one face segment, in order from its entering crossing: at most a sharp feature
/// and two transitions (a run cut off by one segment has at most three solid corners).
struct SegmentPoints {
    FacePoint items[4];
    int count = 0;

    void insert(int at, const FacePoint& p)
    {
        for (int k = count; k > at; --k) items[k] = items[k - 1];
        items[at] = p;
        ++count;
    }
};

/// A segment on one face square, from the crossing where the walk enters the solid to the one where
/// it leaves, with the points inside it.
struct Segment {
    Segment(const EdgeCrossing& enter, const EdgeCrossing& leave) : in(enter), out(leave) {}

    const EdgeCrossing &in, &out; // in the leaf's crossing cache
    SegmentPoints points; // its items stay uninitialised until inserted
};

/// Appends a copy of a segment, walked the other way when `reversed`.
void appendSegment(std::vector<Segment>& to, const Segment& from, bool reversed)
{
    Segment& copy = reversed ? to.emplace_back(from.out, from.in) : to.emplace_back(from.in, from.out);
    const int n = from.points.count;
    copy.points.count = n;
    for (int k = 0; k < n; ++k) {
        FacePoint& point = copy.points.items[k] = from.points.items[reversed ? n - 1 - k : k];
        if (reversed) std::swap(point.materialBefore, point.materialAfter);
    }
}

/// The axes spanning a face with normal `axis`, in cyclic order.
constexpr int kFaceAxes[3][2] = {{1, 2}, {2, 0}, {0, 1}};

/// A vector's coordinates on a face with normal `axis`.
template<typename T>
Vec2 project(const std::array<T, 3>& v, int axis)
{
    return {v[kFaceAxes[axis][0]], v[kFaceAxes[axis][1]]};
}

Vec2 normalized(const Vec2& v)
{
    const double length = std::sqrt(v.x * v.x + v.y * v.y);
    return {v.x / length, v.y / length};
}

template<typename T>
double normalDot(const std::array<T, 3>& a, const std::array<T, 3>& b)
{
    return double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
}

/// The least length of a crossing's normal projected onto a face for its tangent line there to take part
/// in a 2D sharp feature: a surface within 3 degrees of the face's plane (a cylinder's side tangent to a
/// lattice plane, its rim on another) has no direction on it that its normal's rounding does not swing.
constexpr double kMinFaceNormal = 0.05;

/// Whether the normals at the two ends of a segment on a face with normal `axis`, projected onto the
/// face, span the sharp angle there, and so do the normals themselves: the segment is then a candidate
/// for a 2D sharp feature. A normal (nearly) along the axis has no direction on the face, and a surface
/// nearly parallel to the face turns its normals' small differences into wide angles on it: a feature
/// the surface does not have, whose fan folds.
template<typename T>
bool segmentBends(const std::array<T, 3>& normalA, const std::array<T, 3>& normalB, int axis, double cosSharp)
{
    if (normalDot(normalA, normalB) > cosSharp * std::sqrt(normalDot(normalA, normalA) * normalDot(normalB, normalB))) return false;
    const Vec2 a = project(normalA, axis), b = project(normalB, axis);
    const double aa = a.x * a.x + a.y * a.y, bb = b.x * b.x + b.y * b.y;
    if (aa < kMinFaceNormal * kMinFaceNormal || bb < kMinFaceNormal * kMinFaceNormal) return false;
    return a.x * b.x + a.y * b.y <= cosSharp * std::sqrt(aa * bb);
}

template<typename T>
void accumulate(std::array<double, 3>& sum, const std::array<T, 3>& v)
{
    for (int k = 0; k < 3; ++k) sum[k] += v[k];
}

} // namespace

/// Sharp feature points keep this far (in voxels) inside their square or cell, so that points of
/// neighbouring squares and cells never meet on a shared side. Under half the crossings' corner margin
/// (kOffsetMarginCode, 2.4e-4), ten times the distance below which analyzeTopology merges vertices.
constexpr double kFeatureInsetVoxels = 1e-4;
/// How far (in voxels) a corner found from the crossings around a cell may lie from the line of the
/// cell's own sharp edge.
constexpr double kCornerOffEdgeVoxels = 0.1;
/// How far apart two wedge chains reaching into one clear band from opposite sides stay at least.
constexpr double kBandGapVoxels = 1e-2;


/// Buffers reused from cell to cell and leaf to leaf.
struct CubicalMarchingSquaresMesher::Buffers {
    // The chunk being built; copied out when the leaf is done.
    MeshChunk chunk;
    // Vertex index of each voxel edge whose lower end lies in o-1 .. o+8 (per axis) of the leaf at
    // origin o, and of the face points; both cleared per leaf.
    static constexpr int kSpan = CornerGrid::kSpan;
    static constexpr uint32_t kNone = ~uint32_t(0);
    uint32_t edgeVertex[kSpan * kSpan * kSpan * 3];
    // Decoded crossings by the same slots (index into `crossings`), as up to four cells read each.
    // `crossings` is reserved for every slot, so references into it stay valid for the whole leaf.
    uint32_t edgeCrossing[kSpan * kSpan * kSpan * 3];
    std::vector<EdgeCrossing> crossings;
    std::vector<uint32_t> usedEdgeSlots;
    // The segments of each face square, by the slot of its minimum corner and normal axis, as meshed
    // by the first cell that reached it; the cell on its other side reuses them reversed.
    struct SquareRecord {
        uint32_t first = kNone; // into squareSegments
        uint16_t count = 0;
        uint8_t side = 0;  // of the face for the cell that meshed it
        uint8_t width = 0; // in voxels
    };
    SquareRecord squares[kSpan * kSpan * kSpan * 3];
    std::vector<Segment> squareSegments;
    std::vector<uint32_t> usedSquareSlots;
    std::unordered_map<uint64_t, uint32_t> otherVertices;
    // Per cell.
    std::vector<Segment> segments;
    std::vector<int> loop;
    std::vector<uint32_t> ids;
    // Which voxels o-2 .. o+10 (per axis) are solid, bit z of row [x][y]: every voxel the scans for sharp
    // features read. Filled on a leaf's first sharp feature.
    static constexpr int kAroundLow = kMeshingReach.low; // leaf-local coordinate of index 0
    static constexpr int kAroundSpan = kMeshingReach.high - kMeshingReach.low + 1;
    uint32_t solidAround[kAroundSpan][kAroundSpan];
    bool solidAroundReady = false;
    std::vector<MaterialId> pieceMaterials;
    std::vector<bool> used;

    Buffers()
    {
        std::fill(std::begin(edgeVertex), std::end(edgeVertex), kNone);
        std::fill(std::begin(edgeCrossing), std::end(edgeCrossing), kNone);
        crossings.reserve(std::size(edgeCrossing));
    }

    void startLeaf(const Coord& origin)
    {
        chunk.leafOrigin = {origin.x(), origin.y(), origin.z()};
        Mesh& m = chunk.mesh;
        for (auto* v : {&m.positions, &m.normals}) v->clear();
        m.materials.clear();
        m.triangles.clear();
        m.triangleMaterials.clear();
        chunk.vertexKeys.clear();
        for (uint32_t slot : usedEdgeSlots) edgeVertex[slot] = edgeCrossing[slot] = kNone;
        usedEdgeSlots.clear();
        for (uint32_t slot : usedSquareSlots) squares[slot] = SquareRecord{};
        usedSquareSlots.clear();
        squareSegments.clear();
        crossings.clear();
        otherVertices.clear();
        solidAroundReady = false;
    }

    /// The slot of a voxel edge in edgeVertex, or -1 when it lies outside the leaf's span.
    static int edgeSlot(const Coord& origin, const Coord& start, int axis)
    {
        int slot = 0;
        for (int a = 0; a < 3; ++a) {
            const int d = start[a] - origin[a] + 1;
            if (d < 0 || d >= kSpan) return -1;
            slot = slot * kSpan + d;
        }
        return slot * 3 + axis;
    }

    /// The decoded crossing in a slot, decoded by `decode` on first use.
    template<typename Decode>
    const EdgeCrossing& crossingAt(int slot, Decode&& decode)
    {
        uint32_t& index = edgeCrossing[slot];
        if (index == kNone) {
            index = uint32_t(crossings.size()); // below the reserved capacity: one entry per slot at most
            crossings.push_back(decode());
            if (edgeVertex[slot] == kNone) usedEdgeSlots.push_back(uint32_t(slot));
        }
        return crossings[index];
    }

    /// The chunk's vertex for the crossing in a slot, added on first use.
    uint32_t crossingVertex(int slot, const EdgeCrossing& x)
    {
        uint32_t& index = edgeVertex[slot];
        if (index == kNone) {
            index = addVertex(x.key, x.position, x.normal, x.material);
            if (edgeCrossing[slot] == kNone) usedEdgeSlots.push_back(uint32_t(slot));
        }
        return index;
    }

    /// The chunk's vertex for a face point (or a crossing outside the leaf's span), added on first use.
    uint32_t keyedVertex(uint64_t key, const std::array<float, 3>& pos, const std::array<float, 3>& normal,
                         MaterialId material)
    {
        const auto [it, inserted] = otherVertices.try_emplace(key, 0u);
        if (inserted) it->second = addVertex(key, pos, normal, material);
        return it->second;
    }

    uint32_t addVertex(uint64_t key, const std::array<float, 3>& pos, const std::array<float, 3>& normal,
                       MaterialId material)
    {
        Mesh& mesh = chunk.mesh;
        mesh.positions.push_back(pos);
        mesh.normals.push_back(normal);
        mesh.materials.push_back(material);
        chunk.vertexKeys.push_back(key);
        return uint32_t(mesh.positions.size() - 1);
    }

    /// Closes a loop of boundary vertices (closeLoop): a fan from a new inner vertex where one is placed;
    /// triangle i, from boundary vertex i to the next, gets `materials[i]`.
    void addFan(const std::array<double, 3>& centre, const std::array<double, 3>& normalSum, const uint32_t* ids,
                const MaterialId* materials, std::size_t n, bool sharp, const CellBox& cell)
    {
        const std::optional<std::array<double, 3>> at = closeLoop(chunk.mesh, centre, normalSum, ids, materials, n, sharp, cell, fanLimits);
        if (!at) return;
        const double length = std::sqrt(normalSum[0] * normalSum[0] + normalSum[1] * normalSum[1] + normalSum[2] * normalSum[2]);
        const double scale = length > 0.0 ? 1.0 / length : 0.0;
        const uint32_t c = addVertex(kUnsharedVertex, {float((*at)[0]), float((*at)[1]), float((*at)[2])},
                                     {float(normalSum[0] * scale), float(normalSum[1] * scale), float(normalSum[2] * scale)},
                                     materials[0]);
        Mesh& mesh = chunk.mesh;
        for (std::size_t i = 0; i < n; ++i) {
            mesh.triangles.push_back({c, ids[i], ids[i + 1 < n ? i + 1 : 0]});
            mesh.triangleMaterials.push_back(materials[i]);
        }
    }

    LoopFanLimits fanLimits; // set by the mesher from its voxel size

    /// Copies the chunk into `out`; copy-assignment reuses out's vectors, and the buffers keep theirs.
    void finishLeaf(MeshChunk& out) const { out = chunk; }
};

namespace {

using Buffers = CubicalMarchingSquaresMesher::Buffers;

/// What every cell of one leaf shares.
struct LeafContext {
    const Neighbourhood& hood;
    const CornerGrid& grid;
    const CellWidthField* widths; // null: voxel cells only
    Coord origin;
    double voxelSize;
    double cosSharp;
    Buffers& buffers;
    const LodBoundary* lod = nullptr; // a brick of a level-of-detail cut: plain faces beside transition cells

    /// Whether the unit square with this minimum corner and normal is meshed plainly (LodCut::plainFace).
    bool plainSquare(const Coord& minCorner, int axis) const
    {
        return lod && lod->nearBoundary(minCorner, 2) && lod->cut->plainFace(lod->level, {minCorner.x(), minCorner.y(), minCorner.z()}, axis);
    }

    /// The material at a voxel, from the corner grid where it reaches.
    MaterialValue material(const Coord& c) const
    {
        const unsigned x = unsigned(c.x() - origin.x() + 1), y = unsigned(c.y() - origin.y() + 1),
                       z = unsigned(c.z() - origin.z() + 1);
        constexpr unsigned kSpan = CornerGrid::kSpan;
        return x < kSpan && y < kSpan && z < kSpan ? grid.cells[x][y][z] : hood.material(c);
    }

    /// Buffers::solidAround, filled from the leaves and tiles around on first use.
    const uint32_t (&solidAround() const)[Buffers::kAroundSpan][Buffers::kAroundSpan]
    {
        if (!buffers.solidAroundReady) {
            constexpr int kLow = Buffers::kAroundLow;
            for (int x = 0; x < Buffers::kAroundSpan; ++x)
                for (int y = 0; y < Buffers::kAroundSpan; ++y)
                    buffers.solidAround[x][y] = (hood.solidColumn(x + kLow, y + kLow) >> (kLeafDim + kLow)) &
                                                ((1u << Buffers::kAroundSpan) - 1);
            buffers.solidAroundReady = true;
        }
        return buffers.solidAround;
    }
};

/// The crossing on a voxel edge, decoded once per leaf; `uncached` holds it when the edge lies outside
/// the leaf's span (only the ring around an edge cell reaches that far).
template<typename Decode>
const EdgeCrossing& cachedCrossing(const LeafContext& ctx, const Coord& start, int axis, Decode&& decode,
                                   EdgeCrossing& uncached)
{
    const int slot = Buffers::edgeSlot(ctx.origin, start, axis);
    return slot < 0 ? uncached = decode() : ctx.buffers.crossingAt(slot, decode);
}

const EdgeCrossing& cachedCrossing(const LeafContext& ctx, const Coord& start, int axis, MaterialValue low,
                                   MaterialValue high, EdgeCrossing& uncached)
{
    return cachedCrossing(ctx, start, axis, [&] { return voxelEdgeCrossing(ctx.hood, start, axis, low, high, ctx.voxelSize); },
                          uncached);
}

/// The crossing on the grid edge of `length` voxels from `start` along `axis`, whose ends hold `low`
/// and `high`: the crossing of the voxel edge where the material changes (there is one, as the cells
/// that own such an edge are simple). The edges of the cells a leaf owns lie in its span, so the result
/// lives in the leaf's crossing cache.
const EdgeCrossing& crossingAlong(const LeafContext& ctx, const Coord& start, int axis, int length, MaterialValue low,
                                  MaterialValue high, EdgeCrossing& uncached)
{
    if (length == 1) return cachedCrossing(ctx, start, axis, low, high, uncached);
    Coord at = start;
    MaterialValue previous = low;
    for (int k = 1; k < length; ++k) {
        Coord next = at;
        next[axis] += 1;
        const MaterialValue m = ctx.material(next);
        if (m != previous) return cachedCrossing(ctx, at, axis, previous, m, uncached);
        at = next;
    }
    return cachedCrossing(ctx, at, axis, previous, high, uncached);
}

/// Whether the surface crosses face f of a cell: its corners are not all solid or all empty. A face
/// whose corners agree holds no crossing (a wide cell's faces are simple).
bool surfaceCrosses(const MaterialValue mats[8], int f)
{
    const int* c = kFaces[f].corners;
    const bool s0 = mats[c[0]].solid();
    return mats[c[1]].solid() != s0 || mats[c[2]].solid() != s0 || mats[c[3]].solid() != s0;
}

/// One square a cell face is meshed in: the whole face, or a face of a narrower cell beside it.
struct Square {
    int axis;         // the face's normal axis
    int width;
    Coord corners[4]; // counter-clockwise seen from outside the cell being meshed
    MaterialValue mats[4];
    Coord minCorner;
};

class CellMesher {
public:
    CellMesher(LeafContext& ctx, const Coord& base, int width, const MaterialValue mats[8])
        : ctx_(ctx), base_(base), width_(width), mats_(mats), segments_(ctx.buffers.segments)
    {
        segments_.clear();
    }

    void run()
    {
        for (int f = 0; f < 6; ++f) {
            if (!surfaceCrosses(mats_, f)) continue;
            const int axis = f / 2;
            meshFaceRegion(f, base_[(axis + 1) % 3], base_[(axis + 2) % 3], width_);
        }
        std::vector<bool>& used = ctx_.buffers.used;
        used.assign(segments_.size(), false);
        std::vector<int>& loop = ctx_.buffers.loop;
        for (std::size_t start = 0; start < segments_.size(); ++start) {
            if (used[start]) continue;
            loop.clear();
            int s = int(start);
            while (s >= 0 && !used[s]) {
                used[s] = true;
                loop.push_back(s);
                s = segmentStartingAt(segments_[s].out.key);
            }
            if (s == int(start)) emitComponent(loop);
        }
    }

private:
    int segmentStartingAt(uint64_t key) const
    {
        for (std::size_t i = 0; i < segments_.size(); ++i)
            if (segments_[i].in.key == key) return int(i);
        return -1;
    }

    /// Meshes the part (u0, v0, width) of face f, split where the cell across it is narrower.
    void meshFaceRegion(int f, int u0, int v0, int width)
    {
        const int axis = f / 2, side = f % 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
        if (width > 1 && ctx_.widths) {
            Coord across;
            across[axis] = side ? base_[axis] + width_ : base_[axis] - 1;
            across[u] = u0;
            across[v] = v0;
            if (ctx_.widths->widthAt(across) < width) {
                const int half = width / 2;
                for (int q = 0; q < 4; ++q) meshFaceRegion(f, u0 + half * (q & 1), v0 + half * (q >> 1), half);
                return;
            }
        }
        meshSharedSquare(f, u0, v0, width);
    }

    /// A face square is meshed once per leaf: its segments depend on the square alone, and the cell on
    /// its other side walks it the other way round, so it takes them reversed.
    void meshSharedSquare(int f, int u0, int v0, int width)
    {
        const int axis = f / 2, side = f % 2;
        Coord minCorner;
        minCorner[axis] = base_[axis] + side * width_;
        minCorner[(axis + 1) % 3] = u0;
        minCorner[(axis + 2) % 3] = v0;
        Buffers& b = ctx_.buffers;
        const int slot = Buffers::edgeSlot(ctx_.origin, minCorner, axis);
        if (slot >= 0 && b.squares[slot].first != Buffers::kNone && b.squares[slot].width == width) {
            const Buffers::SquareRecord& record = b.squares[slot];
            for (uint32_t i = record.first; i < record.first + record.count; ++i)
                appendSegment(segments_, b.squareSegments[i], record.side != side);
            return;
        }
        const std::size_t before = segments_.size();
        meshSquare(makeSquare(f, u0, v0, width));
        // Squares of different widths never share a minimum corner and axis: both cells split a face
        // where the finer of them does. The check above only guards that.
        if (slot < 0 || b.squares[slot].first != Buffers::kNone) return;
        b.squares[slot] = {uint32_t(b.squareSegments.size()), uint16_t(segments_.size() - before), uint8_t(side),
                           uint8_t(width)};
        b.usedSquareSlots.push_back(uint32_t(slot));
        for (std::size_t i = before; i < segments_.size(); ++i) appendSegment(b.squareSegments, segments_[i], false);
    }

    Square makeSquare(int f, int u0, int v0, int width) const
    {
        const int axis = f / 2, side = f % 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
        Square sq;
        sq.axis = axis;
        sq.width = width;
        const bool wholeFace = width == width_;
        for (int i = 0; i < 4; ++i) {
            const int c = kFaces[f].corners[i];
            Coord& p = sq.corners[i];
            p[axis] = base_[axis] + side * width_;
            p[u] = u0 + width * cornerBit(c, u);
            p[v] = v0 + width * cornerBit(c, v);
            sq.mats[i] = wholeFace ? mats_[c] : ctx_.material(p);
        }
        sq.minCorner[axis] = base_[axis] + side * width_;
        sq.minCorner[u] = u0;
        sq.minCorner[v] = v0;
        return sq;
    }

    /// The crossing on side i of the square (from its corner i to corner i + 1).
    const EdgeCrossing& squareCrossing(const Square& sq, int i)
    {
        if (!squareCrossings_[i]) {
            const int j = (i + 1) % 4;
            const Coord &p = sq.corners[i], &q = sq.corners[j];
            const int axis = p[0] != q[0] ? 0 : (p[1] != q[1] ? 1 : 2);
            const bool forward = p[axis] < q[axis];
            EdgeCrossing uncached;
            const EdgeCrossing& x = crossingAlong(ctx_, forward ? p : q, axis, sq.width, sq.mats[forward ? i : j],
                                                  sq.mats[forward ? j : i], uncached);
            if (&x == &uncached) throw std::logic_error("CMS: a cell edge lies outside its leaf's span");
            squareCrossings_[i] = &x;
        }
        return *squareCrossings_[i];
    }

    /// The shape of a segment between two crossings of a square: the points between them.
    struct SegmentShape {
        static constexpr int kMaxPoints = 4;
        Vec2 points[kMaxPoints]; // in order from the segment's first crossing to its second
        int count = 0;
        bool plausible = true; // false: the normals span the sharp angle but give no point to bend at

        /// The 2D sharp feature of a segment on an ambiguous square, which has at most one point.
        std::optional<Vec2> sharp() const { return count ? std::optional<Vec2>(points[0]) : std::nullopt; }
    };

    /// A crossing in a face's plane. Off its edge's axis it lies exactly on lattice lines (its float
    /// position rounds up to ~1e-4 voxel off them far from the origin at voxel sizes that are not
    /// whole), so a square's sides never cut off the crossings on them.
    Vec2 onFace(const EdgeCrossing& c, int axis) const
    {
        std::array<double, 3> p;
        for (int k = 0; k < 3; ++k) p[std::size_t(k)] = k == c.axis ? double(c.position[std::size_t(k)]) : c.start[k] * ctx_.voxelSize;
        return project(p, axis);
    }

    /// A segment has a 2D sharp feature where its crossings' tangent lines meet, if their normals span
    /// the sharp angle and the point lies on the square. Solved with the crossings in key order, so
    /// both cells sharing the square get the same bits. The only segment of a square of one material
    /// may also reach past the square, to the tip of a wedge that pokes out through a side (tipChain).
    SegmentShape segmentShape(const EdgeCrossing& first, const EdgeCrossing& second, const Square& sq,
                              bool onlySegment) const
    {
        const bool ordered = first.key < second.key;
        const EdgeCrossing& a = ordered ? first : second;
        const EdgeCrossing& b = ordered ? second : first;
        const int axis = sq.axis;
        if (!segmentBends(a.normal, b.normal, axis, ctx_.cosSharp)) return {};
        const Vec2 na = normalized(project(a.normal, axis)), nb = normalized(project(b.normal, axis));
        const double det = cross2(na, nb);
        SegmentShape shape;
        shape.plausible = false;
        if (std::fabs(det) < 1e-9) return shape;
        const Vec2 pa = onFace(a, axis), pb = onFace(b, axis);
        const double ca = na.x * pa.x + na.y * pa.y, cb = nb.x * pb.x + nb.y * pb.y;
        const Vec2 p{(ca * nb.y - cb * na.y) / det, (na.x * cb - nb.x * ca) / det};
        // Only a convex corner of the solid can poke out past the square as a wedge: each crossing lies
        // inside the other's half-plane. A concave one (the valley where two stamps meet) is kept inside.
        const bool convex = nb.x * pa.x + nb.y * pa.y < cb && na.x * pb.x + na.y * pb.y < ca;
        if (onlySegment && convex && !mixedMaterials(sq)) {
            shape.count = tipChain(sq, {pa, na, ca}, {pb, nb, cb}, p, shape.points);
            shape.plausible = shape.count > 0;
            if (!ordered) std::reverse(shape.points, shape.points + shape.count);
            return shape;
        }
        const double vs = ctx_.voxelSize, extent = sq.width * vs;
        const double lo0 = sq.minCorner[(axis + 1) % 3] * vs, lo1 = sq.minCorner[(axis + 2) % 3] * vs;
        // Strictly inside the square: a point on its side or corner would coincide with the points of
        // the squares around that side (a cone's apex on a lattice line gives each of them one there).
        const double inset = kFeatureInsetVoxels * vs;
        if (p.x > lo0 + inset && p.x < lo0 + extent - inset && p.y > lo1 + inset && p.y < lo1 + extent - inset) {
            shape.points[shape.count++] = p;
            shape.plausible = true;
        }
        return shape;
    }

    /// A convex polygon in a face's plane; each vertex remembers whether it is one of the two crossings.
    struct FacePolygon {
        static constexpr int kCapacity = 24;
        Vec2 at[kCapacity];
        int crossing[kCapacity]; // 0 or 1: that crossing; -1: a point between them
        int count = 0;

        /// Keeps the part where n.x <= d; false when the polygon would outgrow its capacity.
        bool clip(const Vec2& n, double d)
        {
            bool cuts = false;
            for (int i = 0; i < count && !cuts; ++i) cuts = n.x * at[i].x + n.y * at[i].y > d;
            if (!cuts) return true;
            FacePolygon kept;
            for (int i = 0; i < count; ++i) {
                const int j = (i + 1) % count;
                const double si = n.x * at[i].x + n.y * at[i].y - d, sj = n.x * at[j].x + n.y * at[j].y - d;
                if (si <= 0.0) {
                    if (kept.count == kCapacity) return false;
                    kept.at[kept.count] = at[i];
                    kept.crossing[kept.count++] = crossing[i];
                }
                if ((si < 0.0) != (sj < 0.0) && si != 0.0 && sj != 0.0) {
                    if (kept.count == kCapacity) return false;
                    const double t = si / (si - sj);
                    kept.at[kept.count] = {at[i].x + t * (at[j].x - at[i].x), at[i].y + t * (at[j].y - at[i].y)};
                    kept.crossing[kept.count++] = -1;
                }
            }
            *this = kept;
            return true;
        }
    };

    /// A crossing's tangent line on a face.
    struct TangentLine {
        Vec2 through;  // the crossing
        Vec2 normal;   // unit, pointing out of the solid
        double offset; // normal . through
    };

    /// Where a segment's tangent lines meet, a wedge of the surface may reach past the square: out
    /// through a side between that side's corners, where the voxel edge crosses the surface twice,
    /// which its corner signs cannot show. The segment follows the wedge: the triangle of the two
    /// crossings and the tip, clipped by the planes of the crossings one voxel around the square (a
    /// third face may cut the tip off) and kept to this square and the squares beside it that the
    /// surface does not cross. It is dropped if a voxel corner inside it has the other sign. Writes the
    /// points from a's crossing to b's and returns their number (0: a straight segment). The inputs
    /// depend on the square alone, so both cells sharing it agree.
    int tipChain(const Square& sq, const TangentLine& a, const TangentLine& b, const Vec2& tip, Vec2* out) const
    {
        const int axis = sq.axis, u = (axis + 1) % 3, v = (axis + 2) % 3;
        const double vs = ctx_.voxelSize, plane = sq.minCorner[axis] * vs;
        const Vec2 &pa = a.through, &pb = b.through;
        auto side = [](const Vec2& q, const Vec2& n, double d) { return n.x * q.x + n.y * q.y - d; };
        const double turn = cross2(sub2(tip, pa), sub2(pb, pa));
        if (std::fabs(turn) < 1e-12 * vs * vs) return 0;
        const double orientation = turn > 0.0 ? 1.0 : -1.0;
        // The wedge is solid when the triangle's inside lies on the solid side of both tangent lines.
        const Vec2 centroid{(pa.x + pb.x + tip.x) / 3.0, (pa.y + pb.y + tip.y) / 3.0};
        const bool solidTip = side(centroid, a.normal, a.offset) < 0.0;
        if (solidTip != (side(centroid, b.normal, b.offset) < 0.0)) return 0;

        FacePolygon poly;
        poly.at[0] = pa, poly.at[1] = tip, poly.at[2] = pb;
        poly.crossing[0] = 0, poly.crossing[1] = -1, poly.crossing[2] = 1;
        poly.count = 3;

        // Kept to this square and the bands beside it (offset du, dv) whose voxel corners all have the
        // other sign. A band is as wide as the square but at most two voxels: a square lies in its leaf's
        // cells, so two voxels past it stay within the meshing reach (a wider band would read past the
        // leaves around and past what an edit's re-meshing accounts for).
        const int width = sq.width, u0 = sq.minCorner[u], v0 = sq.minCorner[v];
        const int band = std::min(width, kMeshingReach.high - kLeafDim);
        auto bandLow = [&](int start, int d) { return d < 0 ? start - band : (d == 0 ? start : start + width); };
        auto bandHigh = [&](int start, int d) { return d < 0 ? start : (d == 0 ? start + width : start + width + band); };
        auto cornerSolid = [&](int i, int j) {
            Coord corner;
            corner[axis] = sq.minCorner[axis];
            corner[u] = i;
            corner[v] = j;
            return ctx_.material(corner).solid();
        };
        auto clear = [&](int du, int dv) {
            for (int i = bandLow(u0, du); i <= bandHigh(u0, du); ++i)
                for (int j = bandLow(v0, dv); j <= bandHigh(v0, dv); ++j)
                    if (cornerSolid(i, j) == solidTip) return false;
            return true;
        };
        // A clear band can lie between two squares whose wedges both reach into it from opposite sides;
        // each keeps to its own half (less a gap), so the two chains never share a point (a pinch).
        // Each side from its own lattice index, as the crossings on it are (lo + width * vs can round
        // off the side and clip a crossing away).
        const double lo0 = u0 * vs, lo1 = v0 * vs, hi0 = (u0 + width) * vs, hi1 = (v0 + width) * vs;
        const double bw = 0.5 * band * vs - kBandGapVoxels * vs;
        if (!poly.clip({1.0, 0.0}, hi0 + (clear(1, 0) ? bw : 0.0)) ||
            !poly.clip({-1.0, 0.0}, -(lo0 - (clear(-1, 0) ? bw : 0.0))) ||
            !poly.clip({0.0, 1.0}, hi1 + (clear(0, 1) ? bw : 0.0)) ||
            !poly.clip({0.0, -1.0}, -(lo1 - (clear(0, -1) ? bw : 0.0))))
            return 0;

        // Clipped by each crossing plane around the square, as seen in the face's plane, on the wedge's
        // side; a plane that would cut the segment's own crossings belongs to another part of the
        // surface. (Where the surface is not convex this may cut a true tip; the chain then lies
        // between the straight segment and the tip.)
        const double tolerance = 0.05 * vs;
        const double sign = solidTip ? 1.0 : -1.0;
        bool overflow = false;
        const int across = width + 3;
        forEachCrossingIn(sq.minCorner.offsetBy(-1), {axis == 0 ? 3 : across, axis == 1 ? 3 : across, axis == 2 ? 3 : across},
                          [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
                              // The plane n.x = n.p within the face's plane: n2.q = d. A solid wedge
                              // keeps n2.q <= d, an empty one n2.q >= d.
                              const Vec2 keep{sign * n[u], sign * n[v]};
                              const double bound = sign * (n.dot(p) - n[axis] * plane) + tolerance;
                              if (side(pa, keep, bound) > 0.0 || side(pb, keep, bound) > 0.0) return;
                              overflow = overflow || !poly.clip(keep, bound);
                          });
        if (overflow) return 0;

        // A voxel corner inside the chain must have the wedge's sign (only a wide square has such
        // corners: those beside it that it may reach have the other sign), and a square beside it
        // diagonally that the chain reaches must be clear too.
        const double margin = 1e-6 * vs;
        double minU = poly.at[0].x, maxU = minU, minV = poly.at[0].y, maxV = minV;
        for (int i = 1; i < poly.count; ++i) {
            minU = std::min(minU, poly.at[i].x), maxU = std::max(maxU, poly.at[i].x);
            minV = std::min(minV, poly.at[i].y), maxV = std::max(maxV, poly.at[i].y);
        }
        const int du = minU < lo0 - margin ? -1 : (maxU > hi0 + margin ? 1 : 0);
        const int dv = minV < lo1 - margin ? -1 : (maxV > hi1 + margin ? 1 : 0);
        if (du != 0 && dv != 0 && !clear(du, dv)) return 0;
        for (int i = u0 - band; i <= u0 + width + band; ++i)
            for (int j = v0 - band; j <= v0 + width + band; ++j) {
                const Vec2 q{i * vs, j * vs};
                if (q.x < minU || q.x > maxU || q.y < minV || q.y > maxV) continue;
                bool inside = true;
                for (int e = 0; e < poly.count && inside; ++e) {
                    const Vec2& p0 = poly.at[e];
                    const Vec2& p1 = poly.at[(e + 1) % poly.count];
                    inside = cross2(sub2(p1, p0), sub2(q, p0)) * orientation > margin * vs;
                }
                if (inside && cornerSolid(i, j) != solidTip) return 0;
            }

        // The polygon runs from a's crossing through the chain to b's, then back along the chord.
        int start = -1;
        for (int i = 0; i < poly.count; ++i)
            if (poly.crossing[i] == 0) start = i;
        if (start < 0) return 0;
        // A point on a lattice line of the face (where the chain is clipped at a side, or a wedge tip
        // on a voxel edge) moves off it (offLatticeLines).
        int n = 0;
        Vec2 previous = pa;
        for (int k = 1; k < poly.count; ++k) {
            const Vec2 q = offLatticeLines(sq, poly.at[(start + k) % poly.count]);
            if (poly.crossing[(start + k) % poly.count] == 1) break;
            // Clipping can leave two corners a rounding error apart: one vertex, not two.
            const double apart = kFeatureInsetVoxels * vs;
            if (std::hypot(q.x - previous.x, q.y - previous.y) < apart) continue;
            if (n == SegmentShape::kMaxPoints) return 0;
            out[n++] = previous = q;
        }
        if (n > 0 && std::hypot(out[n - 1].x - pb.x, out[n - 1].y - pb.y) < kFeatureInsetVoxels * vs) --n;
        return n;
    }

    /// A point of a face within kFeatureInsetVoxels of one of its lattice lines, moved that far off
    /// it towards the square's centre: a square at right angles along that line can put a point of its
    /// own there, and the surface would pinch (a wall thinner than a voxel).
    Vec2 offLatticeLines(const Square& sq, Vec2 q) const
    {
        const double vs = ctx_.voxelSize, inset = kFeatureInsetVoxels * vs;
        const int axis = sq.axis;
        const double centreU = (sq.minCorner[(axis + 1) % 3] + 0.5 * sq.width) * vs;
        const double centreV = (sq.minCorner[(axis + 2) % 3] + 0.5 * sq.width) * vs;
        const double lineU = std::round(q.x / vs) * vs, lineV = std::round(q.y / vs) * vs;
        if (std::fabs(q.x - lineU) < inset) q.x = lineU + (centreU > lineU ? inset : -inset);
        if (std::fabs(q.y - lineV) < inset) q.y = lineV + (centreV > lineV ? inset : -inset);
        return q;
    }

    void meshSquare(const Square& sq)
    {
        for (const EdgeCrossing*& x : squareCrossings_) x = nullptr;
        const int axis = sq.axis;
        int sides[4], count = 0;
        bool entering[4];
        for (int i = 0; i < 4; ++i) {
            const bool sp = sq.mats[i].solid(), sq1 = sq.mats[(i + 1) % 4].solid();
            if (sp == sq1) continue;
            sides[count] = i;
            entering[count] = sq1;
            ++count;
        }
        if (count == 0) return;
        if (sq.width == 1 && ctx_.plainSquare(sq.minCorner, axis)) {
            // Beside a transition cell: each entering crossing joined straight to the leaving one after
            // it, as the transition mesher joins them.
            for (int i = 0; i < count; ++i)
                if (entering[i]) segments_.emplace_back(squareCrossing(sq, sides[i]), squareCrossing(sq, sides[(i + 1) % count]));
            return;
        }
        struct Pairing {
            int in, out; // square sides
            SegmentShape shape;
        };
        struct Pairings {
            Pairing segments[2];
            int count = 0;
            bool plausible() const { return segments[0].shape.plausible && segments[1].shape.plausible; }
        };
        auto pairUp = [&](int shift) {
            Pairings p;
            for (int i = 0; i < count; ++i) {
                if (!entering[i]) continue;
                const int in = sides[i], out = sides[(i + shift) % count];
                p.segments[p.count++] = {in, out, segmentShape(squareCrossing(sq, in), squareCrossing(sq, out), sq, count == 2)};
            }
            return p;
        };
        auto overlap = [&](const Pairings& p) {
            return segmentsOverlap(sq, p.segments[0].in, p.segments[0].out, p.segments[0].shape.sharp(),
                                   p.segments[1].in, p.segments[1].out, p.segments[1].shape.sharp());
        };
        // Each entering crossing to the leaving one that follows it, so the solid corners stay apart;
        // on an ambiguous square, the other pairing (joining the solid corners) when that one's
        // segments cross, or when its segments join crossings whose normals disagree without a sharp
        // feature on the square while the other pairing's do not.
        const Pairings separate = pairUp(1);
        Pairings chosen = separate;
        if (count == 4) {
            const Pairings joined = pairUp(3);
            if (overlap(separate) || (!separate.plausible() && joined.plausible() && !overlap(joined))) chosen = joined;
            // Where every tangent line meets at one point (two solids touching along a voxel edge), both
            // pairings' sharp points land there and the surface would pinch: the solid corners are cut
            // off straight.
            if (overlap(chosen)) {
                chosen = separate;
                for (Pairing& pairing : chosen.segments) pairing.shape = {};
            }
        }
        const Pairing* pairs = chosen.segments;
        const int nSeg = chosen.count;

        // Both cells sharing this square must name its points alike: order segments by their crossings.
        auto minKey = [&](const Pairing& p) {
            return std::min(squareCrossing(sq, p.in).key, squareCrossing(sq, p.out).key);
        };
        const uint64_t key0 = minKey(pairs[0]);
        const uint64_t key1 = nSeg > 1 ? minKey(pairs[1]) : key0;
        const double plane = sq.minCorner[axis] * ctx_.voxelSize;
        auto toWorld = [&](const Vec2& q) {
            std::array<double, 3> pos{};
            pos[axis] = plane;
            pos[(axis + 1) % 3] = q.x;
            pos[(axis + 2) % 3] = q.y;
            return pos;
        };
        for (int s = 0; s < nSeg; ++s) {
            const Pairing& pr = pairs[s];
            Segment& seg = segments_.emplace_back(squareCrossing(sq, pr.in), squareCrossing(sq, pr.out));
            SegmentPoints& points = seg.points;
            for (int k = 0; k < pr.shape.count; ++k) {
                const Vec2& q = pr.shape.points[k];
                points.insert(k, FacePoint{q, toWorld(q), 0, false, kEmptyMaterial, kEmptyMaterial, {}});
            }
            // A square with one segment may hold material interfaces between its solid corners.
            if (nSeg == 1 && mixedMaterials(sq)) insertTransitions(sq, pr.in, seg, toWorld);
            // Slots count along the segment from its end with the smaller key, the same in both cells.
            const int index = (s == 0 ? key0 <= key1 : key1 < key0) ? 0 : 1;
            const bool forward = seg.in.key < seg.out.key;
            for (int k = 0; k < points.count; ++k) {
                const int slot = forward ? k : points.count - 1 - k;
                points.items[k].key = faceKey(sq.minCorner.x(), sq.minCorner.y(), sq.minCorner.z(), axis, index, slot);
            }
        }
    }

    static bool mixedMaterials(const Square& sq)
    {
        MaterialValue first{};
        for (const MaterialValue m : sq.mats) {
            if (!m.solid()) continue;
            if (!first.solid()) first = m;
            else if (m != first) return true;
        }
        return false;
    }

    /// Seed 004 Algorithm 2: where two consecutive solid corners of the square differ in material, the
    /// interface's tangent line (through that edge's Hermite sample) splits the segment. Transitions
    /// are inserted in order along the segment so its pieces never fold.
    template<typename ToWorld>
    void insertTransitions(const Square& sq, int inSide, Segment& seg, const ToWorld& toWorld)
    {
        const int axis = sq.axis;
        SegmentPoints& points = seg.points;
        // The solid run the segment cuts off, in walk order: from the corner after its entering side.
        const int first = (inSide + 1) % 4;
        for (int step = 0; step < 3; ++step) {
            const int p = (first + step) % 4, q = (first + step + 1) % 4;
            if (!sq.mats[p].solid() || !sq.mats[q].solid()) break;
            if (sq.mats[p] == sq.mats[q]) continue;
            const EdgeCrossing& interface = squareCrossing(sq, p);
            Vec2 n = project(interface.normal, axis);
            const double len = std::sqrt(n.x * n.x + n.y * n.y);
            if (len < 1e-6) continue;
            n = {n.x / len, n.y / len};
            const Vec2 c = onFace(interface, axis);
            if (points.count == 4) break;
            // The segment as a polyline: in, the points so far, out.
            Vec2 poly[6];
            int size = 0;
            poly[size++] = onFace(seg.in, axis);
            for (int k = 0; k < points.count; ++k) poly[size++] = points.items[k].onFace;
            poly[size++] = onFace(seg.out, axis);
            for (int k = 0; k + 1 < size; ++k) {
                const double fa = n.x * (poly[k].x - c.x) + n.y * (poly[k].y - c.y);
                const double fb = n.x * (poly[k + 1].x - c.x) + n.y * (poly[k + 1].y - c.y);
                if ((fa < 0.0) == (fb < 0.0) || fa == fb) continue;
                // Kept off the piece's ends, which are other vertices: an interface through a sharp
                // point or a crossing would put two vertices at one position.
                const double pieceLength = std::hypot(poly[k + 1].x - poly[k].x, poly[k + 1].y - poly[k].y);
                const double keepOff = kFeatureInsetVoxels * ctx_.voxelSize / std::max(pieceLength, 1e-300);
                if (keepOff >= 0.5) break;
                const double t = std::clamp(fa / (fa - fb), keepOff, 1.0 - keepOff);
                // Off the face's lattice lines, where the square beside it at right angles could put
                // its own transition (a segment can run along a side when its crossings lie at corners).
                const Vec2 hit = offLatticeLines(sq, {poly[k].x + t * (poly[k + 1].x - poly[k].x), poly[k].y + t * (poly[k + 1].y - poly[k].y)});
                points.insert(k, FacePoint{hit, toWorld(hit), 0, true, sq.mats[p].id, sq.mats[q].id, interface.normal});
                break;
            }
        }
    }

    /// Whether the two segments of an ambiguous square, with their sharp features, cross each other.
    /// The polylines are put in an order both cells sharing the square agree on, so that both make the
    /// same floating-point decision.
    bool segmentsOverlap(const Square& sq, int in0, int out0, const std::optional<Vec2>& sharp0, int in1, int out1,
                         const std::optional<Vec2>& sharp1)
    {
        const int ins[2] = {in0, in1}, outs[2] = {out0, out1};
        const std::optional<Vec2>* sharps[2] = {&sharp0, &sharp1};
        Vec2 poly[2][3];
        int sizes[2];
        uint64_t minKey[2];
        for (int s = 0; s < 2; ++s) {
            const EdgeCrossing& in = squareCrossing(sq, ins[s]);
            const EdgeCrossing& out = squareCrossing(sq, outs[s]);
            const bool forward = in.key < out.key;
            minKey[s] = std::min(in.key, out.key);
            sizes[s] = 0;
            poly[s][sizes[s]++] = onFace(forward ? in : out, sq.axis);
            if (*sharps[s]) poly[s][sizes[s]++] = **sharps[s];
            poly[s][sizes[s]++] = onFace(forward ? out : in, sq.axis);
        }
        if (minKey[1] < minKey[0]) {
            std::swap(poly[0], poly[1]);
            std::swap(sizes[0], sizes[1]);
        }
        // Crossing, or touching: closer than the inset that keeps distinct points apart.
        const double apart = kFeatureInsetVoxels * ctx_.voxelSize;
        for (int i = 0; i + 1 < sizes[0]; ++i)
            for (int j = 0; j + 1 < sizes[1]; ++j) {
                const Vec2 &a = poly[0][i], &b = poly[0][i + 1], &c = poly[1][j], &d = poly[1][j + 1];
                if (segmentsCross(a, b, c, d)) return true;
                if (std::min({pointSegmentDistance(a, c, d), pointSegmentDistance(b, c, d), pointSegmentDistance(c, a, b),
                              pointSegmentDistance(d, a, b)}) < apart)
                    return true;
            }
        return false;
    }

    /// The chunk's vertex for a crossing.
    uint32_t vertex(const EdgeCrossing& x)
    {
        Buffers& b = ctx_.buffers;
        const int slot = Buffers::edgeSlot(ctx_.origin, x.start, x.axis);
        return slot < 0 ? b.keyedVertex(x.key, x.position, x.normal, x.material) : b.crossingVertex(slot, x);
    }

    /// The least-squares point of crossing planes (seed 004 §2.6), solved relative to `massPoint` with
    /// singular values under a tenth of the largest truncated.
    struct QefSolution {
        Eigen::Vector3d point;
        int rank = 0;                    // singular values kept
        double largest = 0.0;            // the largest singular value
        double smallest = 0.0;           // the smallest singular value
        Eigen::Vector3d weakestDirection; // its right singular vector
    };
    static QefSolution solveQef(const Eigen::Matrix3d& ata, const Eigen::Vector3d& atb, const Eigen::Vector3d& massPoint)
    {
        const Eigen::JacobiSVD<Eigen::Matrix3d> svd(ata, Eigen::ComputeFullU | Eigen::ComputeFullV);
        const Eigen::Vector3d sigma = svd.singularValues();
        const Eigen::Vector3d rhs = svd.matrixU().transpose() * (atb - ata * massPoint);
        Eigen::Vector3d scaled = Eigen::Vector3d::Zero();
        QefSolution solution;
        for (int& rank = solution.rank; rank < 3 && sigma[rank] > 0.1 * sigma[0]; ++rank) scaled[rank] = rhs[rank] / sigma[rank];
        solution.point = massPoint + svd.matrixV() * scaled;
        solution.largest = sigma[0];
        solution.smallest = sigma[2];
        solution.weakestDirection = svd.matrixV().col(2);
        return solution;
    }

    /// The cell, inset by kFeatureInsetVoxels: a sharp vertex on a face, edge or corner of its cell
    /// (a cone's apex on a lattice line) would coincide with the vertices of the cells beside it.
    void cellBounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const
    {
        const double inset = kFeatureInsetVoxels * ctx_.voxelSize;
        for (int k = 0; k < 3; ++k) {
            lo[k] = base_[k] * ctx_.voxelSize + inset;
            hi[k] = (base_[k] + width_) * ctx_.voxelSize - inset;
        }
    }

    /// A component's sharp vertex: a corner (rank 3) or the point of a sharp edge nearest the mean
    /// (rank 2), clamped to the box lo .. hi (the cell, grown to the component's face points). A lone
    /// plane (rank 1) has no feature; the caller keeps the mean point. (Clipping an edge's line to the
    /// cell instead of clamping was tried: it measured worse on the rotated box.)
    ///
    /// A corner's tip may poke into a cell whose edges see only two of its faces. An edge cell
    /// therefore also reads the crossings one voxel around it, facing the same way as its own; if
    /// their planes meet in a corner inside the box, the vertex goes there.
    std::optional<Eigen::Vector3d> sharpVertex(Eigen::Matrix3d ata, Eigen::Vector3d atb, const Eigen::Vector3d& massPoint,
                                               const Eigen::Vector3d& normalSum, const Eigen::Vector3d& lo,
                                               const Eigen::Vector3d& hi) const
    {
        const QefSolution own = solveQef(ata, atb, massPoint);
        if (own.rank < 2) return std::nullopt;
        if (own.rank == 2) {
            // The planes around can only make a corner if they lift the weight of the own solve's
            // weakest direction d above the truncation: the wide solve's smallest singular value is at
            // most d's weight, own.smallest + sum (n.d)^2, and its largest at least own.largest.
            // Weighed first: most sharp edges stay edges, and then the planes need not be summed.
            const Eigen::Vector3d facing = normalSum.normalized();
            double weakestWeight = own.smallest;
            forEachCrossingAround([&](const Eigen::Vector3d&, const Eigen::Vector3d& n) {
                if (n.dot(facing) < -0.3) return; // the far side of a thin part
                const double along = n.dot(own.weakestDirection);
                weakestWeight += along * along;
            });
            if (weakestWeight > 0.1 * own.largest) {
                forEachCrossingAround([&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
                    if (n.dot(facing) < -0.3) return;
                    ata += n * n.transpose();
                    atb += n * n.dot(p);
                });
                const QefSolution wide = solveQef(ata, atb, massPoint);
                const Eigen::Vector3d& corner = wide.point;
                const double eps = 1e-6 * ctx_.voxelSize;
                // A corner of this cell's own edge lies on the edge's line; planes of other surfaces
                // near the cell (a second part, a crease beside) can meet elsewhere in it.
                const Eigen::Vector3d offEdge = (corner - own.point) - (corner - own.point).dot(own.weakestDirection) * own.weakestDirection;
                if (wide.rank == 3 && (corner.array() >= lo.array() - eps).all() && (corner.array() <= hi.array() + eps).all() &&
                    offEdge.norm() <= kCornerOffEdgeVoxels * ctx_.voxelSize)
                    return corner;
            }
        }
        return Eigen::Vector3d(own.point.cwiseMax(lo).cwiseMin(hi));
    }

    /// The crossings on the voxel edges of the lattice one voxel around the cell.
    template<typename Fn>
    void forEachCrossingAround(Fn&& fn) const
    {
        const int span = width_ + 3;
        forEachCrossingIn(base_.offsetBy(-1), {span, span, span}, fn);
    }

    /// The crossings on the voxel edges between the voxels lo .. lo + span - 1, found a row of voxels
    /// at a time from bit rows of their solidity.
    template<typename Fn>
    void forEachCrossingIn(const Coord& lo, const std::array<int, 3>& span, Fn&& fn) const
    {
        constexpr int kMaxSpan = kLeafDim + 3;
        uint32_t solidRows[kMaxSpan][kMaxSpan]; // bit z: voxel lo + (x, y, z) is solid
        const CornerGrid& grid = ctx_.grid;
        const int gx = lo.x() - grid.origin.x() + 1, gy = lo.y() - grid.origin.y() + 1, gz = lo.z() - grid.origin.z() + 1;
        const bool inGrid = gx >= 0 && gy >= 0 && gz >= 0 && gx + span[0] <= CornerGrid::kSpan &&
                            gy + span[1] <= CornerGrid::kSpan && gz + span[2] <= CornerGrid::kSpan;
        // Index of lo in Buffers::solidAround, which starts one voxel lower than the corner grid and
        // holds every voxel a scan around a cell or square the leaf meshes can reach.
        const int ax = gx - 1 - Buffers::kAroundLow, ay = gy - 1 - Buffers::kAroundLow, az = gz - 1 - Buffers::kAroundLow;
        const bool inAround = ax >= 0 && ay >= 0 && az >= 0 && ax + span[0] <= Buffers::kAroundSpan &&
                              ay + span[1] <= Buffers::kAroundSpan && az + span[2] <= Buffers::kAroundSpan;
        if (!inGrid && !inAround) throw std::logic_error("CMS: a crossing scan reaches beyond its leaf's surroundings");
        const uint32_t spanBits = (1u << span[2]) - 1;
        for (int x = 0; x < span[0]; ++x)
            for (int y = 0; y < span[1]; ++y)
                solidRows[x][y] = inGrid ? (grid.solidRows[gx + x][gy + y] >> gz) & spanBits
                                         : (ctx_.solidAround()[ax + x][ay + y] >> az) & spanBits;
        // The edges whose ends differ: bit z of `cut` marks the edge from (x, y, z) along `axis`. Edges
        // without a sample are left out: their crossing is decoded with no normal. Inside the grid an
        // edge's cache slot follows from (x, y, z) directly.
        constexpr int kSpan = CornerGrid::kSpan;
        const int gridSlot = ((gx * kSpan + gy) * kSpan + gz) * 3;
        auto visit = [&](int x, int y, int axis, uint32_t cut) {
            for (; cut; cut &= cut - 1) {
                const int z = __builtin_ctz(cut);
                auto decode = [&] {
                    const Coord v = lo.offsetBy(x, y, z);
                    Coord w = v;
                    w[axis] += 1;
                    return voxelEdgeCrossing(ctx_.hood, v, axis, ctx_.material(v), ctx_.material(w), ctx_.voxelSize);
                };
                EdgeCrossing uncached;
                const EdgeCrossing& c = inGrid ? ctx_.buffers.crossingAt(gridSlot + ((x * kSpan + y) * kSpan + z) * 3 + axis, decode)
                                               : cachedCrossing(ctx_, lo.offsetBy(x, y, z), axis, decode, uncached);
                if (c.normal[0] == 0.f && c.normal[1] == 0.f && c.normal[2] == 0.f) continue;
                fn(Eigen::Vector3d(c.position[0], c.position[1], c.position[2]),
                   Eigen::Vector3d(c.normal[0], c.normal[1], c.normal[2]));
            }
        };
        for (int x = 0; x < span[0]; ++x)
            for (int y = 0; y < span[1]; ++y) {
                // Most rows hold no crossing: test before calling.
                const uint32_t row = solidRows[x][y];
                const uint32_t cutX = x + 1 < span[0] ? row ^ solidRows[x + 1][y] : 0u;
                const uint32_t cutY = y + 1 < span[1] ? row ^ solidRows[x][y + 1] : 0u;
                const uint32_t cutZ = (row ^ (row >> 1)) & ((1u << (span[2] - 1)) - 1);
                if (cutX) visit(x, y, 0, cutX);
                if (cutY) visit(x, y, 1, cutY);
                if (cutZ) visit(x, y, 2, cutZ);
            }
    }

    /// The sharp vertex of a component from the planes of its crossings and of its material
    /// transitions: the interface planes join the solve, so the vertex lands on the material boundary
    /// (seed 004 §4.2.2.1).
    std::optional<Eigen::Vector3d> componentFeature(const std::vector<int>& loop, const Eigen::Vector3d& normalSum) const
    {
        Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
        Eigen::Vector3d atb = Eigen::Vector3d::Zero();
        Eigen::Vector3d massPoint = Eigen::Vector3d::Zero();
        int planes = 0;
        auto addPlane = [&](const std::array<double, 3>& at, const std::array<float, 3>& normal) {
            const Eigen::Vector3d p(at[0], at[1], at[2]);
            const Eigen::Vector3d n(normal[0], normal[1], normal[2]);
            ata += n * n.transpose();
            atb += n * n.dot(p);
            massPoint += p;
            ++planes;
        };
        // The vertex stays in the cell, or reaches as far as the component's face points do within
        // their faces' planes; across a face it stays inset, or the cell beside it could put its vertex
        // at the same place (a cone's apex on a lattice plane).
        Eigen::Vector3d lo, hi;
        cellBounds(lo, hi);
        const double vs = ctx_.voxelSize, onPlane = 1e-9 * vs;
        for (const int s : loop) {
            const Segment& seg = segments_[s];
            const auto& p = seg.in.position;
            addPlane({p[0], p[1], p[2]}, seg.in.normal);
            for (int k = 0; k < seg.points.count; ++k) {
                const FacePoint& point = seg.points.items[k];
                if (point.transition) addPlane(point.position, point.interfaceNormal);
                for (int a = 0; a < 3; ++a) {
                    const double c = point.position[a];
                    const double cellLo = base_[a] * vs, cellHi = (base_[a] + width_) * vs;
                    if (std::fabs(c - cellLo) < onPlane || std::fabs(c - cellHi) < onPlane) continue;
                    lo[a] = std::min(lo[a], c);
                    hi[a] = std::max(hi[a], c);
                }
            }
        }
        return sharpVertex(ata, atb, massPoint / double(planes), normalSum, lo, hi);
    }

    /// Fans one closed loop of segments from its inner vertex.
    void emitComponent(const std::vector<int>& loop)
    {
        // The component's boundary: each segment's entering crossing, then the points inside it.
        std::vector<uint32_t>& ids = ctx_.buffers.ids;
        std::vector<MaterialId>& pieceMaterials = ctx_.buffers.pieceMaterials;
        ids.clear();
        pieceMaterials.clear();
        bool hasTransition = false;
        std::array<double, 3> centre{}, normalSum{};
        double minDot = 1.0;
        for (std::size_t i = 0; i < loop.size(); ++i) {
            const Segment& seg = segments_[loop[i]];
            const EdgeCrossing& x = seg.in;
            for (std::size_t j = 0; j < i; ++j) minDot = std::min(minDot, normalDot(x.normal, segments_[loop[j]].in.normal));
            accumulate(normalSum, x.normal);
            accumulate(centre, x.position);
            pieceMaterials.push_back(x.material);
            ids.push_back(vertex(x));
            MaterialId material = x.material;
            for (int k = 0; k < seg.points.count; ++k) {
                const FacePoint& point = seg.points.items[k];
                const auto& q = point.position;
                accumulate(centre, q);
                if (point.transition) {
                    hasTransition = true;
                    material = point.materialAfter;
                }
                pieceMaterials.push_back(material);
                ids.push_back(ctx_.buffers.keyedVertex(point.key, {float(q[0]), float(q[1]), float(q[2])}, x.normal, material));
            }
        }
        const std::size_t n = ids.size();
        for (double& c : centre) c /= double(n); // the mean point

        bool sharp = false;
        if (minDot < ctx_.cosSharp || hasTransition) {
            if (const auto feature = componentFeature(loop, Eigen::Vector3d(normalSum[0], normalSum[1], normalSum[2]))) {
                // Two components of one cell whose features are clamped to the same place in the cell
                // (a corner of its inset box) would share their vertex: a pinch. The later one keeps
                // its mean point.
                const std::array<double, 3> at{feature->x(), feature->y(), feature->z()};
                const double apart = kFeatureInsetVoxels * ctx_.voxelSize;
                const bool taken = std::any_of(featuresPlaced_, featuresPlaced_ + featureCount_, [&](const std::array<double, 3>& p) {
                    return std::hypot(p[0] - at[0], p[1] - at[1], p[2] - at[2]) < apart;
                });
                if (!taken) {
                    centre = at;
                    sharp = true;
                    if (featureCount_ < kMaxFeatures) featuresPlaced_[featureCount_++] = at;
                }
            }
        }
        const double vs = ctx_.voxelSize;
        ctx_.buffers.addFan(centre, normalSum, ids.data(), pieceMaterials.data(), n, sharp,
                            CellBox{{base_[0] * vs, base_[1] * vs, base_[2] * vs}, width_ * vs});
    }

    LeafContext& ctx_;
    Coord base_;
    int width_;
    const MaterialValue* mats_;
    std::vector<Segment>& segments_;
    const EdgeCrossing* squareCrossings_[4] = {};
    // The sharp vertices of this cell's components so far (a cell holds a few components at most).
    static constexpr int kMaxFeatures = 8;
    std::array<double, 3> featuresPlaced_[kMaxFeatures];
    int featureCount_ = 0;
};

/// Slot offset of each cell edge from the slot of the cell's minimum corner (Buffers::edgeSlot).
constexpr std::array<int, 12> kCellEdgeSlotOffsets = [] {
    std::array<int, 12> offsets{};
    for (int e = 0; e < 12; ++e) {
        const int c = edgeLowCorner(e);
        offsets[e] = ((cornerBit(c, 0) * Buffers::kSpan + cornerBit(c, 1)) * Buffers::kSpan + cornerBit(c, 2)) * 3 + e / 4;
    }
    return offsets;
}();

/// Whether each face of a wide cell that the surface crosses borders cells at least as wide, so the
/// face walk meshes it as one square (CellMesher::meshFaceRegion).
bool facesAreWhole(const LeafContext& ctx, const Coord& base, int width, const MaterialValue mats[8])
{
    for (int f = 0; f < 6; ++f) {
        if (!surfaceCrosses(mats, f)) continue;
        Coord across = base;
        across[f / 2] += f % 2 ? width : -1;
        if (ctx.widths->widthAt(across) < width) return false;
    }
    return true;
}

/// Most surface cells are cells of one material with unambiguous faces whose crossings span no sharp
/// angle, on a face or across the cell; a wide one must also have whole faces (facesAreWhole). The
/// face walk gives such a cell its corner case's loops (CellTopology.h) with no face points, each
/// fanned from its mean point; this builds exactly that straight from the table. Returns false,
/// having added no vertex, for any other cell. `Wide`: the cell is wider than a voxel, and its edges'
/// crossings are looked up along them (voxel cells, most of them, keep the short path).
template<bool Wide>
bool meshSmoothCell(LeafContext& ctx, const Coord& base, int width, const MaterialValue mats[8], unsigned solid)
{
    const CellCase& cell = kCellCases[solid];
    if (cell.ambiguousFace) return false;
    MaterialValue material{};
    for (int c = 0; c < 8; ++c) {
        if (!mats[c].solid()) continue;
        if (!material.solid()) material = mats[c];
        else if (mats[c] != material) return false;
    }
    if (Wide && !facesAreWhole(ctx, base, width, mats)) return false;
    Buffers& b = ctx.buffers;
    const int cellSlot = Wide ? -1 : Buffers::edgeSlot(ctx.origin, base, 0);
    const int count = cell.loopEnd[cell.loopCount - 1];
    int slots[12]; // of the voxel edge holding each crossing
    const EdgeCrossing* crossings[12];
    for (int i = 0; i < count; ++i) {
        const int e = cell.edges[i], axis = e / 4, low = edgeLowCorner(e), high = low | (1 << axis);
        if constexpr (!Wide) {
            slots[i] = cellSlot + kCellEdgeSlotOffsets[e];
            crossings[i] = &b.crossingAt(slots[i], [&] {
                const Coord start = base.offsetBy(cornerBit(low, 0), cornerBit(low, 1), cornerBit(low, 2));
                return voxelEdgeCrossing(ctx.hood, start, axis, mats[low], mats[high], ctx.voxelSize);
            });
        } else {
            const Coord start = base.offsetBy(width * cornerBit(low, 0), width * cornerBit(low, 1), width * cornerBit(low, 2));
            EdgeCrossing uncached; // a wide cell lies inside its leaf, whose crossings are all cached
            const EdgeCrossing& x = crossingAlong(ctx, start, axis, width, mats[low], mats[high], uncached);
            if (&x == &uncached) return false;
            slots[i] = Buffers::edgeSlot(ctx.origin, x.start, x.axis);
            crossings[i] = &x;
        }
    }
    // The normals in double once (exactly): each is tested against several others.
    std::array<double, 3> normals[12];
    for (int i = 0; i < count; ++i)
        for (int a = 0; a < 3; ++a) normals[i][a] = crossings[i]->normal[a];
    for (int l = 0, begin = 0; l < cell.loopCount; begin = cell.loopEnd[l++]) {
        const int end = cell.loopEnd[l];
        for (int i = begin; i < end; ++i) {
            if (segmentBends(normals[i], normals[i + 1 < end ? i + 1 : begin], cell.segmentAxis[i], ctx.cosSharp)) return false;
            for (int j = begin; j < i; ++j)
                if (normalDot(normals[i], normals[j]) < ctx.cosSharp) return false;
        }
    }
    uint32_t ids[12];
    MaterialId materials[12];
    std::fill_n(materials, count, material.id);
    for (int l = 0, begin = 0; l < cell.loopCount; begin = cell.loopEnd[l++]) {
        const int size = cell.loopEnd[l] - begin;
        std::array<double, 3> centre{}, normalSum{};
        for (int i = 0; i < size; ++i) {
            const EdgeCrossing& x = *crossings[begin + i];
            accumulate(normalSum, normals[begin + i]);
            accumulate(centre, x.position);
            ids[i] = b.crossingVertex(slots[begin + i], x);
        }
        for (double& c : centre) c /= double(size);
        b.addFan(centre, normalSum, ids, materials, std::size_t(size), false,
                 CellBox{{base[0] * ctx.voxelSize, base[1] * ctx.voxelSize, base[2] * ctx.voxelSize}, width * ctx.voxelSize});
    }
    return true;
}

} // namespace

CubicalMarchingSquaresMesher::CubicalMarchingSquaresMesher(double voxelSize, double sharpAngleDegrees, bool walkEveryCell)
    : voxelSize_(voxelSize), cosSharp_(std::cos(sharpAngleDegrees * M_PI / 180.0)), walkEveryCell_(walkEveryCell),
      buffers_(std::make_unique<Buffers>())
{
    // Ten times analyzeTopology's zero-area bound, so a fan it accepts passes that test after rounding.
    LoopFanLimits& limits = buffers_->fanLimits;
    limits.minFanDoubledArea = 10.0 * kMergeDistanceVoxels * kMergeDistanceVoxels * voxelSize * voxelSize;
    limits.minFanSpacing = kFeatureInsetVoxels * voxelSize;
    limits.inset = kFeatureInsetVoxels * voxelSize;
    limits.voxelSize = voxelSize;
}

CubicalMarchingSquaresMesher::~CubicalMarchingSquaresMesher() = default;

void CubicalMarchingSquaresMesher::setLodBoundary(const LodCut* cut, int level, const Coord& brickMin, int brickEdge)
{
    if (!cut) {
        lod_.reset();
        return;
    }
    lod_ = LodBoundary{cut, level, brickMin, brickMin.offsetBy(brickEdge, brickEdge, brickEdge)};
}

MeshChunk CubicalMarchingSquaresMesher::mesh(const HermiteLeaf& leaf, ConstAccessor& acc, const CellWidthField* widths,
                                             const LeafSurroundings* surroundings)
{
    MeshChunk chunk;
    meshInto(leaf, acc, widths, surroundings, chunk);
    return chunk;
}

void CubicalMarchingSquaresMesher::meshInto(const HermiteLeaf& leaf, ConstAccessor& acc, const CellWidthField* widths,
                                            const LeafSurroundings* surroundings, MeshChunk& out)
{
    LeafSurroundings built;
    if (!surroundings) {
        built.hood = Neighbourhood(leaf, acc);
        built.grid.fill(leaf, built.hood);
    }
    const Neighbourhood& hood = surroundings ? surroundings->hood : built.hood;
    const CornerGrid& grid = surroundings ? surroundings->grid : built.grid;
    buffers_->startLeaf(leaf.origin());
    LeafContext ctx{hood, grid, widths, leaf.origin(), voxelSize_, cosSharp_, *buffers_, lod_ ? &*lod_ : nullptr};
    auto hasPlainFace = [&](const Coord& base) {
        if (!ctx.lod || !ctx.lod->nearBoundary(base, 2)) return false;
        for (int f = 0; f < 6; ++f) {
            Coord corner = base;
            corner[f / 2] += f % 2;
            if (ctx.plainSquare(corner, f / 2)) return true;
        }
        return false;
    };
    auto meshVoxelCell = [&](const Coord& base, const MaterialValue mats[8], unsigned solid) {
        if (ctx.lod && ctx.lod->nearBoundary(base, 1)) {
            if (!ctx.lod->owns(base)) return; // another brick's cell
            if (ctx.lod->cut->transitionCell(ctx.lod->level, {base.x(), base.y(), base.z()})) return; // the transition mesher's
        }
        ++cellsMeshed_;
        if (!walkEveryCell_ && !hasPlainFace(base) && meshSmoothCell<false>(ctx, base, 1, mats, solid)) ++cellsFromCaseTable_;
        else CellMesher(ctx, base, 1, mats).run();
    };
    const LeafCellSizes* own = widths ? widths->own() : nullptr;
    if (!own) {
        forEachOwnedSurfaceCell(grid, hood, OwnedCells::All, meshVoxelCell);
        buffers_->finishLeaf(out);
        return;
    }
    forEachOwnedSurfaceCell(grid, hood, OwnedCells::OutsideLeaf, meshVoxelCell);
    // The leaf's own cells, each visited at its minimum corner.
    for (int x = 0; x < kLeafDim; ++x)
        for (int y = 0; y < kLeafDim; ++y)
            for (uint32_t starts = own->cellStarts[x][y]; starts; starts &= starts - 1) {
                const int z = __builtin_ctz(starts);
                const int width = own->widthAt(x, y, z);
                MaterialValue mats[8];
                unsigned solid = 0;
                for (int c = 0; c < 8; ++c) {
                    mats[c] = grid.at(x + width * cornerBit(c, 0), y + width * cornerBit(c, 1), z + width * cornerBit(c, 2));
                    if (mats[c].solid()) solid |= 1u << c;
                }
                if (solid == 0 || solid == 0xFF) continue;
                const Coord base = grid.origin.offsetBy(x, y, z);
                if (lod_ && lod_->nearBoundary(base, 1) && !lod_->owns(base)) continue; // another brick's cell
                if (width == 1) {
                    meshVoxelCell(base, mats, solid);
                } else {
                    ++cellsMeshed_;
                    if (!walkEveryCell_ && !hasPlainFace(base) && meshSmoothCell<true>(ctx, base, width, mats, solid)) ++cellsFromCaseTable_;
                    else CellMesher(ctx, base, width, mats).run();
                }
            }
    buffers_->finishLeaf(out);
}

} // namespace vdbclay::mesher_detail
