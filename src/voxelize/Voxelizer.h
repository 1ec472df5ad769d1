// Meshes into Hermite data by axis-aligned rays (seed 004 §2.5, Algorithm 7; seed 000 §3): rays along X,
// Y and Z through every lattice line, triangles binned to the rays their projected bounds cover, hits
// sorted along each ray, inside sections filled by parity, the exact crossing offsets and triangle
// normals stored as Hermite samples. Real meshes are not clean: a lattice point is solid where at least
// two of its three rays say so, which closes holes and seams that one ray slips through.
//
// Only the hits are kept (memory that grows with the mesh's surface); the lattice's points are voted
// block by block, so a mesh of more voxels than memory holds goes into a store one brick at a time
// (voxelize/VoxelizeToStore.h).
//
// Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeRegions.h"
#include "voxelize/TriangleMesh.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

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
    uint64_t crossings = 0;          // edge samples, material interfaces included
    uint64_t materialInterfaces = 0; // edges between two solid materials (where touching parts meet)
    uint64_t solidVoxels = 0;
};

/// Adds what voxelizing a block counted (voted and solid points, crossings, patches, interfaces) to a
/// total; the casting counts (triangles, hits) are the voxelizer's, not a block's.
void addBlockCounts(VoxelizeReport& total, const VoxelizeReport& block);

/// A mesh cast into rays, ready to be voxelized block by block.
class MeshVoxelizer {
public:
    /// Casts the rays. Throws std::invalid_argument for a missing or absurd voxel size or resolution,
    /// or a lattice of more than 2^36 points (2^26 on a face).
    MeshVoxelizer(const TriangleSoup& mesh, const VoxelizeOptions& options);
    MeshVoxelizer(MeshVoxelizer&&) noexcept;
    MeshVoxelizer& operator=(MeshVoxelizer&&) noexcept;
    ~MeshVoxelizer();

    double voxelSize() const;
    /// The materials the voxels use: the mesh's (names and colours), or the one named in the options.
    const MaterialTable& materials() const;
    /// What casting counted: triangles, dropped triangles, hits, duplicate hits.
    const VoxelizeReport& castReport() const;

    /// The boxes of `edge` voxels (a multiple of 8, aligned to it) that cover the mesh's lattice.
    std::vector<LeafAlignedBox> blocks(int32_t edge) const;
    /// The voxels inside one box (a volume holding nothing else), exactly what the whole mesh's
    /// voxelization holds there; adds what it counted to `counts`. Safe to call from several threads.
    Volume voxelizeBlock(const LeafAlignedBox& box, VoxelizeReport& counts) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    friend Volume voxelizeMesh(const TriangleSoup&, const VoxelizeOptions&, VoxelizeReport*);
};

/// Voxelizes a triangle soup into one volume. Throws as MeshVoxelizer's constructor.
Volume voxelizeMesh(const TriangleSoup& mesh, const VoxelizeOptions& options, VoxelizeReport* report = nullptr);

/// Why a mesh that encloses no solid voxel at this voxel size has nothing to import.
std::string noSolidMessage(double voxelSize);

} // namespace vdbclay
