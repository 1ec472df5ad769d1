// Cubical Marching Squares (Ho et al., seed 000; seed 004 §2.6 and §4.2.2) over Hermite data, on
// uniform voxel cells.
//
// Each face of a cell is meshed on its own by marching squares. A face segment whose two crossings'
// normals span more than the sharp angle gets a 2D sharp feature: the point where the crossings'
// tangent lines meet, when it lies on the face. On an ambiguous face (two solid corners on a
// diagonal) the segments that cut off each solid corner are used unless their sharp features make them
// cross, in which case the other pairing is. Segments are linked into components; each component gets
// one inner vertex, the least-squares point of its crossing planes (truncated SVD, clamped to the
// cell) when its normals span the sharp angle, else the mean of its vertices, and is fanned from it.
// A face's segments and sharp points depend on the face alone, so neighbouring cells agree on them
// and the welded mesh is watertight.
#include "mesher/CellGrid.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <optional>
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

/// What one cell needs to know about its crossings, computed once per cell.
class CellCrossings {
public:
    CellCrossings(const Neighbourhood& hood, const Coord& base, const MaterialValue mats[8], double voxelSize)
        : hood_(hood), base_(base), mats_(mats), voxelSize_(voxelSize) {}

    const EdgeCrossing& at(int e)
    {
        if (!known_[e]) {
            crossings_[e] = edgeCrossing(hood_, base_, mats_, e, voxelSize_);
            known_[e] = true;
        }
        return crossings_[e];
    }

private:
    const Neighbourhood& hood_;
    Coord base_;
    const MaterialValue* mats_;
    double voxelSize_;
    EdgeCrossing crossings_[12];
    bool known_[12] = {};
};

/// A vertex inside a face segment: its 2D sharp feature, or a material transition (where the
/// tangent line of a material interface on the face meets the segment, seed 004 Algorithm 2).
struct FacePoint {
    Vec2 onFace;
    std::array<double, 3> position;
    uint64_t key;
    bool transition;
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

/// A segment on one face, from the crossing where the walk enters the solid to the one where it
/// leaves, with its optional 2D sharp feature.
struct FaceSegment {
    int in, out;
    std::optional<Vec2> sharp;
};

class CellMesher {
public:
    CellMesher(const Neighbourhood& hood, const Coord& base, const MaterialValue mats[8], unsigned solid,
               double voxelSize, double cosSharp, MeshChunk& chunk, std::unordered_map<uint64_t, uint32_t>& local)
        : crossings_(hood, base, mats, voxelSize), base_(base), mats_(mats), solid_(solid), voxelSize_(voxelSize),
          cosSharp_(cosSharp), chunk_(chunk), local_(local) {}

    void run()
    {
        for (int f = 0; f < 6; ++f) meshFace(f);
        bool used[12] = {};
        for (int start = 0; start < 12; ++start) {
            if (!linked_[start] || used[start]) continue;
            int loop[12], size = 0;
            for (int e = start; !used[e] && size < 12; e = next_[e]) {
                used[e] = true;
                loop[size++] = e;
            }
            emitComponent(loop, size);
        }
    }

private:
    Vec2 project(const std::array<float, 3>& v, int axis) const
    {
        return {v[(axis + 1) % 3], v[(axis + 2) % 3]};
    }

    /// Where the tangent lines of the segment's two crossings meet, if their normals span the sharp
    /// angle and the point lies on the face.
    std::optional<Vec2> sharpFeature(int in, int out, int axis)
    {
        const EdgeCrossing& a = crossings_.at(in);
        const EdgeCrossing& b = crossings_.at(out);
        Vec2 na = project(a.normal, axis), nb = project(b.normal, axis);
        const double la = std::sqrt(na.x * na.x + na.y * na.y), lb = std::sqrt(nb.x * nb.x + nb.y * nb.y);
        if (la < 1e-6 || lb < 1e-6) return std::nullopt;
        na = {na.x / la, na.y / la};
        nb = {nb.x / lb, nb.y / lb};
        if (na.x * nb.x + na.y * nb.y > cosSharp_) return std::nullopt;
        const double det = cross2(na, nb);
        if (std::fabs(det) < 1e-9) return std::nullopt;
        const Vec2 pa = project(a.position, axis), pb = project(b.position, axis);
        const double ca = na.x * pa.x + na.y * pa.y, cb = nb.x * pb.x + nb.y * pb.y;
        const Vec2 p{(ca * nb.y - cb * na.y) / det, (na.x * cb - nb.x * ca) / det};
        const int bAxis = (axis + 1) % 3, cAxis = (axis + 2) % 3;
        const double lo0 = base_[bAxis] * voxelSize_, lo1 = base_[cAxis] * voxelSize_;
        const double eps = 1e-9 * voxelSize_;
        if (p.x < lo0 - eps || p.x > lo0 + voxelSize_ + eps || p.y < lo1 - eps || p.y > lo1 + voxelSize_ + eps)
            return std::nullopt;
        return p;
    }

