// How brushes respect the mask (VoxelMask.h): a brush runs as if there were none, then the masked
// voxels, and the Hermite samples of the edges between them, are put back as they were. Edges from a
// masked voxel to a free one keep a crossing wherever their two materials now differ: the brush's, else
// the old one, else one at the edge's middle. So a masked region stays bit-identical whatever runs over
// it, and the surface around it stays closed.
#pragma once

#include "sculpt/Brush.h"
#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VoxelMask.h"

#include <cstdint>
#include <memory>

namespace vdbclay {

/// The leaves a brush may change that hold masked voxels, or edges ending in one, as they were before it ran.
class MaskedVoxels {
public:
    /// Captures what the mask of `volume` keeps within `reach` (world bounds of what the brush may
    /// change; unbounded: wherever the volume has content). Captures nothing when nothing is masked.
    MaskedVoxels(const Volume& volume, const WorldBounds& reach);
    ~MaskedVoxels();
    MaskedVoxels(MaskedVoxels&&) noexcept;
    MaskedVoxels& operator=(MaskedVoxels&&) noexcept;

    /// Puts the masked voxels back into `volume` (the same volume, after the brush). Returns the leaves
    /// rewritten.
    uint64_t restore(Volume& volume) const;
    /// Leaves captured.
    std::size_t leaves() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Masks (`masked` true) or frees the voxels whose lattice points lie inside `field` (distance <= 0).
/// Returns the voxels tested one by one (whole leaves inside or outside are decided at once).
uint64_t paintMask(VoxelMask& mask, const SdfField& field, double voxelSize, bool masked);

/// The most leaves a mask brush's bounds may span: a box 800 voxels a side (the mask it paints is kept
/// whole in memory, 64 bytes a leaf).
constexpr double kMaxMaskBrushLeaves = 1e6;

} // namespace vdbclay
