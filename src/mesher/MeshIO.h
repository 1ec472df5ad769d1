// Mesh export: Wavefront OBJ (with per-vertex colours as the common "v x y z r g b" extension) and
// binary little-endian PLY (positions, normals, RGBA colours). Written atomically like volumes.
#pragma once

#include "mesher/Mesh.h"
#include "vdb_hermite/Materials.h"

#include <stdexcept>
#include <string>

namespace vdbclay {

class MeshIOError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Picks the format from the extension (.obj or .ply); throws MeshIOError otherwise.
void writeMesh(const Mesh& mesh, const MaterialTable& materials, const std::string& path);

} // namespace vdbclay
