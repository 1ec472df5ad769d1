#include "sculpt/Csg.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/PrintableText.h"

#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>
#include <stdexcept>

namespace vdbclay {

namespace {

constexpr int kFoot = kLeafDim + 1; // a block plus the first layer of its +x/+y/+z neighbours
constexpr int kFootVoxels = kFoot * kFoot * kFoot;

/// The origin of the node of side `dim` (a power of two) that holds `c`.

inline int footIndex(int i, int j, int k) { return (i * kFoot + j) * kFoot + k; }
constexpr int kFootStride[3] = {kFoot * kFoot, kFoot, 1}; // +x, +y, +z neighbours in the footprint
/// Footprint offsets of the voxels of a 3^3 cube from its first voxel, in cube order (x slowest).
constexpr std::array<int, 27> kCubeOffset = [] {
    std::array<int, 27> out{};
    for (int n = 0; n < 27; ++n) out[n] = (n / 9) * kFoot * kFoot + ((n / 3) % 3) * kFoot + n % 3;
    return out;
}();

using ConstAccessor = openvdb::tree::ValueAccessor<const HermiteTree, /*IsSafe=*/false>;

/// Points whose brush distance is within this many voxels of zero lie on the brush's surface, and a
/// point on the surface is inside: every op takes the brush as a closed set. Two solids that touch on
/// the lattice (a face on a shared lattice plane, spheres through one lattice point) therefore share the
/// corners on the contact and fuse, and removing or intersecting with a brush whose surface runs through
/// corners treats those corners as the brush's own, so a difference leaves no sheet of corners behind.
/// The band absorbs the rounding of distances at lattice points (coordinates times a voxel size like
/// 0.1) and is far below the offset quantization.
constexpr double kOnSurfaceVoxels = 1e-9;

/// Everything a block task needs to know about the edit, read-only during the parallel phase.
struct EditContext {
    const SdfField& field;
    CsgMode mode;
    MaterialValue material;
    double voxelSize;
    double onSurface; // kOnSurfaceVoxels in world units
    std::vector<double> erodeOffset; // per material id; empty unless eroding
    double maxErodeOffset = 0.0;
    double lipschitz = 1.0; // field.lipschitz(): every one-side test scales its reach by it

    double offsetFor(MaterialValue m) const { return erodeOffset.empty() ? 0.0 : erodeOffset[m.id]; }

    /// The new material of a point of material `old`, inside the brush or not. The per-mode versions
    /// let the block kernel drop the dispatch from its inner loops.
    template<CsgMode Mode>
    MaterialValue applyMode(MaterialValue old, bool in) const
    {
        if constexpr (Mode == CsgMode::Add) return in ? material : old;
        else if constexpr (Mode == CsgMode::Remove || Mode == CsgMode::Erode) return in ? MaterialValue{} : old;
        else if constexpr (Mode == CsgMode::Intersect) return in ? old : MaterialValue{};
        else return in && old.solid() ? material : old;
    }
    template<CsgMode Mode>
    bool insideMode(double d, MaterialValue m) const
    {
        if constexpr (Mode == CsgMode::Erode) return d + erodeOffset[m.id] < 0.0;
        else return d < 0.0;
    }
    MaterialValue apply(MaterialValue old, bool in) const
    {
        switch (mode) {
        case CsgMode::Add: return applyMode<CsgMode::Add>(old, in);
        case CsgMode::Remove: return applyMode<CsgMode::Remove>(old, in);
        case CsgMode::Intersect: return applyMode<CsgMode::Intersect>(old, in);
        case CsgMode::Paint: return applyMode<CsgMode::Paint>(old, in);
        case CsgMode::Erode: return applyMode<CsgMode::Erode>(old, in);
        }
        return old;
    }

