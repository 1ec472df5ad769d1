#include "sculpt/GridTool.h"

#include "sculpt/Csg.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/VolumeIO.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

namespace vdbclay {

namespace {

/// Lattice points between the tool's solid and the outer layer of its fields' box: room for the
/// distances rebuilt next to the surface (two voxels on either side of a crossing).
constexpr int kMargin = 3;
/// The least |distance| of a lattice point, in tool voxels: its sign is its material's, even where a
/// crossing lies on it.
constexpr float kLeastDistance = 1e-5f;
/// A crossing's tangent plane stands for the surface within this many voxels of it (half a cell's
/// diagonal); farther away only the distance to the crossing itself, less this, bounds the surface.
constexpr double kPlaneReach = 0.87;

struct Crossing {
    Vec3d point;  // index space of the tool
    Vec3d normal;
    std::array<int32_t, 3> end; // the voxel at the edge's end
    MaterialId before, after;   // the materials at the edge's start and end
};

struct Box {
    std::array<int32_t, 3> origin, dims;
    std::size_t index(int i, int j, int k) const
    {
        return (std::size_t(i) * std::size_t(dims[1]) + std::size_t(j)) * std::size_t(dims[2]) + std::size_t(k);
    }
    std::size_t size() const { return std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]); }
};

bool inRegion(MaterialId m, MaterialId region) { return region == kEmptyMaterial ? m != kEmptyMaterial : m == region; }

/// A crossing as the distance propagation reads it: its point relative to the box's origin (small
/// numbers, exact enough in float) and its normal, packed into 24 bytes.
struct SurfaceSeed {
    float x, y, z, nx, ny, nz;
};

/// How far lattice point (i, j, k) of the box lies from the surface near one crossing, in voxels: the
/// tangent-plane distance where the crossing's plane stands for the surface, and a lower bound through
/// the crossing point farther along the plane.
inline float seedDistance(const SurfaceSeed& c, float i, float j, float k)
{
    const float rx = i - c.x, ry = j - c.y, rz = k - c.z;
    const float plane = std::fabs(c.nx * rx + c.ny * ry + c.nz * rz);
    return std::max(plane, std::sqrt(rx * rx + ry * ry + rz * rz) - float(kPlaneReach));
}

