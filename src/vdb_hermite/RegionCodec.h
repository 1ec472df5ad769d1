// A box of whole leaves as bytes, and back: what a scene store keeps per brick. Each leaf is written by
// OpenVDB's leaf serialization (HermiteLeaf::writeBuffers), the whole Blosc-compressed behind a small
// header and sealed by a checksum. Unlike a .vdb stream of the box (encodeVolume), decoding builds no
// tree: the leaves come out on their own, on any thread, and pasting moves them into a volume without a
// copy. Light header: no OpenVDB templates.
#pragma once

#include "vdb_hermite/VolumeRegions.h"

#include <memory>
#include <string>

namespace vdbclay {

/// A box's content outside any volume: a leaf or a uniform material per 8^3 block.
class DecodedRegion {
public:
    struct Impl;

    /// The box filled with one material (0: empty space).
    DecodedRegion(const LeafAlignedBox& box, MaterialId material);
    ~DecodedRegion();
    DecodedRegion(DecodedRegion&&) noexcept;
    DecodedRegion& operator=(DecodedRegion&&) noexcept;

    /// What the box takes in a volume once pasted, counted as regionMemoryBytes() counts it.
    uint64_t memoryBytes() const;

    Impl& impl() { return *impl_; }

private:
    std::unique_ptr<Impl> impl_;
};

/// The box's content as bytes; the same content always gives the same bytes. `leafCount` (optional)
/// receives the number of leaves written.
std::string encodeRegion(const Volume& volume, const LeafAlignedBox& box, uint32_t* leafCount = nullptr);

/// The two steps of encodeRegion, apart for tests and fuzzers that craft bodies: the body (a material
/// id per block, 0xffff for a block stored as a leaf, then the leaves' serialization in block order),
/// and the header (its leaf count taken from the body's block table), compression and checksum around it.
std::string encodeRegionBody(const Volume& volume, const LeafAlignedBox& box);
std::string sealRegion(const std::string& body, const LeafAlignedBox& box, double voxelSize, uint32_t* leafCount = nullptr);

/// Reads what encodeRegion wrote for `box` of a volume of `voxelSize` whose materials table holds
/// `materialCount` materials; also a .vdb stream of the box (encodeVolume), the form stores of format
/// version 1 hold. Throws VolumeIOError naming `name` when the bytes are damaged, were written for
/// another box or voxel size, or use an undefined material.
DecodedRegion decodeRegion(const std::string& bytes, const LeafAlignedBox& box, double voxelSize,
                           std::size_t materialCount, const std::string& name);

/// Replaces what `volume` holds inside the region's box by the region's content, moving its leaves in
/// (the region is left empty), and folds nodes that became uniform.
void pasteRegion(Volume& volume, DecodedRegion&& region);

} // namespace vdbclay
