// A stroke's path as the swept brush follows it: a path of a hundred thousand points costs what the
// voxels it covers cost, not what its points do (each point is a segment the brush is searched along).
#pragma once

#include "sculpt/Brush.h"

#include <vector>

namespace vdbclay {

/// The points of `path` a polyline needs to stay within `tolerance` of it: first points closer than
/// `tolerance` to the last one kept are merged, then Douglas-Peucker drops the points that lie within
/// `tolerance` of the segment between their kept neighbours. Every point of the result is a point of
/// `path` (the first and the last kept), in order, and every point of `path` lies within 2 x `tolerance`
/// of the result's polyline: a brush swept along either differs by at most that distance. A tolerance of
/// zero keeps every point that differs from the one before.
std::vector<Vec3d> simplifyStrokePath(const std::vector<Vec3d>& path, double tolerance);

/// The tolerance scripts' strokes are simplified with, in voxels: far below what a voxel's crossings
/// show, far above the spacing of a pointer's samples.
constexpr double kStrokePathToleranceVoxels = 1.0 / 256.0;

} // namespace vdbclay
