// Meshing one brick of a level-of-detail cut (LodMesh.h): the brick's own cells by the CMS kernel on
// its level's lattice, and its transition cells here. A transition cell is a unit cell of the brick's
// level that touches a finer shown brick. Its faces are polygons: a face that lies on a finer brick's
// box is split into that brick's squares, and every side is split where a finer brick's box holds it,
// so each point, side and square takes the finest data the cut shows there (seed 000 §5: the finer
// side's segments decide the shared face). Each polygon is marched plainly (crossings joined
// straight, each entering one to the next leaving one), the way the kernel meshes the faces beside
// transition cells, and each cell's loops are fanned from their mean point. No skirts, no patching.
#include "mesher/LodMesh.h"

#include "mesher/CellGrid.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace vdbclay {

namespace {

using namespace mesher_detail;
using Point = LodCut::Point;

/// One level's Hermite data, read point by point with a leaf neighbourhood cached per leaf.
class LevelReader {
public:
    explicit LevelReader(const Volume& volume) : tree_(volume.impl().grid->constTree()), acc_(tree_), voxel_(volume.voxelSize()) {}

    MaterialValue material(const Coord& c) { return acc_.getValue(c); }

    EdgeCrossing crossing(const Coord& start, int axis, MaterialValue low, MaterialValue high)
    {
        const Coord origin(start.x() & ~(kLeafDim - 1), start.y() & ~(kLeafDim - 1), start.z() & ~(kLeafDim - 1));
        auto it = hoods_.find(origin);
        if (it == hoods_.end()) {
            const HermiteLeaf* leaf = acc_.probeConstLeaf(origin);
            it = hoods_.emplace(origin, leaf ? std::optional<Neighbourhood>(Neighbourhood(*leaf, acc_)) : std::nullopt).first;
        }
        if (!it->second) {
            // No leaf holds the edge's sample: its middle, normal along the edge out of the solid.
            std::array<float, 3> pos{float(start.x()), float(start.y()), float(start.z())};
            pos[axis] += 0.5f;
            for (float& p : pos) p = float(p * voxel_);
            std::array<float, 3> n{0.f, 0.f, 0.f};
            n[axis] = low.solid() ? 1.f : -1.f;
            return {0, start, axis, pos, n, (low.solid() ? low : high).id};
        }
        return voxelEdgeCrossing(*it->second, start, axis, low, high, voxel_);
    }

private:
    const HermiteTree& tree_;
    ConstAccessor acc_;
    double voxel_;
    std::map<Coord, std::optional<Neighbourhood>> hoods_;
};

struct Crossing {
    std::array<float, 3> position;
    std::array<float, 3> normal;
    MaterialId material;
};

/// An edge of the lattice of some level, by its level-0 ends (lower first).
struct EdgeId {
    Point a, b;
    friend bool operator<(const EdgeId& x, const EdgeId& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
    friend bool operator==(const EdgeId& x, const EdgeId& y) { return x.a == y.a && x.b == y.b; }
};

class TransitionMesher {
public:
    TransitionMesher(const std::vector<const Volume*>& levels, const LodCut& cut) : cut_(cut)
    {
        for (const Volume* v : levels) readers_.push_back(v ? std::make_unique<LevelReader>(*v) : nullptr);
    }

