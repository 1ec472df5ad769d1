#include "voxelize/Voxelizer.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/MemoryLimit.h"
#include "vdb_hermite/NumberText.h"
#include "vdb_hermite/Quantize.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <set>
#include <memory>
#include <stdexcept>

namespace vdbclay {

namespace {

/// Every lattice point is tested a hair off itself, by the same offset on all three rays through it (in
/// voxels): a mesh vertex, edge or face on the lattice (users model on integers) then lies on one side
/// of the point for every ray, so the three rays agree, and a ray grazing a vertex hits it twice or not.
constexpr std::array<double, 3> kPointOffset{1.23e-5, 0.71e-5, 0.97e-5};
/// The most lattice points a mesh's box may span (2^36, 4096^3: the work grows with them), and the most
/// rays along one axis (each keeps an index into the hits: 4 bytes).
constexpr double kMaxLatticePoints = double(uint64_t(1) << 36);
constexpr double kMaxRaysPerAxis = double(uint64_t(1) << 26);
/// The edge of the blocks the whole-mesh voxelization works in, voxels: their votes (5 bytes a point)
/// stay in a core's cache.
constexpr int32_t kWholeMeshBlockEdge = 64;
/// Mesh coordinates this close to a lattice plane, in voxels, are moved onto it. Exported models keep
/// faces that were modelled on a plane a rounding error off it (fandisk's x = 0 side spans 0 .. 2e-6):
/// rays running along such a face a hair inside it would graze its bumps and vote its points at random.
/// Snapped, the face lies on the plane and the offset above settles it. A vertex moves by at most 0.002
/// voxel, and shared vertices move alike, so nothing opens.
constexpr double kLatticeSnap = 2e-3;
/// How far past an edge's end, in voxels, a hit still counts as that edge's crossing.
constexpr double kEndTolerance = 1e-3;

/// One ray's hit: where along the ray (lattice units from the grid's first point), the triangle's unit
/// normal, its material.
struct Hit {
    uint32_t ray;
    double at;
    std::array<float, 3> normal;
    uint32_t material;
};

/// The lattice the mesh is voxelized on: index lo .. lo + dim - 1 per axis, with a layer of empty
/// points on each side.
struct Lattice {
    std::array<int32_t, 3> lo{};
    std::array<int32_t, 3> dim{};
    double voxelSize = 1.0;
};

/// The hits of every ray along `axis`, sorted by ray then position. A lattice point lies inside a
/// triangle's projection by the top-left rule, so a ray through a shared edge or vertex hits exactly
/// one of the triangles around it.
std::vector<Hit> castRays(const TriangleSoup& mesh, const Lattice& lattice, int axis)
{
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double inv = 1.0 / lattice.voxelSize;
    tbb::combinable<std::vector<Hit>> local;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 256), [&](const auto& range) {
        std::vector<Hit>& out = local.local();
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            // Lattice coordinates of the corners (relative to the grid's first point).
            double p[3][3];
            for (int k = 0; k < 3; ++k)
                for (int a = 0; a < 3; ++a) {
                    const double c = mesh.positions[tri[std::size_t(k)]][std::size_t(a)] * inv - lattice.lo[std::size_t(a)];
                    const double plane = std::round(c);
                    p[k][a] = std::fabs(c - plane) < kLatticeSnap ? plane : c;
                }
            double area = (p[1][u] - p[0][u]) * (p[2][v] - p[0][v]) - (p[2][u] - p[0][u]) * (p[1][v] - p[0][v]);
            if (area == 0.0) continue; // parallel to the rays
            int order[3] = {0, 1, 2};
            if (area < 0.0) std::swap(order[1], order[2]), area = -area; // counter-clockwise in (u, v)
            double n[3];
            {
                const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
                const double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
                n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
                const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                for (double& c : n) c /= len;
            }
            const double* a = p[order[0]];
            const double* b = p[order[1]];
            const double* c = p[order[2]];
            const double du = kPointOffset[std::size_t(u)], dv = kPointOffset[std::size_t(v)];
            const int u0 = std::max(0, int(std::ceil(std::min({a[u], b[u], c[u]}) - du)));
            const int u1 = std::min(lattice.dim[std::size_t(u)] - 1, int(std::floor(std::max({a[u], b[u], c[u]}) - du)));
            const int v0 = std::max(0, int(std::ceil(std::min({a[v], b[v], c[v]}) - dv)));
            const int v1 = std::min(lattice.dim[std::size_t(v)] - 1, int(std::floor(std::max({a[v], b[v], c[v]}) - dv)));
            // Edge functions, computed from an edge's lower end whichever way a triangle runs along it, so
            // the two triangles of an edge get values of opposite sign exactly and a ray through the edge
            // hits one of them. An edge is top-left when it runs left (dv == 0, du < 0) or down (dv < 0).
            auto edge = [&](const double* s, const double* e, double qu, double qv) {
                const bool swap = e[u] < s[u] || (e[u] == s[u] && e[v] < s[v]);
                const double* from = swap ? e : s;
                const double* to = swap ? s : e;
                const double f = (to[u] - from[u]) * (qv - from[v]) - (to[v] - from[v]) * (qu - from[u]);
                return swap ? -f : f;
            };
            auto topLeft = [&](const double* s, const double* e) {
                const double du = e[u] - s[u], dv = e[v] - s[v];
                return (dv == 0.0 && du < 0.0) || dv < 0.0;
            };
            const bool tl[3] = {topLeft(b, c), topLeft(c, a), topLeft(a, b)};
            for (int iu = u0; iu <= u1; ++iu)
                for (int iv = v0; iv <= v1; ++iv) {
                    const double qu = iu + du, qv = iv + dv;
                    const double w0 = edge(b, c, qu, qv), w1 = edge(c, a, qu, qv), w2 = edge(a, b, qu, qv);
                    if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
                    if ((w0 == 0.0 && !tl[0]) || (w1 == 0.0 && !tl[1]) || (w2 == 0.0 && !tl[2])) continue;
                    const double at = (w0 * a[axis] + w1 * b[axis] + w2 * c[axis]) / (w0 + w1 + w2);
                    out.push_back({uint32_t(std::size_t(iu) * std::size_t(lattice.dim[std::size_t(v)]) + std::size_t(iv)), at,
                                   {float(n[0]), float(n[1]), float(n[2])}, mesh.triangleMaterials[t]});
                }
        }
    });
    std::vector<Hit> hits;
    local.combine_each([&](const std::vector<Hit>& h) { hits.insert(hits.end(), h.begin(), h.end()); });
    tbb::parallel_sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) {
        return x.ray != y.ray ? x.ray < y.ray : x.at != y.at ? x.at < y.at : x.material < y.material;
    });
    return hits;
}

