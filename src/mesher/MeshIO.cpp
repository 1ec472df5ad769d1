#include "mesher/MeshIO.h"

#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/FileExtension.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

std::array<float, 4> materialColor(const MaterialTable& materials, MaterialId id)
{
    return id != kEmptyMaterial && id <= materials.size() ? materials.at(id).color : std::array<float, 4>{0.8f, 0.8f, 0.8f, 1.0f};
}

std::array<uint8_t, 4> colorOf(const MaterialTable& materials, MaterialId id)
{
    const std::array<float, 4> c = materialColor(materials, id);
    std::array<uint8_t, 4> out{};
    for (int i = 0; i < 4; ++i) out[i] = uint8_t(std::lround(std::clamp(c[i], 0.0f, 1.0f) * 255.0f));
    return out;
}

/// Triangle indices per material: each triangle's own material, or its first vertex's for meshes
/// without per-triangle materials.
std::map<MaterialId, std::vector<uint32_t>> trianglesByMaterial(const Mesh& mesh)
{
    std::map<MaterialId, std::vector<uint32_t>> groups;
    const bool perTriangle = mesh.triangleMaterials.size() == mesh.triangles.size();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const uint32_t v0 = mesh.triangles[t][0];
        const MaterialId id = perTriangle ? mesh.triangleMaterials[t]
                                          : (v0 < mesh.materials.size() ? mesh.materials[v0] : kEmptyMaterial);
        groups[id].push_back(uint32_t(t));
    }
    return groups;
}

/// A material's name as an MTL statement takes it: one word (blanks become '_'), unique within the
/// file (a clash after that gets its id appended), "default" for an id the table does not know.
std::map<MaterialId, std::string> mtlNames(const std::map<MaterialId, std::vector<uint32_t>>& groups, const MaterialTable& materials)
{
    std::map<MaterialId, std::string> names;
    std::set<std::string> taken;
    for (const auto& group : groups) {
        const MaterialId id = group.first;
        std::string name = id != kEmptyMaterial && id <= materials.size() ? materials.at(id).name : "default";
        for (char& c : name)
            if (std::isspace(static_cast<unsigned char>(c))) c = '_';
        if (name.empty() || !taken.insert(name).second) {
            name += "_" + std::to_string(id);
            taken.insert(name);
        }
        names[id] = name;
    }
    return names;
}

void writeMtl(std::ostream& os, const std::map<MaterialId, std::string>& names, const MaterialTable& materials)
{
    os << "# VDBClay materials\n";
    char line[128];
    for (const auto& [id, name] : names) {
        const auto c = materialColor(materials, id);
        std::snprintf(line, sizeof(line), "Kd %.4g %.4g %.4g\nd %.4g\n", c[0], c[1], c[2], c[3]);
        os << "newmtl " << name << "\n" << line;
    }
}

/// OBJ with per-vertex colours (the common "v x y z r g b" extension). With `mtlFile`, the faces come
/// in runs per material, each after "usemtl NAME" of the materials `mtlFile` defines.
void writeObj(std::ostream& os, const Mesh& mesh, const MaterialTable& materials, const std::string& mtlFile)
{
    os << "# VDBClay mesh: " << mesh.vertexCount() << " vertices, " << mesh.triangleCount() << " triangles\n";
    if (!mtlFile.empty()) os << "mtllib " << mtlFile << "\n";
    char line[160];
    for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
        const auto& p = mesh.positions[v];
        const auto c = colorOf(materials, mesh.materials[v]);
        std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g %.4g %.4g %.4g\n", p[0], p[1], p[2], c[0] / 255.0,
                      c[1] / 255.0, c[2] / 255.0);
        os << line;
    }
    for (const auto& n : mesh.normals) {
        std::snprintf(line, sizeof(line), "vn %.5g %.5g %.5g\n", n[0], n[1], n[2]);
        os << line;
    }
    auto face = [&](const std::array<uint32_t, 3>& t) {
        std::snprintf(line, sizeof(line), "f %u//%u %u//%u %u//%u\n", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1,
                      t[2] + 1, t[2] + 1);
        os << line;
    };
    if (mtlFile.empty()) {
        for (const auto& t : mesh.triangles) face(t);
        return;
    }
    const auto groups = trianglesByMaterial(mesh);
    const auto names = mtlNames(groups, materials);
    for (const auto& [id, triangles] : groups) {
        os << "usemtl " << names.at(id) << "\n";
        for (uint32_t t : triangles) face(mesh.triangles[t]);
    }
}

