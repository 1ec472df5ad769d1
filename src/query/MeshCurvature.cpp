#include "query/MeshCurvature.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace vdbclay::query {

namespace {

using Vec = std::array<double, 3>;

Vec minus(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double length(const Vec& a) { return std::sqrt(dot(a, a)); }

/// A position rounded to a lattice a billionth of the mesh's size fine: corners a file repeats with
/// rounding noise (a revolved surface's seam, sin(2 pi) against 0) join; distinct corners stay apart.
using Cell = std::array<int64_t, 3>;
struct CellHash {
    std::size_t operator()(const Cell& c) const
    {
        uint64_t h = 1469598103934665603ull;
        for (int64_t v : c) h = (h ^ uint64_t(v)) * 1099511628211ull;
        return std::size_t(h ^ (h >> 29));
    }
};

uint64_t edgeKey(uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a; }

} // namespace

VertexWeld weldVertices(const TriangleSoup& soup)
{
    VertexWeld out;
    out.index.resize(soup.positions.size());
    double extent = 0.0;
    for (const Vec& p : soup.positions)
        for (double c : p) extent = std::max(extent, std::abs(c));
    const double cell = std::max(extent, 1e-300) * 1e-9;
    std::unordered_map<Cell, uint32_t, CellHash> seen;
    seen.reserve(soup.positions.size());
    for (std::size_t i = 0; i < soup.positions.size(); ++i) {
        const Vec& p = soup.positions[i];
        const Cell key{std::llround(p[0] / cell), std::llround(p[1] / cell), std::llround(p[2] / cell)};
        const auto [at, inserted] = seen.emplace(key, uint32_t(out.positions.size()));
        if (inserted) out.positions.push_back(p);
        out.index[i] = at->second;
    }
    return out;
}

WeldedMesh weldMesh(const TriangleSoup& soup)
{
    WeldedMesh out;
    VertexWeld weld = weldVertices(soup);
    out.positions = std::move(weld.positions);
    const std::vector<uint32_t>& remap = weld.index;
    out.triangles.reserve(soup.triangles.size());
    std::unordered_map<uint64_t, uint32_t> edgeUses;
    edgeUses.reserve(soup.triangles.size() * 2);
    for (const auto& t : soup.triangles) {
        const std::array<uint32_t, 3> w{remap[t[0]], remap[t[1]], remap[t[2]]};
        out.triangles.push_back(w);
        for (int e = 0; e < 3; ++e)
            if (w[std::size_t(e)] != w[std::size_t((e + 1) % 3)]) ++edgeUses[edgeKey(w[std::size_t(e)], w[std::size_t((e + 1) % 3)])];
    }
    // Neighbours from the edges, in CSR.
    const std::size_t n = out.positions.size();
    out.neighbourStart.assign(n + 1, 0);
    out.boundary.assign(n, false);
    for (const auto& [key, uses] : edgeUses) {
        const uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
        ++out.neighbourStart[a + 1], ++out.neighbourStart[b + 1];
        if (uses == 1) out.boundary[a] = out.boundary[b] = true;
    }
    for (std::size_t v = 0; v < n; ++v) out.neighbourStart[v + 1] += out.neighbourStart[v];
    out.neighbours.resize(out.neighbourStart[n]);
    std::vector<uint32_t> fill(out.neighbourStart.begin(), out.neighbourStart.end() - 1);
    for (const auto& entry : edgeUses) {
        const uint32_t a = uint32_t(entry.first >> 32), b = uint32_t(entry.first);
        out.neighbours[fill[a]++] = b;
        out.neighbours[fill[b]++] = a;
    }
    // The hash map's order is not the same everywhere: sort, so that sums over neighbours are repeatable.
    for (std::size_t v = 0; v < n; ++v) std::sort(out.neighbours.begin() + out.neighbourStart[v], out.neighbours.begin() + out.neighbourStart[v + 1]);
    return out;
}

double absoluteGaussianCurvature(const WeldedMesh& mesh)
{
    std::vector<double> angles(mesh.positions.size(), 0.0);
    std::vector<bool> used(mesh.positions.size(), false);
    for (const auto& t : mesh.triangles)
        for (int c = 0; c < 3; ++c) {
            const Vec& p = mesh.positions[t[std::size_t(c)]];
            const Vec u = minus(mesh.positions[t[std::size_t((c + 1) % 3)]], p), w = minus(mesh.positions[t[std::size_t((c + 2) % 3)]], p);
            const double lu = length(u), lw = length(w);
            if (lu > 0.0 && lw > 0.0) angles[t[std::size_t(c)]] += std::acos(std::clamp(dot(u, w) / (lu * lw), -1.0, 1.0));
            used[t[std::size_t(c)]] = true;
        }
    double total = 0.0;
    for (std::size_t v = 0; v < angles.size(); ++v)
        if (used[v]) total += std::abs((mesh.boundary[v] ? M_PI : 2.0 * M_PI) - angles[v]);
    return total;
}

std::vector<double> meanCurvature(const WeldedMesh& mesh)
{
    const std::size_t n = mesh.positions.size();
    // Vertex normals (area-weighted) and, per edge, the area of the triangles beside it.
    std::vector<Vec> normals(n, Vec{0, 0, 0});
    std::unordered_map<uint64_t, double> edgeArea;
    edgeArea.reserve(mesh.triangles.size() * 2);
    for (const auto& t : mesh.triangles) {
        const Vec area2 = cross(minus(mesh.positions[t[1]], mesh.positions[t[0]]), minus(mesh.positions[t[2]], mesh.positions[t[0]]));
        const double a = 0.5 * length(area2);
        for (int c = 0; c < 3; ++c) {
            for (int k = 0; k < 3; ++k) normals[t[std::size_t(c)]][std::size_t(k)] += area2[std::size_t(k)];
            const uint32_t p = t[std::size_t(c)], q = t[std::size_t((c + 1) % 3)];
            if (p != q) edgeArea[edgeKey(p, q)] += a;
        }
    }
    std::vector<double> curvature(n, 0.0);
    for (std::size_t v = 0; v < n; ++v) {
        const double nl = length(normals[v]);
        if (!(nl > 0.0)) continue;
        const Vec normal{normals[v][0] / nl, normals[v][1] / nl, normals[v][2] / nl};
        double sum = 0.0, weights = 0.0;
        for (uint32_t i = mesh.neighbourStart[v]; i < mesh.neighbourStart[v + 1]; ++i) {
            const uint32_t w = mesh.neighbours[i];
            const Vec d = minus(mesh.positions[v], mesh.positions[w]);
            const double d2 = dot(d, d);
            const auto at = edgeArea.find(edgeKey(uint32_t(v), w));
            const double weight = at == edgeArea.end() ? 0.0 : at->second;
            if (!(d2 > 0.0) || !(weight > 0.0)) continue;
            sum += weight * 2.0 * dot(normal, d) / d2;
            weights += weight;
        }
        curvature[v] = weights > 0.0 ? sum / weights : 0.0;
    }
    return curvature;
}

} // namespace vdbclay::query