    /// Meshes the transition cell of `level` at level index `cell` into `out`.
    void meshCell(int level, const std::array<int32_t, 3>& cell, Mesh& out)
    {
        segments_.clear();
        const int64_t size = int64_t(1) << level;
        Point lo;
        for (int a = 0; a < 3; ++a) lo[std::size_t(a)] = int64_t(cell[std::size_t(a)]) * size;
        for (int f = 0; f < 6; ++f) {
            Point corners[4];
            for (int i = 0; i < 4; ++i) {
                const int c = kFaces[f].corners[i];
                for (int a = 0; a < 3; ++a) corners[i][std::size_t(a)] = lo[std::size_t(a)] + size * cornerBit(c, a);
            }
            face(corners, level);
        }
        // Loops: each segment continues with the one that starts where it ends.
        std::map<EdgeId, std::size_t> startingAt;
        for (std::size_t i = 0; i < segments_.size(); ++i) startingAt[segments_[i].in] = i;
        std::vector<bool> used(segments_.size(), false);
        std::vector<Crossing> loop;
        for (std::size_t start = 0; start < segments_.size(); ++start) {
            if (used[start]) continue;
            loop.clear();
            std::size_t s = start;
            bool closed = false;
            while (!used[s]) {
                used[s] = true;
                const Segment& seg = segments_[s];
                loop.push_back(crossings_.at(seg.in));
                if (seg.bends) loop.push_back({seg.point, seg.normal, seg.material});
                const auto next = startingAt.find(seg.out);
                if (next == startingAt.end()) break;
                s = next->second;
                closed = s == start;
            }
            if (!closed) throw std::logic_error("LOD transition: a cell's segments do not close");
            fan(loop, out);
        }
    }

private:
    LevelReader& reader(int level)
    {
        if (level < 0 || std::size_t(level) >= readers_.size() || !readers_[std::size_t(level)])
            throw std::logic_error("LOD transition: level " + std::to_string(level) + " has no data");
        return *readers_[std::size_t(level)];
    }

    static Coord at(const Point& p, int level)
    {
        return Coord(int32_t(p[0] >> level), int32_t(p[1] >> level), int32_t(p[2] >> level));
    }

    /// A point's material, from the finest shown brick whose closed box holds it.
    MaterialValue pointMaterial(const Point& p, int ownLevel)
    {
        const int level = finerHolding(p, p, ownLevel);
        return reader(level).material(at(p, level));
    }

    /// The finest level holding a box, if finer than `level`.
    int finerHolding(const Point& a, const Point& b, int level) const
    {
        Point lo, hi;
        for (int k = 0; k < 3; ++k) lo[std::size_t(k)] = std::min(a[std::size_t(k)], b[std::size_t(k)]), hi[std::size_t(k)] = std::max(a[std::size_t(k)], b[std::size_t(k)]);
        const int m = cut_.finestHolding(lo, hi, level - 1);
        return m >= 0 && m < level ? m : level;
    }

    /// A square of `level`, corners counter-clockwise seen from outside the cell: split into the squares
    /// of a finer brick whose box holds it, else marched as a polygon.
    void face(const Point c[4], int level)
    {
        if (finerHolding(c[0], c[2], level) < level) {
            Point mid[4], centre;
            for (int i = 0; i < 4; ++i)
                for (int k = 0; k < 3; ++k) mid[i][std::size_t(k)] = (c[i][std::size_t(k)] + c[(i + 1) % 4][std::size_t(k)]) / 2;
            for (int k = 0; k < 3; ++k) centre[std::size_t(k)] = (c[0][std::size_t(k)] + c[2][std::size_t(k)]) / 2;
            const Point q0[4] = {c[0], mid[0], centre, mid[3]}, q1[4] = {mid[0], c[1], mid[1], centre};
            const Point q2[4] = {centre, mid[1], c[2], mid[2]}, q3[4] = {mid[3], centre, mid[2], c[3]};
            for (const Point* q : {q0, q1, q2, q3}) face(q, level - 1);
            return;
        }
        polygon_.clear();
        for (int i = 0; i < 4; ++i) side(c[i], c[(i + 1) % 4], level);
        for (int k = 0; k < 3; ++k) faceCentre2_[std::size_t(k)] = c[0][std::size_t(k)] + c[2][std::size_t(k)];
        march(level);
    }

