// Small hand-built meshes for the mesh quality and mesh export tests: a unit cube, an octahedron, a
// tetrahedron and an icosphere, all closed and oriented counter-clockwise seen from outside.
#pragma once

#include "mesher/Mesh.h"

#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace vdbclay::test {

/// Flips every triangle whose normal points towards `centre` (valid for convex shapes around it).
inline void orientOutward(Mesh& mesh, const std::array<double, 3>& centre)
{
    for (auto& t : mesh.triangles) {
        const auto& a = mesh.positions[t[0]];
        const auto& b = mesh.positions[t[1]];
        const auto& c = mesh.positions[t[2]];
        const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
        const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
        const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const double g[3] = {(double(a[0]) + b[0] + c[0]) / 3.0 - centre[0], (double(a[1]) + b[1] + c[1]) / 3.0 - centre[1],
                             (double(a[2]) + b[2] + c[2]) / 3.0 - centre[2]};
        if (n[0] * g[0] + n[1] * g[1] + n[2] * g[2] < 0.0) std::swap(t[1], t[2]);
    }
}

/// Radial unit normals and one material for every vertex.
inline void finishMesh(Mesh& mesh, const std::array<double, 3>& centre, MaterialId material = 1)
{
    orientOutward(mesh, centre);
    mesh.normals.clear();
    for (const auto& p : mesh.positions) {
        double d[3] = {p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]};
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        mesh.normals.push_back({float(d[0] / len), float(d[1] / len), float(d[2] / len)});
    }
    mesh.materials.assign(mesh.positions.size(), material);
}

/// The cube [c-h, c+h]^3 as 8 vertices and 12 triangles (each face split along a diagonal).
inline Mesh cubeMesh(double h = 0.5, std::array<double, 3> c = {0, 0, 0})
{
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({float(c[0] + ((i & 1) ? h : -h)), float(c[1] + ((i & 2) ? h : -h)),
                               float(c[2] + ((i & 4) ? h : -h))});
    // Quads as corner index lists, in cyclic order around each face.
    const int quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    for (const auto& q : quads) {
        m.triangles.push_back({uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2])});
        m.triangles.push_back({uint32_t(q[0]), uint32_t(q[2]), uint32_t(q[3])});
    }
    finishMesh(m, c);
    return m;
}

/// The octahedron |x| + |y| + |z| = r.
inline Mesh octahedronMesh(double r = 1.0)
{
    Mesh m;
    for (int axis = 0; axis < 3; ++axis)
        for (int s : {1, -1}) {
            std::array<float, 3> p{0, 0, 0};
            p[axis] = float(s * r);
            m.positions.push_back(p);
        }
    // Vertices 0/1 = +-x, 2/3 = +-y, 4/5 = +-z.
    for (uint32_t x : {0u, 1u})
        for (uint32_t y : {2u, 3u})
            for (uint32_t z : {4u, 5u}) m.triangles.push_back({x, y, z});
    finishMesh(m, {0, 0, 0});
    return m;
}

/// A tetrahedron with the given corners.
inline Mesh tetrahedronMesh(const std::array<std::array<float, 3>, 4>& corners, MaterialId material = 1)
{
    Mesh m;
    std::array<double, 3> centre{0, 0, 0};
    for (const auto& p : corners) {
        m.positions.push_back(p);
        for (int i = 0; i < 3; ++i) centre[i] += p[i] / 4.0;
    }
    m.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
    finishMesh(m, centre, material);
    return m;
}

/// An icosphere: an icosahedron subdivided `levels` times (20 * 4^levels triangles), projected onto the
/// sphere of the given radius and centre.
inline Mesh icosphereMesh(double radius, int levels, std::array<double, 3> c = {0, 0, 0})
{
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                              {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                              {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                              {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    auto normalize = [](std::array<double, 3>& p) {
        const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (double& x : p) x /= len;
    };
    for (auto& p : v) normalize(p);
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            const auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            std::array<double, 3> p{(v[a][0] + v[b][0]) / 2, (v[a][1] + v[b][1]) / 2, (v[a][2] + v[b][2]) / 2};
            normalize(p);
            v.push_back(p);
            mid.emplace(key, uint32_t(v.size() - 1));
            return uint32_t(v.size() - 1);
        };
        std::vector<std::array<uint32_t, 3>> next;
        next.reserve(f.size() * 4);
        for (const auto& tri : f) {
            const uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
            next.push_back({tri[0], ab, ca});
            next.push_back({tri[1], bc, ab});
            next.push_back({tri[2], ca, bc});
            next.push_back({ab, bc, ca});
        }
        f.swap(next);
    }
    Mesh m;
    for (const auto& p : v)
        m.positions.push_back({float(c[0] + radius * p[0]), float(c[1] + radius * p[1]), float(c[2] + radius * p[2])});
    m.triangles = f;
    finishMesh(m, c);
    return m;
}

} // namespace vdbclay::test