/// Unsigned distances to the region's boundary, in voxels. Each lattice point within two voxels of a
/// crossing that bounds the region takes the nearest such crossing; a two-pass vector propagation
/// (each point offered its 26 neighbours' crossings, forward then backward) carries the nearest
/// crossing through the box, so far values are Euclidean distances to the surface's samples and the
/// field's gradient stays close to 1 (a chamfer transform's diagonal steps made it √3).
/// `band` (voxels, finite): distances beyond it are capped at it, and the propagation skips the blocks
/// of points farther than it (and a block more) from every seeded point: a crossing reaches a point
/// through points about as near to it, which those blocks hold.
/// `innerBand` (voxels, at most `band`, with the box's `material`): the same inside the region, whose
/// points beyond it are not computed either. A point's nearest crossing is carried to it through points
/// on its own side (the ball round it up to that crossing holds no surface), so the points outside the
/// region keep exactly their distances.
std::vector<float> boundaryDistances(const Box& box, const std::vector<Crossing>& crossings, MaterialId region,
                                     float band = std::numeric_limits<float>::infinity(), float innerBand = std::numeric_limits<float>::infinity(),
                                     const std::vector<MaterialId>* material = nullptr)
{
    innerBand = std::min(innerBand, band);
    const bool innerCapped = material && innerBand < band;
    const auto capAt = [&](std::size_t n) { return innerCapped && inRegion((*material)[n], region) ? innerBand : band; };
    std::vector<float> d(box.size(), std::numeric_limits<float>::max());
    std::vector<int32_t> nearest(box.size(), -1);
    std::vector<SurfaceSeed> seeds(crossings.size());
    for (std::size_t id = 0; id < crossings.size(); ++id) {
        const Crossing& c = crossings[id];
        seeds[id] = {float(c.point[0] - box.origin[0]), float(c.point[1] - box.origin[1]), float(c.point[2] - box.origin[2]),
                     float(c.normal[0]), float(c.normal[1]), float(c.normal[2])};
    }
    const std::size_t sentinel = crossings.size();
    seeds.push_back({std::numeric_limits<float>::max(), 0.0f, 0.0f, 0.0f, 0.0f, 0.0f});
    const int nx = box.dims[0], ny = box.dims[1], nz = box.dims[2];
    // Blocks of 2^3 points: those within the band of a seeded point's block.
    constexpr int kBlock = 2;
    const bool banded = std::isfinite(band);
    const int bx = (nx + kBlock - 1) / kBlock, by = (ny + kBlock - 1) / kBlock, bz = (nz + kBlock - 1) / kBlock;
    const auto blockIndex = [&](int i, int j, int k) {
        return (std::size_t(i / kBlock) * std::size_t(by) + std::size_t(j / kBlock)) * std::size_t(bz) + std::size_t(k / kBlock);
    };
    std::vector<uint8_t> nearBlock;
    if (banded) nearBlock.assign(std::size_t(bx) * std::size_t(by) * std::size_t(bz), 0);
    for (std::size_t id = 0; id < crossings.size(); ++id) {
        const Crossing& c = crossings[id];
        if (inRegion(c.before, region) == inRegion(c.after, region)) continue;
        const int base[3] = {int(std::floor(c.point[0])) - box.origin[0], int(std::floor(c.point[1])) - box.origin[1],
                             int(std::floor(c.point[2])) - box.origin[2]};
        for (int i = base[0] - 1; i <= base[0] + 2; ++i)
            for (int j = base[1] - 1; j <= base[1] + 2; ++j)
                for (int k = base[2] - 1; k <= base[2] + 2; ++k) {
                    // A tool's box keeps a margin round its crossings; a box cut from a scene does not.
                    if (i < 0 || j < 0 || k < 0 || i >= box.dims[0] || j >= box.dims[1] || k >= box.dims[2]) continue;
                    const float candidate = seedDistance(seeds[id], float(i), float(j), float(k));
                    const std::size_t n = box.index(i, j, k);
                    if (candidate < d[n]) d[n] = candidate, nearest[n] = int32_t(id);
                    if (banded) nearBlock[blockIndex(i, j, k)] = 1;
                }
    }
    // Per row (i, j): the span of k its blocks within the band cover (points outside it are never
    // offered anything).
    std::vector<std::array<int, 2>> rowSpan;
    if (banded) {
        // Grown by the band plus a block (the seeds sit anywhere in theirs), one axis at a time.
        const int grow = int(std::ceil(band / float(kBlock))) + 1;
        const int bdims[3] = {bx, by, bz};
        for (int axis = 0; axis < 3; ++axis) {
            const std::vector<uint8_t> before = nearBlock;
            const std::size_t stride[3] = {std::size_t(by) * std::size_t(bz), std::size_t(bz), 1};
            for (int a = 0; a < bx; ++a)
                for (int b = 0; b < by; ++b)
                    for (int c = 0; c < bz; ++c) {
                        const std::size_t n = std::size_t(a) * stride[0] + std::size_t(b) * stride[1] + std::size_t(c);
                        if (!before[n]) continue;
                        const int at = axis == 0 ? a : axis == 1 ? b : c;
                        for (int t = std::max(0, at - grow); t <= std::min(bdims[axis] - 1, at + grow); ++t)
                            nearBlock[std::size_t(std::ptrdiff_t(n) + std::ptrdiff_t(t - at) * std::ptrdiff_t(stride[axis]))] = 1;
                    }
        }
        rowSpan.assign(std::size_t(bx) * std::size_t(by), {nz, -1});
        for (int a = 0; a < bx; ++a)
            for (int b = 0; b < by; ++b) {
                const uint8_t* row = &nearBlock[(std::size_t(a) * std::size_t(by) + std::size_t(b)) * std::size_t(bz)];
                int first = 0, last = bz - 1;
                while (first <= last && !row[first]) ++first;
                while (last >= first && !row[last]) --last;
                if (first <= last) rowSpan[std::size_t(a) * std::size_t(by) + std::size_t(b)] = {first * kBlock, std::min(nz - 1, last * kBlock + kBlock - 1)};
            }
    }
    const auto spanOf = [&](int i, int j) -> std::array<int, 2> {
        return banded ? rowSpan[std::size_t(i / kBlock) * std::size_t(by) + std::size_t(j / kBlock)] : std::array<int, 2>{0, nz - 1};
    };
    struct Step {
        int di, dj, dk;
        std::ptrdiff_t offset; // in the arrays
    };
    constexpr std::size_t kEarlier = 13;
    std::array<Step, kEarlier> earlier; // the 13 neighbours a forward raster scan has visited
    std::size_t filled = 0;
    for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj)
            for (int dk = -1; dk <= 1; ++dk)
                if (di * 9 + dj * 3 + dk < 0) earlier[filled++] = {di, dj, dk, (std::ptrdiff_t(di) * ny + dj) * nz + dk};
    // A point keeps the nearest of its own crossing and those of its 13 visited neighbours. Every
    // candidate is evaluated (a bound on which can win turns few away this close to the surface, and
    // costs a branch the processor cannot predict); the best is written once.
    auto offer = [&](int i, int j, int k, int sign) {
        if (banded && !nearBlock[blockIndex(i, j, k)]) return;
        const std::size_t n = box.index(i, j, k);
        const float pi = float(i), pj = float(j), pk = float(k);
        float best = d[n];
        int32_t bestId = nearest[n];
        const bool inner = i > 0 && j > 0 && k > 0 && i < nx - 1 && j < ny - 1 && k < nz - 1;
        const float cap = capAt(n);
        if (banded && inner && best >= cap) {
            // A neighbour's crossing lies at most a step (< 1.75) nearer to this point than to the
            // neighbour: none can bring it within the band unless a neighbour lies within band + 1.75.
            float nearestNeighbour = std::numeric_limits<float>::max();
            for (const Step& s : earlier) nearestNeighbour = std::min(nearestNeighbour, d[std::size_t(std::ptrdiff_t(n) + sign * s.offset)]);
            if (nearestNeighbour >= cap + 1.75f) return;
        }
        for (const Step& s : earlier) {
            std::size_t q;
            if (inner) {
                q = std::size_t(std::ptrdiff_t(n) + sign * s.offset);
            } else {
                const int a = i + sign * s.di, b = j + sign * s.dj, c = k + sign * s.dk;
                if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
                q = box.index(a, b, c);
            }
            // A point no crossing has reached yet reads the far sentinel, which never wins.
            const int32_t id = nearest[q];
            const float candidate = seedDistance(seeds[id < 0 ? sentinel : std::size_t(id)], pi, pj, pk);
            const bool closer = candidate < best;
            best = closer ? candidate : best;
            bestId = closer ? id : bestId;
        }
        d[n] = best;
        nearest[n] = bestId;
    };
    // Each pass in wavefronts of rows: row (i, j) reads rows (i - 1, j - 1..j + 1) and (i, j - 1) of its
    // pass (mirrored for the backward one), all on earlier fronts 2i + j, so a front's rows run in
    // parallel and every point sees what the raster scan shows it.
    for (const int sign : {1, -1})
        for (int front = 0; front <= 2 * (nx - 1) + (ny - 1); ++front) {
            const int first = std::max(0, (front - (ny - 1) + 1) / 2), last = std::min(nx - 1, front / 2);
            tbb::parallel_for(tbb::blocked_range<int>(first, last + 1, 4), [&](const tbb::blocked_range<int>& rows) {
                for (int r = rows.begin(); r != rows.end(); ++r) {
                    const int j = front - 2 * r;
                    if (sign > 0) {
                        const auto [k0, k1] = spanOf(r, j);
                        for (int k = k0; k <= k1; ++k) offer(r, j, k, 1);
                    } else {
                        const auto [k0, k1] = spanOf(nx - 1 - r, ny - 1 - j);
                        for (int k = k1; k >= k0; --k) offer(nx - 1 - r, ny - 1 - j, k, -1);
                    }
                }
            });
        }
    if (banded)
        for (std::size_t n = 0; n < d.size(); ++n) d[n] = std::min(d[n], capAt(n));
    return d;
}