/// Per ray of `axis`: [first, last) of its hits, after merging hits at one place.
struct RayHits {
    std::vector<Hit> hits;
    std::vector<uint32_t> first; // per ray, into hits; size rays + 1
};

RayHits groupByRay(std::vector<Hit> hits, std::size_t rays, int axis, uint64_t& duplicates)
{
    RayHits out;
    out.hits.reserve(hits.size());
    for (std::size_t i = 0; i < hits.size(); ++i) {
        // A duplicated triangle: one place, facing the same way along the ray. (Two hits at one place
        // facing opposite ways are a fold the ray grazes: both count, or parity would flip.)
        const Hit& last = out.hits.empty() ? hits[i] : out.hits.back();
        if (!out.hits.empty() && last.ray == hits[i].ray && std::fabs(last.at - hits[i].at) < 1e-9 &&
            (last.normal[std::size_t(axis)] > 0.0f) == (hits[i].normal[std::size_t(axis)] > 0.0f)) {
            ++duplicates;
            continue;
        }
        out.hits.push_back(hits[i]);
    }
    out.first.assign(rays + 1, 0);
    for (const Hit& h : out.hits) ++out.first[h.ray + 1];
    for (std::size_t r = 0; r < rays; ++r) out.first[r + 1] += out.first[r];
    return out;
}


