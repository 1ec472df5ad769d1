#include "mesher/MeshMetrics.h"

#include <unordered_map>

namespace vdbclay {

MeshTopology analyzeTopology(const Mesh& mesh)
{
    MeshTopology topo;
    std::unordered_map<uint64_t, uint32_t> directed; // (from << 32 | to) -> count
    directed.reserve(mesh.triangles.size() * 3);
    for (const auto& t : mesh.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
            ++topo.degenerateTriangles;
            continue;
        }
        for (int e = 0; e < 3; ++e) ++directed[(uint64_t(t[e]) << 32) | t[(e + 1) % 3]];
    }
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
    return topo;
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
