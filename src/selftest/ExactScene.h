// A stroke script replayed on single points with the brushes' exact distances: the material a point
// holds after every op, by the same closed-set rule as the CSG kernel (a point on a brush's surface is
// inside). It is the reference the randomized checks compare the volume and its meshes with.
#pragma once

#include "sculpt/StrokeScript.h"
#include "vdb_hermite/Materials.h"

#include <memory>
#include <vector>

namespace vdbclay {

class ExactScene {
public:
    /// `materials` is the volume's table after the script ran (ids and toughness, for paint and erode).
    ExactScene(const StrokeScript& script, const MaterialTable& materials, double voxelSize);
    ~ExactScene();

    /// The material at a world point after all ops (0: empty).
    MaterialId materialAt(const Vec3d& world) const;
    /// Whether the point lies within `band` (world units) of some op's brush surface, where rounding may
    /// decide either way.
    bool nearSurface(const Vec3d& world, double band) const;
    /// Bounds of everything the ops can have made solid (the union of the bounds of the adds).
    WorldBounds solidBounds() const;

private:
    struct Op;
    std::vector<Op> ops_;
    double onSurface_;
};

} // namespace vdbclay
