// Brushes that reshape the surface rather than add or carve a solid: smooth, flatten, inflate, deflate
// and move (the sculpting brushes of Medium, Blender and SculptGL). Each rebuilds a signed distance
// field around the brush from the Hermite data (as grid tools do), changes it inside the brush, weighted
// by strength and falloff, and writes the result back with the CSG kernel: voxels the new field holds
// and the old did not are added, voxels the new field leaves are removed, so every edge keeps one
// consistent crossing and the surface stays closed.
//
// Definitions, with phi the old distance (world units, negative inside), w in [0, 1] the weight at a
// point (strength times the falloff of its depth in the brush) and phi' the new distance:
//   inflate   phi' = phi - w D            (the surface moves out by w D along its normal)
//   deflate   phi' = phi + w D
//   smooth    phi' = phi + w (blur(phi) - phi), blur a symmetric box filter of radius rho (a plane's
//             distance is linear and stays as it is; edges and corners round off)
//   flatten   phi' = phi + w (P - phi), P the distance to the plane fitted under the brush (centroid and
//             mean normal of the surface there, weighted by w)
//   move      each point p moves to p + w(p) offset, so phi'(x) = phi(p) for the p that lands on x (the
//             surface under the brush centre moves by offset); w is full within a voxel and a half
//             of the centre, so a drag of several radii keeps the grabbed point under the pointer
// Voxels the brush adds take `material`, else the most common solid material under the brush.
#pragma once

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/Volume.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

enum class FieldMode { Smooth, Flatten, Inflate, Deflate, Move };
/// How a brush's weight rises from its rim (0) to its deepest point (1). Curve: a user's curve, weights at
/// evenly spaced depths (FalloffCurve), linear between them.
enum class Falloff { Smooth, Linear, Constant, Curve };
/// A falloff curve's weights from the rim to the deepest point: 2 to 16 values in [0, 1].
using FalloffCurve = std::vector<double>;
constexpr std::size_t kMaxFalloffPoints = 16;

const char* fieldModeName(FieldMode mode);
/// nullopt for a name that is not a field mode.
std::optional<FieldMode> parseFieldMode(const std::string& name);
const char* falloffName(Falloff falloff);
Falloff parseFalloff(const std::string& name); // throws std::invalid_argument

struct FieldBrushOp {
    FieldMode mode = FieldMode::Smooth;
    double strength = 1.0;                 // in [0, 1]
    Falloff falloff = Falloff::Smooth;     // of the weight from the brush's rim (0) to its deepest point (1)
    FalloffCurve curve;                    // Falloff::Curve
    double distance = 0.0;                 // inflate, deflate: world units at full weight
    Vec3d offset{0.0, 0.0, 0.0};           // move: world units at full weight
    std::optional<MaterialId> material;    // what added voxels are made of
};

/// The weight of a point `depth` inside a brush whose deepest point is `innerRadius` deep: 0 outside,
/// rising to 1 at the deepest point as the falloff says (constant: 1 everywhere inside; a curve: its
/// weights, linear between them).
double falloffWeight(Falloff falloff, double depth, double innerRadius, const FalloffCurve& curve = {});
/// Throws std::invalid_argument unless the curve holds 2 to kMaxFalloffPoints finite weights in [0, 1].
void checkFalloffCurve(const FalloffCurve& curve);

/// The smoothing filter's radius (each of its two box passes) for a brush, in voxels: half the brush's
/// inner radius, 1 to 12 (wide enough that one pass at strength 1 takes a one-voxel bump away and rounds
/// a crease between stamps).
int smoothingRadiusVoxels(const SdfField& brush, double voxelSize);

/// World units beyond the brush's bounds the op reads: its field must see the surface there.
double fieldBrushReach(const SdfField& brush, const FieldBrushOp& op, double voxelSize);
/// The box an op reads and changes: the brush's bounds grown by its reach, or for a move the bounds its
/// brush sweeps along the drag, grown by a few voxels (a drag reaches along its offset, not every way).
WorldBounds fieldBrushRegion(const SdfField& brush, const FieldBrushOp& op, double voxelSize);

/// The largest region (voxels a side) a field brush rebuilds its field over.
constexpr int32_t kMaxFieldBrushVoxels = 200;

/// Throws std::invalid_argument, changing nothing, for strength or distance out of range, an unbounded
/// brush, a region wider than kMaxFieldBrushVoxels, or an unknown material.
void checkFieldBrush(const Volume& volume, const SdfField& brush, const FieldBrushOp& op);

/// Checks the op, then applies it. A region without solid voxels is left as it is. `strokeStart`, the
/// state the op's stroke began from (right over the op's region), caps inflate and deflate per stroke:
///   inflate   phi' = min(phi, phi0 - w D),   deflate   phi' = max(phi, phi0 + w D)
/// with phi0 the start's distance, so overlapping stamps of one stroke move the surface at most w D from
/// where the stroke found it (the stroke's swept weight), never their sum.
EditStats applyFieldBrush(Volume& volume, const SdfField& brush, const FieldBrushOp& op, const Volume* strokeStart = nullptr);

/// What an op writes, prepared from the volume as it stands: applying it to that volume (or to one
/// that differs only outside the op's region) is the op. Preparing only reads, so the copies of a
/// symmetric op whose regions lie apart are prepared side by side.
using EditWriteBack = std::function<EditStats(Volume&)>;
/// applyFieldBrush in two steps (it checks the op first, throwing as applyFieldBrush does). `brush` and
/// `strokeStart` must outlive the write-back.
EditWriteBack prepareFieldBrush(const Volume& volume, const SdfField& brush, const FieldBrushOp& op, const Volume* strokeStart = nullptr);

/// An add that blends into the surface (clay pressed on, not a sphere stuck on): the brush is added
/// exactly (applyCsg), then the fillet where it meets the old surface, the smooth union
///   min(a, b) - k/4 h^2,  h = max(k - |a - b|, 0) / k
/// of the old distance a and the brush's b with width k = `width` (world units). The fillet only adds,
/// within k of the brush. A fillet region wider than kMaxFieldBrushVoxels is left out (the add stays
/// exact): the op is decided by its size, never by timing.
EditStats applyBlendedAdd(Volume& volume, const SdfField& brush, const CsgOp& op, double width);
/// applyBlendedAdd in two steps (EditWriteBack); `brush` must outlive the write-back.
EditWriteBack prepareBlendedAdd(const Volume& volume, const SdfField& brush, const CsgOp& op, double width);
/// World units beyond the brush's bounds a blended add reads and changes.
double blendReach(double width, double voxelSize);
/// The box a blended add reads and changes: the brush's bounds grown by blendReach (unbounded stays so).
WorldBounds blendedAddRegion(WorldBounds brushBounds, double width, double voxelSize);

} // namespace vdbclay
