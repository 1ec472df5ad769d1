// The Hermite grid: an OpenVDB tree whose voxels hold a material id and whose leaves also hold the
// Hermite samples (crossing offset + normal) of the voxels' three positive edges.
//
// OpenVDB-heavy: include this only in the translation units that walk or build the tree.
//
// Invariants every writer keeps (HermiteLeaf::assign enforces the per-leaf ones):
//  * edge (v, v + e_axis) carries a sample iff material(v) != material(v + e_axis); the sample lives
//    in the leaf that contains v, so a voxel whose positive edge crosses is always inside a leaf;
//  * a voxel is active iff at least one of its three positive edges carries a sample, so the active
//    voxel count is the surface voxel count and a leaf without samples and with one material is
//    exactly what OpenVDB's prune folds into a tile;
//  * tiles are inactive and carry a material (0 = empty, the background).
#pragma once

#include "vdb_hermite/BlockChange.h"
#include "vdb_hermite/Materials.h"
#include "vdb_hermite/Quantize.h"
#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VoxelMask.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/Compression.h>
#include <openvdb/tree/LeafNode.h>

#include <array>
#include <optional>
#include <ostream>
#include <set>
#include <type_traits>
#include <vector>

namespace vdbclay {

/// The value type of the tree: one material id per voxel or tile.
struct MaterialValue {
    MaterialId id = kEmptyMaterial;

    bool solid() const { return id != kEmptyMaterial; }
    friend bool operator==(MaterialValue a, MaterialValue b) { return a.id == b.id; }
    friend bool operator!=(MaterialValue a, MaterialValue b) { return a.id != b.id; }
    friend bool operator<(MaterialValue a, MaterialValue b) { return a.id < b.id; }
    friend bool operator>(MaterialValue a, MaterialValue b) { return a.id > b.id; }
    // OpenVDB's generic tolerance arithmetic (prune, isApproxEqual) is meaningless for ids.
    friend MaterialValue operator+(MaterialValue a, float) { return a; }
    friend MaterialValue operator-(MaterialValue a) { return a; }
    friend std::ostream& operator<<(std::ostream& os, MaterialValue v) { return os << v.id; }
};
static_assert(sizeof(MaterialValue) == 2, "MaterialValue is part of the file format");

} // namespace vdbclay

namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
template<> inline vdbclay::MaterialValue zeroVal<vdbclay::MaterialValue>() { return {}; }
template<> inline const char* typeNameAsString<vdbclay::MaterialValue>() { return "vdbclay_material16"; }
namespace math {
template<> inline vdbclay::MaterialValue negative(const vdbclay::MaterialValue& v) { return v; }
OPENVDB_EXACT_IS_APPROX_EQUAL(vdbclay::MaterialValue)
template<> inline auto cwiseAdd(const vdbclay::MaterialValue& v, const float) { return v; }
} // namespace math
} // namespace OPENVDB_VERSION_NAME
} // namespace openvdb

namespace vdbclay {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::Index;

constexpr int kLeafVoxels = kLeafDim * kLeafDim * kLeafDim;
constexpr int kEdgeBits = kLeafVoxels * 3;        // one bit per (voxel, positive edge)
constexpr int kEdgeWords = kEdgeBits / 64;

/// What a leaf holds, in plain arrays: built by the CSG kernel, then moved into a HermiteLeaf.
struct HermiteLeafData {
    std::array<MaterialValue, kLeafVoxels> material{};
    std::array<uint64_t, kEdgeWords> edgeBits{}; // bit (voxelOffset * 3 + axis)
    std::vector<PackedSample> samples;           // one per set bit, in bit order
};

/// A LeafNode of material ids with the Hermite samples of its voxels' positive edges beside it
/// (the way PointDataLeafNode keeps attributes beside its index buffer). Samples are stored
/// sparsely: a 1536-bit edge mask, a per-word prefix count, and a packed array.
class HermiteLeaf : public openvdb::tree::LeafNode<MaterialValue, kLeafLog2Dim> {
public:
    using BaseLeaf = openvdb::tree::LeafNode<MaterialValue, kLeafLog2Dim>;
    using LeafNodeType = HermiteLeaf;
    using ValueType = MaterialValue;
    using BuildType = MaterialValue;
    using Ptr = openvdb::SharedPtr<HermiteLeaf>;
    template<typename OtherValueType>
    struct ValueConverter { using Type = openvdb::tree::LeafNode<OtherValueType, kLeafLog2Dim>; };
    template<typename OtherNodeType>
    struct SameConfiguration {
        static const bool value = openvdb::tree::SameLeafConfig<LOG2DIM, OtherNodeType>::value;
    };