    void meshFace(int f)
    {
        const CellFace& face = kFaces[f];
        const int axis = f / 2, side = f % 2;
        int edges[4], count = 0;
        bool entering[4];
        for (int i = 0; i < 4; ++i) {
            const int p = face.corners[i], q = face.corners[(i + 1) % 4];
            const bool sp = (solid_ >> p) & 1u, sq = (solid_ >> q) & 1u;
            if (sp == sq) continue;
            edges[count] = cellEdge(p, q);
            entering[count] = sq;
            ++count;
        }
        if (count == 0) return;
        FaceSegment segments[2];
        int nSeg = 0;
        auto pairUp = [&](int shift) {
            nSeg = 0;
            for (int i = 0; i < count; ++i) {
                if (!entering[i]) continue;
                const int in = edges[i], out = edges[(i + shift) % count];
                segments[nSeg++] = {in, out, sharpFeature(in, out, axis)};
            }
        };
        pairUp(1); // each entering crossing to the leaving one that follows it: solid corners stay apart
        if (count == 4 && segmentsOverlap(segments, axis)) pairUp(3);

        // Both cells sharing this face must name its points alike: order segments by their crossings.
        const uint64_t key0 = std::min(crossings_.at(segments[0].in).key, crossings_.at(segments[0].out).key);
        const uint64_t key1 =
            nSeg > 1 ? std::min(crossings_.at(segments[1].in).key, crossings_.at(segments[1].out).key) : key0;
        const Coord faceCorner = side ? base_.offsetBy(axis == 0, axis == 1, axis == 2) : base_;
        auto toWorld = [&](const Vec2& q) {
            std::array<double, 3> pos{};
            pos[axis] = faceCorner[axis] * voxelSize_;
            pos[(axis + 1) % 3] = q.x;
            pos[(axis + 2) % 3] = q.y;
            return pos;
        };
        for (int s = 0; s < nSeg; ++s) {
            const FaceSegment& seg = segments[s];
            next_[seg.in] = seg.out;
            linked_[seg.in] = true;
            SegmentPoints& points = facePoints_[seg.in];
            if (seg.sharp) points.insert(0, FacePoint{*seg.sharp, toWorld(*seg.sharp), 0, false, kEmptyMaterial, {}});
            // A face with one segment may hold material interfaces between its solid corners.
            if (nSeg == 1) insertTransitions(face, seg, axis, points, toWorld);
            // Slots count along the segment from its end with the smaller key, the same in both cells.
            const int index = (s == 0 ? key0 <= key1 : key1 < key0) ? 0 : 1;
            const bool forward = crossings_.at(seg.in).key < crossings_.at(seg.out).key;
            for (int k = 0; k < points.count; ++k) {
                const int slot = forward ? k : points.count - 1 - k;
                points.items[k].key = faceKey(faceCorner.x(), faceCorner.y(), faceCorner.z(), axis, index, slot);
            }
        }
    }

    /// Seed 004 Algorithm 2: where two consecutive solid corners of the face differ in material, the
    /// interface's tangent line (through that edge's Hermite sample) splits the segment. Transitions
    /// are inserted in order along the segment so its pieces never fold.
    template<typename ToWorld>
    void insertTransitions(const CellFace& face, const FaceSegment& seg, int axis, SegmentPoints& points,
                           const ToWorld& toWorld)
    {
        // The solid run the segment cuts off, in walk order: from the corner after `in` to the one
        // before `out`.
        int first = -1;
        for (int i = 0; i < 4; ++i) {
            const int p = face.corners[i], q = face.corners[(i + 1) % 4];
            if (cellEdge(p, q) == seg.in && ((solid_ >> q) & 1u)) first = (i + 1) % 4;
        }
        if (first < 0) return;
        for (int step = 0; step < 3; ++step) {
            const int p = face.corners[(first + step) % 4], q = face.corners[(first + step + 1) % 4];
            if (!((solid_ >> p) & 1u) || !((solid_ >> q) & 1u)) break;
            const int e = cellEdge(p, q);
            const EdgeCrossing& interface = crossings_.at(e);
            if (mats_[p] == mats_[q]) continue;
            Vec2 n = project(interface.normal, axis);
            const double len = std::sqrt(n.x * n.x + n.y * n.y);
            if (len < 1e-6) continue;
            n = {n.x / len, n.y / len};
            const Vec2 c = project(interface.position, axis);
            if (points.count == 4) break;
            // The segment as a polyline: in, the points so far, out.
            Vec2 poly[6];
            int size = 0;
            poly[size++] = project(crossings_.at(seg.in).position, axis);
            for (int k = 0; k < points.count; ++k) poly[size++] = points.items[k].onFace;
            poly[size++] = project(crossings_.at(seg.out).position, axis);
            for (int k = 0; k + 1 < size; ++k) {
                const double fa = n.x * (poly[k].x - c.x) + n.y * (poly[k].y - c.y);
                const double fb = n.x * (poly[k + 1].x - c.x) + n.y * (poly[k + 1].y - c.y);
                if ((fa < 0.0) == (fb < 0.0) || fa == fb) continue;
                const double t = fa / (fa - fb);
                const Vec2 hit{poly[k].x + t * (poly[k + 1].x - poly[k].x), poly[k].y + t * (poly[k + 1].y - poly[k].y)};
                points.insert(k, FacePoint{hit, toWorld(hit), 0, true, mats_[q].id, interface.normal});
                break;
            }
        }
    }