    Vec3d world(const Coord& c) const { return Vec3d(c.x(), c.y(), c.z()) * voxelSize; }
    /// The brush distance shifted so that "inside" is "below zero" for points on the surface too.
    double distance(const Vec3d& p) const { return field.distance(p) - onSurface; }
    void distances(const LatticePatch& patch, double* out) const
    {
        field.distances(patch, out);
        for (std::size_t i = 0; i < patch.size(); ++i) out[i] -= onSurface;
    }
};

enum class RegionClass { Outside, Inside, Mixed };

/// Margin, in voxels, added to every "this region lies on one side" test: it absorbs the rounding of
/// distances and the small error of brushes whose distance is itself a numerical minimum (strokes).
constexpr double kSideMargin = 1e-3;

/// Classifies the footprint [origin, origin + size]^3 (voxel centres) against the brush. The distance
/// bound is Lipschitz-1, so a centre farther from the surface than the half-diagonal decides the region.
RegionClass classifyRegion(const EditContext& ctx, const Coord& origin, int size)
{
    const double half = 0.5 * size;
    const Vec3d centre = ctx.world(origin) + Vec3d(half * ctx.voxelSize);
    const double radius = (std::sqrt(3.0) * half + kSideMargin) * ctx.voxelSize * ctx.lipschitz;
    const double d = ctx.field.distance(centre);
    if (d > radius) return RegionClass::Outside;
    if (d + ctx.maxErodeOffset < -radius) return RegionClass::Inside;
    return RegionClass::Mixed;
}

struct BlockTask {
    Coord origin;
    const HermiteLeaf* oldLeaf = nullptr;
    MaterialValue tileValue{};
};

struct BlockResult {
    bool uniform = false;
    bool unchanged = false; // the block keeps its old content exactly
    BlockChange change;     // otherwise: what changed (the whole block unless a leaf stays a leaf)
    MaterialValue value{};
    HermiteLeafData data;
    uint64_t crossings = 0;
};

struct TileEdit {
    Coord origin;
    Index level; // 1: an 8^3 tile, 2: a 128^3 tile
    MaterialValue value;
};

/// Finds the zero of f(t) = distance(p0 + t * edge) + offset on [lo, hi], where the signs differ at the
/// ends. Each step first narrows the bracket by the distance values (a distance bound never overshoots
/// the surface, seed 004 Fig 4.11: a plane crossing the edge is found in one step), then tries the secant
/// point inside what is left; when that fails to halve the bracket, it bisects instead.
double findCrossing(const EditContext& ctx, const Vec3d& p0, const Vec3d& edge, double lo, double hi, double flo,
                    double fhi, double offset)
{
    const double len = ctx.voxelSize;
    const double step = ctx.voxelSize * ctx.lipschitz; // the distance changes at most this much per unit t
    bool bisectNext = false;
    for (int it = 0; it < 64 && hi - lo > 4e-6; ++it) { // offsets are stored to 1/65535 of an edge
        const double width = hi - lo;
        const double a = std::min(hi, lo + std::fabs(flo) / step);
        const double b = std::max(lo, hi - std::fabs(fhi) / step);
        double t;
        if (a >= b) t = 0.5 * (a + b);
        else if (bisectNext) t = 0.5 * (a + b);
        else t = std::clamp(lo + (hi - lo) * flo / (flo - fhi), a, b);
        const double ft = ctx.distance(p0 + edge * t) + offset;
        if (std::fabs(ft) < 1e-6 * len) return t;
        if ((ft < 0.0) == (flo < 0.0)) lo = t, flo = ft;
        else hi = t, fhi = ft;
        bisectNext = !bisectNext && hi - lo > 0.5 * width;
    }
    const double denom = flo - fhi;
    return denom != 0.0 ? std::clamp(lo + (hi - lo) * flo / denom, lo, hi) : 0.5 * (lo + hi);
}

/// The offset a crossing at t is stored with (kept off the voxel corners).
double storedOffset(double t) { return dequantizeOffset(quantizeOffset(t)); }

Vec3d brushGradient(const EditContext& ctx, const Vec3d& p, int axis)
{
    // A tiny step: a crossing can lie 2.4e-4 voxel from a box's edge (a face on a lattice plane), and a
    // stencil wider than that mixes the two faces' normals there.
    const Vec3d g = ctx.field.gradient(p, 1e-6 * ctx.voxelSize);
    if (g.lengthSqr() > 0.0) return g;
    Vec3d fallback(0.0);
    fallback[axis] = 1.0;
    return fallback;
}

/// Re-computes the Hermite sample of one edge as 1D CSG: the old edge is one or two material runs,
/// the brush splits each run where it crosses it, and the result's runs give the new sample. When more
/// than one boundary remains, the one that changes occupancy wins, so a solid/empty crossing is never
/// traded for a material boundary (paint keeps every surface crossing bit-exact).
bool resolveEdge(const EditContext& ctx, const Vec3d& p0, int axis, MaterialValue m0, MaterialValue m1,
                 const PackedSample* old, double d0, double d1, PackedSample& out, uint64_t& crossings)
{
    Vec3d edge(0.0);
    edge[axis] = ctx.voxelSize;

    // One material along the whole edge: at most one boundary, where the brush crosses it.
    if (m0 == m1) {
        const double off = ctx.offsetFor(m0);
        const bool inA = d0 + off < 0.0, inB = d1 + off < 0.0;
        const MaterialValue before = ctx.apply(m0, inA), after = ctx.apply(m0, inB);
        if (before == after) return false;
        ++crossings;
        // A field that knows this edge's crossing exactly (a grid tool on the lattice) gives it; the
        // erosion offset moves the zero away from the field's surface, so it is searched then.
        const std::optional<EdgeCrossing> exact = off == 0.0 ? ctx.field.latticeCrossing(p0, axis, ctx.voxelSize)
                                                             : std::nullopt;
        // The normal is taken where the crossing is stored: kept off the corner, as a box edge through the
        // corner has no single normal there.
        const double t = storedOffset(exact ? exact->offset : findCrossing(ctx, p0, edge, 0.0, 1.0, d0 + off, d1 + off, off));
        Vec3d normal = exact ? exact->normal : brushGradient(ctx, p0 + edge * t, axis); // points out of the brush
        if (!(inA ? before : after).solid()) normal = -normal; // surface normals point into empty space
        out = packSample(t, {normal.x(), normal.y(), normal.z()});
        return true;
    }

    // Two materials: two runs meeting at the old crossing, each of which the brush may split.
    struct Segment { double ta, tb, fa, fb; MaterialValue m; };
    const double tOld = old ? dequantizeOffset(old->offset) : 0.5;
    const double dOld = ctx.distance(p0 + edge * tOld);
    const Segment segs[2] = {{0.0, tOld, d0, dOld, m0}, {tOld, 1.0, dOld, d1, m1}};
    constexpr int segCount = 2;

    enum class Kind { Start, Old, Brush };
    struct Run { double t; MaterialValue m; Kind kind; bool insideBefore; bool atOld; std::optional<Vec3d> normal; };
    Run runs[4];
    int runCount = 0;
    auto push = [&](const Run& r) {
        if (runCount > 0 && runs[runCount - 1].m == r.m) return; // same material: no boundary
        runs[runCount++] = r;
    };
    for (int s = 0; s < segCount; ++s) {
        const Segment& seg = segs[s];
        const double off = ctx.offsetFor(seg.m);
        const bool inA = seg.fa + off < 0.0, inB = seg.fb + off < 0.0;
        const MaterialValue before = ctx.apply(seg.m, inA), after = ctx.apply(seg.m, inB);
        push({seg.ta, before, s == 0 ? Kind::Start : Kind::Old, false, false, std::nullopt});
        if (before != after) {
            std::optional<EdgeCrossing> exact = off == 0.0 ? ctx.field.latticeCrossing(p0, axis, ctx.voxelSize)
                                                           : std::nullopt;
            if (exact && !(exact->offset >= seg.ta && exact->offset <= seg.tb)) exact.reset();
            const double tc =
                exact ? exact->offset : findCrossing(ctx, p0, edge, seg.ta, seg.tb, seg.fa + off, seg.fb + off, off);
            ++crossings;
            // The brush surface runs through the old surface point when its distance there is below
            // the offset quantization (1/65535 of an edge); on an edge the surface grazes, the found
            // crossing can still drift from it by more than kSameCrossing.
            const bool atOld = std::fabs(dOld + off) < 1e-5 * ctx.voxelSize;
            push({tc, after, Kind::Brush, inA, atOld, exact ? std::optional<Vec3d>(exact->normal) : std::nullopt});
        }
    }
    if (runCount < 2) return false;

    int chosen = 1;
    if (runs[0].m.solid() != runs[runCount - 1].m.solid()) {
        while (chosen < runCount - 1 && runs[chosen - 1].m.solid() == runs[chosen].m.solid()) ++chosen;
    }
    const Run& b = runs[chosen];
    // A brush crossing that coincides with the old one (the brush surface runs through the old surface
    // point, as in A union A) keeps the stored sample, so re-applying an edit changes nothing.
    constexpr double kSameCrossing = 1e-4;
    if (old && (b.kind == Kind::Old || (b.kind == Kind::Brush && (b.atOld || std::fabs(b.t - tOld) < kSameCrossing)))) {
        out = *old;
        return true;
    }
    double t = storedOffset(b.t);
    Vec3d normal;
    if (b.kind == Kind::Brush) {
        normal = b.normal ? *b.normal : brushGradient(ctx, p0 + edge * t, axis); // points out of the brush
        const MaterialValue insideMaterial = b.insideBefore ? runs[chosen - 1].m : b.m;
        if (!insideMaterial.solid()) normal = -normal;    // surface normals point into empty space
    } else {
        // Old boundary without a stored sample (inconsistent input): a flat crossing mid-edge.
        t = tOld;
        normal = Vec3d(0.0);
        normal[axis] = runs[chosen - 1].m.solid() ? 1.0 : -1.0;
    }
    out = packSample(t, {normal.x(), normal.y(), normal.z()});
    return true;
}

/// Old materials of a block's footprint: its own voxels and the first layer of the seven leaves or tiles
/// above it, copied row by row from their buffers.
void gatherFootprint(const BlockTask& task, ConstAccessor& acc, std::array<MaterialValue, kFootVoxels>& out)
{
    const MaterialValue* values[8];
    MaterialValue tiles[8];
    for (int n = 0; n < 8; ++n) {
        const HermiteLeaf* leaf = task.oldLeaf;
        tiles[n] = task.tileValue;
        if (n > 0) {
            const Coord o = task.origin.offsetBy((n & 1) * kLeafDim, ((n >> 1) & 1) * kLeafDim, ((n >> 2) & 1) * kLeafDim);
            leaf = acc.probeConstLeaf(o);
            if (!leaf) tiles[n] = acc.getValue(o);
        }
        values[n] = leaf ? leaf->buffer().data() : nullptr;
    }
    for (int i = 0; i < kFoot; ++i) {
        for (int j = 0; j < kFoot; ++j) {
            const int n = (i >> 3) | ((j >> 3) << 1);
            MaterialValue* row = &out[footIndex(i, j, 0)];
            const Index rowOffset = Index(((i & 7) << 6) | ((j & 7) << 3));
            if (values[n]) std::copy_n(values[n] + rowOffset, kLeafDim, row);
            else std::fill_n(row, kLeafDim, tiles[n]);
            row[kLeafDim] = values[n | 4] ? values[n | 4][rowOffset] : tiles[n | 4];
        }
    }
}

/// Whether two runs of eight materials are equal (one compare instead of eight).
inline bool sameRow(const MaterialValue* a, const MaterialValue* b)
{
    return std::memcmp(a, b, kLeafDim * sizeof(MaterialValue)) == 0;
}

template<CsgMode Mode>
BlockResult computeBlockFor(const EditContext& ctx, const BlockTask& task, ConstAccessor& acc)
{
    std::array<MaterialValue, kFootVoxels> oldMat;
    std::array<MaterialValue, kFootVoxels> newMat;
    std::array<double, kFootVoxels> dist;
    const Coord& o = task.origin;
    gatherFootprint(task, acc, oldMat);
    // The footprint is 3x3x3 cubes of 3^3 voxels. A cube whose centre lies farther from the surface than
    // its half-diagonal is on one side of it: its voxels get a sign-correct bound |d(c)| - |p - c| instead
    // of an exact distance, which is all the inside tests and the crossing search need from them.
    const double vs = ctx.voxelSize;
    const double cubeReach = (std::sqrt(3.0) + kSideMargin) * vs * ctx.lipschitz;
    double offsetLength[27]; // most the distance changes from the cube's centre to each of its voxels
    for (int n = 0; n < 27; ++n) {
        const int di = n / 9 - 1, dj = (n / 3) % 3 - 1, dk = n % 3 - 1;
        offsetLength[n] = vs * ctx.lipschitz * std::sqrt(double(di * di + dj * dj + dk * dk));
    }
    double values[27];
    double cubeCentre[27];
    ctx.distances(LatticePatch{{o.x() + 1, o.y() + 1, o.z() + 1}, 3, 3, vs}, cubeCentre);
    for (int c = 0; c < 27; ++c) {
        const int ci = c / 9 * 3, cj = (c / 3) % 3 * 3, ck = c % 3 * 3;
        const double dc = cubeCentre[c];
        const bool settled = dc > cubeReach || dc + ctx.maxErodeOffset < -cubeReach;
        if (settled) {
            for (int n = 0; n < 27; ++n) values[n] = dc > 0.0 ? dc - offsetLength[n] : dc + offsetLength[n];
        } else {
            ctx.distances(LatticePatch{{o.x() + ci, o.y() + cj, o.z() + ck}, 1, 3, vs}, values);
        }
        const int cubeBase = footIndex(ci, cj, ck);
        for (int n = 0; n < 27; ++n) {
            const int f = cubeBase + kCubeOffset[n];
            dist[f] = values[n];
            newMat[f] = ctx.applyMode<Mode>(oldMat[f], ctx.insideMode<Mode>(values[n], oldMat[f]));
        }
    }

    BlockResult result;
    HermiteLeafData& data = result.data;
    bool uniform = true;
    const MaterialValue first = newMat[0];
    for (int i = 0; i < kLeafDim; ++i) {
        for (int j = 0; j < kLeafDim; ++j) {
            const int rowStart = footIndex(i, j, 0);
            const MaterialValue* row = &newMat[rowStart];
            std::copy_n(row, kLeafDim, &data.material[Index((i << 6) | (j << 3))]);
            const bool crossX = !sameRow(row, row + kFootStride[0]);
            const bool crossY = !sameRow(row, row + kFootStride[1]);
            const bool crossZ = !sameRow(row, row + 1);
            uniform = uniform && !crossZ && row[0] == first;
            if (!crossX && !crossY && !crossZ) continue;
            for (int k = 0; k < kLeafDim; ++k) {
                const Index n = Index((i << 6) | (j << 3) | k);
                const int v = rowStart + k;
                for (int a = 0; a < 3; ++a) {
                    const int nb = v + kFootStride[a];
                    if (newMat[v] == newMat[nb]) continue;
                    const PackedSample* old = task.oldLeaf ? task.oldLeaf->sample(n, a) : nullptr;
                    const bool touched = dist[v] < 0.0 || dist[nb] < 0.0 || newMat[v] != oldMat[v] ||
                                         newMat[nb] != oldMat[nb] || !old;
                    PackedSample sample;
                    if (!touched) {
                        sample = *old;
                    } else if (!resolveEdge(ctx, ctx.world(o.offsetBy(i, j, k)), a, oldMat[v], oldMat[nb], old,
                                            dist[v], dist[nb], sample, result.crossings)) {
                        continue;
                    }
                    const int bit = HermiteLeaf::edgeBit(n, a);
                    data.edgeBits[bit >> 6] |= uint64_t(1) << (bit & 63);
                    data.samples.push_back(sample);
                }
            }
        }
    }
    result.uniform = uniform && data.samples.empty();
    result.value = first;
    return result;
}

BlockResult computeBlock(const EditContext& ctx, const BlockTask& task, ConstAccessor& acc)
{
    switch (ctx.mode) {
    case CsgMode::Add: return computeBlockFor<CsgMode::Add>(ctx, task, acc);
    case CsgMode::Remove: return computeBlockFor<CsgMode::Remove>(ctx, task, acc);
    case CsgMode::Intersect: return computeBlockFor<CsgMode::Intersect>(ctx, task, acc);
    case CsgMode::Paint: return computeBlockFor<CsgMode::Paint>(ctx, task, acc);
    case CsgMode::Erode: return computeBlockFor<CsgMode::Erode>(ctx, task, acc);
    }
    return {};
}

/// Walks the touched region from 128^3 nodes down to leaf-sized blocks, settling whole regions as
/// tiles where the brush covers or misses them, and queueing mixed blocks as tasks.
class RegionWalker {
public:
    RegionWalker(const EditContext& ctx, HermiteTree& tree, const CoordBBox& region)
        : ctx_(ctx), acc_(tree), region_(region) {}

