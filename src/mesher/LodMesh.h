// Meshing a level of the LOD pyramid with the same mesher as level 0.
#pragma once

#include "mesher/Mesher.h"
#include "wavelet/LodPyramid.h"

namespace vdbclay {

/// Moves every vertex by `offset` (world units).
void translateMesh(Mesh& mesh, const std::array<double, 3>& offset);

/// The mesh of a level's Hermite data (level 0: the volume itself; level k: voxels 2^k times the fine
/// size, as LodPyramid::coarseVolume or a store's level k holds), moved by the level's offset so it
/// lies on the fine surface.
Mesh meshLevelVolume(const Volume& levelVolume, int level, const MeshOptions& options = {});

/// The mesh of level `level` of `pyramid` (built from `fine`), in world units: level 0 is the fine
/// volume's own mesh; level k meshes the coarse Hermite data (LodPyramid::coarseVolume) and moves it by
/// the level's offset.
Mesh meshLevel(const Volume& fine, const wavelet::LodPyramid& pyramid, int level, const MeshOptions& options = {});

} // namespace vdbclay