void writePly(std::ostream& os, const Mesh& mesh, const MaterialTable& materials)
{
    os << "ply\nformat binary_little_endian 1.0\ncomment VDBClay mesh\n"
       << "element vertex " << mesh.vertexCount() << "\n"
       << "property float x\nproperty float y\nproperty float z\n"
       << "property float nx\nproperty float ny\nproperty float nz\n"
       << "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
       << "element face " << mesh.triangleCount() << "\n"
       << "property list uchar uint vertex_indices\nend_header\n";
    static_assert(sizeof(float) == 4, "PLY floats are 32-bit");
    for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
        os.write(reinterpret_cast<const char*>(mesh.positions[v].data()), 12);
        os.write(reinterpret_cast<const char*>(mesh.normals[v].data()), 12);
        const auto c = colorOf(materials, mesh.materials[v]);
        os.write(reinterpret_cast<const char*>(c.data()), 4);
    }
    for (const auto& t : mesh.triangles) {
        const uint8_t three = 3;
        os.write(reinterpret_cast<const char*>(&three), 1);
        os.write(reinterpret_cast<const char*>(t.data()), 12);
    }
}

/// glTF 2.0 binary: one mesh with one primitive per material (each triangle's material, or the material
/// of its first vertex for meshes without per-triangle materials), each with its own compacted
/// POSITION, NORMAL and uint32 index accessors.
void writeGlb(std::ostream& os, const Mesh& mesh, const MaterialTable& materials)
{
    using nlohmann::json;
    static_assert(sizeof(float) == 4 && sizeof(uint32_t) == 4, "glTF components are 32-bit");
    constexpr uint32_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
    constexpr uint32_t kFloat = 5126, kUnsignedInt = 5125;

    const std::map<MaterialId, std::vector<uint32_t>> groups = trianglesByMaterial(mesh);
    std::vector<char> bin;
    auto append = [&bin](const void* data, std::size_t bytes) {
        const char* c = static_cast<const char*>(data);
        bin.insert(bin.end(), c, c + bytes);
    };
    json doc;
    doc["asset"] = {{"version", "2.0"}, {"generator", "VDBClay"}};
    json bufferViews = json::array(), accessors = json::array(), primitives = json::array(),
         gltfMaterials = json::array();
    auto addView = [&](std::size_t offset, std::size_t bytes, uint32_t target) {
        bufferViews.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}});
        return bufferViews.size() - 1;
    };

    for (const auto& [id, tris] : groups) {
        // Compact the vertices this primitive uses.
        std::vector<uint32_t> remap(mesh.positions.size(), std::numeric_limits<uint32_t>::max());
        std::vector<uint32_t> vertices, indices;
        indices.reserve(tris.size() * 3);
        for (uint32_t t : tris)
            for (uint32_t v : mesh.triangles[t]) {
                if (remap[v] == std::numeric_limits<uint32_t>::max()) {
                    remap[v] = uint32_t(vertices.size());
                    vertices.push_back(v);
                }
                indices.push_back(remap[v]);
            }
        std::array<float, 3> lo{}, hi{};
        lo.fill(std::numeric_limits<float>::infinity());
        hi.fill(-std::numeric_limits<float>::infinity());
        const std::size_t posOffset = bin.size();
        for (uint32_t v : vertices) {
            const auto& p = mesh.positions[v];
            for (int i = 0; i < 3; ++i) {
                lo[i] = std::min(lo[i], p[i]);
                hi[i] = std::max(hi[i], p[i]);
            }
            append(p.data(), 12);
        }
        json attributes;
        accessors.push_back({{"bufferView", addView(posOffset, bin.size() - posOffset, kArrayBuffer)},
                             {"componentType", kFloat},
                             {"count", vertices.size()},
                             {"type", "VEC3"},
                             {"min", {lo[0], lo[1], lo[2]}},
                             {"max", {hi[0], hi[1], hi[2]}}});
        attributes["POSITION"] = accessors.size() - 1;
        const std::size_t nOffset = bin.size();
        for (uint32_t v : vertices) {
            std::array<float, 3> n = mesh.normals[v];
            const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (len > 0.0f && std::isfinite(len)) {
                for (float& c : n) c /= len;
            } else {
                n = {0.0f, 0.0f, 1.0f}; // glTF requires unit normals
            }
            append(n.data(), 12);
        }
        accessors.push_back({{"bufferView", addView(nOffset, bin.size() - nOffset, kArrayBuffer)},
                             {"componentType", kFloat},
                             {"count", vertices.size()},
                             {"type", "VEC3"}});
        attributes["NORMAL"] = accessors.size() - 1;
        const std::size_t iOffset = bin.size();
        append(indices.data(), indices.size() * 4);
        accessors.push_back({{"bufferView", addView(iOffset, bin.size() - iOffset, kElementArrayBuffer)},
                             {"componentType", kUnsignedInt},
                             {"count", indices.size()},
                             {"type", "SCALAR"}});
        const std::size_t indexAccessor = accessors.size() - 1;

        std::array<float, 4> color{0.8f, 0.8f, 0.8f, 1.0f};
        std::string name = "material " + std::to_string(id);
        if (id != kEmptyMaterial && id <= materials.size()) {
            color = materials.at(id).color;
            name = materials.at(id).name;
        }
        for (float& c : color) c = std::clamp(c, 0.0f, 1.0f);
        gltfMaterials.push_back({{"name", name},
                                 {"pbrMetallicRoughness",
                                  {{"baseColorFactor", {color[0], color[1], color[2], color[3]}},
                                   {"metallicFactor", 0.0},
                                   {"roughnessFactor", 0.8}}}});
        primitives.push_back({{"attributes", attributes},
                              {"indices", indexAccessor},
                              {"material", gltfMaterials.size() - 1},
                              {"mode", 4}});
    }
    if (!primitives.empty()) {
        doc["buffers"] = json::array({{{"byteLength", bin.size()}}});
        doc["bufferViews"] = bufferViews;
        doc["accessors"] = accessors;
        doc["materials"] = gltfMaterials;
        doc["meshes"] = json::array({{{"name", "VDBClay mesh"}, {"primitives", primitives}}});
        doc["nodes"] = json::array({{{"mesh", 0}, {"name", "VDBClay mesh"}}});
        doc["scenes"] = json::array({{{"nodes", {0}}}});
        doc["scene"] = 0;
    }

    std::string text = doc.dump();
    while (text.size() % 4) text.push_back(' ');
    while (bin.size() % 4) bin.push_back('\0');
    const bool withBin = !bin.empty();
    const uint64_t total = 12 + 8 + text.size() + (withBin ? 8 + bin.size() : 0);
    if (total > std::numeric_limits<uint32_t>::max()) throw MeshIOError("mesh too large for a GLB file (4 GiB)");
    auto put32 = [&os](uint32_t v) {
        const unsigned char b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
        os.write(reinterpret_cast<const char*>(b), 4);
    };
    put32(0x46546C67u); // "glTF"
    put32(2);
    put32(uint32_t(total));
    put32(uint32_t(text.size()));
    put32(0x4E4F534Au); // "JSON"
    os.write(text.data(), std::streamsize(text.size()));
    if (withBin) {
        put32(uint32_t(bin.size()));
        put32(0x004E4942u); // "BIN\0"
        os.write(bin.data(), std::streamsize(bin.size()));
    }
}

} // namespace

