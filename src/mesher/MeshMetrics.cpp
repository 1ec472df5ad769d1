#include "mesher/MeshMetrics.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace vdbclay {

namespace {

struct DisjointSets {
    std::vector<uint32_t> parent;
    explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t v)
    {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    }
    void join(uint32_t a, uint32_t b)
    {
        a = find(a), b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

/// Each vertex's representative: the lowest-numbered vertex within `distance` of it (transitively).
/// Points closer than `distance` fall into the same or neighbouring cells of a grid of that spacing.
std::vector<uint32_t> mergeClosePoints(const std::vector<std::array<float, 3>>& positions, double distance)
{
    DisjointSets sets(positions.size());
    if (!(distance > 0.0)) return sets.parent;
    const double inv = 1.0 / distance;
    auto cellOf = [&](const std::array<float, 3>& p) {
        return std::array<int64_t, 3>{int64_t(std::floor(p[0] * inv)), int64_t(std::floor(p[1] * inv)),
                                      int64_t(std::floor(p[2] * inv))};
    };
    auto hashOf = [](const std::array<int64_t, 3>& c) {
        return uint64_t(c[0]) * 0x9E3779B97F4A7C15ull ^ uint64_t(c[1]) * 0xC2B2AE3D27D4EB4Full ^
               uint64_t(c[2]) * 0x165667B19E3779F9ull;
    };
    std::unordered_multimap<uint64_t, uint32_t> cells;
    cells.reserve(positions.size());
    const double d2 = distance * distance;
    for (uint32_t v = 0; v < positions.size(); ++v) {
        const auto& p = positions[v];
        const auto c = cellOf(p);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto range = cells.equal_range(hashOf({c[0] + dx, c[1] + dy, c[2] + dz}));
                    for (auto it = range.first; it != range.second; ++it) {
                        const auto& q = positions[it->second];
                        const double ex = double(p[0]) - q[0], ey = double(p[1]) - q[1], ez = double(p[2]) - q[2];
                        if (ex * ex + ey * ey + ez * ez < d2) sets.join(v, it->second);
                    }
                }
        cells.emplace(hashOf(c), v);
    }
    std::vector<uint32_t> representative(positions.size());
    for (uint32_t v = 0; v < positions.size(); ++v) representative[v] = sets.find(v);
    return representative;
}

double doubledArea(const std::array<float, 3>& a, const std::array<float, 3>& b, const std::array<float, 3>& c)
{
    const double ux = double(b[0]) - a[0], uy = double(b[1]) - a[1], uz = double(b[2]) - a[2];
    const double vx = double(c[0]) - a[0], vy = double(c[1]) - a[1], vz = double(c[2]) - a[2];
    const double x = uy * vz - uz * vy, y = uz * vx - ux * vz, z = ux * vy - uy * vx;
    return std::sqrt(x * x + y * y + z * z);
}

} // namespace

MeshTopology analyzeTopology(const Mesh& mesh, double mergeDistance)
{
    MeshTopology topo;
    const std::vector<uint32_t> rep = mergeClosePoints(mesh.positions, mergeDistance);
    for (uint32_t v = 0; v < rep.size(); ++v) topo.mergedVertices += rep[v] == v;

    std::vector<std::array<uint32_t, 3>> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
        const std::array<uint32_t, 3> m{rep[t[0]], rep[t[1]], rep[t[2]]};
        // A triangle with two corners at one point drops out of the surface; a sliver of zero area
        // (three distinct points on a line) still joins its edges, but is a defect as well.
        const bool collapsed = m[0] == m[1] || m[1] == m[2] || m[2] == m[0];
        if (collapsed ||
            doubledArea(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]) < mergeDistance * mergeDistance)
            ++topo.degenerateTriangles;
        if (!collapsed) triangles.push_back(m);
    }

    std::unordered_map<uint64_t, uint32_t> directed; // (from << 32 | to) -> count
    directed.reserve(triangles.size() * 3);
    for (const auto& t : triangles)
        for (int e = 0; e < 3; ++e) ++directed[(uint64_t(t[e]) << 32) | t[(e + 1) % 3]];
    for (const auto& [key, count] : directed) {
        const uint32_t from = uint32_t(key >> 32), to = uint32_t(key);
        const auto reverse = directed.find((uint64_t(to) << 32) | from);
        const uint32_t back = reverse == directed.end() ? 0 : reverse->second;
        if (from > to && back > 0) continue; // counted from the other side
        const uint32_t total = count + back;
        if (total == 1) ++topo.boundaryEdges;
        else if (total > 2) ++topo.nonManifoldEdges;
        else if (back != 1) ++topo.misorientedEdges; // two uses, both in the same direction
    }

    // Each vertex's link: the edge opposite it in each of its triangles, oriented. On a manifold the
    // link is one cycle; two or more cycles are fans that touch at the vertex only (a pinch).
    std::vector<uint32_t> start(mesh.positions.size() + 1, 0);
    for (const auto& t : triangles)
        for (uint32_t v : t) ++start[v + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<std::array<uint32_t, 2>> link(start.back());
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (const auto& t : triangles)
        for (int e = 0; e < 3; ++e) link[fill[t[e]]++] = {t[(e + 1) % 3], t[(e + 2) % 3]};
    std::vector<char> seen;
    for (uint32_t v = 0; v < mesh.positions.size(); ++v) {
        const uint32_t begin = start[v], n = start[v + 1] - begin;
        if (n == 0) continue;
        seen.assign(n, 0);
        uint32_t visited = 0, at = 0;
        while (!seen[at]) { // follow the cycle through link edge 0
            seen[at] = 1;
            ++visited;
            const uint32_t next = link[begin + at][1];
            uint32_t k = 0;
            while (k < n && link[begin + k][0] != next) ++k;
            if (k == n) break; // an open link: a boundary, counted with the edges
            at = k;
        }
        if (visited < n) ++topo.pinchedVertices;
    }

    DisjointSets pieces(mesh.positions.size());
    for (const auto& t : triangles) pieces.join(t[0], t[1]), pieces.join(t[1], t[2]);
    std::vector<char> root(mesh.positions.size(), 0);
    for (const auto& t : triangles) {
        const uint32_t r = pieces.find(t[0]);
        if (!root[r]) root[r] = 1, ++topo.components;
    }
    return topo;
}

double surfaceArea(const Mesh& mesh)
{
    double doubled = 0.0;
    for (const auto& t : mesh.triangles) doubled += doubledArea(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]);
    return 0.5 * doubled;
}

double enclosedVolume(const Mesh& mesh)
{
    double sum = 0.0;
    for (const auto& t : mesh.triangles) {
        const auto& a = mesh.positions[t[0]];
        const auto& b = mesh.positions[t[1]];
        const auto& c = mesh.positions[t[2]];
        const double cx = double(b[1]) * c[2] - double(b[2]) * c[1];
        const double cy = double(b[2]) * c[0] - double(b[0]) * c[2];
        const double cz = double(b[0]) * c[1] - double(b[1]) * c[0];
        sum += a[0] * cx + a[1] * cy + a[2] * cz;
    }
    return sum / 6.0;
}

} // namespace vdbclay