    /// A side of a square, split where a finer brick's box holds a part of it.
    void side(const Point& a, const Point& b, int level)
    {
        if (level > 0 && finerHolding(a, b, level) < level) {
            Point mid;
            for (int k = 0; k < 3; ++k) mid[std::size_t(k)] = (a[std::size_t(k)] + b[std::size_t(k)]) / 2;
            side(a, mid, level - 1);
            side(mid, b, level - 1);
            return;
        }
        polygon_.push_back({a, b, level});
    }

    /// The crossing on a polygon side whose ends differ in solidity.
    const Crossing& crossing(const Point& a, const Point& b, int level, MaterialValue ma, MaterialValue mb)
    {
        const bool forward = a < b;
        const EdgeId id{forward ? a : b, forward ? b : a};
        const auto found = crossings_.find(id);
        if (found != crossings_.end()) return found->second;
        const Point& low = id.a;
        const Point& high = id.b;
        const MaterialValue mLow = forward ? ma : mb, mHigh = forward ? mb : ma;
        int axis = 0;
        while (low[std::size_t(axis)] == high[std::size_t(axis)]) ++axis;
        LevelReader& r = reader(level);
        const MaterialValue dataLow = r.material(at(low, level)), dataHigh = r.material(at(high, level));
        Crossing x;
        if (dataLow.solid() != dataHigh.solid()) {
            // The level's own crossing of this edge.
            const EdgeCrossing e = r.crossing(at(low, level), axis, dataLow, dataHigh);
            x = {e.position, e.normal, (mLow.solid() ? mLow : mHigh).id};
        } else {
            // An end took a finer level's material: the surface crosses the edge's middle, facing along it.
            const double voxel = levelVoxel(level) / double(int64_t(1) << level);
            for (int k = 0; k < 3; ++k) x.position[std::size_t(k)] = float(double(low[std::size_t(k)] + high[std::size_t(k)]) * 0.5 * voxel);
            x.normal = {0.f, 0.f, 0.f};
            x.normal[std::size_t(axis)] = mLow.solid() ? 1.f : -1.f;
            x.material = (mLow.solid() ? mLow : mHigh).id;
        }
        return crossings_.emplace(id, x).first->second;
    }

    double levelVoxel(int level) { return levelVoxels_.count(level) ? levelVoxels_[level] : 0.0; }

public:
    void setVoxelSizes(const std::vector<const Volume*>& levels)
    {
        for (std::size_t k = 0; k < levels.size(); ++k)
            if (levels[k]) levelVoxels_[int(k)] = levels[k]->voxelSize();
    }

private:
    /// Plain marching of the polygon: each entering crossing joined to the next (leaving) one.
    void march(int ownLevel)
    {
        const std::size_t n = polygon_.size();
        solid_.resize(n);
        mats_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            mats_[i] = pointMaterial(polygon_[i].a, ownLevel);
            solid_[i] = mats_[i].solid();
        }
        crossingSides_.clear();
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t j = (i + 1) % n;
            if (solid_[i] != solid_[j]) crossingSides_.push_back(i);
        }
        const std::size_t count = crossingSides_.size();
        for (std::size_t k = 0; k < count; ++k) {
            const std::size_t i = crossingSides_[k];
            if (!solid_[(i + 1) % n]) continue; // leaving
            const std::size_t o = crossingSides_[(k + 1) % count];
            const Side& in = polygon_[i];
            const Side& out = polygon_[o];
            const Crossing& a = crossing(in.a, in.b, in.level, mats_[i], mats_[(i + 1) % n]);
            const Crossing& b = crossing(out.a, out.b, out.level, mats_[o], mats_[(o + 1) % n]);
            Segment seg{edgeId(in), edgeId(out)};
            if (sameLine(in, out)) {
                // Both crossings on one side of the square (a finer brick's detail along it): the segment
                // bends into the face, so the two faces at that side do not run along the same line.
                seg.bends = true;
                double len = 0.0, toCentre = 0.0;
                std::array<double, 3> mid, dir;
                const double h = levelVoxel(0);
                for (int k = 0; k < 3; ++k) {
                    mid[std::size_t(k)] = 0.5 * (double(a.position[std::size_t(k)]) + double(b.position[std::size_t(k)]));
                    dir[std::size_t(k)] = double(faceCentre2_[std::size_t(k)]) * 0.5 * h - mid[std::size_t(k)];
                    const double d = double(a.position[std::size_t(k)]) - double(b.position[std::size_t(k)]);
                    len += d * d;
                    toCentre += dir[std::size_t(k)] * dir[std::size_t(k)];
                }
                len = std::sqrt(len), toCentre = std::sqrt(toCentre);
                const double step = toCentre > 0.0 ? std::min(0.5 * len, 0.5 * toCentre) / toCentre : 0.0;
                std::array<double, 3> nsum;
                for (int k = 0; k < 3; ++k) {
                    seg.point[std::size_t(k)] = float(mid[std::size_t(k)] + step * dir[std::size_t(k)]);
                    nsum[std::size_t(k)] = double(a.normal[std::size_t(k)]) + double(b.normal[std::size_t(k)]);
                }
                const double nl = std::sqrt(nsum[0] * nsum[0] + nsum[1] * nsum[1] + nsum[2] * nsum[2]);
                for (int k = 0; k < 3; ++k) seg.normal[std::size_t(k)] = nl > 0.0 ? float(nsum[std::size_t(k)] / nl) : 0.f;
                seg.material = a.material;
            }
            segments_.push_back(seg);
        }
    }