    void walk()
    {
        const Coord lo = alignDown(region_.min(), kLowerDim), hi = region_.max();
        for (int x = lo.x(); x <= hi.x(); x += kLowerDim)
            for (int y = lo.y(); y <= hi.y(); y += kLowerDim)
                for (int z = lo.z(); z <= hi.z(); z += kLowerDim) visitLower(Coord(x, y, z));
    }

    std::vector<BlockTask> tasks;
    std::vector<TileEdit> edits;

private:
    /// Regions without children that no op can change: empty space under every op but add, and a solid
    /// tile of the op's own material under add and paint. A tile holds no crossings, so the first layer of
    /// its +x/+y/+z neighbours holds its material too, and keeps it.
    bool untouched(bool hasChildren, MaterialValue tile) const
    {
        if (hasChildren) return false;
        if (!tile.solid()) return ctx_.mode != CsgMode::Add;
        return (ctx_.mode == CsgMode::Add || ctx_.mode == CsgMode::Paint) && tile == ctx_.material;
    }

    /// Settles a region the brush misses or covers entirely, with a tile edit where its content
    /// changes. Returns false when the region must be looked at more closely.
    bool settle(const Coord& origin, Index level, bool hasChildren, MaterialValue tile, RegionClass cls)
    {
        if (cls == RegionClass::Mixed) return false;
        if (cls == RegionClass::Outside) {
            if (ctx_.mode == CsgMode::Intersect && (hasChildren || tile.solid())) edits.push_back({origin, level, {}});
            return true;
        }
        if (!hasChildren) {
            const MaterialValue value = ctx_.apply(tile, true);
            if (value != tile) edits.push_back({origin, level, value});
            return true;
        }
        switch (ctx_.mode) {
        case CsgMode::Add:
        case CsgMode::Remove: edits.push_back({origin, level, ctx_.apply(MaterialValue{}, true)}); return true;
        case CsgMode::Intersect: return true;
        case CsgMode::Paint:
        case CsgMode::Erode: return false; // the outcome depends on each voxel's material
        }
        return false;
    }