/// The votes of the lattice points of one box (lattice indices lo .. lo + dim - 1, which may reach past
/// the lattice: no ray runs there, so those points are empty): a bit per axis whose ray has the point
/// inside, and the material of the nearest face along the rays that have it inside (with how far it is).
struct WindowVotes {
    std::array<int32_t, 3> lo{};
    int32_t dim = 0;
    std::vector<uint8_t> votes;
    std::vector<uint32_t> material; // mesh material + 1; 0: no ray has the point inside
    std::vector<float> faceDistance;

    std::size_t index(int x, int y, int z) const
    {
        return (std::size_t(x - lo[0]) * std::size_t(dim) + std::size_t(y - lo[1])) * std::size_t(dim) + std::size_t(z - lo[2]);
    }
    /// Solid where two rays of three agree.
    bool solidAt(int x, int y, int z) const
    {
        const uint8_t b = votes[index(x, y, z)];
        return ((b & 1) + ((b >> 1) & 1) + ((b >> 2) & 1)) >= 2;
    }
};

/// Hits closer than this along a ray (lattice units) lie at one spot: faces of touching parts.
constexpr double kSameSpot = 1e-9;

/// Of the hits at the spot of `*hit` (the nearest behind a point when `ahead` is false, the nearest
/// ahead of it otherwise), the face that bounds the point's own part: one the ray enters that part
/// through, or leaves it through; any of them when the winding says neither.
const Hit* boundingFace(const Hit* hit, const Hit* first, const Hit* end, int axis, bool ahead)
{
    const double spot = hit->at;
    if (ahead) {
        for (const Hit* h = hit; h != end && h->at - spot < kSameSpot; ++h)
            if (h->normal[std::size_t(axis)] > 0.0f) return h;
    } else {
        for (const Hit* h = hit;; --h) {
            if (h->normal[std::size_t(axis)] < 0.0f) return h;
            if (h == first || spot - h[-1].at >= kSameSpot) break;
        }
    }
    return hit;
}

/// Fills the votes of a cube of lattice points from the rays through it. A ray's parity where the cube
/// starts is the number of its hits before: the same answer as walking the ray from the lattice's start.
/// A point inside takes the material of the nearest face along its rays, so each face's material shows
/// on the surface it covers whichever way a ray crosses the solid. Returns false when no point of the
/// cube is inside along any ray (then it holds nothing).
bool fillVotes(const Lattice& lattice, const std::array<RayHits, 3>& rays, WindowVotes& window)
{
    const std::size_t points = std::size_t(window.dim) * std::size_t(window.dim) * std::size_t(window.dim);
    window.votes.assign(points, 0);
    window.material.assign(points, 0);
    window.faceDistance.assign(points, std::numeric_limits<float>::infinity());
    bool any = false;
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const RayHits& rh = rays[std::size_t(axis)];
        const double offset = kPointOffset[std::size_t(axis)];
        const int w0 = std::max(window.lo[std::size_t(axis)], 0);
        const int w1 = std::min(window.lo[std::size_t(axis)] + window.dim, lattice.dim[std::size_t(axis)]);
        for (int iu = std::max(window.lo[std::size_t(u)], 0); iu < std::min(window.lo[std::size_t(u)] + window.dim, lattice.dim[std::size_t(u)]); ++iu)
            for (int iv = std::max(window.lo[std::size_t(v)], 0); iv < std::min(window.lo[std::size_t(v)] + window.dim, lattice.dim[std::size_t(v)]); ++iv) {
                const std::size_t ray = std::size_t(iu) * std::size_t(lattice.dim[std::size_t(v)]) + std::size_t(iv);
                const Hit* first = rh.hits.data() + rh.first[ray];
                const Hit* end = rh.hits.data() + rh.first[ray + 1];
                // A ray with an odd number of hits has no outside at one of its ends: it passes through a
                // hole, a seam or an open surface and cannot tell inside from outside. It does not vote; the
                // other two rays settle its points (a lone triangle or open sheet then encloses nothing).
                if (first == end || ((end - first) & 1) != 0) continue;
                const Hit* h = std::partition_point(first, end, [&](const Hit& hit) { return hit.at < double(w0) + offset; });
                bool inside = ((h - first) & 1) != 0;
                for (int w = w0; w < w1; ++w) {
                    const double point = double(w) + offset;
                    for (; h != end && h->at < point; ++h) inside = !inside;
                    if (!inside) continue;
                    int c[3];
                    c[axis] = w, c[u] = iu, c[v] = iv;
                    const std::size_t at = window.index(c[0], c[1], c[2]);
                    window.votes[at] |= uint8_t(1u << axis);
                    any = true;
                    // Inside, a hit lies behind the point (the parity is odd); one ahead is missing only
                    // where a hole leaves the ray open.
                    const Hit* face = boundingFace(h - 1, first, end, axis, false);
                    float distance = float(point - face->at);
                    if (h != end && float(h->at - point) < distance) {
                        face = boundingFace(h, first, end, axis, true);
                        distance = float(face->at - point);
                    }
                    if (distance < window.faceDistance[at]) {
                        window.faceDistance[at] = distance;
                        window.material[at] = face->material + 1;
                    }
                }
            }
    }
    return any;
}

