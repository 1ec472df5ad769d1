// Signed distance bounds for synthetic scenes (vdbclay synth): noise-displaced terrain with carved
// tunnels, noise-displaced blobs, horizontal slabs, and any field clipped to a box. Each is a
// Lipschitz-1 lower bound of the true distance, as the CSG kernel needs; the noise is a pure function
// of position and seed, so a scene is the same whatever the thread count or brick order.
#pragma once

#include "sculpt/Brush.h"

#include <cstdint>
#include <vector>

namespace vdbclay {

/// Value noise in [-1, 1] on the integer lattice, quintic fade; gradient magnitude at most
/// kValueNoiseSlope per unit of frequency (2D) or kValueNoiseSlope3D (3D).
double valueNoise2(double x, double y, uint64_t seed);
double valueNoise3(double x, double y, double z, uint64_t seed);
constexpr double kValueNoiseSlope = 5.31;   // 1.875 * 2 * sqrt(2)
constexpr double kValueNoiseSlope3D = 6.50; // 1.875 * 2 * sqrt(3)

struct TerrainParams {
    double baseHeight = 0.0;      // world units
    double amplitude = 1.0;       // of the first octave
    double wavelength = 16.0;     // of the first octave
    int octaves = 4;              // each of half the amplitude and wavelength
    uint64_t seed = 1;
    double spacing = 1.0;         // heights are sampled on columns this far apart and interpolated
};

/// The solid below a height field of fBm value noise, sampled on a lattice of columns and interpolated
/// bilinearly between them: (y - h(x, z)) / sqrt(1 + L^2), L bounding |grad h|.
class TerrainField : public SdfField {
public:
    explicit TerrainField(const TerrainParams& params);
    double height(double x, double z) const;
    double distance(const Vec3d& p) const override;
    WorldBounds bounds() const override { return {}; }
    double innerRadius() const override { return 1e30; }
    double maxHeight() const { return params_.baseHeight + amplitudeSum_; }
    double minHeight() const { return params_.baseHeight - amplitudeSum_; }

private:
    double latticeHeight(int64_t i, int64_t j) const;

    TerrainParams params_;
    uint64_t id_; // tells this field's entries in the per-thread height cache from another's
    double amplitudeSum_ = 0.0;
    double slopeNorm_ = 1.0;
};

/// A sphere whose radius is displaced by value noise: (|p - c| - r - a n(p)) / (1 + a L).
class BlobField : public SdfField {
public:
    BlobField(const Vec3d& centre, double radius, double amplitude, double wavelength, uint64_t seed);
    double distance(const Vec3d& p) const override;
    WorldBounds bounds() const override;
    double innerRadius() const override { return radius_ - amplitude_; }

private:
    Vec3d centre_;
    double radius_, amplitude_, frequency_;
    uint64_t seed_;
};

/// The horizontal slab minY <= y < maxY (either side may be infinite).
class SlabField : public SdfField {
public:
    SlabField(double minY, double maxY) : minY_(minY), maxY_(maxY) {}
    double distance(const Vec3d& p) const override { return std::max(minY_ - p.y(), p.y() - maxY_); }
    WorldBounds bounds() const override { return {}; }
    double innerRadius() const override { return 0.5 * (maxY_ - minY_); }

private:
    double minY_, maxY_;
};

/// `inner` intersected with an axis-aligned box: max of both distances, bounded by the box. Used to
/// evaluate an unbounded or large field one region at a time; the box's own walls fall outside the
/// region the caller keeps.
class ClippedField : public SdfField {
public:
    ClippedField(const SdfField& inner, const Vec3d& min, const Vec3d& max) : inner_(inner), min_(min), max_(max) {}
    double distance(const Vec3d& p) const override;
    WorldBounds bounds() const override;
    double innerRadius() const override;
    double evaluationCost() const override { return inner_.evaluationCost(); }

private:
    const SdfField& inner_;
    Vec3d min_, max_;
};

} // namespace vdbclay