    void visitLower(const Coord& origin)
    {
        const HermiteLower* node = acc_.template probeConstNode<HermiteLower>(origin);
        const MaterialValue tile = node ? MaterialValue{} : acc_.getValue(origin);
        if (untouched(node, tile) || settle(origin, 2, node, tile, classifyRegion(ctx_, origin, kLowerDim))) return;
        CoordBBox sub(origin, origin.offsetBy(kLowerDim - 1));
        sub.intersect(region_);
        const Coord lo = alignDown(sub.min(), kLeafDim);
        for (int x = lo.x(); x <= sub.max().x(); x += kLeafDim)
            for (int y = lo.y(); y <= sub.max().y(); y += kLeafDim)
                for (int z = lo.z(); z <= sub.max().z(); z += kLeafDim) visitBlock(Coord(x, y, z), node, tile);
    }

    void visitBlock(const Coord& origin, const HermiteLower* node, MaterialValue nodeTile)
    {
        const HermiteLeaf* leaf = node ? node->probeConstLeaf(origin) : nullptr;
        // Without a leaf the node's table holds the block's tile; read it there (getValue would go through
        // the child path, which GCC then warns about as a write through a null leaf).
        const MaterialValue tile =
            leaf ? MaterialValue{} : (node ? node->getTable()[HermiteLower::coordToOffset(origin)].getValue() : nodeTile);
        if (untouched(leaf, tile) || settle(origin, 1, leaf, tile, classifyRegion(ctx_, origin, kLeafDim))) return;
        tasks.push_back({origin, leaf, tile});
    }