    struct Side {
        Point a, b;
        int level;
    };
    /// Whether two sides of a polygon lie on one line (parts of one side of its square).
    static bool sameLine(const Side& x, const Side& y)
    {
        int same = 0;
        for (int k = 0; k < 3; ++k) {
            const bool xFixed = x.a[std::size_t(k)] == x.b[std::size_t(k)], yFixed = y.a[std::size_t(k)] == y.b[std::size_t(k)];
            if (xFixed != yFixed) return false;
            if (xFixed) same += x.a[std::size_t(k)] == y.a[std::size_t(k)];
        }
        return same == 2;
    }
    static EdgeId edgeId(const Side& s) { return s.a < s.b ? EdgeId{s.a, s.b} : EdgeId{s.b, s.a}; }

    void fan(const std::vector<Crossing>& loop, Mesh& out)
    {
        std::array<double, 3> centre{0, 0, 0}, normalSum{0, 0, 0};
        for (const Crossing& x : loop)
            for (int k = 0; k < 3; ++k) {
                centre[std::size_t(k)] += x.position[std::size_t(k)];
                normalSum[std::size_t(k)] += x.normal[std::size_t(k)];
            }
        const double length = std::sqrt(normalSum[0] * normalSum[0] + normalSum[1] * normalSum[1] + normalSum[2] * normalSum[2]);
        const uint32_t c = uint32_t(out.positions.size());
        out.positions.push_back({float(centre[0] / double(loop.size())), float(centre[1] / double(loop.size())),
                                 float(centre[2] / double(loop.size()))});
        out.normals.push_back(length > 0.0 ? std::array<float, 3>{float(normalSum[0] / length), float(normalSum[1] / length),
                                                                  float(normalSum[2] / length)}
                                           : std::array<float, 3>{0.f, 0.f, 1.f});
        out.materials.push_back(loop.front().material);
        const uint32_t first = uint32_t(out.positions.size());
        for (const Crossing& x : loop) {
            out.positions.push_back(x.position);
            out.normals.push_back(x.normal);
            out.materials.push_back(x.material);
        }
        for (std::size_t i = 0; i < loop.size(); ++i) {
            out.triangles.push_back({c, first + uint32_t(i), first + uint32_t((i + 1) % loop.size())});
            out.triangleMaterials.push_back(loop[i].material);
        }
    }

