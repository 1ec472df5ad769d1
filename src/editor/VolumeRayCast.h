// Where a ray first meets the surface of a volume, from its Hermite data (not from drawn triangles): the
// crossing stored on the lattice edge the ray enters the solid through. What puts the editor's brush on
// the surface under the pointer.
#pragma once

#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <vector>

namespace vdbclay {

struct SurfaceHit {
    std::array<double, 3> point{0, 0, 0};  // world units, on the surface
    std::array<double, 3> normal{0, 0, 1}; // outward unit normal there
    double distance = 0.0;                 // along the ray, world units
    int level = 0;                         // the level of detail whose data the ray met
};

/// The first entry of the ray into solid matter within `maxDistance` (world units; `direction` need not
/// be unit length). A ray that starts inside solid matter hits where it enters solid matter again after
/// leaving it. Steps voxel by voxel: at most about maxDistance / voxelSize * 1.8 lookups.
std::optional<SurfaceHit> castRay(const Volume& volume, const std::array<double, 3>& origin,
                                  const std::array<double, 3>& direction, double maxDistance);

/// A volume as it was before some of its leaves changed (a stroke's starting state): `current`, except
/// the leaf-sized boxes whose origins `replaced` lists, which are read from `before`.
struct OverlaidVolume {
    const Volume& current;
    const Volume& before;
    const std::set<std::array<int32_t, 3>>& replaced;
};

/// castRay on the overlaid volume.
std::optional<SurfaceHit> castRay(const OverlaidVolume& volume, const std::array<double, 3>& origin,
                                  const std::array<double, 3>& direction, double maxDistance);

/// The ray against every level's data (index = level, each on its own lattice): the finest level's hit,
/// unless a coarser level meets the surface clearly in front of it (two of that level's voxels), where
/// the finer data are not resident.
/// Null levels are skipped. `finestResidentAt`, when given, says where the finest level's data are resident: a coarser level's
/// hit stands in only elsewhere (coarse levels may lag the finest one's edits).
std::optional<SurfaceHit> castRayAcrossLevels(const std::vector<const Volume*>& levels, const std::array<double, 3>& origin,
                                              const std::array<double, 3>& direction, double maxDistance,
                                              const std::function<bool(const std::array<double, 3>&)>& finestResidentAt = {});

} // namespace vdbclay