    const EditContext& ctx_;
    openvdb::tree::ValueAccessor<HermiteTree> acc_;
    CoordBBox region_;
};

/// Whether a leaf lies in the block at `origin` or in one of its 26 neighbours.
bool hasLeafAround(openvdb::tree::ValueAccessor<const HermiteTree>& acc, const Coord& origin)
{
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
                if (acc.probeConstLeaf(origin.offsetBy(dx * kLeafDim, dy * kLeafDim, dz * kLeafDim))) return true;
    return false;
}

CoordBBox solidBounds(const HermiteTree& tree)
{
    CoordBBox box;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) box.expand(leaf->getNodeBoundingBox());
    forEachTile(tree, [&](const CoordBBox& tile, MaterialValue value) {
        if (value.solid()) box.expand(tile);
    });
    return box;
}

} // namespace

void EditStats::append(const EditStats& more)
{
    blocksComputed += more.blocksComputed;
    leavesWritten += more.leavesWritten;
    tilesWritten += more.tilesWritten;
    crossingsComputed += more.crossingsComputed;
    dirtyBlocks.insert(dirtyBlocks.end(), more.dirtyBlocks.begin(), more.dirtyBlocks.end());
    blockChanges.insert(blockChanges.end(), more.blockChanges.begin(), more.blockChanges.end());
}