    HermiteLeaf() = default;
    HermiteLeaf(const HermiteLeaf&) = default;
    HermiteLeaf& operator=(const HermiteLeaf&) = default;
    explicit HermiteLeaf(const Coord& origin, const ValueType& value = {}, bool active = false)
        : BaseLeaf(origin, value, active) {}
    HermiteLeaf(openvdb::PartialCreate, const Coord& origin, const ValueType& value = {}, bool active = false)
        : BaseLeaf(openvdb::PartialCreate(), origin, value, active) {}
    template<typename OtherValueType>
    HermiteLeaf(const openvdb::tree::LeafNode<OtherValueType, kLeafLog2Dim>& other, const ValueType& background,
                openvdb::TopologyCopy)
        : BaseLeaf(other, background, openvdb::TopologyCopy()) {}

    static constexpr int edgeBit(Index voxelOffset, int axis) { return int(voxelOffset) * 3 + axis; }

    /// Set bits of a word, inline: without a POPCNT target the builtin is a library call, and this
    /// lookup runs for every sample the mesher reads.
    static int bitCount(uint64_t w)
    {
#if defined(__POPCNT__)
        return __builtin_popcountll(w);
#else
        w -= (w >> 1) & 0x5555555555555555ull;
        w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
        w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
        return int((w * 0x0101010101010101ull) >> 56);
#endif
    }

    /// The sample on the positive `axis` edge of the voxel, or nullptr when that edge does not cross.
    const PackedSample* sample(Index voxelOffset, int axis) const
    {
        const int bit = edgeBit(voxelOffset, axis);
        const uint64_t word = edgeBits_[bit >> 6];
        if (!((word >> (bit & 63)) & 1u)) return nullptr;
        const uint64_t below = word & ((uint64_t(1) << (bit & 63)) - 1);
        return &samples_[prefix_[bit >> 6] + bitCount(below)];
    }
    std::size_t sampleCount() const { return samples_.size(); }

    /// Replaces the whole content (materials, samples, active states). Throws std::invalid_argument
    /// when the sample count does not match the edge mask.
    void assign(HermiteLeafData&& data);
    /// Copies the content out, the inverse of assign().
    HermiteLeafData extract() const;
    /// What assign(data) would change: the bounds of the voxels whose material or samples would differ,
    /// or nullopt where it would leave this leaf as it is.
    std::optional<BlockChange> changeTo(const HermiteLeafData& data) const;

    // Tree-facing overrides: the tree templates call these on the child node type directly.
    void readBuffers(std::istream& is, bool fromHalf = false);
    void readBuffers(std::istream& is, const CoordBBox& clipBBox, bool fromHalf = false);
    void writeBuffers(std::ostream& os, bool toHalf = false) const;
    openvdb::Index64 memUsage() const;
    /// Voxels outside the box become background; their samples go with them.
    void clip(const CoordBBox& clipBBox, const ValueType& background);

    // Tree traversal returns leaves through these; they must yield this type, not the base LeafNode.
    HermiteLeaf* touchLeaf(const Coord&) { return this; }
    template<typename AccessorT> HermiteLeaf* touchLeafAndCache(const Coord&, AccessorT&) { return this; }
    HermiteLeaf* probeLeaf(const Coord&) { return this; }
    const HermiteLeaf* probeLeaf(const Coord&) const { return this; }
    const HermiteLeaf* probeConstLeaf(const Coord&) const { return this; }
    template<typename AccessorT> HermiteLeaf* probeLeafAndCache(const Coord&, AccessorT&) { return this; }
    template<typename AccessorT> const HermiteLeaf* probeLeafAndCache(const Coord&, AccessorT&) const { return this; }
    template<typename AccessorT> const HermiteLeaf* probeConstLeafAndCache(const Coord&, AccessorT&) const { return this; }
    template<typename NodeT, typename AccessorT> NodeT* probeNodeAndCache(const Coord&, AccessorT&)
    {
        if constexpr (std::is_same_v<NodeT, HermiteLeaf>) return this;
        else return nullptr;
    }
    template<typename NodeT, typename AccessorT> const NodeT* probeConstNodeAndCache(const Coord&, AccessorT&) const
    {
        if constexpr (std::is_same_v<NodeT, HermiteLeaf>) return this;
        else return nullptr;
    }
    void addLeaf(HermiteLeaf*) {}
    template<typename AccessorT> void addLeafAndCache(HermiteLeaf*, AccessorT&) {}