/// The materials at the box's lattice points (dense) and the Hermite crossings of the voxels inside it,
/// with the materials at both ends of their edges (empty beyond the box).
void readLattice(const Volume& volume, const Box& box, std::vector<MaterialId>& material, std::vector<Crossing>& crossings)
{
    material.assign(box.size(), kEmptyMaterial);
    const HermiteTree& tree = volume.impl().grid->tree();
    const CoordBBox dense(Coord(box.origin[0], box.origin[1], box.origin[2]),
                          Coord(box.origin[0] + box.dims[0] - 1, box.origin[1] + box.dims[1] - 1, box.origin[2] + box.dims[2] - 1));
    auto put = [&](const Coord& c, MaterialValue v) {
        material[box.index(c.x() - box.origin[0], c.y() - box.origin[1], c.z() - box.origin[2])] = v.id;
    };
    forEachTile(tree, [&](const CoordBBox& tile, MaterialValue value) {
        if (!value.solid() || !tile.hasOverlap(dense)) return; // an empty intersection still iterates
        CoordBBox clipped = tile;
        clipped.intersect(dense);
        for (auto it = clipped.begin(); it; ++it) put(*it, value);
    });
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        if (!dense.hasOverlap(leaf->getNodeBoundingBox())) continue;
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            const Coord c = leaf->offsetToGlobalCoord(n);
            if (!dense.isInside(c)) continue;
            const MaterialValue m = leaf->getValue(n);
            if (m.solid()) put(c, m);
            for (int a = 0; a < 3; ++a) {
                const PackedSample* s = leaf->sample(n, a);
                if (!s) continue;
                Crossing x;
                x.point = Vec3d(c.x(), c.y(), c.z());
                x.point[a] += dequantizeOffset(s->offset);
                const auto normal = decodeNormal(s->normalU, s->normalV);
                x.normal = Vec3d(normal[0], normal[1], normal[2]);
                x.end = {c.x(), c.y(), c.z()};
                x.end[std::size_t(a)] += 1;
                x.before = m.id;
                crossings.push_back(x);
            }
        }
    }
    // The material at each crossing's far end, read once the dense materials are complete.
    for (Crossing& x : crossings) {
        bool inside = true;
        for (std::size_t a = 0; a < 3; ++a) inside = inside && x.end[a] >= box.origin[a] && x.end[a] < box.origin[a] + box.dims[a];
        x.after = inside ? material[box.index(x.end[0] - box.origin[0], x.end[1] - box.origin[1], x.end[2] - box.origin[2])] : kEmptyMaterial;
    }
}

