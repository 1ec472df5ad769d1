// CSG operators on a Hermite volume. Each touches only the tree nodes inside the brush's bounds (grown
// by one voxel on the low side, whose positive edges reach into the brush), computes the new content of
// every leaf-sized block there as one TBB task, then swaps the results in and prunes locally.
//
// Erosion rule: a voxel of material m is removed where  d(x) < -(1 - s * (1 - toughness(m))) * r,
// with d the brush distance, s the strength in [0,1] and r the brush's inner radius (or the op's
// explicit depth). A soft material (toughness 0) at full strength loses the whole brush volume; a
// material of toughness t loses only the part deeper than t*r inside the brush, i.e. the brush bites
// (1 - t) * s * r deep; toughness 1 never erodes.
#pragma once

#include "sculpt/Brush.h"
#include "vdb_hermite/BlockChange.h"
#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

enum class CsgMode { Add, Remove, Intersect, Paint, Erode };

const char* csgModeName(CsgMode mode);
CsgMode parseCsgMode(const std::string& name); // throws std::invalid_argument

struct CsgOp {
    CsgMode mode = CsgMode::Add;
    MaterialId material = 1;              // add, paint
    double strength = 1.0;                // erode, in [0,1]
    std::optional<double> erodeDepth;     // erode: world units; default is the brush's inner radius
};

struct EditStats {
    uint64_t blocksComputed = 0;   // leaf-sized blocks recomputed voxel by voxel
    uint64_t leavesWritten = 0;    // blocks that are (still) leaves afterwards
    uint64_t tilesWritten = 0;     // blocks or nodes that became (or stayed) uniform tiles
    uint64_t crossingsComputed = 0;
    /// Origins of the leaf-sized blocks whose content changed and that a mesh can read (for
    /// re-meshing): every changed block that was or became a leaf, and every other changed block with
    /// a leaf in its 3x3x3 neighbourhood afterwards. Blocks the brush left as they were, and changed
    /// tiles deep inside solid or empty space, are not listed: the list grows with the surface an
    /// edit touches, not with its volume.
    std::vector<std::array<int32_t, 3>> dirtyBlocks;
    /// The same blocks in the same order, each with the bounds of the voxels that changed in it, so
    /// that re-meshing can leave alone the leaves that read only unchanged parts of a block.
    std::vector<BlockChange> blockChanges;

    /// Adds another edit's counts and blocks (an op made of several kernel runs).
    void append(const EditStats& more);
};

/// What one edit may ask for, checked before any work starts (checkCsgLimits):
/// - the brush stays within kMaxReachVoxels of the origin on every axis: the meshers' vertex keys and
///   the lattice arithmetic cover +-262,144 voxels;
/// - its surface (SdfField::surfaceAreaBound, in voxels squared) is at most kMaxSurfaceVoxels: an edit
///   makes about one leaf of 6 KB per 40 surface voxels, so this caps the new leaves near 9 GB;
/// - its work, surface voxels times the primitive distances per evaluation (a blend's parts, a stroke's
///   window search) times the ~30 evaluations per surface voxel, is at most kMaxDistanceEvaluations
///   (about half a minute on one core).
constexpr double kMaxReachVoxels = 250000.0;
constexpr double kMaxSurfaceVoxels = 6e7;
/// What the leaves of one square voxel of new surface take in memory (kMaxSurfaceVoxels: about 9 GB).
constexpr double kBytesPerSurfaceVoxel = 150.0;
constexpr double kMaxDistanceEvaluations = 5e9;

/// Throws std::invalid_argument, naming the limit, when the edit exceeds one of the limits above or
/// makes no sense (an unbounded add, a material id that is not in the volume's table, strength out of
/// range). Changes nothing.
void checkCsgLimits(double voxelSize, const MaterialTable& materials, const SdfField& brush, const CsgOp& op);

/// Checks the op (checkCsgLimits), then applies it.
EditStats applyCsg(Volume& volume, const SdfField& brush, const CsgOp& op);

} // namespace vdbclay