    const LodCut& cut_;
    std::vector<std::unique_ptr<LevelReader>> readers_;
    std::map<int, double> levelVoxels_;
    std::map<EdgeId, Crossing> crossings_;
    struct Segment {
        EdgeId in, out;
        bool bends = false;                // a point inside the face between the crossings
        std::array<float, 3> point{}, normal{};
        MaterialId material = kEmptyMaterial;
    };
    std::vector<Segment> segments_;
    Point faceCentre2_{}; // twice the centre of the square being marched (integers)
    std::vector<Side> polygon_;
    std::vector<bool> solid_;
    std::vector<MaterialValue> mats_;
    std::vector<std::size_t> crossingSides_;
};

void checkLevel(const std::vector<const Volume*>& levels, int level)
{
    if (level < 0 || std::size_t(level) >= levels.size() || !levels[std::size_t(level)])
        throw std::invalid_argument("meshLodBrick: no data for level " + std::to_string(level));
}

std::array<int32_t, 3> brickMin(const LodBrick& brick)
{
    std::array<int32_t, 3> b{};
    for (int a = 0; a < 3; ++a) b[std::size_t(a)] = brick.brick[std::size_t(a)] * kLodBrickVoxels;
    return b;
}

} // namespace

std::vector<MeshChunk> meshLodBrickChunks(const std::vector<const Volume*>& levels, const LodCut& cut, const LodBrick& brick,
                                          const MeshOptions& options, const std::vector<std::array<int32_t, 3>>* onlyLeaves)
{
    const int level = brick.level;
    checkLevel(levels, level);
    if (options.kind != MesherKind::CubicalMarchingSquares)
        throw std::invalid_argument("meshing levels of detail side by side needs CMS (its faces decide the transitions)");
    MeshOptions o = options;
    o.lodCut = &cut;
    o.lodLevel = level;
    o.lodBrickMin = brickMin(brick);
    if (level > 0) o.planeTolerance = std::max(o.planeTolerance, options.coarseLevelPlaneTolerance);
    const int widest = options.maxCellWidth;
    o.leafMaxCellWidth = [&cut, level, widest](const std::array<int32_t, 3>& origin) { return cut.leafMaxCellWidth(level, origin, widest); };
    return meshRegionChunks(*levels[std::size_t(level)], o.lodBrickMin, kLodBrickVoxels, o, onlyLeaves);
}

Mesh meshLodBrick(const std::vector<const Volume*>& levels, const LodCut& cut, const LodBrick& brick, const MeshOptions& options)
{
    Mesh mesh = weldChunks(meshLodBrickChunks(levels, cut, brick, options));
    appendLodTransitions(levels, cut, brick, mesh);
    return mesh;
}

