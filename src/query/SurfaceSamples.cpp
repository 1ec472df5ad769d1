#include "query/SurfaceSamples.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace vdbclay::query {

namespace {

double triangleArea(const std::array<double, 3>& a, const std::array<double, 3>& b, const std::array<double, 3>& c)
{
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2], z = u[0] * v[1] - u[1] * v[0];
    return 0.5 * std::sqrt(x * x + y * y + z * z);
}

} // namespace

namespace {

std::array<float, 3> triangleColour(const TriangleSoup& mesh, std::size_t t)
{
    if (t < mesh.triangleMaterials.size() && mesh.triangleMaterials[t] < mesh.materials.size()) {
        const auto& m = mesh.materials[mesh.triangleMaterials[t]].color;
        return {m[0], m[1], m[2]};
    }
    return {0.8f, 0.8f, 0.8f};
}

} // namespace

std::array<float, 3> meanColour(const TriangleSoup& mesh)
{
    double sum[3] = {0, 0, 0}, total = 0.0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        const double a = triangleArea(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]);
        const std::array<float, 3> c = triangleColour(mesh, t);
        for (int k = 0; k < 3; ++k) sum[k] += a * c[std::size_t(k)];
        total += a;
    }
    if (!(total > 0.0)) return {0.8f, 0.8f, 0.8f};
    return {float(sum[0] / total), float(sum[1] / total), float(sum[2] / total)};
}

SurfaceSamples sampleSurface(const TriangleSoup& mesh, std::size_t count, uint64_t seed)
{
    std::vector<double> cumulative;
    cumulative.reserve(mesh.triangles.size());
    double total = 0.0;
    for (const auto& t : mesh.triangles) {
        total += triangleArea(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]);
        cumulative.push_back(total);
    }
    if (!(total > 0.0) || !std::isfinite(total)) throw std::invalid_argument("the mesh has no surface area to sample");
    SurfaceSamples out;
    out.area = total;
    out.points.reserve(count);
    out.colours.reserve(count);
    out.triangles.reserve(count);
    out.barycentric.reserve(count);
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (std::size_t i = 0; i < count; ++i) {
        const double at = unit(random) * total;
        const std::size_t t = std::min<std::size_t>(std::size_t(std::upper_bound(cumulative.begin(), cumulative.end(), at) - cumulative.begin()),
                                                    mesh.triangles.size() - 1);
        // A point uniform in the triangle: the square root folds the unit square onto it evenly.
        const double r1 = std::sqrt(unit(random)), r2 = unit(random);
        const auto& tri = mesh.triangles[t];
        const auto &a = mesh.positions[tri[0]], &b = mesh.positions[tri[1]], &c = mesh.positions[tri[2]];
        std::array<double, 3> p;
        for (int k = 0; k < 3; ++k) p[std::size_t(k)] = (1 - r1) * a[std::size_t(k)] + r1 * (1 - r2) * b[std::size_t(k)] + r1 * r2 * c[std::size_t(k)];
        out.points.push_back(p);
        out.colours.push_back(triangleColour(mesh, t));
        out.triangles.push_back(uint32_t(t));
        out.barycentric.push_back({1 - r1, r1 * (1 - r2), r1 * r2});
    }
    return out;
}

} // namespace vdbclay::query
