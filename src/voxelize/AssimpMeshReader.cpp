#include "voxelize/AssimpMeshReader.h"

#include "vdb_hermite/PrintableText.h"
#include "voxelize/MeshHeaderCheck.h"
#include "voxelize/PlyStrips.h"

#include <optional>

#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

// Debian builds Assimp with its internal assertions on (ASSIMP_BUILD_DEBUG): a malformed file that
// trips one (an OFF whose face counts lie, found by fuzz_mesh_import) would abort the whole process.
// Defining the violation handler here replaces the library's (symbol interposition, as for malloc):
// it throws instead, Importer::ReadFile catches that like any import failure and returns no scene, and
// loadTriangleMesh reports it as a file that cannot be read.
namespace Assimp {
void aiAssertViolation(const char* failedExpression, const char* /*file*/, int /*line*/)
{
    throw std::runtime_error(std::string("the file trips Assimp's check '") + failedExpression + "'");
}
} // namespace Assimp

namespace vdbclay {

namespace {

/// Files as Assimp opens them, but only the model itself and files inside its folder: a glTF may name
/// its buffers and images by any path ("/etc/passwd", "../../secret"), and a model from elsewhere must
/// not make the importer read the user's other files. Links are followed before the check.
class ModelFolderIOSystem : public Assimp::DefaultIOSystem {
public:
    explicit ModelFolderIOSystem(const std::string& model)
    {
        namespace fs = std::filesystem;
        std::error_code ec;
        model_ = fs::weakly_canonical(model, ec);
        folder_ = model_.parent_path();
    }
    bool Exists(const char* file) const override { return allowed(file) && Assimp::DefaultIOSystem::Exists(file); }
    Assimp::IOStream* Open(const char* file, const char* mode = "rb") override
    {
        return allowed(file) ? Assimp::DefaultIOSystem::Open(file, mode) : nullptr;
    }

private:
    bool allowed(const char* file) const
    {
        namespace fs = std::filesystem;
        std::error_code ec;
        const fs::path resolved = fs::weakly_canonical(file, ec);
        if (ec || folder_.empty()) return false;
        if (resolved == model_) return true;
        const fs::path relative = resolved.lexically_relative(folder_);
        return !relative.empty() && *relative.begin() != ".." && !relative.is_absolute();
    }

    std::filesystem::path model_, folder_;
};

/// Few distinct vertex colours (a painted model, VDBClay's own PLY) each become a material; more (a
/// colour scan) are binned on a palette of 4 levels per channel, so the table stays small.
constexpr std::size_t kMaxExactColours = 64;

uint32_t packColour(const aiColor4D& c)
{
    auto byte = [](float v) { return uint32_t(std::lround(std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) * 255.0f)); };
    return byte(c.r) << 16 | byte(c.g) << 8 | byte(c.b);
}

/// The colour of a triangle: the one at least two of its corners share, else its first corner's.
uint32_t triangleColour(const aiMesh& mesh, const aiFace& face)
{
    const uint32_t a = packColour(mesh.mColors[0][face.mIndices[0]]), b = packColour(mesh.mColors[0][face.mIndices[1]]),
                   c = packColour(mesh.mColors[0][face.mIndices[2]]);
    return (b == c && a != b) ? b : a;
}

uint32_t binColour(uint32_t rgb)
{
    uint32_t out = 0;
    for (int shift : {16, 8, 0}) out |= ((((rgb >> shift) & 0xffu) + 42u) / 85u * 85u) << shift;
    return out;
}

/// Appends a material per colour of the coloured triangles and points them at it.
void coloursToMaterials(TriangleSoup& soup, const std::vector<std::pair<std::size_t, uint32_t>>& coloured)
{
    std::map<uint32_t, uint32_t> material;
    for (const auto& [triangle, rgb] : coloured) material.emplace(rgb, 0);
    const bool binned = material.size() > kMaxExactColours;
    if (binned) {
        material.clear();
        for (const auto& [triangle, rgb] : coloured) material.emplace(binColour(rgb), 0);
    }
    for (auto& [rgb, index] : material) {
        index = uint32_t(soup.materials.size());
        char name[16];
        std::snprintf(name, sizeof name, "colour-%06x", rgb);
        soup.materials.push_back({name, {float(rgb >> 16) / 255.0f, float((rgb >> 8) & 0xffu) / 255.0f, float(rgb & 0xffu) / 255.0f, 1.0f}});
    }
    for (const auto& [triangle, rgb] : coloured) soup.triangleMaterials[triangle] = material.at(binned ? binColour(rgb) : rgb);
    soup.colourMaterials = material.size();
    soup.colourBinned = binned;
}

} // namespace

