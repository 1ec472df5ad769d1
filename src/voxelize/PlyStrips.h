// PLY files that store their surface as triangle strips (element "tristrips", as scanned models saved by
// older tools do: Cyberware's igea.ply among them). Debian's Assimp 5.2 reads such strips as loose
// vertices, so they are read here; every other PLY goes to Assimp. Internal to src/voxelize.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <optional>
#include <string>

namespace vdbclay {

/// Nothing when `path` is not a PLY file with a non-empty tristrips element; else its triangles: each
/// strip's consecutive corners, -1 restarting the strip, every other triangle's corners swapped so the
/// strip keeps one winding; triangles on a repeated corner (a strip's stitches) are left out. Faces of a
/// "face" element in the same file are read too. ASCII and both binary forms. Throws MeshImportError
/// for a damaged file.
std::optional<TriangleSoup> readPlyTriangleStrips(const std::string& path);

} // namespace vdbclay
