// Meshing a Hermite volume. Cells are meshed per leaf with TBB; every cell is owned by exactly one leaf,
// so chunks tile the surface without overlaps and weld into a watertight mesh.
#pragma once

#include "mesher/LodCut.h"
#include "mesher/Mesh.h"
#include "vdb_hermite/BlockChange.h"
#include "vdb_hermite/Volume.h"

#include <array>
#include <functional>
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
    /// CMS: the widest cell in voxels (1, 2, 4 or 8). 1 meshes every voxel cell (uniform CMS); wider
    /// cells cover flat, simple stretches of surface with fewer triangles.
    int maxCellWidth = 8;
    /// CMS: a cell wider than one voxel is split while its crossings' normals span more than this angle.
    double subdivisionAngleDegrees = 15.0;
    /// CMS, voxels: a cell wider than one voxel whose normals spread wider than that angle still stays
    /// whole when its crossings lie within this distance of one plane and its normals within a right
    /// angle of that plane's (a height field over it). 0: the normals alone decide.
    double planeTolerance = 0.0;
    /// CMS, voxels of the level: the plane tolerance meshLodBrick uses for levels above 0. Their
    /// densities are resampled to 8 bits, which leaves ripples a fraction of a voxel high whose
    /// normals tilt by tens of degrees: under the normals alone their cells hardly ever merge.
    double coarseLevelPlaneTolerance = 0.5;
    /// CMS, voxels of the level: how far streaming scenes let a coarse brick's mesh be simplified from
    /// its lattice mesh (simplifyMesh: every plane a kept vertex absorbs within it; its open edges, where
    /// it meets the bricks beside it, kept). Counted in the brick's error, with the plane tolerance.
    double coarseLevelSimplifyTolerance = 0.25;
    /// CMS, optional: a cap on the cell width per leaf (given its origin; rounded down to 1, 2, 4 or 8),
    /// for meshing regions at different depths; the mesh stays watertight across them.
    /// Called from several threads at once, so it must be thread-safe.
    std::function<int(const std::array<int32_t, 3>&)> leafMaxCellWidth;
    /// CMS, optional: the brick of a level-of-detail cut being meshed (meshLodBrick in LodMesh.h sets
    /// these): its level and box (level-`lodLevel` index space, 64 voxels wide).
    const LodCut* lodCut = nullptr;
    int lodLevel = 0;
    std::array<int32_t, 3> lodBrickMin{0, 0, 0};
};

/// Throws std::invalid_argument for options the meshers cannot use (angles outside (0, 180), a widest
/// cell other than 1, 2, 4 or 8). The meshing functions check this too; callers that load a volume
/// first can check before.
void validateMeshOptions(const MeshOptions& options);

/// Whether the options mesh cells wider than a voxel (adaptive CMS), which need subdividing first.
bool meshesAdaptiveCells(const MeshOptions& options);

/// The leaves whose chunks can change when the given leaf-sized blocks change (EditStats::dirtyBlocks):
/// the leaves whose cells read a voxel of those blocks and, for adaptive CMS, the face neighbours of
/// the leaves whose subdivision reads one. Sorted and unique.
std::vector<std::array<int32_t, 3>> leavesAffectedBy(const std::vector<std::array<int32_t, 3>>& dirtyBlocks,
                                                     const MeshOptions& options);
/// The same from what changed in each block (EditStats::blockChanges): only the leaves that read a
/// changed voxel, directly or through a face neighbour's subdivision. (MeshChunkSet::update, which
/// subdivides first, re-meshes only the face neighbours whose shared face's cells changed.)
std::vector<std::array<int32_t, 3>> leavesAffectedBy(const std::vector<BlockChange>& changes, const MeshOptions& options);

namespace mesher_detail {
class AdaptiveCellCache;
}

/// `cells` (optional): adaptive cells kept from earlier calls on the same volume and options, used
/// where present and filled in where missing (MeshChunkSet keeps one between updates).
std::vector<MeshChunk> meshVolumeChunks(const Volume& volume, const MeshOptions& options = {},
                                        mesher_detail::AdaptiveCellCache* cells = nullptr);
Mesh meshVolume(const Volume& volume, const MeshOptions& options = {});
/// The chunks of the leaves whose origins lie in the box [min, min + edge) of index space, each the same
/// as meshVolumeChunks gives for that leaf (cells read their neighbours outside the box as usual), in the
/// order of their origins. `onlyLeaves` (optional, sorted): mesh only the leaves with these origins.
std::vector<MeshChunk> meshRegionChunks(const Volume& volume, const std::array<int32_t, 3>& min, int32_t edge,
                                        const MeshOptions& options = {},
                                        const std::vector<std::array<int32_t, 3>>* onlyLeaves = nullptr);

} // namespace vdbclay
