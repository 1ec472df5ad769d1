// A mesh voxelized straight into a new store (.vdbclay), one batch of bricks at a time: memory holds the
// rays' hits and a batch, never the whole volume, so a mesh of more voxels than memory holds comes in.
#pragma once

#include "scene/SceneStore.h"
#include "voxelize/Voxelizer.h"

#include <cstdint>
#include <string>

namespace vdbclay {

struct StoreVoxelizeReport {
    VoxelizeReport mesh;
    uint64_t bricks = 0;       // stored (empty space stores nothing)
    uint64_t leaves = 0;
    uint64_t activeVoxels = 0; // voxels with a Hermite sample
    MaterialTable materials;
};

/// Voxelizes `mesh` into a new store at `path` (an existing store is replaced only once the new one is
/// complete). Level 0 holds exactly what voxelizeMesh gives. Throws as MeshVoxelizer's constructor, and
/// as createStoreFile; MeshImportError (noSolidMessage) when the mesh encloses no solid voxel.
StoreVoxelizeReport voxelizeMeshToStore(const TriangleSoup& mesh, const VoxelizeOptions& options, const std::string& path,
                                        const Progress& progress = {});

} // namespace vdbclay
