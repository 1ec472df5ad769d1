// How Cubical Marching Squares closes a loop of boundary vertices in a cell: a fan from one inner
// vertex (the loop's sharp feature or its mean point), moved where its triangles would fold back against
// the surface, or the loop triangulated without one. It works on the mesh of the chunk being built, whose
// vertices carry the crossings' normals.
#pragma once

#include "mesher/Mesh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace vdbclay {

/// A cell's place in world units: its lowest corner and width.
struct CellBox {
    std::array<double, 3> lo{};
    double width = 1.0;
};

struct LoopFanLimits {
    double voxelSize = 1.0;         // world units
    double minFanDoubledArea = 0.0; // world units squared: a fan triangle's least doubled area
    double minFanSpacing = 0.0;     // world units: the least distance of a fan's vertex from its loop
    double inset = 0.0;             // world units a vertex placed anywhere in its cell keeps off its sides
};

/// Closes the loop `ids[0 .. n)` of `mesh`'s vertices, triangle i (from vertex i to the next) of material
/// `materials[i]`: returns where its fan's inner vertex goes (`centre`, a sharp feature when `sharp`,
/// moved as needed), or nothing when the loop was triangulated without one (its triangles added to
/// `mesh`). The caller adds the vertex and the fan.
std::optional<std::array<double, 3>> closeLoop(Mesh& mesh, std::array<double, 3> centre, const std::array<double, 3>& normalSum,
                                               const uint32_t* ids, const MaterialId* materials, std::size_t n, bool sharp,
                                               const CellBox& cell, const LoopFanLimits& limits);

} // namespace vdbclay
