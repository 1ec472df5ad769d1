// Where materials meet, a vertex shows a blend of them rather than its own alone: a soft paint stroke's
// stipple of voxels reads as a gradient, a hard edge as one a voxel or two wide, not a staircase.
#pragma once

#include "mesher/Mesh.h"
#include "vdb_hermite/Volume.h"

#include <cstdint>
#include <vector>

namespace vdbclay {

/// A vertex's blend: the solid material beside its own that weighs most around it (bits 0-15; 0: none),
/// and that material's share of the two (bits 16-23, 0..255 for 0..1).
struct MaterialBlend {
    static uint32_t pack(MaterialId other, double share);
    static MaterialId other(uint32_t packed) { return MaterialId(packed & 0xffffu); }
    static double share(uint32_t packed) { return double((packed >> 16) & 0xffu) / 255.0; }
};

/// Per vertex (from `firstVertex` on), its blend, weighed over the solid voxels of the 5^3 lattice points
/// nearest to it with a disc-shaped tent reaching 2.5 voxels along the surface (wide enough to read a soft
/// paint stroke's one-voxel stipple as its coverage) and one across it (so material beneath the surface,
/// or on the far side of a crease, does not show), then mapped linearly so that a trace (under 15%) counts
/// as none and over 85% as all;
/// a vertex whose nearest 3^3 hold no other material has none. The vertex's own material is
/// mesh.materials[v]. `mesh` is in the volume's world units.
std::vector<uint32_t> vertexMaterialBlend(const Volume& volume, const Mesh& mesh, std::size_t firstVertex = 0);

} // namespace vdbclay
