// Meshing a Hermite volume. Cells are meshed per leaf with TBB; every cell is owned by exactly one leaf,
// so chunks tile the surface without overlaps and weld into a watertight mesh.
#pragma once

#include "mesher/Mesh.h"
#include "vdb_hermite/Volume.h"

#include <array>
#include <optional>
#include <stdexcept>
#include <vector>
#include <string>

namespace vdbclay {

enum class MesherKind { MarchingCubes, CubicalMarchingSquares };

const char* mesherName(MesherKind kind);          // "mc", "cms"
MesherKind parseMesherKind(const std::string& s); // throws std::invalid_argument

struct MeshOptions {
    MesherKind kind = MesherKind::MarchingCubes;
    /// CMS: crossings whose normals span more than this angle make a sharp feature (edge or corner).
    double sharpAngleDegrees = 30.0;
};

std::vector<MeshChunk> meshVolumeChunks(const Volume& volume, const MeshOptions& options = {});
/// The chunks of the leaves at the given origins (leaf-aligned); empty where there is no leaf.
std::vector<std::optional<MeshChunk>> meshLeafChunks(const Volume& volume,
                                                     const std::vector<std::array<int32_t, 3>>& leafOrigins,
                                                     const MeshOptions& options = {});
Mesh meshVolume(const Volume& volume, const MeshOptions& options = {});

} // namespace vdbclay