/// The signed field of one region: signs from the materials, outside values capped so that the outer
/// layer holds one value (the field's continuation beyond the box, that value plus the distance to the
/// box, is then continuous and changes at rate 1), and the largest gradient of its interpolant.
ToolField regionField(const Box& box, const std::vector<MaterialId>& materials, const std::vector<Crossing>& crossings,
                      MaterialId region)
{
    ToolField field;
    field.region = region;
    field.distance = boundaryDistances(box, crossings, region);
    std::vector<float>& d = field.distance;
    const int nx = box.dims[0], ny = box.dims[1], nz = box.dims[2];
    for (std::size_t n = 0; n < d.size(); ++n) {
        const float magnitude = std::max(d[n], kLeastDistance);
        d[n] = inRegion(materials[n], region) ? -magnitude : magnitude;
    }
    auto layersIn = [&](int i, int j, int k) { // how far inside the box's outer layer a point lies
        return std::min({i, j, k, nx - 1 - i, ny - 1 - j, nz - 1 - k});
    };
    float outer = std::numeric_limits<float>::max();
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j)
            for (int k = 0; k < nz; ++k)
                if (layersIn(i, j, k) == 0) outer = std::min(outer, d[box.index(i, j, k)]);
    // Outside values are capped by `outer` plus the layers to the outer layer over √3, so the outer layer
    // holds one value and the field's continuation beyond the box, that value plus the distance to the
    // box, joins it continuously. The cap rises by 1/√3 per layer: in a corner of the box, where a point's
    // three neighbours towards the corner all lie a layer lower, its gradient is then 1, not √3.
    const float capSlope = float(1.0 / std::sqrt(3.0));
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j)
            for (int k = 0; k < nz; ++k) {
                float& v = d[box.index(i, j, k)];
                if (v > 0.0f) v = std::min(v, outer + capSlope * float(layersIn(i, j, k)));
            }
    field.outerValue = outer;

    // The trilinear interpolant's gradient is largest at a cell corner, where its components are the
    // differences along the corner's three edges; the largest of those per axis and point bounds it.
    double worst = 0.0, deepest = 0.0;
    const std::size_t stride[3] = {std::size_t(ny) * std::size_t(nz), std::size_t(nz), 1};
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j)
            for (int k = 0; k < nz; ++k) {
                const std::size_t n = box.index(i, j, k);
                const int at[3] = {i, j, k};
                double sum = 0.0;
                for (int a = 0; a < 3; ++a) {
                    double largest = 0.0;
                    if (at[a] > 0) largest = std::fabs(double(d[n]) - d[n - stride[a]]);
                    if (at[a] + 1 < box.dims[std::size_t(a)]) largest = std::max(largest, std::fabs(double(d[n + stride[a]]) - d[n]));
                    sum += largest * largest;
                }
                worst = std::max(worst, sum);
                deepest = std::max(deepest, -double(d[n]));
            }
    field.lipschitz = std::sqrt(worst);
    field.deepest = deepest;
    return field;
}

} // namespace

