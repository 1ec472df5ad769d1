// Meshing a level of the LOD pyramid with the same mesher as level 0.
#pragma once

#include "mesher/LodCut.h"
#include "mesher/Mesher.h"
#include "wavelet/LodPyramid.h"

#include <cstdint>
#include <vector>

namespace vdbclay {

/// The mesh of level `level` of `pyramid` (built from `fine`), in world units: level 0 is the fine
/// volume's own mesh; level k meshes the coarse Hermite data (LodPyramid::coarseVolume).
Mesh meshLevel(const Volume& fine, const wavelet::LodPyramid& pyramid, int level, const MeshOptions& options = {});

/// The mesh of one brick of a level-of-detail cut, on its level's own lattice, vertex-aligned: level k's
/// point i is the level-0 point 2^k i, at world position i times level k's voxel size (every level's
/// lattice lies on the finer ones', and its data is resampled there: LodPyramid.h). `levels[k]`: level k's Hermite data (voxel size 2^k times level 0's), holding
/// at least the cut's bricks of level k. Together the meshes of a cut's bricks are closed wherever the
/// scene is: a brick's cells that touch a finer brick (transition cells) take the finer side's data
/// where they meet it and are meshed by the transition mesher, and the kernel meshes the faces beside
/// them plainly (LodCut::plainFace). Needs CMS; throws std::invalid_argument otherwise.
Mesh meshLodBrick(const std::vector<const Volume*>& levels, const LodCut& cut, const LodBrick& brick,
                  const MeshOptions& options);

/// meshLodBrick in two parts, for re-meshing a brick where an edit changed it. First, the chunks of the
/// leaves whose cells the brick meshes (its own, and one layer of leaves past its high faces), in the
/// order of their origins; `onlyLeaves` (optional, sorted): only the chunks of those leaves.
std::vector<MeshChunk> meshLodBrickChunks(const std::vector<const Volume*>& levels, const LodCut& cut, const LodBrick& brick,
                                          const MeshOptions& options,
                                          const std::vector<std::array<int32_t, 3>>* onlyLeaves = nullptr);
/// A coarse brick's mesh simplified as streaming scenes show it: within
/// `options.coarseLevelSimplifyTolerance` voxels of its level (`levelVoxel` wide), by simplifyMesh, which
/// keeps its open edges, so the cut's bricks still meet. Level 0 and a zero tolerance leave it as it is.
/// Returns whether it simplified; `kept`: as simplifyMesh's.
bool simplifyLodBrickMesh(Mesh& mesh, int level, double levelVoxel, const MeshOptions& options, std::vector<uint32_t>* kept = nullptr);

/// A transition cell's closed box on the level-0 lattice.
struct TransitionCellBox {
    LodCut::Point lo, hi;
};
/// Then the transition cells, appended to the welded chunks (`cells`, optional: the boxes of the cells
/// meshed, in the order they were, which is all their triangles read of the finest level).
void appendLodTransitions(const std::vector<const Volume*>& levels, const LodCut& cut, const LodBrick& brick, Mesh& mesh,
                          std::vector<TransitionCellBox>* cells = nullptr);

} // namespace vdbclay
