#include "voxelize/Voxelizer.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/Quantize.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <set>
#include <stdexcept>

namespace vdbclay {

namespace {

/// Every lattice point is tested a hair off itself, by the same offset on all three rays through it (in
/// voxels): a mesh vertex, edge or face on the lattice (users model on integers) then lies on one side
/// of the point for every ray, so the three rays agree, and a ray grazing a vertex hits it twice or not.
constexpr std::array<double, 3> kPointOffset{1.23e-5, 0.71e-5, 0.97e-5};
/// The most lattice points a mesh's box may span (the lattice is dense).
constexpr double kMaxLatticePoints = double(1u << 28);
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
    std::size_t index(int x, int y, int z) const { return (std::size_t(x) * dim[1] + std::size_t(y)) * dim[2] + std::size_t(z); }
    std::size_t size() const { return std::size_t(dim[0]) * dim[1] * dim[2]; }
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
                for (int a = 0; a < 3; ++a) p[k][a] = mesh.positions[tri[std::size_t(k)]][std::size_t(a)] * inv - lattice.lo[std::size_t(a)];
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

} // namespace

Volume voxelizeMesh(const TriangleSoup& mesh, const VoxelizeOptions& options, VoxelizeReport* report)
{
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], mesh.positions[i][a]), hi[a] = std::max(hi[a], mesh.positions[i][a]);
    if (mesh.triangles.empty()) throw std::invalid_argument("the mesh holds no triangle");
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
        throw std::invalid_argument("a voxel size of " + std::to_string(voxelSize) + " is outside " + std::to_string(kMinVoxelSize) +
                                    " .. " + std::to_string(kMaxVoxelSize));
    Lattice lattice;
    lattice.voxelSize = voxelSize;
    double points = 1.0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double first = std::floor(lo[a] / voxelSize) - 1.0, last = std::ceil(hi[a] / voxelSize) + 1.0;
        if (!(std::fabs(first) < 1e9 && std::fabs(last) < 1e9)) throw std::invalid_argument("the mesh lies too far out for this voxel size");
        lattice.lo[a] = int32_t(first);
        lattice.dim[a] = int32_t(last - first) + 1;
        points *= double(lattice.dim[a]);
    }
    // Five bytes a lattice point (votes, materials): 2^28 points is 1.3 GB.
    if (points > kMaxLatticePoints)
        throw std::invalid_argument("the mesh spans " + std::to_string(uint64_t(points)) +
                                    " lattice points at this voxel size (at most 2^28): choose a coarser one");

    VoxelizeReport r;
    r.voxelSize = voxelSize;
    r.triangles = mesh.triangles.size();
    r.droppedTriangles = mesh.droppedTriangles;
    // Per axis: parity along its rays, and the material of the hit each inside section starts at.
    std::array<RayHits, 3> rays;
    std::vector<uint8_t> votes(lattice.size(), 0);
    std::vector<uint32_t> material(lattice.size(), 0);
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const std::size_t count = std::size_t(lattice.dim[std::size_t(u)]) * std::size_t(lattice.dim[std::size_t(v)]);
        std::vector<Hit> hits = castRays(mesh, lattice, axis);
        r.hits += hits.size();
        rays[std::size_t(axis)] = groupByRay(std::move(hits), count, axis, r.duplicateHits);
        const RayHits& rh = rays[std::size_t(axis)];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
            for (std::size_t ray = range.begin(); ray != range.end(); ++ray) {
                const int iu = int(ray / std::size_t(lattice.dim[std::size_t(v)])), iv = int(ray % std::size_t(lattice.dim[std::size_t(v)]));
                uint32_t h = rh.first[ray];
                const uint32_t end = rh.first[ray + 1];
                bool inside = false;
                uint32_t entering = 0;
                for (int w = 0; w < lattice.dim[std::size_t(axis)]; ++w) {
                    for (; h < end && rh.hits[h].at < double(w) + kPointOffset[std::size_t(axis)]; ++h) {
                        inside = !inside;
                        entering = rh.hits[h].material;
                    }
                    if (!inside) continue;
                    int c[3];
                    c[axis] = w, c[u] = iu, c[v] = iv;
                    const std::size_t at = lattice.index(c[0], c[1], c[2]);
                    // Rays of different axes write different bits of one byte: no two rays of one axis
                    // share a point, and the axes run one after another.
                    votes[at] |= uint8_t(1u << axis);
                    if (axis == 0 || material[at] == 0) material[at] = entering + 1;
                }
            }
        });
    }

    // The volume, leaf by leaf: solid where two rays of three agree, crossings from the hits.
    Volume volume(voxelSize);
    std::vector<MaterialId> ids(mesh.materials.size(), 1);
    if (!options.material.empty()) {
        const auto found = volume.materials().find(options.material);
        const MaterialId id = found ? *found : volume.materials().define(Material{options.material});
        std::fill(ids.begin(), ids.end(), id);
    } else if (mesh.materials.size() > 1 || !mesh.materials[0].name.empty()) {
        for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
            if (mesh.materials[m].name.empty()) continue; // unnamed: the default material
            Material out;
            out.name = mesh.materials[m].name;
            out.color = mesh.materials[m].color;
            ids[m] = volume.materials().define(out);
        }
    }
    auto solidAt = [&](int x, int y, int z) {
        if (x < 0 || y < 0 || z < 0 || x >= lattice.dim[0] || y >= lattice.dim[1] || z >= lattice.dim[2]) return false;
        const uint8_t b = votes[lattice.index(x, y, z)];
        return ((b & 1) + ((b >> 1) & 1) + ((b >> 2) & 1)) >= 2;
    };
    // A crossing the vote made where no ray hit: the normal of the solid's shape around the edge (its
    // occupancy's gradient over the 3x3x3 points about each end), else along the edge.
    auto patchNormal = [&](const int* p, const int* q, int axis, double sign) {
        std::array<double, 3> n{0.0, 0.0, 0.0};
        for (const int* c : {p, q})
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        if (!solidAt(c[0] + dx, c[1] + dy, c[2] + dz)) continue;
                        n[0] -= dx, n[1] -= dy, n[2] -= dz; // out of the solid: away from its points
                    }
        if (n[std::size_t(axis)] * sign <= 0.0) {
            n = {0.0, 0.0, 0.0};
            n[std::size_t(axis)] = sign;
        }
        return n;
    };
    std::vector<Coord> origins;
    for (int32_t x = lattice.lo[0] & ~(kLeafDim - 1); x < lattice.lo[0] + lattice.dim[0]; x += kLeafDim)
        for (int32_t y = lattice.lo[1] & ~(kLeafDim - 1); y < lattice.lo[1] + lattice.dim[1]; y += kLeafDim)
            for (int32_t z = lattice.lo[2] & ~(kLeafDim - 1); z < lattice.lo[2] + lattice.dim[2]; z += kLeafDim) origins.emplace_back(x, y, z);
    std::vector<HermiteLeafData> data(origins.size());
    std::vector<uint8_t> any(origins.size(), 0);
    std::atomic<uint64_t> voted{0}, patched{0}, crossings{0}, solid{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 8), [&](const auto& range) {
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            HermiteLeafData& d = data[l];
            uint64_t leafVoted = 0, leafPatched = 0, leafCrossings = 0, leafSolid = 0;
            for (int x = 0; x < kLeafDim; ++x)
                for (int y = 0; y < kLeafDim; ++y)
                    for (int z = 0; z < kLeafDim; ++z) {
                        const int g[3] = {origins[l].x() + x - lattice.lo[0], origins[l].y() + y - lattice.lo[1], origins[l].z() + z - lattice.lo[2]};
                        const int offset = (x << (2 * kLeafLog2Dim)) | (y << kLeafLog2Dim) | z;
                        const bool s = solidAt(g[0], g[1], g[2]);
                        if (s) {
                            const std::size_t at = lattice.index(g[0], g[1], g[2]);
                            const uint8_t b = votes[at];
                            if (b != 7) ++leafVoted;
                            d.material[std::size_t(offset)].id = ids[std::min<std::size_t>(material[at] ? material[at] - 1 : 0, ids.size() - 1)];
                            ++leafSolid;
                        } else if (g[0] >= 0 && g[1] >= 0 && g[2] >= 0 && g[0] < lattice.dim[0] && g[1] < lattice.dim[1] &&
                                   g[2] < lattice.dim[2] && votes[lattice.index(g[0], g[1], g[2])] != 0) {
                            ++leafVoted;
                        }
                        for (int axis = 0; axis < 3; ++axis) {
                            int n[3] = {g[0], g[1], g[2]};
                            n[axis] += 1;
                            if (solidAt(n[0], n[1], n[2]) == s) continue;
                            // The hit on this edge whose normal leaves the solid the right way, else
                            // any hit on it, else (the vote made it cross) mid-edge along the axis. A hit a
                            // hair past an end counts (a face a rounding error off a lattice plane, whose
                            // points the vote settles): it lands on that end.
                            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                            const RayHits& rh = rays[std::size_t(axis)];
                            const std::size_t ray = std::size_t(g[u]) * std::size_t(lattice.dim[std::size_t(v)]) + std::size_t(g[v]);
                            const double sign = s ? 1.0 : -1.0;
                            const Hit* best = nullptr;
                            for (uint32_t h = rh.first[ray]; h < rh.first[ray + 1]; ++h) {
                                const Hit& hit = rh.hits[h];
                                if (hit.at < double(g[axis]) - kEndTolerance || hit.at > double(g[axis] + 1) + kEndTolerance) continue;
                                if (!best || (best->normal[std::size_t(axis)] * sign <= 0.0 && hit.normal[std::size_t(axis)] * sign > 0.0)) best = &hit;
                            }
                            double t = 0.5;
                            std::array<double, 3> normal = patchNormal(g, n, axis, sign);
                            if (best) {
                                t = std::clamp(best->at - double(g[axis]), 0.0, 1.0);
                                // Out of the solid along this edge, whatever the triangle's winding.
                                const double flip = best->normal[std::size_t(axis)] * sign < 0.0 ? -1.0 : 1.0;
                                for (int i = 0; i < 3; ++i) normal[std::size_t(i)] = flip * best->normal[std::size_t(i)];
                            } else {
                                ++leafPatched;
                            }
                            const int bit = HermiteLeaf::edgeBit(Index(offset), axis);
                            d.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                            d.samples.push_back(packSample(t, normal));
                            ++leafCrossings;
                        }
                    }
            any[l] = leafSolid > 0 || leafCrossings > 0;
            voted += leafVoted, patched += leafPatched, crossings += leafCrossings, solid += leafSolid;
        }
    });
    // Leaves wholly inside one material without a crossing become tiles.
    std::vector<Coord> placed;
    std::vector<HermiteLeafData> placedData;
    for (std::size_t l = 0; l < origins.size(); ++l)
        if (any[l]) placed.push_back(origins[l]), placedData.push_back(std::move(data[l]));
    placeLeaves(volume.impl().grid->tree(), placed, placedData);
    r.votedPoints = voted;
    r.patchedCrossings = patched;
    r.crossings = crossings;
    r.solidVoxels = solid;
    if (report) *report = r;
    return volume;
}

} // namespace vdbclay