Volume toolFromScene(Volume scene, const std::optional<WorldBounds>& requested)
{
    if (requested) {
        for (int a = 0; a < 3; ++a)
            if (!(requested->max[a] > requested->min[a]) || !std::isfinite(requested->min[a]) || !std::isfinite(requested->max[a]))
                throw std::invalid_argument("the box must have finite corners with x0 < x1, y0 < y1 and z0 < z1");
        // The part of the box that can hold solid voxels: a box far larger than the scene means all of it.
        const VolumeStats stats = scene.stats();
        WorldBounds box = *requested;
        for (int a = 0; a < 3; ++a) {
            box.min[a] = std::max(box.min[a], (stats.bboxMin[std::size_t(a)] - 1.5) * scene.voxelSize());
            box.max[a] = std::min(box.max[a], (stats.bboxMax[std::size_t(a)] + 1.5) * scene.voxelSize());
            if (stats.empty || !(box.max[a] > box.min[a])) throw std::invalid_argument("the box holds no solid voxel of the scene");
        }
        Primitive cut;
        cut.shape = Shape::Box;
        cut.size = (box.max - box.min) * 0.5;
        Placement at;
        at.translation = (box.max + box.min) * 0.5;
        CsgOp intersect;
        intersect.mode = CsgMode::Intersect;
        applyCsg(scene, Brush(cut, at), intersect);
    }
    if (scene.stats().empty) throw std::invalid_argument(requested ? "the box holds no solid voxel of the scene" : "the scene holds no solid voxel");
    return scene;
}

GridTool::GridTool(Volume volume) : volume_(std::move(volume))
{
    const VolumeStats stats = volume_.stats();
    if (stats.empty) throw std::invalid_argument("the tool holds no solid voxel");
    double points = 1.0;
    for (std::size_t a = 0; a < 3; ++a) {
        origin_[a] = stats.bboxMin[a] - kMargin;
        dims_[a] = stats.bboxMax[a] - stats.bboxMin[a] + 1 + 2 * kMargin;
        points *= dims_[a];
    }
    if (points > kMaxToolPoints) {
        throw std::invalid_argument("the tool spans " + std::to_string(dims_[0]) + " x " + std::to_string(dims_[1]) + " x " +
                                    std::to_string(dims_[2]) + " voxels, more than the " +
                                    std::to_string(uint64_t(kMaxToolPoints)) +
                                    " a tool may hold (make it from a smaller box or a coarser scene)");
    }
    const Box box{origin_, dims_};
    std::vector<Crossing> crossings;
    readLattice(volume_, box, material_, crossings);
    // The pivot: the middle of the solid voxels' box (the stats' box also holds empty surface voxels).
    std::array<int32_t, 3> lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
    for (int32_t i = 0; i < dims_[0]; ++i)
        for (int32_t j = 0; j < dims_[1]; ++j)
            for (int32_t k = 0; k < dims_[2]; ++k) {
                if (material_[box.index(i, j, k)] == kEmptyMaterial) continue;
                const int32_t at[3] = {i, j, k};
                for (std::size_t a = 0; a < 3; ++a) {
                    lo[a] = std::min(lo[a], origin_[a] + at[a]);
                    hi[a] = std::max(hi[a], origin_[a] + at[a]);
                }
            }
    for (std::size_t a = 0; a < 3; ++a) pivot_[a] = int32_t((int64_t(lo[a]) + hi[a]) >> 1); // floor of the mean

    const std::vector<MaterialId> present = regions();
    std::vector<MaterialId> wanted{kEmptyMaterial};
    if (present.size() > 1) wanted.insert(wanted.end(), present.begin(), present.end());
    fields_.resize(wanted.size());
    tbb::parallel_for(std::size_t(0), wanted.size(),
                      [&](std::size_t f) { fields_[f] = regionField(box, material_, crossings, wanted[f]); });
}

GridTool::~GridTool() = default;

std::shared_ptr<const GridTool> GridTool::load(const std::string& path)
{
    return std::make_shared<const GridTool>(loadVolume(path));
}

std::vector<MaterialId> GridTool::regions() const
{
    std::vector<bool> seen(volume_.materials().size() + 1, false);
    for (MaterialId m : material_)
        if (m < seen.size()) seen[m] = true;
    std::vector<MaterialId> out;
    for (MaterialId m = 1; m < seen.size(); ++m)
        if (seen[m]) out.push_back(m);
    return out;
}

const ToolField* GridTool::field(MaterialId region) const
{
    if (region == kEmptyMaterial || fields_.size() == 1) {
        if (region == kEmptyMaterial) return &fields_.front();
        const std::vector<MaterialId> present = regions();
        return std::find(present.begin(), present.end(), region) != present.end() ? &fields_.front() : nullptr;
    }
    for (const ToolField& f : fields_)
        if (f.region == region) return &f;
    return nullptr;
}