    bool operator==(const HermiteLeaf& other) const
    {
        return BaseLeaf::operator==(other) && edgeBits_ == other.edgeBits_ && samples_ == other.samples_;
    }
    bool operator!=(const HermiteLeaf& other) const { return !(*this == other); }

    // The tree's iterators need leaf iterators typed on this class, not on the base LeafNode.
protected:
    using MaskOnIterator = NodeMaskType::OnIterator;
    using MaskOffIterator = NodeMaskType::OffIterator;
    using MaskDenseIterator = NodeMaskType::DenseIterator;
    friend class openvdb::tree::IteratorBase<MaskOnIterator, HermiteLeaf>;
    friend class openvdb::tree::IteratorBase<MaskOffIterator, HermiteLeaf>;
    friend class openvdb::tree::IteratorBase<MaskDenseIterator, HermiteLeaf>;

public:
    using ValueOnIter = BaseLeaf::ValueIter<MaskOnIterator, HermiteLeaf, const ValueType, BaseLeaf::ValueOn>;
    using ValueOnCIter = BaseLeaf::ValueIter<MaskOnIterator, const HermiteLeaf, const ValueType, BaseLeaf::ValueOn>;
    using ValueOffIter = BaseLeaf::ValueIter<MaskOffIterator, HermiteLeaf, const ValueType, BaseLeaf::ValueOff>;
    using ValueOffCIter = BaseLeaf::ValueIter<MaskOffIterator, const HermiteLeaf, const ValueType, BaseLeaf::ValueOff>;
    using ValueAllIter = BaseLeaf::ValueIter<MaskDenseIterator, HermiteLeaf, const ValueType, BaseLeaf::ValueAll>;
    using ValueAllCIter = BaseLeaf::ValueIter<MaskDenseIterator, const HermiteLeaf, const ValueType, BaseLeaf::ValueAll>;
    using ChildOnIter = BaseLeaf::ChildIter<MaskOnIterator, HermiteLeaf, BaseLeaf::ChildOn>;
    using ChildOnCIter = BaseLeaf::ChildIter<MaskOnIterator, const HermiteLeaf, BaseLeaf::ChildOn>;
    using ChildOffIter = BaseLeaf::ChildIter<MaskOffIterator, HermiteLeaf, BaseLeaf::ChildOff>;
    using ChildOffCIter = BaseLeaf::ChildIter<MaskOffIterator, const HermiteLeaf, BaseLeaf::ChildOff>;
    using ChildAllIter = BaseLeaf::DenseIter<HermiteLeaf, ValueType, BaseLeaf::ChildAll>;
    using ChildAllCIter = BaseLeaf::DenseIter<const HermiteLeaf, const ValueType, BaseLeaf::ChildAll>;

#define VDBCLAY_LEAF_ITERS(Name, Iter, CIter, BeginMask, EndMask)                         \
    CIter cbegin##Name() const { return CIter(this->getValueMask().BeginMask(), this); } \
    CIter begin##Name() const { return CIter(this->getValueMask().BeginMask(), this); }  \
    Iter begin##Name() { return Iter(this->getValueMask().BeginMask(), this); }          \
    CIter cend##Name() const { return CIter(this->getValueMask().EndMask(), this); }     \
    CIter end##Name() const { return CIter(this->getValueMask().EndMask(), this); }      \
    Iter end##Name() { return Iter(this->getValueMask().EndMask(), this); }
    VDBCLAY_LEAF_ITERS(ValueOn, ValueOnIter, ValueOnCIter, beginOn, endOn)
    VDBCLAY_LEAF_ITERS(ValueOff, ValueOffIter, ValueOffCIter, beginOff, endOff)
    VDBCLAY_LEAF_ITERS(ValueAll, ValueAllIter, ValueAllCIter, beginDense, endDense)
    // A leaf has no children: its child iterators start at the end.
    VDBCLAY_LEAF_ITERS(ChildOn, ChildOnIter, ChildOnCIter, endOn, endOn)
    VDBCLAY_LEAF_ITERS(ChildOff, ChildOffIter, ChildOffCIter, endOff, endOff)
    VDBCLAY_LEAF_ITERS(ChildAll, ChildAllIter, ChildAllCIter, beginDense, endDense)
#undef VDBCLAY_LEAF_ITERS

private:
    void rebuildPrefixAndMask();