    /// Whether the two segments of an ambiguous face, with their sharp features, cross each other.
    /// The polylines are put in an order both cells sharing the face agree on, so that both make the
    /// same floating-point decision.
    bool segmentsOverlap(const FaceSegment segments[2], int axis)
    {
        Vec2 poly[2][3];
        int sizes[2];
        uint64_t minKey[2];
        for (int s = 0; s < 2; ++s) {
            const EdgeCrossing& in = crossings_.at(segments[s].in);
            const EdgeCrossing& out = crossings_.at(segments[s].out);
            const bool forward = in.key < out.key;
            minKey[s] = std::min(in.key, out.key);
            sizes[s] = 0;
            poly[s][sizes[s]++] = project(forward ? in.position : out.position, axis);
            if (segments[s].sharp) poly[s][sizes[s]++] = *segments[s].sharp;
            poly[s][sizes[s]++] = project(forward ? out.position : in.position, axis);
        }
        if (minKey[1] < minKey[0]) {
            std::swap(poly[0], poly[1]);
            std::swap(sizes[0], sizes[1]);
        }
        for (int i = 0; i + 1 < sizes[0]; ++i)
            for (int j = 0; j + 1 < sizes[1]; ++j)
                if (segmentsCross(poly[0][i], poly[0][i + 1], poly[1][j], poly[1][j + 1])) return true;
        return false;
    }

    uint32_t vertex(uint64_t key, const std::array<float, 3>& pos, const std::array<float, 3>& normal,
                    MaterialId material)
    {
        auto [it, inserted] = local_.emplace(key, uint32_t(chunk_.mesh.positions.size()));
        if (inserted) addVertex(key, pos, normal, material);
        return it->second;
    }

    uint32_t addVertex(uint64_t key, const std::array<float, 3>& pos, const std::array<float, 3>& normal,
                       MaterialId material)
    {
        chunk_.mesh.positions.push_back(pos);
        chunk_.mesh.normals.push_back(normal);
        chunk_.mesh.materials.push_back(material);
        chunk_.vertexKeys.push_back(key);
        return uint32_t(chunk_.mesh.positions.size() - 1);
    }

    /// The least-squares point of a component's crossing planes (seed 004 §2.6), solved relative to the
    /// crossings' mean with singular values under a tenth of the largest truncated, and clamped to the
    /// cell: a corner (rank 3) or the point of a sharp edge nearest the mean (rank 2). A lone plane
    /// (rank 1) has no feature; the caller keeps the mean point. (Clipping an edge's line to the cell
    /// instead of clamping was tried: it measured worse on the rotated box.)
    std::optional<Eigen::Vector3d> sharpVertex(const Eigen::Matrix3d& ata, const Eigen::Vector3d& atb,
                                               const Eigen::Vector3d& massPoint) const
    {
        const Eigen::JacobiSVD<Eigen::Matrix3d> svd(ata, Eigen::ComputeFullU | Eigen::ComputeFullV);
        const Eigen::Vector3d sigma = svd.singularValues();
        const Eigen::Vector3d rhs = svd.matrixU().transpose() * (atb - ata * massPoint);
        Eigen::Vector3d scaled = Eigen::Vector3d::Zero();
        int rank = 0;
        for (; rank < 3 && sigma[rank] > 0.1 * sigma[0]; ++rank) scaled[rank] = rhs[rank] / sigma[rank];
        if (rank < 2) return std::nullopt;
        Eigen::Vector3d lo, hi;
        for (int k = 0; k < 3; ++k) lo[k] = base_[k] * voxelSize_, hi[k] = (base_[k] + 1) * voxelSize_;
        return Eigen::Vector3d((massPoint + svd.matrixV() * scaled).cwiseMax(lo).cwiseMin(hi));
    }