TriangleSoup readMeshWithAssimp(const std::string& path)
{
    refuseImplausibleMeshHeader(path);
    if (std::optional<TriangleSoup> strips = readPlyTriangleStrips(path)) return std::move(*strips);
    Assimp::Importer importer;
    importer.SetIOHandler(new ModelFolderIOSystem(path)); // the importer owns it
    // Points and lines are no surface. No normals are asked for: the voxelizer takes each triangle's own.
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_PreTransformVertices);
    // Assimp turns every exception into an error string; running out of memory is told apart (the
    // child's memory cap, loadTriangleMesh) so the user learns it was not a syntax error.
    if (!scene && std::string(importer.GetErrorString()).find("bad_alloc") != std::string::npos) throw std::bad_alloc();
    if (!scene) throw MeshImportError("'" + path + "' cannot be read as a mesh: " + printableText(importer.GetErrorString(), 200));
    // Vertices shared by position save memory (an STL repeats each corner per triangle), but Assimp's
    // join ignores vertex colours: it would give a corner where two colours meet only one of them.
    bool vertexColours = false;
    for (unsigned k = 0; k < scene->mNumMeshes; ++k) vertexColours = vertexColours || scene->mMeshes[k]->HasVertexColors(0);
    if (!vertexColours) scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
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
    std::vector<std::pair<std::size_t, uint32_t>> coloured; // triangle, colour: for meshes with vertex colours
    for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
        const aiMesh* mesh = scene->mMeshes[k];
        if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const uint32_t base = uint32_t(soup.positions.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v)
            soup.positions.push_back({double(mesh->mVertices[v].x), double(mesh->mVertices[v].y), double(mesh->mVertices[v].z)});
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;
            if (face.mIndices[0] >= mesh->mNumVertices || face.mIndices[1] >= mesh->mNumVertices ||
                face.mIndices[2] >= mesh->mNumVertices) { // a damaged file's index
                ++soup.droppedTriangles;
                continue;
            }
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
            const uint32_t material = mesh->mMaterialIndex < soup.materials.size() ? mesh->mMaterialIndex : 0;
            // A named material says more than colours painted over it (VDBClay's own OBJ has both).
            if (mesh->HasVertexColors(0) && (material >= soup.materials.size() || soup.materials[material].name.empty()))
                coloured.emplace_back(soup.triangles.size(), triangleColour(*mesh, face));
            soup.triangles.push_back(t);
            soup.triangleMaterials.push_back(material);
        }
    }
    if (soup.materials.empty()) soup.materials.push_back({});
    if (!coloured.empty()) coloursToMaterials(soup, coloured);
    if (soup.triangles.empty() && soup.droppedTriangles > 0)
        throw MeshImportError("'" + path + "' holds " + std::to_string(soup.droppedTriangles) +
                              " triangles and none encloses an area: their corners coincide once read in single precision "
                              "(as the importer reads them; move the model near the origin or scale it up), or are not finite numbers");
    if (soup.triangles.empty()) throw MeshImportError("'" + path + "' holds no triangle");
    return soup;
}

} // namespace vdbclay