MeshFormat meshFormatOf(const std::string& path)
{
    const std::string ext = lowerCaseExtension(path);
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".ply") return MeshFormat::Ply;
    if (ext == ".glb") return MeshFormat::Glb;
    throw MeshIOError("cannot tell the mesh format of '" + path + "': use a .obj, .ply or .glb file name");
}

void validateMesh(const Mesh& mesh)
{
    const std::size_t n = mesh.positions.size();
    if (mesh.normals.size() != n || mesh.materials.size() != n)
        throw MeshIOError("the mesh has " + std::to_string(mesh.normals.size()) + " normals and " +
                          std::to_string(mesh.materials.size()) + " materials for " + std::to_string(n) + " vertices");
    if (!mesh.triangleMaterials.empty() && mesh.triangleMaterials.size() != mesh.triangles.size())
        throw MeshIOError("the mesh has " + std::to_string(mesh.triangleMaterials.size()) + " triangle materials for " +
                          std::to_string(mesh.triangles.size()) + " triangles");
    if (n > std::numeric_limits<uint32_t>::max()) throw MeshIOError("the mesh has more vertices than 32-bit indices reach");
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (uint32_t v : mesh.triangles[t])
            if (v >= n) throw MeshIOError("triangle " + std::to_string(t) + " names vertex " + std::to_string(v) + " of " + std::to_string(n));
    for (std::size_t v = 0; v < n; ++v)
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(mesh.positions[v][a]) || !std::isfinite(mesh.normals[v][a]))
                throw MeshIOError("vertex " + std::to_string(v) + " has a position or normal that is not a finite number");
}

void writeMesh(const Mesh& mesh, const MaterialTable& materials, MeshFormat format, std::ostream& out)
{
    validateMesh(mesh);
    switch (format) {
    case MeshFormat::Obj: writeObj(out, mesh, materials, ""); break;
    case MeshFormat::Ply: writePly(out, mesh, materials); break;
    case MeshFormat::Glb: writeGlb(out, mesh, materials); break;
    }
}

void writeMesh(const Mesh& mesh, const MaterialTable& materials, const std::string& path)
{
    const MeshFormat format = meshFormatOf(path);
    try {
        validateMesh(mesh);
    } catch (const MeshIOError& e) {
        throw MeshIOError("cannot write '" + path + "': " + e.what());
    }
    try {
        if (format == MeshFormat::Obj) {
            // The materials file first: the OBJ never names one that is not there.
            const fs::path mtl = fs::path(path).replace_extension(".mtl");
            const auto names = mtlNames(trianglesByMaterial(mesh), materials);
            writeFileAtomically(mtl.string(), [&](std::ostream& os) { writeMtl(os, names, materials); });
            writeFileAtomically(path, [&](std::ostream& os) { writeObj(os, mesh, materials, mtl.filename().string()); });
        } else {
            writeFileAtomically(path, [&](std::ostream& os) { writeMesh(mesh, materials, format, os); });
        }
    } catch (const FileWriteError& e) {
        throw MeshIOError(e.what());
    }
}

} // namespace vdbclay
