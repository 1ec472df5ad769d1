// Seeded random scenes the way users build them: integer and half-voxel sizes and positions as often as
// arbitrary ones, rotations by multiples of 90 degrees, solids that touch and faces that are coplanar,
// every shape and mode, strokes, blends and several materials. A scene is a voxel size and a stroke
// script, so a failing one can be replayed with the vdbclay command.
#pragma once

#include <cstdint>
#include <string>

namespace vdbclay {

struct RandomScene {
    uint64_t seed = 0;
    uint64_t index = 0;
    double voxelSize = 1.0;
    std::string script; // a stroke script (docs/SCRIPTS.md); its first op clears the volume
};

/// Scene `index` of the sequence `seed`: the same pair always gives the same scene.
RandomScene randomScene(uint64_t seed, uint64_t index);

/// One primitive of `vdbclay new --shape NAME --size S` (primitiveOfSize) at the origin, for sweeps of
/// sizes; `index` only labels the scene.
RandomScene primitiveScene(const std::string& shape, double size, double voxelSize, uint64_t index = 0);

} // namespace vdbclay
