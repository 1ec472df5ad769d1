// Mesh properties the tests and the CLI report: closedness and enclosed volume.
#pragma once

#include "mesher/Mesh.h"

#include <cstddef>

namespace vdbclay {

struct MeshTopology {
    std::size_t boundaryEdges = 0;     // edges used by one triangle only
    std::size_t nonManifoldEdges = 0;  // edges used by more than two triangles
    std::size_t misorientedEdges = 0;  // edges whose two triangles traverse them the same way
    std::size_t degenerateTriangles = 0; // triangles that repeat a vertex index
    /// Every edge is shared by exactly two triangles that traverse it in opposite directions.
    bool watertight() const { return boundaryEdges == 0 && nonManifoldEdges == 0 && misorientedEdges == 0; }
};

MeshTopology analyzeTopology(const Mesh& mesh);

/// Signed volume enclosed by a closed, outward-oriented mesh (divergence theorem), world units cubed.
double enclosedVolume(const Mesh& mesh);

} // namespace vdbclay
