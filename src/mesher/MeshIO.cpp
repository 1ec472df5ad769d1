#include "mesher/MeshIO.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

std::array<uint8_t, 4> colorOf(const MaterialTable& materials, MaterialId id)
{
    std::array<float, 4> c{0.8f, 0.8f, 0.8f, 1.0f};
    if (id != kEmptyMaterial && id <= materials.size()) c = materials.at(id).color;
    std::array<uint8_t, 4> out{};
    for (int i = 0; i < 4; ++i) out[i] = uint8_t(std::lround(std::clamp(c[i], 0.0f, 1.0f) * 255.0f));
    return out;
}

void writeObj(std::ostream& os, const Mesh& mesh, const MaterialTable& materials)
{
    os << "# VDBClay mesh: " << mesh.vertexCount() << " vertices, " << mesh.triangleCount() << " triangles\n";
    char line[160];
    for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
        const auto& p = mesh.positions[v];
        const auto c = colorOf(materials, mesh.materials[v]);
        std::snprintf(line, sizeof(line), "v %.6g %.6g %.6g %.4g %.4g %.4g\n", p[0], p[1], p[2], c[0] / 255.0,
                      c[1] / 255.0, c[2] / 255.0);
        os << line;
    }
    for (const auto& n : mesh.normals) {
        std::snprintf(line, sizeof(line), "vn %.5g %.5g %.5g\n", n[0], n[1], n[2]);
        os << line;
    }
    for (const auto& t : mesh.triangles) {
        std::snprintf(line, sizeof(line), "f %u//%u %u//%u %u//%u\n", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1,
                      t[2] + 1, t[2] + 1);
        os << line;
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

} // namespace

void writeMesh(const Mesh& mesh, const MaterialTable& materials, const std::string& path)
{
    const fs::path target(path);
    std::string ext = target.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".obj" && ext != ".ply")
        throw MeshIOError("cannot tell the mesh format of '" + path + "': use a .obj or .ply file name");
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(dir)) throw MeshIOError("directory '" + dir.string() + "' does not exist");
    if (fs::is_directory(target)) throw MeshIOError("'" + path + "' is a directory");

    const fs::path temp = dir / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()));
    {
        std::ofstream os(temp, std::ios::binary | std::ios::trunc);
        if (!os) throw MeshIOError("cannot create '" + temp.string() + "': " + std::strerror(errno));
        if (ext == ".obj") writeObj(os, mesh, materials);
        else writePly(os, mesh, materials);
        os.flush();
        if (!os) {
            std::error_code ec;
            fs::remove(temp, ec);
            throw MeshIOError("cannot write '" + path + "' (disk full?)");
        }
    }
    std::error_code ec;
    fs::rename(temp, target, ec);
    if (ec) {
        fs::remove(temp, ec);
        throw MeshIOError("cannot replace '" + path + "': " + ec.message());
    }
}

} // namespace vdbclay
