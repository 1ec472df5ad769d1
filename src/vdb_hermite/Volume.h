// A sculptable volume: the Hermite grid plus its materials table. Light header: the OpenVDB
// templates stay behind detail::VolumeGrid (HermiteGrid.h) so most of the project compiles fast.
#pragma once

#include "vdb_hermite/Materials.h"

#include <array>
#include <cstdint>
#include <memory>

namespace vdbclay {

namespace detail {
struct VolumeGrid;
}
class VoxelMask;

/// Leaves are cubes of 8^3 voxels; edits report, and meshers chunk, by leaf.
constexpr int kLeafLog2Dim = 3;
constexpr int kLeafDim = 1 << kLeafLog2Dim;

struct VolumeStats {
    double voxelSize = 1.0;
    uint64_t activeVoxels = 0; // voxels with at least one Hermite sample (surface voxels)
    uint64_t samples = 0;      // Hermite samples (crossing edges)
    uint64_t leafCount = 0;
    uint64_t tileCount = 0;    // non-empty tiles
    bool empty = true;
    std::array<int32_t, 3> bboxMin{0, 0, 0}; // index space, solid voxels included
    std::array<int32_t, 3> bboxMax{0, 0, 0};
    uint64_t memoryBytes = 0;
};

/// Voxel sizes a volume may have (world units). The unit is the user's: positions are held in voxels,
/// so only OpenVDB's transforms bound it (they refuse scales below about 1.5e-5: "non-zero scale values
/// required"). 2e-5 lets a 10 cm scan in metres take 4096 voxels; finer lattices need a smaller unit.
constexpr double kMinVoxelSize = 2e-5, kMaxVoxelSize = 1e6;

/// The farthest a voxel may lie from the origin along an axis, in voxels: OpenVDB indexes 32-bit
/// coordinates, and the levels of detail, bricks and meshers need room beyond a solid's own voxels.
constexpr double kMaxLatticeCoordinate = double(1 << 30);

class Volume {
public:
    /// Throws std::invalid_argument unless kMinVoxelSize <= voxelSize <= kMaxVoxelSize.
    explicit Volume(double voxelSize = 1.0);
    ~Volume();
    Volume(Volume&&) noexcept;
    Volume& operator=(Volume&&) noexcept;
    Volume(const Volume&) = delete;
    Volume& operator=(const Volume&) = delete;

    Volume clone() const; // deep copy

    double voxelSize() const;
    MaterialTable& materials();
    const MaterialTable& materials() const;
    /// The voxels no brush changes (VoxelMask.h); saved with the volume.
    VoxelMask& mask();
    const VoxelMask& mask() const;
    VolumeStats stats() const;
    /// Format version of the file this volume was loaded from; the version saves write for a new one.
    int formatVersion() const;
    /// Material at an index-space voxel.
    MaterialId materialAt(const std::array<int32_t, 3>& ijk) const;

    detail::VolumeGrid& impl() { return *impl_; }
    const detail::VolumeGrid& impl() const { return *impl_; }

private:
    explicit Volume(detail::VolumeGrid*); // an empty shell, filled by clone()
    std::unique_ptr<detail::VolumeGrid> impl_;
};

/// Bit-exact comparison: same voxel size, materials table, tree topology, tiles, voxels, samples and mask.
bool identical(const Volume& a, const Volume& b);

} // namespace vdbclay