std::size_t GridTool::index(const std::array<int32_t, 3>& ijk) const
{
    return Box{origin_, dims_}.index(ijk[0] - origin_[0], ijk[1] - origin_[1], ijk[2] - origin_[2]);
}

MaterialId GridTool::materialAt(const std::array<int32_t, 3>& ijk) const
{
    for (std::size_t a = 0; a < 3; ++a)
        if (ijk[a] < origin_[a] || ijk[a] >= origin_[a] + dims_[a]) return kEmptyMaterial;
    return material_[index(ijk)];
}

std::optional<PackedSample> GridTool::sampleAt(const std::array<int32_t, 3>& ijk, int axis) const
{
    const Coord c(ijk[0], ijk[1], ijk[2]);
    const HermiteLeaf* leaf = volume_.impl().grid->tree().probeConstLeaf(c);
    const PackedSample* s = leaf ? leaf->sample(HermiteLeaf::coordToOffset(c), axis) : nullptr;
    if (!s) return std::nullopt;
    return *s;
}

SolidDistances solidDistances(const Volume& volume, const std::array<int32_t, 3>& origin, const std::array<int32_t, 3>& dims, float band,
                              float innerBand)
{
    const Box box{origin, dims};
    SolidDistances out;
    out.origin = origin;
    out.dims = dims;
    std::vector<Crossing> crossings;
    readLattice(volume, box, out.material, crossings);
    out.distance = boundaryDistances(box, crossings, kEmptyMaterial, band, innerBand, &out.material);
    for (std::size_t n = 0; n < out.distance.size(); ++n) {
        const float magnitude = std::max(out.distance[n], kLeastDistance);
        out.distance[n] = out.material[n] != kEmptyMaterial ? -magnitude : magnitude;
    }
    return out;
}

std::vector<SurfaceSample> surfaceSamples(const Volume& volume, const std::array<int32_t, 3>& origin, const std::array<int32_t, 3>& dims)
{
    // One point more on the high sides: the material at each crossing's far end is then read, not
    // taken as empty.
    const Box box{origin, {dims[0] + 1, dims[1] + 1, dims[2] + 1}};
    std::vector<MaterialId> material;
    std::vector<Crossing> crossings;
    readLattice(volume, box, material, crossings);
    std::vector<SurfaceSample> out;
    for (const Crossing& c : crossings) {
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside = inside && c.point[a] < double(origin[std::size_t(a)] + dims[std::size_t(a)]);
        if (inside && inRegion(c.before, kEmptyMaterial) != inRegion(c.after, kEmptyMaterial)) out.push_back({c.point, c.normal});
    }
    return out;
}

// --- PlacedTool ----------------------------------------------------------------------------------

PlacedTool::PlacedTool(std::shared_ptr<const GridTool> tool, const Placement& placement, MaterialId region)
    : tool_(std::move(tool)), field_(tool_->field(region)), placement_(placement)
{
    if (!field_) throw std::invalid_argument("the tool holds no voxel of material id " + std::to_string(region));
    validatePlacement(placement);
    const double h = tool_->voxelSize();
    const Mat3d linear = placementLinear(placement);
    latticeToWorld_ = linear * h;
    worldToLattice_ = linear.inverse() * (1.0 / h);
    toWorldDistance_ = h * std::min({placement.scale.x(), placement.scale.y(), placement.scale.z()});

    const auto& o = tool_->origin();
    const auto& n = tool_->dims();
    const auto& pivot = tool_->pivot();
    bounds_ = WorldBounds{Vec3d(std::numeric_limits<double>::infinity()), Vec3d(-std::numeric_limits<double>::infinity())};
    for (int corner = 0; corner < 8; ++corner) {
        Vec3d local;
        for (int a = 0; a < 3; ++a) local[a] = double(o[std::size_t(a)] + ((corner >> a) & 1) * (n[std::size_t(a)] - 1) - pivot[std::size_t(a)]);
        const Vec3d w = latticeToWorld_ * local;
        boundingRadius_ = std::max(boundingRadius_, w.length());
        for (int a = 0; a < 3; ++a) {
            bounds_.min[a] = std::min(bounds_.min[a], w[a] + placement.translation[a]);
            bounds_.max[a] = std::max(bounds_.max[a], w[a] + placement.translation[a]);
        }
    }

    // On the lattice: unit scale, a rotation of quarter turns (rotationFromEuler makes those exact) and a
    // whole-voxel position.
    const Mat3d rotation = rotationFromEuler(placement.rotationDegrees);
    onLattice_ = placement.scale == Vec3d(1.0);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            const double v = rotation(r, c);
            onLattice_ = onLattice_ && (v == 0.0 || v == 1.0 || v == -1.0);
            quarterTurn_[std::size_t(r)][std::size_t(c)] = int(v);
        }
    for (int a = 0; a < 3; ++a) {
        const double t = placement.translation[a] / h;
        onLattice_ = onLattice_ && std::fabs(t - std::round(t)) < 1e-7;
    }
}

