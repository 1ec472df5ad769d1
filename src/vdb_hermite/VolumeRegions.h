// Boxes of whole leaves cut out of a volume and put back: what the scene store's bricks are made of.
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace vdbclay {

using IndexCoord = std::array<int32_t, 3>;

/// A cube of `edge` voxels per side starting at `min` (index space); both multiples of the leaf size.
struct LeafAlignedBox {
    IndexCoord min{0, 0, 0};
    int32_t edge = kLeafDim;
};

/// The part of `volume` inside the box, with the same voxel size and materials: its leaves copied,
/// its tiles cut to the box's 8^3 blocks. Throws std::invalid_argument for a box not on leaf bounds.
Volume copyRegion(const Volume& volume, const LeafAlignedBox& box);

/// Replaces what `volume` holds inside the box by what `part` holds there (leaves and tiles), and folds
/// nodes that became uniform. `part` must have the same voxel size; its materials are not copied.
void pasteRegion(Volume& volume, const Volume& part, const LeafAlignedBox& box);

/// Fills the box with one material (0 = empty), dropping its leaves.
void fillRegion(Volume& volume, const LeafAlignedBox& box, MaterialId material);

/// Memory the box takes in its volume: its leaves (with their samples), and a share of the 128^3 nodes
/// above them; the volume's upper nodes, shared by thousands of boxes, are not counted.
uint64_t regionMemoryBytes(const Volume& volume, const LeafAlignedBox& box);
/// The share of the 128^3 nodes above the box's leaves that regionMemoryBytes counts.
uint64_t nodeShareBytes(const LeafAlignedBox& box);

/// The material filling the whole box when it holds no leaf (0 = empty), or nullopt.
std::optional<MaterialId> uniformMaterial(const Volume& volume, const LeafAlignedBox& box);

/// How two volumes differ inside a box, voxel by voxel.
struct RegionDifference {
    uint64_t occupancy = 0; // voxels solid in one and empty in the other
    uint64_t materials = 0; // voxels solid in both, of different materials
    uint64_t samples = 0;   // voxel edges whose Hermite samples differ where the materials agree
    /// The bounds (inclusive) of the voxels that differ in material or in the samples of their
    /// positive edges; lo > hi where none does.
    IndexCoord lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
    bool any() const { return occupancy || materials || samples; }
};
RegionDifference compareRegion(const Volume& a, const Volume& b, const LeafAlignedBox& box);

/// The boxes of `edge` voxels (a multiple of the leaf size) on a lattice of that spacing that hold a
/// leaf or a solid tile, sorted.
std::vector<IndexCoord> occupiedBoxes(const Volume& volume, int32_t edge);

} // namespace vdbclay