/// One block's leaves, built as plain data, and what building them counted.
struct BlockLeaves {
    std::vector<Coord> origins;
    std::vector<HermiteLeafData> data;
    std::vector<Coord> uniformOrigins; // leaves of one material without crossings: the solid's inside
    std::vector<MaterialValue> uniformValues;
    VoxelizeReport counts;

    void placeInto(HermiteTree& tree)
    {
        placeLeaves(tree, origins, data);
        placeUniformLeaves(tree, uniformOrigins, uniformValues);
    }
};

} // namespace

void addBlockCounts(VoxelizeReport& total, const VoxelizeReport& block)
{
    total.votedPoints += block.votedPoints;
    total.patchedCrossings += block.patchedCrossings;
    total.crossings += block.crossings;
    total.materialInterfaces += block.materialInterfaces;
    total.solidVoxels += block.solidVoxels;
}

/// The mesh cast into rays: the sorted hits of every lattice line along X, Y and Z (memory that grows
/// with the mesh's surface), and the lattice they run on.
struct MeshVoxelizer::Impl {
    Lattice lattice;
    std::array<RayHits, 3> rays;
    MaterialTable materials;
    std::vector<MaterialId> ids; // per mesh material
    VoxelizeReport cast;         // what casting counted: triangles, hits, duplicates

    BlockLeaves voxelizeBlock(const LeafAlignedBox& box) const;
};

