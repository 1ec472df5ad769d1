#include "voxelize/TriangleMesh.h"

#include "vdb_hermite/PrintableText.h"

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace vdbclay {

bool isMeshPath(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    for (const char* known : {".obj", ".ply", ".stl", ".off", ".gltf", ".glb", ".fbx", ".dae"})
        if (ext == known) return true;
    return false;
}

TriangleSoup loadTriangleMesh(const std::string& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw MeshImportError("'" + path + "' does not exist or is not a file");
    Assimp::Importer importer;
    // Points and lines are no surface; vertices shared by position so that duplicated corners of one
    // seam become one. No normals are asked for: the voxelizer takes each triangle's own.
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                                                       aiProcess_PreTransformVertices);
    if (!scene) throw MeshImportError("'" + path + "' cannot be read as a mesh: " + printableText(importer.GetErrorString(), 200));
    TriangleSoup soup;
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
        const aiMaterial* material = scene->mMaterials[m];
        MeshMaterial out;
        aiString name;
        // Assimp names the material it makes for a file that has none; that one stays unnamed.
        if (material->Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0 && std::string(name.C_Str()) != AI_DEFAULT_MATERIAL_NAME)
            out.name = printableText(name.C_Str(), 64);
        aiColor4D color;
        if (material->Get(AI_MATKEY_COLOR_DIFFUSE, color) == AI_SUCCESS)
            out.color = {std::clamp(color.r, 0.0f, 1.0f), std::clamp(color.g, 0.0f, 1.0f), std::clamp(color.b, 0.0f, 1.0f),
                         std::clamp(color.a, 0.0f, 1.0f)};
        soup.materials.push_back(out);
    }
    for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
        const aiMesh* mesh = scene->mMeshes[k];
        if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const uint32_t base = uint32_t(soup.positions.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v)
            soup.positions.push_back({double(mesh->mVertices[v].x), double(mesh->mVertices[v].y), double(mesh->mVertices[v].z)});
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;
            const std::array<uint32_t, 3> t{base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]};
            const auto& a = soup.positions[t[0]];
            const auto& b = soup.positions[t[1]];
            const auto& c = soup.positions[t[2]];
            bool finite = true;
            for (const auto* p : {&a, &b, &c})
                for (double x : *p) finite = finite && std::isfinite(x);
            const std::array<double, 3> u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const double nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2], nz = u[0] * w[1] - u[1] * w[0];
            if (!finite || !(nx * nx + ny * ny + nz * nz > 0.0)) {
                ++soup.droppedTriangles;
                continue;
            }
            soup.triangles.push_back(t);
            soup.triangleMaterials.push_back(mesh->mMaterialIndex < soup.materials.size() ? mesh->mMaterialIndex : 0);
        }
    }
    if (soup.materials.empty()) soup.materials.push_back({});
    if (soup.triangles.empty()) throw MeshImportError("'" + path + "' holds no triangle");
    return soup;
}

} // namespace vdbclay
