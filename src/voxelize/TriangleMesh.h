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
    /// Materials made from vertex colours ("colour-rrggbb"): a triangle with coloured corners and an
    /// unnamed material takes the colour two of its corners share, else its first corner's. Binned: the colours
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

/// What one reading of a mesh file may take before it is stopped: a parser stuck in a loop, or one
/// that believes a damaged file's counts and allocates without end, costs this much and no more.
struct MeshReadLimits {
    std::chrono::seconds time{20};
    /// Address space the reader may map beyond what the process maps already.
    uint64_t memoryBytes = uint64_t(4) << 30;
};

/// Whether MeshReadLimits::memoryBytes is enforced: not in builds with AddressSanitizer, whose shadow
/// memory alone maps terabytes.
bool meshReadMemoryIsCapped();

/// The limits for a file of this size: 20 s plus a second per MB (Assimp reads tens of MB a second),
/// and 4 GiB or 64 bytes per byte of the file, whichever is more.
MeshReadLimits meshReadLimits(const std::string& path);

/// Reads a mesh file (its whole scene, node transforms applied, polygons triangulated, points and lines
/// dropped). Throws MeshImportError when Assimp cannot read it, it holds no triangle, or reading it
/// passes `limits`.
TriangleSoup loadTriangleMesh(const std::string& path, const MeshReadLimits& limits);
TriangleSoup loadTriangleMesh(const std::string& path); // with meshReadLimits(path)

/// The program loadTriangleMesh runs to read a file (installed beside vdbclay; VDBCLAY_MESH_READER names
/// another). Without it, or with VDBCLAY_MESH_READER=fork (a process of one thread, such as a fuzzer,
/// forks safely and faster), the reading runs in a fork of this process.
constexpr const char* kMeshReaderProgram = "vdbclay-read-mesh";
/// That program's main: `PROGRAM PATH MEMORY_BYTES` reads PATH and answers on stdout.
int meshReaderMain(int argc, char** argv);

/// loadTriangleMesh's isolation, open to tests: runs `read` in a child process and returns the soup it
/// made, sent back through a pipe. A MeshImportError it throws comes back as one printable line; a
/// crash, an early exit, running out of its memory or no answer within the time limit (the child is
/// then killed) becomes a MeshImportError naming `path`.
TriangleSoup readInChildProcess(const std::string& path, const std::function<TriangleSoup()>& read, const MeshReadLimits& limits);

} // namespace vdbclay
