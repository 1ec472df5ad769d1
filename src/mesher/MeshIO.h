// Mesh export: Wavefront OBJ (with per-vertex colours as the common "v x y z r g b" extension),
// binary little-endian PLY (positions, normals, RGBA colours) and binary glTF 2.0 (.glb: one mesh with
// one primitive per material, grouped by the material of each triangle's first vertex; each primitive
// has POSITION with min/max, NORMAL and uint32 indices, and a material whose baseColorFactor and name
// come from the MaterialTable). Written atomically like volumes.
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

/// Picks the format from the extension (.obj, .ply or .glb, any case); throws MeshIOError otherwise.
void writeMesh(const Mesh& mesh, const MaterialTable& materials, const std::string& path);

} // namespace vdbclay
