#include "query/SilhouetteMesh.h"

#include "query/MeshCurvature.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

namespace vdbclay::query {

namespace {

/// A cell's key: 21 bits per axis, cells counted from the lowest corner (a welded position may lie a
/// rounding below it).
uint64_t cellKey(const std::array<double, 3>& p, const std::array<double, 3>& lo, double cell)
{
    uint64_t key = 0;
    for (std::size_t a = 0; a < 3; ++a) key = key << 21 | uint64_t(std::clamp(std::floor((p[a] - lo[a]) / cell), 0.0, double((1 << 21) - 1)));
    return key;
}

/// `out`'s mesh: the soup's triangles on the vertices `vertexOf` (per welded vertex) gives them, those
/// whose corners meet dropped, and whether the triangles close.
void buildTriangles(const TriangleSoup& soup, const VertexWeld& weld, const std::vector<uint32_t>& vertexOf,
                    std::vector<std::array<float, 3>> positions, SilhouetteMesh& out)
{
    Mesh& mesh = out.mesh;
    mesh = Mesh{};
    mesh.positions = std::move(positions);
    mesh.normals.assign(mesh.positions.size(), {0.0f, 0.0f, 1.0f});
    mesh.materials.assign(mesh.positions.size(), MaterialId(1));
    // Directed edges counted +1 one way and -1 the other: all zero when the surface closes.
    std::unordered_map<uint64_t, int> edgeBalance;
    edgeBalance.reserve(soup.triangles.size() * 2);
    for (const auto& t : soup.triangles) {
        const std::array<uint32_t, 3> c{vertexOf[weld.index[t[0]]], vertexOf[weld.index[t[1]]], vertexOf[weld.index[t[2]]]};
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
        mesh.triangles.push_back(c);
        for (int i = 0; i < 3; ++i) {
            const uint32_t a = c[std::size_t(i)], b = c[std::size_t((i + 1) % 3)];
            edgeBalance[uint64_t(std::min(a, b)) << 32 | std::max(a, b)] += a < b ? 1 : -1;
        }
    }
    mesh.triangleMaterials.assign(mesh.triangles.size(), MaterialId(1));
    out.closed = !mesh.triangles.empty();
    for (const auto& [edge, balance] : edgeBalance)
        if (balance != 0) {
            out.closed = false;
            break;
        }
}

} // namespace

SilhouetteMesh silhouetteMesh(const TriangleSoup& soup, double cell)
{
    if (!(cell > 0.0) || !std::isfinite(cell)) throw std::invalid_argument("a silhouette mesh needs a positive cell size");
    // Welded first: corners a file repeats, or that differ by rounding along a seam, must fall in one
    // cluster, or the surface would open where they straddle a cell's side.
    const VertexWeld weld = weldVertices(soup);
    std::array<double, 3> lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (const auto& t : soup.triangles) // the corners drawn (a file's other vertices may be anything)
        for (const uint32_t v : t)
            for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], soup.positions[v][a]), hi[a] = std::max(hi[a], soup.positions[v][a]);
    for (std::size_t a = 0; a < 3; ++a) cell = std::max(cell, (hi[a] - lo[a]) / double((1 << 21) - 2)); // keys fit 21 bits

    // Each used vertex's cluster, a cluster's position the mean of its vertices (inside its cell).
    SilhouetteMesh out;
    std::vector<uint32_t> clusterOf(weld.positions.size(), UINT32_MAX);
    std::unordered_map<uint64_t, uint32_t> clusters;
    std::vector<std::array<double, 4>> sums;
    for (const auto& t : soup.triangles)
        for (const uint32_t soupVertex : t) {
            const uint32_t v = weld.index[soupVertex];
            if (clusterOf[v] != UINT32_MAX) continue;
            const auto [it, added] = clusters.try_emplace(cellKey(weld.positions[v], lo, cell), uint32_t(sums.size()));
            if (added) sums.push_back({0.0, 0.0, 0.0, 0.0});
            clusterOf[v] = it->second;
            auto& s = sums[it->second];
            for (std::size_t a = 0; a < 3; ++a) s[a] += weld.positions[v][a];
            s[3] += 1.0;
        }
    std::vector<std::array<float, 3>> positions;
    positions.reserve(sums.size());
    for (const auto& s : sums) positions.push_back({float(s[0] / s[3]), float(s[1] / s[3]), float(s[2] / s[3])});
    buildTriangles(soup, weld, clusterOf, std::move(positions), out);
    if (out.mesh.triangles.empty() && !soup.triangles.empty()) {
        // Every triangle fell inside a cell (a model far smaller than the cell): its welded triangles.
        std::vector<uint32_t> itself(weld.positions.size());
        std::vector<std::array<float, 3>> welded;
        for (uint32_t v = 0; v < itself.size(); ++v) {
            itself[v] = v;
            welded.push_back({float(weld.positions[v][0]), float(weld.positions[v][1]), float(weld.positions[v][2])});
        }
        buildTriangles(soup, weld, itself, std::move(welded), out);
    }
    return out;
}

} // namespace vdbclay::query