const char* csgModeName(CsgMode mode)
{
    switch (mode) {
    case CsgMode::Add: return "add";
    case CsgMode::Remove: return "remove";
    case CsgMode::Intersect: return "intersect";
    case CsgMode::Paint: return "paint";
    case CsgMode::Erode: return "erode";
    }
    return "?";
}

CsgMode parseCsgMode(const std::string& name)
{
    for (CsgMode m : {CsgMode::Add, CsgMode::Remove, CsgMode::Intersect, CsgMode::Paint, CsgMode::Erode}) {
        if (name == csgModeName(m)) return m;
    }
    throw std::invalid_argument("unknown mode '" + printableText(name, 80) + "' (expected add, remove, intersect, paint or erode)");
}

void checkCsgLimits(double vs, const MaterialTable& materials, const SdfField& brush, const CsgOp& op)
{
    const bool needsMaterial = op.mode == CsgMode::Add || op.mode == CsgMode::Paint;
    if (needsMaterial && (op.material == kEmptyMaterial || op.material > materials.size()))
        throw std::invalid_argument("material id " + std::to_string(op.material) + " is not in the volume's table");
    if (op.mode == CsgMode::Erode && !(op.strength >= 0.0 && op.strength <= 1.0))
        throw std::invalid_argument("erode strength must lie in [0,1]");
    const WorldBounds wb = brush.bounds();
    if (op.mode == CsgMode::Add && !wb.bounded()) throw std::invalid_argument("cannot add an unbounded brush (half-space)");
    if (!wb.bounded()) return; // it works within the solid's bounds, which the limits below already held to
    // Numbers in messages: three significant digits ("9e+08", "6.1e+07").
    auto n = [](double v) {
        char text[32];
        std::snprintf(text, sizeof(text), "%.3g", v);
        return std::string(text);
    };
    double reach = 0.0;
    for (int i = 0; i < 3; ++i) reach = std::max({reach, std::fabs(wb.min[i]) / vs, std::fabs(wb.max[i]) / vs});
    if (!(reach <= kMaxReachVoxels))
        throw std::invalid_argument("the brush reaches " + n(reach) + " voxels from the origin; volumes span at most " +
                                    n(kMaxReachVoxels) + " voxels each way (move it closer or raise the voxel size)");
    const double surface = brush.surfaceAreaBound() / (vs * vs);
    if (!(surface <= kMaxSurfaceVoxels))
        throw std::invalid_argument("the brush's surface covers about " + n(surface) + " square voxels, more than the " +
                                    n(kMaxSurfaceVoxels) + " an edit may make (about 9 GB of leaves); raise the "
                                    "voxel size or use a smaller brush");
    const double evaluations = 30.0 * surface * brush.evaluationCost();
    if (!(evaluations <= kMaxDistanceEvaluations))
        throw std::invalid_argument("the edit would take about " + n(evaluations) + " distance evaluations (" +
                                    n(surface) + " surface voxels, " + n(brush.evaluationCost()) +
                                    " per evaluation: blend parts, stroke search), more than the " +
                                    n(kMaxDistanceEvaluations) + " allowed; use fewer parts or a shorter stroke");
}