MeshVoxelizer::MeshVoxelizer(const TriangleSoup& mesh, const VoxelizeOptions& options) : impl_(std::make_unique<Impl>())
{
    if (mesh.triangles.empty()) throw std::invalid_argument("the mesh holds no triangle");
    if (options.material.empty() && mesh.materials.size() >= kMaxMaterials) {
        std::set<std::string> named;
        for (const MeshMaterial& m : mesh.materials)
            if (!m.name.empty()) named.insert(m.name);
        if (named.size() >= kMaxMaterials) // before any work: the table holds 65535 with 'default'
            throw MeshImportError("the mesh has " + std::to_string(named.size()) + " materials; a scene holds at most " +
                                  std::to_string(kMaxMaterials - 1) + " besides 'default': give --material NAME to import it as one");
    }
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], mesh.positions[i][a]), hi[a] = std::max(hi[a], mesh.positions[i][a]);
    const double longest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    double voxelSize = 0.0;
    if (options.voxelSize) voxelSize = *options.voxelSize;
    else if (options.resolution) {
        if (*options.resolution < 1 || *options.resolution > 16384)
            throw std::invalid_argument("a resolution must be 1 to 16384 voxels, not " + std::to_string(*options.resolution));
        voxelSize = longest / double(*options.resolution);
    } else {
        throw std::invalid_argument("give --voxel-size V or --resolution N (voxels along the longest side)");
    }
    if (!(voxelSize >= kMinVoxelSize && voxelSize <= kMaxVoxelSize))
        throw std::invalid_argument("a voxel size of " + formatNumber(voxelSize) + " is outside " + formatNumber(kMinVoxelSize) + " .. " +
                                    formatNumber(kMaxVoxelSize));
    Lattice& lattice = impl_->lattice;
    lattice.voxelSize = voxelSize;
    std::array<double, 3> extent{};
    for (std::size_t a = 0; a < 3; ++a) {
        const double first = std::floor(lo[a] / voxelSize) - 1.0, last = std::ceil(hi[a] / voxelSize) + 1.0;
        if (!(std::fabs(first) <= kMaxLatticeCoordinate && std::fabs(last) <= kMaxLatticeCoordinate))
            throw std::invalid_argument("the mesh reaches " + formatNumber(std::fabs(lo[a]) > std::fabs(hi[a]) ? lo[a] : hi[a]) +
                                        " along " + "xyz"[a] + ", " + formatNumber(std::max(std::fabs(first), std::fabs(last))) +
                                        " voxels from the origin at this voxel size; the lattice indexes at most " +
                                        formatNumber(kMaxLatticeCoordinate) + ": move the mesh near the origin or choose a coarser voxel size");
        lattice.lo[a] = int32_t(first);
        lattice.dim[a] = int32_t(last - first) + 1;
        extent[a] = double(lattice.dim[a]);
    }
    const double points = extent[0] * extent[1] * extent[2];
    const double face = std::max({extent[0] * extent[1], extent[1] * extent[2], extent[0] * extent[2]});
    if (points > kMaxLatticePoints || face > kMaxRaysPerAxis) {
        // The finest resolution this mesh's proportions allow, so the user knows what to type.
        const auto fits = [&](int resolution) {
            std::array<double, 3> d{};
            for (std::size_t a = 0; a < 3; ++a) d[a] = std::ceil((hi[a] - lo[a]) / longest * resolution) + 3.0;
            return d[0] * d[1] * d[2] <= kMaxLatticePoints && std::max({d[0] * d[1], d[1] * d[2], d[0] * d[2]}) <= kMaxRaysPerAxis;
        };
        int finest = 0;
        for (int step = 1 << 14; step > 0; step >>= 1)
            if (finest + step <= 16384 && fits(finest + step)) finest += step;
        throw std::invalid_argument("the mesh spans " + std::to_string(lattice.dim[0]) + " x " + std::to_string(lattice.dim[1]) + " x " +
                                    std::to_string(lattice.dim[2]) +
                                    " lattice points at this voxel size (the voxelizer's vote takes at most 2^36, and 2^26 on a face): "
                                    "for this mesh --resolution may be at most " + std::to_string(finest) +
                                    " (--voxel-size at least " + formatNumber(longest / std::max(finest, 1)) + ")");
    }

    // Each ray keeps its hits until the blocks are voxelized: a mesh of many large triangles (a 50 MB
    // soup across its box) makes billions. Counted from the triangles' projected areas before casting.
    double expectedHits = 0.0;
    for (const auto& t : mesh.triangles) {
        const auto& a = mesh.positions[t[0]];
        const auto& b = mesh.positions[t[1]];
        const auto& c = mesh.positions[t[2]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        expectedHits += 0.5 * (std::fabs(u[1] * w[2] - u[2] * w[1]) + std::fabs(u[2] * w[0] - u[0] * w[2]) + std::fabs(u[0] * w[1] - u[1] * w[0]));
    }
    expectedHits /= voxelSize * voxelSize;
    requireMemory(expectedHits * double(sizeof(Hit)) * 2.0, // the hits, and their copy while sorted and grouped
                  "voxelizing the mesh at voxel size " + formatNumber(voxelSize) + " (its triangles cross about " +
                      formatNumber(expectedHits) + " lattice lines)",
                  "choose a coarser voxel size or a lower --resolution");

    VoxelizeReport& r = impl_->cast;
    r.voxelSize = voxelSize;
    r.triangles = mesh.triangles.size();
    r.droppedTriangles = mesh.droppedTriangles;
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const std::size_t count = std::size_t(lattice.dim[std::size_t(u)]) * std::size_t(lattice.dim[std::size_t(v)]);
        std::vector<Hit> hits = castRays(mesh, lattice, axis);
        if (hits.size() >= std::size_t(UINT32_MAX))
            throw std::invalid_argument("the mesh crosses the lattice's lines more than 2^32 times at this voxel size: choose a coarser one");
        r.hits += hits.size();
        impl_->rays[std::size_t(axis)] = groupByRay(std::move(hits), count, axis, r.duplicateHits);
    }

    impl_->ids.assign(mesh.materials.size(), 1);
    MaterialTable& table = impl_->materials;
    if (!options.material.empty()) {
        const auto found = table.find(options.material);
        const MaterialId id = found ? *found : table.define(Material{options.material});
        std::fill(impl_->ids.begin(), impl_->ids.end(), id);
    } else if (mesh.materials.size() > 1 || !mesh.materials[0].name.empty()) {
        for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
            if (mesh.materials[m].name.empty()) continue; // unnamed: the default material
            Material out;
            out.name = mesh.materials[m].name;
            out.color = mesh.materials[m].color;
            impl_->ids[m] = table.define(out);
        }
    }
}

