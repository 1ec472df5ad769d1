// Paint with a soft edge. A voxel holds one material, so a stroke's falloff cannot be a weight per voxel;
// it is a coverage instead: inside the brush a voxel takes the paint where strength x falloff exceeds a
// smooth noise threshold (value noise a voxel across, in [0, 1)). Where the weight is 1 every voxel is
// painted, where it is 0 none, and in between the painted share follows the weight, in patches about a
// voxel across whose boundaries are smooth surfaces (the CSG kernel finds their crossings as for any
// field): the edge is a stipple whose density follows the falloff, like an airbrush's.
#pragma once

#include "sculpt/Brush.h"
#include "sculpt/FieldBrushes.h"

#include <memory>

namespace vdbclay {

/// The paint threshold at a world point: smooth value noise in [0, 1) on a lattice one voxel apart.
double paintThreshold(const Vec3d& world, double voxelSize);

class SoftPaintField : public SdfField {
public:
    /// `brush` where strength x falloff(depth) exceeds paintThreshold, on a lattice of `voxelSize`.
    SoftPaintField(std::shared_ptr<const SdfField> brush, double strength, Falloff falloff, double voxelSize, FalloffCurve curve = {});
    double distance(const Vec3d& world) const override;
    WorldBounds bounds() const override { return brush_->bounds(); }
    double innerRadius() const override { return brush_->innerRadius(); }
    double surfaceAreaBound() const override { return brush_->surfaceAreaBound() * 4.0; } // the patches' boundaries
    double evaluationCost() const override { return brush_->evaluationCost() + 2.0; }
    double lipschitz() const override { return std::max(brush_->lipschitz(), 2.0); }

private:
    std::shared_ptr<const SdfField> brush_;
    double strength_;
    Falloff falloff_;
    double voxelSize_;
    FalloffCurve curve_;
};

} // namespace vdbclay
