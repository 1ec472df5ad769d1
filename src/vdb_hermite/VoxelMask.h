// The sculptor's mask: a set of voxels no brush changes. Kept beside the Hermite grid, not in it, so
// the meshers, the levels of detail and the brick codec never see it: a brush runs unmasked and the
// masked voxels are put back afterwards (sculpt/MaskedEdit.h).
//
// Stored sparsely as one 512-bit word set per 8^3 leaf that holds a masked voxel, with an `inverted`
// flag so that inverting a mask painted on a small region masks all the rest of space without listing it.
#pragma once

#include "vdb_hermite/Volume.h"

#include <array>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>

namespace vdbclay {

using IndexCoord = std::array<int32_t, 3>;

/// Damaged mask bytes (a file's or store's): what() says what is wrong.
class MaskFormatError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class VoxelMask {
public:
    using LeafBits = std::array<uint64_t, kLeafDim * kLeafDim * kLeafDim / 64>; // bit = voxel offset in its leaf

    bool masked(const IndexCoord& voxel) const;
    /// Whether any voxel at all is masked (the kernels skip the mask's work otherwise).
    bool any() const { return inverted_ || !leaves_.empty(); }
    bool inverted() const { return inverted_; }
    /// Masks (true) or unmasks (false) one voxel.
    void set(const IndexCoord& voxel, bool masked);
    /// Masks or unmasks every voxel of the leaf at `leafOrigin` at once.
    void setLeaf(const IndexCoord& leafOrigin, bool masked);
    /// Every voxel changes state: masked ones are freed, all others (all of space) masked.
    void invert() { inverted_ = !inverted_; }
    void clear();

    /// The leaves whose voxels are listed (masked, or free when inverted), keyed by leaf origin.
    const std::map<IndexCoord, LeafBits>& listedLeaves() const { return leaves_; }
    /// Whether a leaf may hold masked voxels: a listed leaf, or any leaf of an inverted mask.
    bool touchesLeaf(const IndexCoord& leafOrigin) const { return inverted_ || leaves_.count(leafOrigin) != 0; }

    /// Compact bytes (a version, the flag, the listed leaves); decode() reads them back exactly.
    std::string encode() const;
    /// Throws MaskFormatError for bytes encode() could not have written.
    static VoxelMask decode(const std::string& bytes);

    friend bool operator==(const VoxelMask& a, const VoxelMask& b) { return a.inverted_ == b.inverted_ && a.leaves_ == b.leaves_; }
    friend bool operator!=(const VoxelMask& a, const VoxelMask& b) { return !(a == b); }

private:
    bool inverted_ = false;
    std::map<IndexCoord, LeafBits> leaves_; // never holds an all-zero entry
};

/// The origin of the leaf holding a voxel.
inline IndexCoord leafOriginOf(const IndexCoord& voxel)
{
    return {voxel[0] & ~int32_t(kLeafDim - 1), voxel[1] & ~int32_t(kLeafDim - 1), voxel[2] & ~int32_t(kLeafDim - 1)};
}

} // namespace vdbclay