MeshVoxelizer::MeshVoxelizer(MeshVoxelizer&&) noexcept = default;
MeshVoxelizer& MeshVoxelizer::operator=(MeshVoxelizer&&) noexcept = default;
MeshVoxelizer::~MeshVoxelizer() = default;

double MeshVoxelizer::voxelSize() const { return impl_->lattice.voxelSize; }
const MaterialTable& MeshVoxelizer::materials() const { return impl_->materials; }
const VoxelizeReport& MeshVoxelizer::castReport() const { return impl_->cast; }

std::vector<LeafAlignedBox> MeshVoxelizer::blocks(int32_t edge) const
{
    if (edge < kLeafDim || edge % kLeafDim != 0) throw std::invalid_argument("a block's edge must be a multiple of 8 voxels");
    const Lattice& lattice = impl_->lattice;
    auto down = [&](int32_t c) { return c >= 0 ? c / edge * edge : -((-c + edge - 1) / edge) * edge; };
    std::vector<LeafAlignedBox> out;
    for (int32_t x = down(lattice.lo[0]); x < lattice.lo[0] + lattice.dim[0]; x += edge)
        for (int32_t y = down(lattice.lo[1]); y < lattice.lo[1] + lattice.dim[1]; y += edge)
            for (int32_t z = down(lattice.lo[2]); z < lattice.lo[2] + lattice.dim[2]; z += edge) out.push_back({{x, y, z}, edge});
    return out;
}

