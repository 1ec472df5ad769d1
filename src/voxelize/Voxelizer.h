// Meshes into Hermite data by axis-aligned rays (seed 004 §2.5, Algorithm 7; seed 000 §3): rays along X,
// Y and Z through every lattice line, triangles binned to the rays their projected bounds cover, hits
// sorted along each ray, inside sections filled by parity, the exact crossing offsets and triangle
// normals stored as Hermite samples. Real meshes are not clean: a lattice point is solid where at least
// two of its three rays say so, which closes holes and seams that one ray slips through.
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"
#include "voxelize/TriangleMesh.h"

#include <cstdint>
#include <optional>
#include <string>

namespace vdbclay {

struct VoxelizeOptions {
    std::optional<double> voxelSize; // world units; or
    std::optional<int> resolution;   // voxels along the mesh's longest side
    std::string material;            // every solid voxel this material; empty: the mesh's materials
};

struct VoxelizeReport {
    double voxelSize = 0.0;
    uint64_t triangles = 0, droppedTriangles = 0;
    uint64_t hits = 0;
    uint64_t duplicateHits = 0;   // hits of one ray at one place (duplicated triangles), merged
    uint64_t votedPoints = 0;     // lattice points whose three rays disagreed (holes, seams, self-intersections)
    uint64_t patchedCrossings = 0; // edges the vote made cross with no hit on them (placed mid-edge)
    uint64_t crossings = 0;
    uint64_t solidVoxels = 0;
};

/// Voxelizes a triangle soup. Throws std::invalid_argument for a missing or absurd voxel size or
/// resolution, or a grid of more than 2^28 lattice points.
Volume voxelizeMesh(const TriangleSoup& mesh, const VoxelizeOptions& options, VoxelizeReport* report = nullptr);

} // namespace vdbclay
