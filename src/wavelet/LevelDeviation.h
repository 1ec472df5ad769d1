// How far one level of the LOD pyramid lies from the next finer one: the geometric error that lets a
// view show a smooth region at a coarser level than its voxel size alone would allow (StoreLod keeps it
// per coarse brick, the view selection turns it into pixels).
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"

#include <array>

namespace vdbclay::wavelet {

/// The two-sided deviation, in world units, between `coarse` and `fine` (two levels' Hermite data on
/// vertex-aligned lattices, as the cut shows them) over the world box [lo, hi): the largest distance,
/// over the solid/empty crossings of either volume inside the box, from a crossing to the other volume's
/// surface near it. That distance is taken to the tangent plane of the other volume's nearest crossing
/// within a coarse cell around the crossing; where it has none that near (a feature one level lost or
/// made), `unmatched`. Only what the volumes hold inside the box is read, so the crossings within a
/// coarse voxel of the box's faces, whose nearest match may lie beyond them, are left out. 0 where
/// neither volume crosses the box.
double levelDeviation(const Volume& coarse, const Volume& fine, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                      double unmatched);

} // namespace vdbclay::wavelet