    std::array<uint64_t, kEdgeWords> edgeBits_{};
    std::array<uint16_t, kEdgeWords> prefix_{};
    std::vector<PackedSample> samples_;
};

using HermiteTree = openvdb::tree::Tree<openvdb::tree::RootNode<
    openvdb::tree::InternalNode<openvdb::tree::InternalNode<HermiteLeaf, 4>, 5>>>;
using HermiteGrid = openvdb::Grid<HermiteTree>;
using HermiteLower = HermiteTree::RootNodeType::ChildNodeType::ChildNodeType; // 128^3, tiles of 8^3
using HermiteUpper = HermiteTree::RootNodeType::ChildNodeType;                // 4096^3, tiles of 128^3

/// Calls fn(bbox, value) for every tile of the tree (root, upper and lower node tiles, solid or empty),
/// never for its voxels. Walks the node tables directly: OpenVDB's value iterators spend tens of
/// nanoseconds a tile, and one upper node alone holds 32,768.
template<typename Fn>
void forEachTile(const HermiteTree& tree, Fn&& fn)
{
    for (auto tile = tree.root().cbeginValueAll(); tile; ++tile)
        fn(CoordBBox::createCube(tile.getCoord(), HermiteUpper::DIM), *tile);
    for (auto upper = tree.root().cbeginChildOn(); upper; ++upper) {
        const auto* upperTable = upper->getTable();
        for (Index i = 0; i < HermiteUpper::NUM_VALUES; ++i) {
            if (!upper->isChildMaskOn(i)) {
                fn(CoordBBox::createCube(upper->offsetToGlobalCoord(i), HermiteLower::DIM), upperTable[i].getValue());
                continue;
            }
            const HermiteLower& lower = *upperTable[i].getChild();
            const auto* lowerTable = lower.getTable();
            for (Index j = 0; j < HermiteLower::NUM_VALUES; ++j)
                if (!lower.isChildMaskOn(j))
                    fn(CoordBBox::createCube(lower.offsetToGlobalCoord(j), HermiteLeaf::DIM), lowerTable[j].getValue());
        }
    }
}

constexpr int kLowerDim = 128;  // voxels per side of a HermiteLower node
constexpr int kUpperDim = 4096; // voxels per side of a HermiteUpper node
inline Coord alignDown(const Coord& c, int dim) { return Coord(c.x() & ~(dim - 1), c.y() & ~(dim - 1), c.z() & ~(dim - 1)); }

/// Folds the HermiteLower nodes at `lowers` (their origins) and their HermiteUpper parents that became
/// uniform into tiles, and erases empty root entries. Works on the tree directly: OpenVDB 10's
/// ValueAccessor::addTile ignores levels above the node it has cached. Not openvdb::tools::prune, which
/// would fold a leaf of one material whose border edges carry samples.
void pruneNodes(HermiteTree& tree, const std::set<Coord>& lowers);

/// Whether a leaf's data is one material throughout without a sample (then `value` holds it).
bool uniformWithoutSamples(const HermiteLeafData& data, MaterialValue& value);

/// Puts leaves built as plain data into a tree, where the tree holds no leaf of theirs yet: a leaf of one
/// material without samples becomes a tile (none where the tree already has that value), the others
/// leaves; then the nodes made uniform are pruned. `data` is moved from.
void placeLeaves(HermiteTree& tree, const std::vector<Coord>& origins, std::vector<HermiteLeafData>& data);
/// The same for leaves of one material without samples, given by that material alone (a solid's
/// interior: its leaves as data would take a kilobyte each); call after placeLeaves for the others.
void placeUniformLeaves(HermiteTree& tree, const std::vector<Coord>& origins, const std::vector<MaterialValue>& values);

/// Metadata keys stored on the grid.
constexpr const char* kFormatVersionKey = "vdbclay_format_version";
constexpr const char* kMaterialsKey = "vdbclay_materials";
constexpr const char* kMaskKey = "vdbclay_mask"; // VoxelMask::encode(), present only for a mask in use
constexpr int kFormatVersion = 1;

namespace detail {
/// What a Volume owns; see Volume.h.
struct VolumeGrid {
    HermiteGrid::Ptr grid;
    MaterialTable materials;
    VoxelMask mask;
    int formatVersion = kFormatVersion;
};
} // namespace detail

/// Registers the Hermite grid type with OpenVDB (idempotent, thread-safe).
void initializeHermiteGrid();

} // namespace vdbclay
