// Symmetry for every brush: mirrors across one, two or three planes through a centre, and radial
// repetition (N copies about an axis through it). An op with symmetry runs once per copy, each with its
// field seen through the copy's isometry, so paint, erosion, grid tools and reshaping brushes all follow.
#pragma once

#include "sculpt/Brush.h"

#include <array>
#include <memory>
#include <vector>

namespace vdbclay {

constexpr int kMaxRadialCopies = 64;

struct Symmetry {
    std::array<bool, 3> mirror{false, false, false}; // across the planes x = c, y = c, z = c
    int radialAxis = 1;                              // 0 x, 1 y, 2 z
    int radialCount = 1;                             // copies about the axis, 1 .. kMaxRadialCopies
    Vec3d center{0.0, 0.0, 0.0};

    bool any() const { return mirror[0] || mirror[1] || mirror[2] || radialCount > 1; }
};

/// The linear parts of the copies (each p -> A (p - center) + center), the identity first: every
/// combination of the mirrors, times every radial step. Quarter turns are exact.
std::vector<Mat3d> symmetryCopies(const Symmetry& symmetry);

/// A field seen through an isometry about a centre: distance(p) = field.distance(A^T (p - c) + c).
class TransformedField : public SdfField {
public:
    TransformedField(std::shared_ptr<const SdfField> field, const Mat3d& linear, const Vec3d& center);
    double distance(const Vec3d& world) const override;
    /// The field's own gradient, turned with the copy (its normals, not finite differences).
    Vec3d gradient(const Vec3d& world, double step) const override;
    WorldBounds bounds() const override;
    double innerRadius() const override { return field_->innerRadius(); }
    double surfaceAreaBound() const override { return field_->surfaceAreaBound(); }
    double evaluationCost() const override { return field_->evaluationCost(); }
    double lipschitz() const override { return field_->lipschitz(); }
    /// The field copied, and where the copy puts a point of it (A (p - c) + c).
    const SdfField& original() const { return *field_; }
    Vec3d place(const Vec3d& p) const { return linear_ * (p - center_) + center_; }

private:
    std::shared_ptr<const SdfField> field_;
    Mat3d linear_, inverse_;
    Vec3d center_;
};

/// The box holding `bounds` after the copy p -> A (p - c) + c.
WorldBounds transformBounds(const WorldBounds& bounds, const Mat3d& linear, const Vec3d& center);

} // namespace vdbclay
