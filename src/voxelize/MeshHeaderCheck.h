// Checks of a mesh file's header made before Assimp reads it. Debian's Assimp 5.2 believes the element
// counts a PLY or OFF header states: a 100-byte file claiming a billion vertices makes it allocate
// gigabytes and loop for a minute, and a PLY header without end_header makes it loop forever (both
// found by fuzz_mesh_import). A header whose counts cannot fit in the bytes that follow it is refused.
// Internal to src/voxelize.
#pragma once

#include <string>

namespace vdbclay {

/// Throws MeshImportError naming the count and the bytes when a PLY file (content starting "ply") or an
/// OFF file (extension .off) states more elements than its size can hold, or a PLY header never ends.
/// Other files, and headers it cannot parse (left to Assimp's own errors), pass.
void refuseImplausibleMeshHeader(const std::string& path);

} // namespace vdbclay
