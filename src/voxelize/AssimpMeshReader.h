// Reading a mesh file with Assimp, in the calling process. Internal to src/voxelize: everything else
// calls loadTriangleMesh (TriangleMesh.h), which runs this in a child process, because Debian's Assimp
// can crash or hang on a damaged file.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <string>

namespace vdbclay {

/// Throws MeshImportError when Assimp cannot read the file or it holds no triangle.
TriangleSoup readMeshWithAssimp(const std::string& path);

} // namespace vdbclay