void appendLodTransitions(const std::vector<const Volume*>& levels, const LodCut& cut, const LodBrick& brick, Mesh& mesh,
                          std::vector<TransitionCellBox>* cells)
{
    const int level = brick.level;
    checkLevel(levels, level);
    TransitionMesher transitions(levels, cut);
    transitions.setVoxelSizes(levels);
    std::set<std::array<int32_t, 3>> meshed;
    const std::array<int32_t, 3> b = brickMin(brick);
    if (level > cut.finestLevel()) {
        // Only cells on a face of the brick that a finer brick touches can touch one, and the cells of
        // an empty region just below its low faces that it meshes (LodCut::cellOwner).
        const int32_t n = kLodBrickVoxels;
        for (int face = 0; face < 6; ++face) {
            const int axis = face / 2, high = face % 2;
            LodCut::Point lo, hi;
            for (int a = 0; a < 3; ++a) {
                lo[std::size_t(a)] = int64_t(b[std::size_t(a)]) * (int64_t(1) << level);
                hi[std::size_t(a)] = (int64_t(b[std::size_t(a)]) + n) * (int64_t(1) << level);
            }
            (high ? lo : hi)[std::size_t(axis)] = (high ? hi : lo)[std::size_t(axis)];
            const std::vector<LodBrick> finer = cut.finerTouching(lo, hi, level);
            if (finer.empty()) continue;
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const int32_t depths[2] = {high ? n - 1 : -1, 0};
            for (int d = 0; d < (high ? 1 : 2); ++d)
                for (int32_t i = -1; i < n; ++i)
                    for (int32_t j = -1; j < n; ++j) {
                        std::array<int32_t, 3> cell;
                        const int32_t depth = depths[d];
                        cell[std::size_t(axis)] = b[std::size_t(axis)] + depth;
                        cell[std::size_t(u)] = b[std::size_t(u)] + i;
                        cell[std::size_t(v)] = b[std::size_t(v)] + j;
                        const bool outside = depth < 0 || i < 0 || j < 0;
                        LodCut::Point clo, chi;
                        for (int a = 0; a < 3; ++a) {
                            clo[std::size_t(a)] = int64_t(cell[std::size_t(a)]) * (int64_t(1) << level);
                            chi[std::size_t(a)] = (int64_t(cell[std::size_t(a)]) + 1) * (int64_t(1) << level);
                        }
                        // LodCut::transitionCell, against the few bricks that touch this face.
                        if (std::none_of(finer.begin(), finer.end(), [&](const LodBrick& f) { return LodCut::touches(f, clo, chi); }))
                            continue;
                        if (outside) {
                            const std::optional<LodBrick> owner = cut.cellOwner(level, cell);
                            if (!owner || !(*owner == brick)) continue;
                        }
                        if (!meshed.insert(cell).second) continue; // on two faces: once
                        transitions.meshCell(level, cell, mesh);
                        if (cells) cells->push_back({clo, chi});
                    }
        }
    }
    // Space outside the cut is the coarsest level's: its cells beside this finer brick that this
    // brick owns are transition cells of that level.
    const int top = cut.coarsestLevel();
    if (level < top) {
        std::array<int32_t, 2> range[3];
        for (int a = 0; a < 3; ++a) {
            const int64_t lo0 = int64_t(b[std::size_t(a)]) * (int64_t(1) << level), hi0 = (int64_t(b[std::size_t(a)]) + kLodBrickVoxels) * (int64_t(1) << level);
            const int64_t size = int64_t(1) << top;
            const int64_t first = (lo0 >= 0 ? lo0 / size : -((-lo0 + size - 1) / size)) - 1;
            const int64_t last = hi0 >= 0 ? hi0 / size : -((-hi0 + size - 1) / size);
            range[a] = {int32_t(first), int32_t(last)};
        }
        for (int32_t x = range[0][0]; x <= range[0][1]; ++x)
            for (int32_t y = range[1][0]; y <= range[1][1]; ++y)
                for (int32_t z = range[2][0]; z <= range[2][1]; ++z) {
                    // Only the shell around the brick lies outside it.
                    const bool shell = x == range[0][0] || x == range[0][1] || y == range[1][0] || y == range[1][1] ||
                                       z == range[2][0] || z == range[2][1];
                    if (!shell) {
                        z = range[2][1] - 1;
                        continue;
                    }
                    const std::array<int32_t, 3> cell{x, y, z};
                    const std::optional<LodBrick> owner = cut.cellOwner(top, cell);
                    if (!owner || !(*owner == brick)) continue;
                    LodCut::Point lo, hi;
                    for (int a = 0; a < 3; ++a) {
                        lo[std::size_t(a)] = int64_t(cell[std::size_t(a)]) * (int64_t(1) << top);
                        hi[std::size_t(a)] = (int64_t(cell[std::size_t(a)]) + 1) * (int64_t(1) << top);
                    }
                    if (cut.levelAround(lo, hi) >= 0 || !cut.transitionCell(top, cell)) continue;
                    transitions.meshCell(top, cell, mesh);
                    if (cells) cells->push_back({lo, hi});
                }
    }
}

} // namespace vdbclay