Vec3d PlacedTool::toLattice(const Vec3d& world, const Vec3d& origin) const
{
    const auto& pivot = tool_->pivot();
    Vec3d q = worldToLattice_ * (world - origin);
    for (int a = 0; a < 3; ++a) {
        q[a] += pivot[std::size_t(a)];
        // On the lattice, a volume's lattice point is a tool's lattice point: snap away the rounding of
        // coordinates such as 0.1 * i so that it reads the stored value exactly.
        if (onLattice_ && std::fabs(q[a] - std::round(q[a])) < 1e-7) q[a] = std::round(q[a]);
    }
    return q;
}

namespace {

/// The lattice cell of a field that holds `rel` (a position relative to the fields' origin, inside their
/// box): its first corner's value, the strides to the others, and where `rel` lies in it.
struct Cell {
    const float* first;
    std::size_t sx, sy;
    double w[3];

    double corner(int x, int y, int z) const { return first[std::size_t(x) * sx + std::size_t(y) * sy + std::size_t(z)]; }
};

inline Cell cellAt(const ToolField& field, const std::array<int32_t, 3>& dims, const Vec3d& rel)
{
    Cell cell;
    int i0[3];
    for (int a = 0; a < 3; ++a) {
        // rel may fall a rounding error below 0 or above the last point: truncation and the cap keep the
        // cell inside the box.
        i0[a] = std::clamp(int(rel[a]), 0, dims[std::size_t(a)] - 2);
        cell.w[a] = rel[a] - i0[a];
    }
    cell.sy = std::size_t(dims[2]);
    cell.sx = std::size_t(dims[1]) * cell.sy;
    cell.first = field.distance.data() + std::size_t(i0[0]) * cell.sx + std::size_t(i0[1]) * cell.sy + std::size_t(i0[2]);
    return cell;
}

/// Exact at both ends (without a branch), so that lattice points read their stored values.
inline double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }

inline double interpolate(const Cell& c)
{
    const auto alongZ = [&](int x, int y) { return lerp(c.corner(x, y, 0), c.corner(x, y, 1), c.w[2]); };
    return lerp(lerp(alongZ(0, 0), alongZ(0, 1), c.w[1]), lerp(alongZ(1, 0), alongZ(1, 1), c.w[1]), c.w[0]);
}

/// The interpolant's gradient inside the cell, in tool voxels.
Vec3d interpolantGradient(const Cell& c)
{
    Vec3d g;
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, e = (a + 2) % 3; // the two other axes
        double sum = 0.0;
        for (int u = 0; u < 2; ++u)
            for (int v = 0; v < 2; ++v) {
                int hi[3], lo[3];
                hi[a] = 1, lo[a] = 0;
                hi[b] = lo[b] = u;
                hi[e] = lo[e] = v;
                const double weight = (u ? c.w[b] : 1.0 - c.w[b]) * (v ? c.w[e] : 1.0 - c.w[e]);
                sum += weight * (c.corner(hi[0], hi[1], hi[2]) - c.corner(lo[0], lo[1], lo[2]));
            }
        g[a] = sum;
    }
    return g;
}

} // namespace

bool PlacedTool::insideFields(const Vec3d& rel) const
{
    const auto& n = tool_->dims();
    for (int a = 0; a < 3; ++a)
        if (!(rel[a] >= 0.0 && rel[a] <= double(n[std::size_t(a)] - 1))) return false;
    return true;
}

Vec3d PlacedTool::relative(const Vec3d& q) const
{
    const auto& o = tool_->origin();
    return Vec3d(q[0] - o[0], q[1] - o[1], q[2] - o[2]);
}

double PlacedTool::sample(const Vec3d& q) const { return sampleRelative(relative(q)); }

double PlacedTool::sampleRelative(const Vec3d& rel) const
{
    if (insideFields(rel)) return interpolate(cellAt(*field_, tool_->dims(), rel));
    const auto& n = tool_->dims();
    Vec3d clamped;
    for (int a = 0; a < 3; ++a) clamped[a] = std::clamp(rel[a], 0.0, double(n[std::size_t(a)] - 1));
    return field_->outerValue + (rel - clamped).length();
}

double PlacedTool::distanceAt(const Vec3d& world, const Vec3d& origin) const
{
    return sample(toLattice(world, origin)) * toWorldDistance_;
}