BlockLeaves MeshVoxelizer::Impl::voxelizeBlock(const LeafAlignedBox& box) const
{
    BlockLeaves out;
    // The block's points and a margin: one point below for the normals a patched crossing takes from
    // its ends' neighbourhoods, two above for the edges leaving the block and those neighbourhoods.
    WindowVotes window;
    window.dim = box.edge + 3;
    for (std::size_t a = 0; a < 3; ++a) window.lo[a] = box.min[a] - lattice.lo[a] - 1;
    if (!fillVotes(lattice, rays, window)) return out;

    // A crossing the vote made where no ray hit: the normal of the solid's shape around the edge (its
    // occupancy's gradient over the 3x3x3 points about each end), else along the edge.
    auto patchNormal = [&](const int* p, const int* q, int axis, double sign) {
        std::array<double, 3> n{0.0, 0.0, 0.0};
        for (const int* c : {p, q})
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        if (!window.solidAt(c[0] + dx, c[1] + dy, c[2] + dz)) continue;
                        n[0] -= dx, n[1] -= dy, n[2] -= dz; // out of the solid: away from its points
                    }
        if (n[std::size_t(axis)] * sign <= 0.0) {
            n = {0.0, 0.0, 0.0};
            n[std::size_t(axis)] = sign;
        }
        return n;
    };
    // The hits on the edge from lattice point g along `axis`; a hit a hair past an end counts (a face a
    // rounding error off a lattice plane, whose points the vote settles) and lands on that end.
    auto edgeHits = [&](const int* g, int axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const RayHits& rh = rays[std::size_t(axis)];
        const std::size_t ray = std::size_t(g[u]) * std::size_t(lattice.dim[std::size_t(v)]) + std::size_t(g[v]);
        const Hit* first = rh.hits.data() + rh.first[ray];
        const Hit* last = rh.hits.data() + rh.first[ray + 1];
        first = std::partition_point(first, last, [&](const Hit& h) { return h.at < double(g[axis]) - kEndTolerance; });
        last = std::partition_point(first, last, [&](const Hit& h) { return h.at <= double(g[axis] + 1) + kEndTolerance; });
        return std::make_pair(first, last);
    };
    // Two materials meet inside the solid: where touching parts of the mesh meet on this edge (a hit),
    // else mid-edge, facing along it.
    auto materialInterface = [&](const int* g, int axis) {
        const auto [first, last] = edgeHits(g, axis);
        if (first != last)
            return packSample(std::clamp(first->at - double(g[axis]), 0.0, 1.0),
                              std::array<double, 3>{first->normal[0], first->normal[1], first->normal[2]});
        std::array<double, 3> along{0.0, 0.0, 0.0};
        along[std::size_t(axis)] = 1.0;
        return packSample(0.5, along);
    };
    auto materialAt = [&](const int* c) -> MaterialId {
        if (!window.solidAt(c[0], c[1], c[2])) return kEmptyMaterial;
        const uint32_t m = window.material[window.index(c[0], c[1], c[2])];
        return ids[std::min<std::size_t>(m ? m - 1 : 0, ids.size() - 1)];
    };
    VoxelizeReport& counts = out.counts;
    for (int32_t lx = 0; lx < box.edge; lx += kLeafDim)
        for (int32_t ly = 0; ly < box.edge; ly += kLeafDim)
            for (int32_t lz = 0; lz < box.edge; lz += kLeafDim) {
                const Coord origin(box.min[0] + lx, box.min[1] + ly, box.min[2] + lz);
                // A leaf beyond the lattice (a block larger than a small mesh) is empty: no point of it
                // is solid and no edge crosses, so it is not visited.
                bool outside = false;
                for (std::size_t a = 0; a < 3; ++a)
                    outside = outside || origin[int(a)] + kLeafDim <= lattice.lo[a] || origin[int(a)] >= lattice.lo[a] + lattice.dim[a];
                if (outside) continue;
                HermiteLeafData d;
                uint64_t leafSolid = 0, leafCrossings = 0;
                for (int x = 0; x < kLeafDim; ++x)
                    for (int y = 0; y < kLeafDim; ++y)
                        for (int z = 0; z < kLeafDim; ++z) {
                            const int g[3] = {origin.x() + x - lattice.lo[0], origin.y() + y - lattice.lo[1], origin.z() + z - lattice.lo[2]};
                            const int offset = (x << (2 * kLeafLog2Dim)) | (y << kLeafLog2Dim) | z;
                            const std::size_t at = window.index(g[0], g[1], g[2]);
                            const MaterialId here = materialAt(g);
                            const bool s = here != kEmptyMaterial;
                            if (s) {
                                if (window.votes[at] != 7) ++counts.votedPoints;
                                d.material[std::size_t(offset)].id = here;
                                ++leafSolid;
                            } else if (window.votes[at] != 0) {
                                ++counts.votedPoints;
                            }
                            for (int axis = 0; axis < 3; ++axis) {
                                int n[3] = {g[0], g[1], g[2]};
                                n[axis] += 1;
                                const MaterialId there = materialAt(n);
                                if (there == here) continue;
                                const int bit = HermiteLeaf::edgeBit(Index(offset), axis);
                                d.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                                ++leafCrossings;
                                if (s && there != kEmptyMaterial) {
                                    d.samples.push_back(materialInterface(g, axis));
                                    ++counts.materialInterfaces;
                                    continue;
                                }
                                // The hit on this edge whose normal leaves the solid the right way, else
                                // any hit on it, else (the vote made it cross) mid-edge along the axis.
                                const double sign = s ? 1.0 : -1.0;
                                const Hit* best = nullptr;
                                const auto [first, last] = edgeHits(g, axis);
                                for (const Hit* hit = first; hit != last; ++hit)
                                    if (!best || (best->normal[std::size_t(axis)] * sign <= 0.0 && hit->normal[std::size_t(axis)] * sign > 0.0)) best = hit;
                                double t = 0.5;
                                std::array<double, 3> normal = patchNormal(g, n, axis, sign);
                                if (best) {
                                    t = std::clamp(best->at - double(g[axis]), 0.0, 1.0);
                                    // Out of the solid along this edge, whatever the triangle's winding.
                                    const double flip = best->normal[std::size_t(axis)] * sign < 0.0 ? -1.0 : 1.0;
                                    for (int i = 0; i < 3; ++i) normal[std::size_t(i)] = flip * best->normal[std::size_t(i)];
                                } else {
                                    ++counts.patchedCrossings;
                                }
                                d.samples.push_back(packSample(t, normal));
                            }
                        }
                counts.solidVoxels += leafSolid;
                counts.crossings += leafCrossings;
                MaterialValue uniform;
                if (leafSolid == 0 && leafCrossings == 0) continue;
                if (uniformWithoutSamples(d, uniform)) out.uniformOrigins.push_back(origin), out.uniformValues.push_back(uniform);
                else out.origins.push_back(origin), out.data.push_back(std::move(d));
            }
    return out;
}

