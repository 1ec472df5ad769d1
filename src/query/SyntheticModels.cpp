#include "query/SyntheticModels.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace vdbclay::query {

namespace {

using Vec = std::array<double, 3>;

/// Appends a grid of (u, v) in [0,1]^2 mapped by `at`, `nu` x `nv` quads, two triangles each.
template <typename At>
void addGrid(TriangleSoup& soup, int nu, int nv, const At& at)
{
    const uint32_t base = uint32_t(soup.positions.size());
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) soup.positions.push_back(at(double(i) / nu, double(j) / nv));
    const auto index = [&](int i, int j) { return base + uint32_t(j * (nu + 1) + i); };
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            soup.triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
            soup.triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
        }
}

Vec offset(const Vec& p, const Vec& at) { return {p[0] + at[0], p[1] + at[1], p[2] + at[2]}; }

void addBox(TriangleSoup& soup, const Vec& half, int n, const Vec& at = {0, 0, 0})
{
    // Six faces, each an n x n grid.
    for (int axis = 0; axis < 3; ++axis)
        for (double side : {-1.0, 1.0}) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            addGrid(soup, n, n, [&](double s, double t) {
                Vec p{0, 0, 0};
                p[std::size_t(axis)] = side * half[std::size_t(axis)];
                p[std::size_t(u)] = (2 * s - 1) * half[std::size_t(u)];
                p[std::size_t(v)] = (2 * t - 1) * half[std::size_t(v)] * side;
                return offset(p, at);
            });
        }
}

void addEllipsoid(TriangleSoup& soup, const Vec& radii, int n)
{
    addGrid(soup, 2 * n, n, [&](double s, double t) {
        const double phi = 2 * M_PI * s, theta = M_PI * t;
        return Vec{radii[0] * std::sin(theta) * std::cos(phi), radii[1] * std::cos(theta), radii[2] * std::sin(theta) * std::sin(phi)};
    });
}

/// A solid of revolution about +Y: radius r(t) at height y(t), t from bottom to top, closed by caps.
template <typename Profile>
void addRevolved(TriangleSoup& soup, int n, int rings, const Profile& profile, const Vec& at = {0, 0, 0})
{
    addGrid(soup, n, rings, [&](double s, double t) {
        const auto [r, y] = profile(t);
        const double phi = 2 * M_PI * s;
        return offset(Vec{r * std::cos(phi), y, r * std::sin(phi)}, at);
    });
    for (double t : {0.0, 1.0}) {
        const std::pair<double, double> edge = profile(t); // (lambdas may not capture structured bindings in C++17)
        const double r = edge.first, y = edge.second;
        if (r <= 0.0) continue;
        addGrid(soup, n, 2, [&](double s, double u) {
            const double phi = 2 * M_PI * s;
            const double rr = r * (t == 0.0 ? u : 1.0 - u);
            return offset(Vec{rr * std::cos(phi), y, rr * std::sin(phi)}, at);
        });
    }
}

void addTorus(TriangleSoup& soup, double major, double minor, int n)
{
    addGrid(soup, 2 * n, n, [&](double s, double t) {
        const double a = 2 * M_PI * s, b = 2 * M_PI * t;
        const double r = major + minor * std::cos(b);
        return Vec{r * std::cos(a), minor * std::sin(b), r * std::sin(a)};
    });
}

Vec rotate(const std::array<double, 4>& q, const Vec& v)
{
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double cx = y * v[2] - z * v[1], cy = z * v[0] - x * v[2], cz = x * v[1] - y * v[0];
    const double dx = y * cz - z * cy, dy = z * cx - x * cz, dz = x * cy - y * cx;
    return {v[0] + 2 * (w * cx + dx), v[1] + 2 * (w * cy + dy), v[2] + 2 * (w * cz + dz)};
}

} // namespace

const std::vector<std::string>& syntheticFamilies()
{
    static const std::vector<std::string> families{"box", "ellipsoid", "cylinder", "cone", "torus", "table"};
    return families;
}

SyntheticShape randomShape(const std::string& family, std::mt19937_64& random)
{
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    SyntheticShape s;
    s.family = family;
    for (double& p : s.proportions) p = 0.75 + 0.5 * unit(random);
    s.tessellation = 8 + int(unit(random) * 24);
    // A uniform random rotation (Shoemake).
    const double u1 = unit(random), u2 = 2 * M_PI * unit(random), u3 = 2 * M_PI * unit(random);
    s.rotation = {std::sqrt(1 - u1) * std::sin(u2), std::sqrt(1 - u1) * std::cos(u2), std::sqrt(u1) * std::sin(u3), std::sqrt(u1) * std::cos(u3)};
    s.scale = std::exp(std::log(0.2) + unit(random) * std::log(50.0)); // 0.2 .. 10
    for (double& p : s.position) p = (unit(random) - 0.5) * 200.0;
    for (float& c : s.colour) c = float(unit(random));
    return s;
}

