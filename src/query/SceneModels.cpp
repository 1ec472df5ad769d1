#include "query/SceneModels.h"

#include <map>

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

} // namespace vdbclay::query
