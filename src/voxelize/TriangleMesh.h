// Meshes made elsewhere (scanners, CAD, DCC tools), read with Assimp into one triangle soup in world
// units, with the materials the file names or its vertex colours.
//
// Light header: no Assimp types.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay {

struct MeshMaterial {
    std::string name;
    std::array<float, 4> color{0.8f, 0.8f, 0.8f, 1.0f};
};

struct TriangleSoup {
    std::vector<std::array<double, 3>> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<uint32_t> triangleMaterials; // index into materials, per triangle
    std::vector<MeshMaterial> materials;
    uint64_t droppedTriangles = 0; // of zero area, or with a corner that is not a finite number
    /// Materials made from vertex colours ("colour-rrggbb"): a triangle with coloured corners takes the
    /// colour two of them share, else its first corner's, over its mesh's material. Binned: the colours
    /// were too many and were rounded to 4 levels per channel.
    std::size_t colourMaterials = 0;
    bool colourBinned = false;
};

/// Every failure to read a mesh file; what() is one line meant for the user.
class MeshImportError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The extensions `vdbclay import` reads as meshes: obj ply stl off gltf glb fbx dae.
bool isMeshPath(const std::string& path);

/// Reads a mesh file (its whole scene, node transforms applied, polygons triangulated, points and lines
/// dropped). Throws MeshImportError when Assimp cannot read it or it holds no triangle.
TriangleSoup loadTriangleMesh(const std::string& path);

/// loadTriangleMesh's isolation, open to tests: runs `read` in a child process and returns the soup it
/// made, sent back through a pipe. A MeshImportError it throws comes back as one printable line; a
/// crash, an early exit or no answer within `limit` (the child is then killed) becomes a
/// MeshImportError naming `path`.
TriangleSoup readInChildProcess(const std::string& path, const std::function<TriangleSoup()>& read, std::chrono::seconds limit);

} // namespace vdbclay