TriangleSoup buildShape(const SyntheticShape& shape)
{
    TriangleSoup soup;
    const auto& p = shape.proportions;
    const int n = std::max(3, shape.tessellation);
    if (shape.family == "box") {
        addBox(soup, {1.0 * p[0], 0.6 * p[1], 0.4 * p[2]}, std::max(1, n / 4));
    } else if (shape.family == "ellipsoid") {
        addEllipsoid(soup, {1.0 * p[0], 0.7 * p[1], 0.5 * p[2]}, n);
    } else if (shape.family == "cylinder") {
        const double r = 0.35 * p[0], h = 1.0 * p[1];
        addRevolved(soup, 2 * n, std::max(1, n / 4), [&](double t) { return std::pair<double, double>{r, (t - 0.5) * 2 * h}; });
    } else if (shape.family == "cone") {
        const double r = 0.6 * p[0], h = 1.0 * p[1];
        addRevolved(soup, 2 * n, std::max(1, n / 4), [&](double t) { return std::pair<double, double>{r * (1 - t), (t - 0.5) * 2 * h}; });
    } else if (shape.family == "torus") {
        addTorus(soup, 1.0 * p[0], 0.3 * p[1], n);
    } else if (shape.family == "table") {
        const double w = 1.0 * p[0], d = 0.7 * p[1], legs = 0.8 * p[2];
        addBox(soup, {w, 0.05, d}, std::max(1, n / 4), {0, legs, 0});
        for (double sx : {-1.0, 1.0})
            for (double sz : {-1.0, 1.0})
                addRevolved(soup, std::max(6, n / 2), 1, [&](double t) { return std::pair<double, double>{0.06, t * legs}; },
                            {sx * (w - 0.1), 0.0, sz * (d - 0.1)});
    } else {
        throw std::invalid_argument("unknown synthetic family '" + shape.family + "'");
    }
    for (auto& v : soup.positions) {
        const Vec r = rotate(shape.rotation, v);
        for (int k = 0; k < 3; ++k) v[std::size_t(k)] = shape.scale * r[std::size_t(k)] + shape.position[std::size_t(k)];
    }
    MeshMaterial material;
    char name[32];
    std::snprintf(name, sizeof name, "colour-%02x%02x%02x", int(shape.colour[0] * 255), int(shape.colour[1] * 255), int(shape.colour[2] * 255));
    material.name = name;
    material.color = {shape.colour[0], shape.colour[1], shape.colour[2], 1.0f};
    soup.materials.push_back(material);
    soup.triangleMaterials.assign(soup.triangles.size(), 0);
    return soup;
}

std::vector<LabeledModel> syntheticSet(int perFamily, uint64_t seed)
{
    std::mt19937_64 random(seed);
    std::vector<LabeledModel> out;
    for (const std::string& family : syntheticFamilies())
        for (int i = 0; i < perFamily; ++i) out.push_back({family, family + "-" + std::to_string(i), randomShape(family, random)});
    return out;
}

void writeColouredPly(const TriangleSoup& mesh, const std::string& path)
{
    std::ofstream out(path);
    if (!out) throw std::runtime_error("cannot write " + path);
    // A vertex takes the colour of the first triangle that names it.
    std::vector<std::array<int, 3>> colours(mesh.positions.size(), {204, 204, 204});
    std::vector<bool> coloured(mesh.positions.size(), false);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (t >= mesh.triangleMaterials.size() || mesh.triangleMaterials[t] >= mesh.materials.size()) continue;
        const auto& c = mesh.materials[mesh.triangleMaterials[t]].color;
        for (uint32_t v : mesh.triangles[t])
            if (!coloured[v]) {
                colours[v] = {int(std::lround(c[0] * 255)), int(std::lround(c[1] * 255)), int(std::lround(c[2] * 255))};
                coloured[v] = true;
            }
    }
    out << "ply\nformat ascii 1.0\nelement vertex " << mesh.positions.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    out.precision(9);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v)
        out << mesh.positions[v][0] << ' ' << mesh.positions[v][1] << ' ' << mesh.positions[v][2] << ' ' << colours[v][0] << ' ' << colours[v][1] << ' '
            << colours[v][2] << '\n';
    for (const auto& t : mesh.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    if (!out) throw std::runtime_error("cannot write " + path);
}

} // namespace vdbclay::query