    void emitComponent(const int* loop, int size)
    {
        // The component's boundary: each crossing, then the points inside the face segment it starts.
        uint32_t ids[64];
        MaterialId segmentMaterial[64];
        int planes = size;
        bool hasTransition = false;
        int n = 0;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        Eigen::Vector3d crossingMean = Eigen::Vector3d::Zero();
        Eigen::Vector3d normalSum = Eigen::Vector3d::Zero();
        Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
        Eigen::Vector3d atb = Eigen::Vector3d::Zero();
        double minDot = 1.0;
        for (int i = 0; i < size; ++i) {
            const EdgeCrossing& x = crossings_.at(loop[i]);
            const Eigen::Vector3d p(x.position[0], x.position[1], x.position[2]);
            const Eigen::Vector3d nrm(x.normal[0], x.normal[1], x.normal[2]);
            for (int j = 0; j < i; ++j) {
                const auto& other = crossings_.at(loop[j]).normal;
                minDot = std::min(minDot, double(nrm.x() * other[0] + nrm.y() * other[1] + nrm.z() * other[2]));
            }
            ata += nrm * nrm.transpose();
            atb += nrm * nrm.dot(p);
            crossingMean += p;
            normalSum += nrm;
            mean += p;
            segmentMaterial[n] = x.material;
            ids[n++] = vertex(x.key, x.position, x.normal, x.material);
            MaterialId material = x.material;
            {
                const SegmentPoints& points = facePoints_[loop[i]];
                for (int k = 0; k < points.count; ++k) {
                    const FacePoint& point = points.items[k];
                    const auto& q = point.position;
                    const Eigen::Vector3d qv(q[0], q[1], q[2]);
                    mean += qv;
                    if (point.transition) {
                        // The interface plane joins the solve, so the vertex lands on the material
                        // boundary (seed 004 §4.2.2.1).
                        const Eigen::Vector3d in(point.interfaceNormal[0], point.interfaceNormal[1],
                                                 point.interfaceNormal[2]);
                        ata += in * in.transpose();
                        atb += in * in.dot(qv);
                        crossingMean += qv;
                        ++planes;
                        hasTransition = true;
                        material = point.materialAfter;
                    }
                    segmentMaterial[n] = material;
                    ids[n++] = vertex(point.key, {float(q[0]), float(q[1]), float(q[2])}, x.normal, material);
                }
            }
        }
        mean /= double(n);
        crossingMean /= double(planes);

        Eigen::Vector3d centre = mean;
        if (minDot < cosSharp_ || hasTransition) {
            if (const auto feature = sharpVertex(ata, atb, crossingMean)) centre = *feature;
        }
        const Eigen::Vector3d avgNormal = normalSum.norm() > 0.0 ? Eigen::Vector3d(normalSum.normalized()) : normalSum;
        const uint32_t c = addVertex(kUnsharedVertex, {float(centre.x()), float(centre.y()), float(centre.z())},
                                     {float(avgNormal.x()), float(avgNormal.y()), float(avgNormal.z())},
                                     segmentMaterial[0]);
        for (int i = 0; i < n; ++i) {
            chunk_.mesh.triangles.push_back({c, ids[i], ids[(i + 1) % n]});
            chunk_.mesh.triangleMaterials.push_back(segmentMaterial[i]);
        }
    }

    CellCrossings crossings_;
    Coord base_;
    const MaterialValue* mats_;
    unsigned solid_;
    double voxelSize_;
    double cosSharp_;
    MeshChunk& chunk_;
    std::unordered_map<uint64_t, uint32_t>& local_;
    int next_[12] = {};
    bool linked_[12] = {};
    SegmentPoints facePoints_[12]; // by the segment's entering edge
};

} // namespace

MeshChunk meshLeafCubicalMarchingSquares(const HermiteLeaf& leaf, ConstAccessor& acc, double voxelSize,
                                         double sharpAngleDegrees)
{
    const Neighbourhood hood(leaf, acc);
    MeshChunk chunk;
    chunk.leafOrigin = {leaf.origin().x(), leaf.origin().y(), leaf.origin().z()};
    std::unordered_map<uint64_t, uint32_t> local;
    const double cosSharp = std::cos(sharpAngleDegrees * M_PI / 180.0);
    forEachOwnedSurfaceCell(leaf, hood, [&](const Coord& base, const MaterialValue mats[8], unsigned solid) {
        CellMesher(hood, base, mats, solid, voxelSize, cosSharp, chunk, local).run();
    });
    return chunk;
}

} // namespace vdbclay::mesher_detail
