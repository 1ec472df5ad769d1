#include "query/SceneModels.h"

#include "query/MeshCurvature.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

namespace vdbclay::query {

TriangleSoup soupOfMesh(const Mesh& mesh, const MaterialTable& materials)
{
    TriangleSoup soup;
    soup.positions.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) soup.positions.push_back({p[0], p[1], p[2]});
    soup.triangles = mesh.triangles;
    std::map<MaterialId, uint32_t> index;
    soup.triangleMaterials.reserve(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const MaterialId id = t < mesh.triangleMaterials.size() ? mesh.triangleMaterials[t] : kEmptyMaterial;
        auto it = index.find(id);
        if (it == index.end()) {
            MeshMaterial m;
            try {
                const Material& known = materials.at(id);
                m.name = known.name;
                m.color = known.color;
            } catch (const std::out_of_range&) {
                m.name = "unknown";
            }
            it = index.emplace(id, uint32_t(soup.materials.size())).first;
            soup.materials.push_back(m);
        }
        soup.triangleMaterials.push_back(it->second);
    }
    return soup;
}

TriangleSoup smoothedSculpture(const TriangleSoup& soup, int passes)
{
    const WeldedMesh welded = weldMesh(soup);
    std::vector<std::array<double, 3>> positions = welded.positions, next(positions.size());
    const auto step = [&](double factor) {
        for (std::size_t v = 0; v < positions.size(); ++v) {
            const uint32_t from = welded.neighbourStart[v], to = welded.neighbourStart[v + 1];
            next[v] = positions[v];
            if (from == to || welded.boundary[v]) continue; // an open rim stays where it is
            std::array<double, 3> mean{0, 0, 0};
            for (uint32_t i = from; i < to; ++i)
                for (int a = 0; a < 3; ++a) mean[std::size_t(a)] += positions[welded.neighbours[i]][std::size_t(a)] / double(to - from);
            for (int a = 0; a < 3; ++a) next[v][std::size_t(a)] += factor * (mean[std::size_t(a)] - positions[v][std::size_t(a)]);
        }
        positions.swap(next);
    };
    for (int p = 0; p < passes; ++p) {
        step(0.5);   // shrinks and smooths
        step(-0.53); // grows back: the shape's size stays
    }
    TriangleSoup out;
    out.positions = std::move(positions);
    out.triangles = welded.triangles;
    out.triangleMaterials = soup.triangleMaterials;
    out.materials = soup.materials;
    return out;
}

Mesh meshOfSoup(const TriangleSoup& soup, MaterialTable& materials)
{
    std::vector<MaterialId> ids;
    for (std::size_t i = 0; i < soup.materials.size(); ++i) {
        Material m;
        m.name = "model-" + std::to_string(i);
        m.color = soup.materials[i].color;
        for (float& c : m.color) c = std::isfinite(c) ? std::clamp(c, 0.0f, 1.0f) : 0.8f;
        try {
            ids.push_back(materials.define(m));
        } catch (const std::invalid_argument&) {
            ids.push_back(1); // the table is full: the default material
        }
    }
    Mesh mesh;
    mesh.positions.reserve(soup.triangles.size() * 3);
    for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
        const auto& tri = soup.triangles[t];
        const auto &a = soup.positions[tri[0]], &b = soup.positions[tri[1]], &c = soup.positions[tri[2]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (double& x : n) x = length > 0.0 ? x / length : 0.0;
        const uint32_t soupMaterial = t < soup.triangleMaterials.size() ? soup.triangleMaterials[t] : uint32_t(ids.size());
        const MaterialId material = soupMaterial < ids.size() ? ids[soupMaterial] : MaterialId(1);
        const uint32_t first = uint32_t(mesh.positions.size());
        for (const auto* p : {&a, &b, &c}) {
            mesh.positions.push_back({float((*p)[0]), float((*p)[1]), float((*p)[2])});
            mesh.normals.push_back({float(n[0]), float(n[1]), float(n[2])});
            mesh.materials.push_back(material);
        }
        mesh.triangles.push_back({first, first + 1, first + 2});
        mesh.triangleMaterials.push_back(material);
    }
    return mesh;
}

} // namespace vdbclay::query
