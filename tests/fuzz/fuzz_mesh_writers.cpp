// The OBJ, PLY and glTF writers on meshes built from arbitrary bytes (any counts, indices, NaNs and
// material ids): a mesh is written, or refused by validateMesh with a MeshIOError.
#include "mesher/MeshIO.h"

#include <cstdint>
#include <cstring>
#include <sstream>

namespace {

class Bytes {
public:
    Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
    template<typename T>
    T take()
    {
        T v{};
        const size_t n = std::min(sizeof(T), size_ - at_);
        std::memcpy(&v, data_ + at_, n);
        at_ += n;
        return v;
    }
    bool empty() const { return at_ >= size_; }

private:
    const uint8_t* data_;
    size_t size_, at_ = 0;
};

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    Bytes in(data, size);
    vdbclay::Mesh mesh;
    const unsigned vertices = in.take<uint8_t>() % 64, triangles = in.take<uint8_t>() % 96;
    const uint8_t shape = in.take<uint8_t>(); // which per-vertex and per-triangle arrays are complete
    for (unsigned v = 0; v < vertices; ++v) {
        mesh.positions.push_back({in.take<float>(), in.take<float>(), in.take<float>()});
        if (!(shape & 1) || v + 1 < vertices) mesh.normals.push_back({in.take<float>(), in.take<float>(), in.take<float>()});
        if (!(shape & 2) || v + 1 < vertices) mesh.materials.push_back(in.take<uint16_t>());
    }
    for (unsigned t = 0; t < triangles; ++t) {
        mesh.triangles.push_back({in.take<uint8_t>(), in.take<uint8_t>(), in.take<uint8_t>()});
        if (shape & 4) mesh.triangleMaterials.push_back(in.take<uint16_t>());
    }
    vdbclay::MaterialTable materials;
    if (shape & 8) materials.define(vdbclay::Material{"stone", {0.5f, 0.4f, 0.3f, 1.0f}, 0.5f, {}});
    for (vdbclay::MeshFormat format : {vdbclay::MeshFormat::Obj, vdbclay::MeshFormat::Ply, vdbclay::MeshFormat::Glb}) {
        std::ostringstream out;
        try {
            vdbclay::writeMesh(mesh, materials, format, out);
        } catch (const vdbclay::MeshIOError&) {
        }
    }
    return 0;
}