void PlacedTool::distances(const LatticePatch& patch, double* out) const
{
    // Off the lattice (where toLattice snaps), the patch's points map to positions in the tool that step
    // by three fixed vectors.
    if (onLattice_) return SdfField::distances(patch, out);
    const Vec3d first = relative(toLattice(patch.point(0, 0, 0), placement_.translation));
    const double spacing = double(patch.stride) * patch.voxelSize;
    const Vec3d step[3] = {worldToLattice_.col(0) * spacing, worldToLattice_.col(1) * spacing, worldToLattice_.col(2) * spacing};
    for (int32_t i = 0; i < patch.count; ++i)
        for (int32_t j = 0; j < patch.count; ++j) {
            const Vec3d row = first + step[0] * double(i) + step[1] * double(j);
            for (int32_t k = 0; k < patch.count; ++k) *out++ = sampleRelative(row + step[2] * double(k)) * toWorldDistance_;
        }
}

Vec3d PlacedTool::gradient(const Vec3d& world, double step) const
{
    // The interpolant's gradient on the lattice (that of the cell holding the point, on a cell face), by
    // the chain rule in world space; outside the box, a finite difference of the continuation.
    const Vec3d q = toLattice(world, placement_.translation);
    const Vec3d rel = relative(q);
    Vec3d g;
    if (insideFields(rel)) {
        g = interpolantGradient(cellAt(*field_, tool_->dims(), rel));
    } else {
        const double h = 1e-4;
        for (int a = 0; a < 3; ++a) {
            Vec3d lo = q, hi = q;
            lo[a] -= h;
            hi[a] += h;
            g[a] = (sample(hi) - sample(lo)) / (2.0 * h);
        }
    }
    const Vec3d worldGradient = worldToLattice_.transpose() * g;
    const double len = worldGradient.length();
    if (len > 0.0 && std::isfinite(len)) return worldGradient / len;
    return SdfField::gradient(world, step);
}

WorldBounds PlacedTool::bounds() const { return bounds_; }

double PlacedTool::innerRadius() const { return field_->deepest * toWorldDistance_; }

std::optional<EdgeCrossing> PlacedTool::latticeCrossing(const Vec3d& start, int axis, double voxelSize) const
{
    if (!onLattice_ || std::fabs(voxelSize - tool_->voxelSize()) > 1e-12 * voxelSize) return std::nullopt;
    const Vec3d q = toLattice(start, placement_.translation);
    std::array<int32_t, 3> from;
    for (int a = 0; a < 3; ++a) {
        if (q[a] != std::round(q[a])) return std::nullopt; // not a lattice point
        from[std::size_t(a)] = int32_t(q[a]);
    }
    // The world edge's direction in the tool: the rotation's row `axis` (its inverse is its transpose).
    int toolAxis = 0, sign = 1;
    for (int b = 0; b < 3; ++b) {
        const int v = quarterTurn_[std::size_t(axis)][std::size_t(b)];
        if (v != 0) toolAxis = b, sign = v;
    }
    std::array<int32_t, 3> to = from;
    to[std::size_t(toolAxis)] += sign;
    const MaterialId region = field_->region;
    const MaterialId mFrom = tool_->materialAt(from), mTo = tool_->materialAt(to);
    const bool inFrom = inRegion(mFrom, region);
    if (inFrom == inRegion(mTo, region)) return std::nullopt;
    const std::optional<PackedSample> sample = tool_->sampleAt(sign > 0 ? from : to, toolAxis);
    if (!sample) return std::nullopt;
    // A reversed edge's offset is the code's mirror, so that storing it again gives that code exactly.
    const double offset = dequantizeOffset(sign > 0 ? sample->offset : uint16_t(65535 - sample->offset));
    const auto decoded = decodeNormal(sample->normalU, sample->normalV);
    Vec3d normal(decoded[0], decoded[1], decoded[2]);
    // Solid/empty normals point into empty space, out of any region; a boundary between two materials
    // is turned to point out of this region.
    if (mFrom != kEmptyMaterial && mTo != kEmptyMaterial) {
        const double outward = (inFrom ? sign : -sign) * normal[toolAxis];
        if (outward < 0.0) normal = -normal;
    }
    Vec3d worldNormal;
    for (int r = 0; r < 3; ++r) {
        worldNormal[r] = 0.0;
        for (int c = 0; c < 3; ++c) worldNormal[r] += quarterTurn_[std::size_t(r)][std::size_t(c)] * normal[c];
    }
    return EdgeCrossing{offset, worldNormal};
}

} // namespace vdbclay
