// White-box access to a volume's Hermite tree for the tests. Light header: the OpenVDB templates stay
// in HermiteProbe.cpp.
#pragma once

#include "vdb_hermite/Quantize.h"
#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay::test {

/// One stored Hermite sample: the positive `axis` edge of `voxel`, its two end materials and the sample.
struct EdgeRecord {
    std::array<int32_t, 3> voxel{};
    int axis = 0;
    MaterialId from = 0; // material of `voxel`
    MaterialId to = 0;   // material of voxel + e_axis
    PackedSample sample;

    bool crossesSurface() const { return (from != kEmptyMaterial) != (to != kEmptyMaterial); }
};

/// Every stored sample of the volume, in leaf order.
std::vector<EdgeRecord> collectEdges(const Volume& volume);

/// Checks the grid invariants documented in HermiteGrid.h: an edge carries a sample iff its end
/// materials differ (and such an edge always lives in a leaf), a voxel is active iff one of its edges
/// carries a sample, and decoded offsets lie in [0,1]. Returns "" or a description of the first violation.
std::string checkInvariants(const Volume& volume);

/// Origins of the leaf-sized blocks whose materials or samples differ between two volumes, sorted.
std::vector<std::array<int32_t, 3>> changedBlocks(const Volume& a, const Volume& b);

/// Origins of the volume's leaves, sorted.
std::vector<std::array<int32_t, 3>> leafOrigins(const Volume& volume);

/// Number of solid voxels (leaf voxels and tile voxels) per material id; index 0 is unused.
std::vector<uint64_t> solidVoxelsPerMaterial(const Volume& volume);

/// Writes the volume's grid with hand-made VDBClay metadata through openvdb::io::File: a format version
/// and a materials JSON (each left out when not given), then, unless `trailer` is false, the integrity
/// trailer saveVolume appends (see appendIntegrityTrailer).
void writeHermiteFile(const Volume& volume, const std::string& path, std::optional<int> formatVersion,
                      std::optional<std::string> materialsJson, bool trailer = true);

/// Appends the 24-byte trailer that saveVolume writes after OpenVDB's data (VolumeIO.cpp): the magic
/// "VDBCLAY\0", the payload size (uint64), the CRC-32 of the payload (uint32) and the format version 1
/// (uint32), little-endian. Lets a test hand-craft files that pass the integrity check.
void appendIntegrityTrailer(const std::string& path);
/// The format version this build writes (kFormatVersion).
int currentFormatVersion();

/// Writes a .vdb holding only a standard FloatGrid level set (a sphere).
void writeFloatGridFile(const std::string& path);

} // namespace vdbclay::test