EditStats applyCsg(Volume& volume, const SdfField& brush, const CsgOp& op)
{
    checkCsgLimits(volume.voxelSize(), volume.materials(), brush, op);
    HermiteGrid& grid = *volume.impl().grid;
    HermiteTree& tree = grid.tree();
    const MaterialTable& materials = volume.materials();

    EditContext ctx{brush, op.mode, MaterialValue{op.material}, volume.voxelSize(), kOnSurfaceVoxels * volume.voxelSize(),
                    {}, 0.0, brush.lipschitz()};
    if (op.mode == CsgMode::Erode) {
        const double depth = op.erodeDepth ? *op.erodeDepth : brush.innerRadius();
        if (!(depth > 0.0) || !std::isfinite(depth))
            throw std::invalid_argument("erode needs a positive depth (an unbounded brush needs an explicit depth)");
        // A material the op cannot bite (toughness 1, or strength 0) is never inside: an explicit
        // depth below the brush's inner radius would otherwise remove its deepest part.
        ctx.erodeOffset.assign(materials.size() + 1, 0.0);
        for (MaterialId id = 1; id <= materials.size(); ++id) {
            const double bite = op.strength * (1.0 - materials.at(id).toughness);
            ctx.erodeOffset[id] = bite > 0.0 ? (1.0 - bite) * depth : std::numeric_limits<double>::infinity();
        }
        ctx.maxErodeOffset = *std::max_element(ctx.erodeOffset.begin(), ctx.erodeOffset.end());
    }

    // Voxels the brush can change lie in [a, b]; edges starting one voxel lower reach into it.
    CoordBBox region;
    const WorldBounds wb = brush.bounds();
    if (op.mode == CsgMode::Intersect || !wb.bounded()) {
        region = solidBounds(tree);
        if (region.empty()) return {};
        region.expand(1);
    }
    if (op.mode != CsgMode::Intersect && wb.bounded()) {
        const double vs = ctx.voxelSize;
        const CoordBBox brushBox(Coord(int(std::floor(wb.min.x() / vs)) - 1, int(std::floor(wb.min.y() / vs)) - 1,
                                       int(std::floor(wb.min.z() / vs)) - 1),
                                 Coord(int(std::ceil(wb.max.x() / vs)), int(std::ceil(wb.max.y() / vs)),
                                       int(std::ceil(wb.max.z() / vs))));
        if (region.empty()) region = brushBox;
        else region.intersect(brushBox);
    }
    if (region.empty()) return {};

    RegionWalker walker(ctx, tree, region);
    walker.walk();

    std::vector<BlockResult> results(walker.tasks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, walker.tasks.size(), 4), [&](const auto& range) {
        ConstAccessor acc(tree);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const BlockTask& task = walker.tasks[i];
            BlockResult& r = results[i] = computeBlock(ctx, task, acc);
            // A block the brush only grazes needs no write and no re-mesh.
            r.change.origin = {task.origin.x(), task.origin.y(), task.origin.z()};
            if (r.uniform) {
                r.unchanged = !task.oldLeaf && task.tileValue == r.value;
            } else if (task.oldLeaf) {
                const std::optional<BlockChange> change = task.oldLeaf->changeTo(r.data);
                r.unchanged = !change;
                if (change) r.change = *change;
            }
        }
    });

    EditStats stats;
    std::set<Coord> lowers;
    // Blocks whose content changed: those that were or become leaves are always dirty; a block that
    // stays a tile is dirty only if a leaf borders it afterwards, as only a leaf's cells read it.
    auto addChange = [&](const BlockChange& change) {
        stats.dirtyBlocks.push_back(change.origin);
        stats.blockChanges.push_back(change);
    };
    auto addDirty = [&](const Coord& c) { // changed throughout
        BlockChange whole;
        whole.origin = {c.x(), c.y(), c.z()};
        addChange(whole);
    };
    std::vector<Coord> changedTiles;
    // Tiles go through the tree itself (see pruneNodes); leaves through an accessor made afterwards.
    for (const TileEdit& e : walker.edits) {
        if (e.level == 2) {
            // The node's leaves change, and so do the blocks on its faces, which the cells of
            // neighbouring leaves read even when the node was and stays a tile.
            if (const HermiteLower* node = tree.probeConstNode<HermiteLower>(e.origin)) {
                for (auto it = node->cbeginChildOn(); it; ++it) addDirty(it->origin());
            }
            constexpr int kLast = kLowerDim - kLeafDim;
            for (int x = 0; x <= kLast; x += kLeafDim)
                for (int y = 0; y <= kLast; y += kLeafDim)
                    for (int z = 0; z <= kLast; z += kLeafDim) {
                        const bool onFace = x == 0 || y == 0 || z == 0 || x == kLast || y == kLast || z == kLast;
                        if (onFace) changedTiles.push_back(e.origin.offsetBy(x, y, z));
                    }
        } else if (tree.probeConstLeaf(e.origin)) {
            addDirty(e.origin);
        } else {
            changedTiles.push_back(e.origin);
        }
        tree.addTile(e.level, e.origin, e.value, false);
        lowers.insert(alignDown(e.origin, kLowerDim));
        ++stats.tilesWritten;
    }
    std::vector<std::pair<HermiteLeaf*, std::size_t>> writes;
    for (std::size_t i = 0; i < walker.tasks.size(); ++i) {
        const BlockTask& task = walker.tasks[i];
        const BlockResult& r = results[i];
        stats.crossingsComputed += r.crossings;
        ++stats.blocksComputed;
        lowers.insert(alignDown(task.origin, kLowerDim));
        if (r.uniform) ++stats.tilesWritten;
        else ++stats.leavesWritten;
        if (r.unchanged) continue;
        if (r.uniform) tree.addTile(1, task.origin, r.value, false);
        else writes.emplace_back(tree.touchLeaf(task.origin), i);
        if (r.uniform && !task.oldLeaf) changedTiles.push_back(task.origin);
        else addChange(r.change);
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, writes.size(), 8), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            writes[i].first->assign(std::move(results[writes[i].second].data));
    });
    pruneNodes(tree, lowers);
    openvdb::tree::ValueAccessor<const HermiteTree> acc(tree);
    for (const Coord& c : changedTiles)
        if (hasLeafAround(acc, c)) addDirty(c);
    return stats;
}

} // namespace vdbclay
