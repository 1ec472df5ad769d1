// Synthetic scenes generated straight into a store, brick by brick (vdbclay synth): never more than a
// batch of bricks in memory, and the same store for the same seed whatever the thread count, as every
// brick is computed on its own from pure functions of position and seed.
#pragma once

#include "scene/SceneStore.h"

#include <cstdint>
#include <string>

namespace vdbclay {

enum class SynthKind {
    Terrain,   // a noise-displaced height field, tunnels carved under it (overhangs), materials by height
    Asteroids, // many noise-displaced blobs of three materials
    CsgStack,  // a deterministic pile of sharp CSG primitives on the voxel lattice, touching and coplanar
};

const char* synthKindName(SynthKind kind);
SynthKind parseSynthKind(const std::string& name); // throws std::invalid_argument

struct SynthOptions {
    SynthKind kind = SynthKind::Terrain;
    int32_t extent = 256; // voxels along the scene's longest side
    uint64_t seed = 1;
    double voxelSize = 1.0;
};

/// Throws std::invalid_argument for an extent outside 16 .. 65536 voxels or a bad voxel size.
void validateSynthOptions(const SynthOptions& options);

struct SynthReport {
    uint64_t bricks = 0;      // bricks stored (payloads and uniform)
    uint64_t bricksVisited = 0;
    uint64_t leaves = 0;
    uint64_t bytes = 0;       // payload bytes
};

/// A terrain's ground height (world units) at world (x, z), before its tunnels are carved: where a
/// viewer flying over it stands clear of the ground. Throws std::invalid_argument for other kinds.
double synthGroundHeight(const SynthOptions& options, double x, double z);

/// Generates the scene into a new store at `path` (replaced only once complete, like writeStoreFile).
SynthReport synthesizeStore(const SynthOptions& options, const std::string& path, const Progress& progress = {});

} // namespace vdbclay