Volume MeshVoxelizer::voxelizeBlock(const LeafAlignedBox& box, VoxelizeReport& counts) const
{
    BlockLeaves leaves = impl_->voxelizeBlock(box);
    Volume volume(impl_->lattice.voxelSize);
    volume.materials() = impl_->materials;
    leaves.placeInto(volume.impl().grid->tree());
    addBlockCounts(counts, leaves.counts);
    return volume;
}

std::string noSolidMessage(double voxelSize)
{
    return "the mesh encloses no solid voxel at voxel size " + formatNumber(voxelSize) +
           " (an open or flat surface, or parts thinner than a voxel): nothing to import";
}

Volume voxelizeMesh(const TriangleSoup& mesh, const VoxelizeOptions& options, VoxelizeReport* report)
{
    const MeshVoxelizer voxelizer(mesh, options);
    const std::vector<LeafAlignedBox> blocks = voxelizer.blocks(kWholeMeshBlockEdge);
    std::vector<BlockLeaves> leaves(blocks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1), [&](const auto& range) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) leaves[b] = voxelizer.impl_->voxelizeBlock(blocks[b]);
    });
    VoxelizeReport r = voxelizer.castReport();
    Volume volume(voxelizer.voxelSize());
    volume.materials() = voxelizer.materials();
    for (BlockLeaves& block : leaves) { // block by block: each one's memory goes once it is placed
        addBlockCounts(r, block.counts);
        block.placeInto(volume.impl().grid->tree());
        block = {};
    }
    if (report) *report = r;
    return volume;
}

} // namespace vdbclay
