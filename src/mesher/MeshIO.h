// Mesh export: Wavefront OBJ (with per-vertex colours as the common "v x y z r g b" extension, and
// written to a path, its materials' names and colours in an MTL file of the same stem beside it),
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

enum class MeshFormat { Obj, Ply, Glb };

/// The format named by a path's extension (.obj, .ply or .glb, any case); throws MeshIOError otherwise.
MeshFormat meshFormatOf(const std::string& path);

/// Throws MeshIOError unless the mesh can be written: one normal and one material per vertex, triangle
/// corners that name vertices, per-triangle materials for all triangles or none, finite positions.
void validateMesh(const Mesh& mesh);

/// Picks the format from the extension; validates the mesh first; the file is replaced atomically. An
/// OBJ gets its materials file (the same path ending in .mtl) beside it, written first.
void writeMesh(const Mesh& mesh, const MaterialTable& materials, const std::string& path);
/// Writes a validated mesh to a stream (an OBJ without materials file: no mtllib, no usemtl).
void writeMesh(const Mesh& mesh, const MaterialTable& materials, MeshFormat format, std::ostream& out);

} // namespace vdbclay
