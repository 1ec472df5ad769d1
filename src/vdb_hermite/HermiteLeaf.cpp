#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/io/io.h>

#include <algorithm>
#include <array>
#include <mutex>
#include <stdexcept>
#include <string>

namespace vdbclay {

namespace {

/// Throws std::invalid_argument unless `data` holds one sample per set bit of its edge mask.
void requireSamplesMatchMask(const HermiteLeafData& data, const char* caller)
{
    std::size_t expected = 0;
    for (uint64_t w : data.edgeBits) expected += std::size_t(HermiteLeaf::bitCount(w));
    if (expected != data.samples.size())
        throw std::invalid_argument(std::string(caller) + ": sample count does not match the edge mask");
}

/// For 12 edge bits (the three edges of four voxels), which of the four voxels has a crossing edge.
constexpr std::array<uint8_t, 4096> kVoxelsOfEdgeBits = [] {
    std::array<uint8_t, 4096> out{};
    for (unsigned bits = 0; bits < 4096; ++bits)
        for (unsigned v = 0; v < 4; ++v)
            if ((bits >> (3 * v)) & 7u) out[bits] = uint8_t(out[bits] | (1u << v));
    return out;
}();

/// Twelve bits of a 192-bit group (three words) from bit `at`.
inline unsigned twelveBits(const uint64_t* group, unsigned at)
{
    const unsigned word = at >> 6, shift = at & 63;
    uint64_t bits = group[word] >> shift;
    if (shift > 52) bits |= group[word + 1] << (64 - shift);
    return unsigned(bits & 0xfffu);
}

} // namespace

void HermiteLeaf::rebuildPrefixAndMask()
{
    uint16_t running = 0;
    for (int w = 0; w < kEdgeWords; ++w) {
        prefix_[w] = running;
        running = uint16_t(running + bitCount(edgeBits_[w]));
    }
    // A voxel is active when one of its three edges crosses: the 192 edge bits of 64 voxels give one
    // word of the mask, four voxels per table lookup.
    auto& mask = this->getValueMask();
    for (Index m = 0; m < Index(kLeafVoxels / 64); ++m) {
        const uint64_t* group = &edgeBits_[3 * m];
        uint64_t voxels = 0;
        for (unsigned quad = 0; quad < 16; ++quad) voxels |= uint64_t(kVoxelsOfEdgeBits[twelveBits(group, 12 * quad)]) << (4 * quad);
        mask.getWord<uint64_t>(m) = voxels;
    }
}

void HermiteLeaf::assign(HermiteLeafData&& data)
{
    requireSamplesMatchMask(data, "HermiteLeaf::assign");
    std::copy(data.material.begin(), data.material.end(), this->buffer().data());
    edgeBits_ = data.edgeBits;
    samples_ = std::move(data.samples);
    samples_.shrink_to_fit();
    rebuildPrefixAndMask();
}

HermiteLeafData HermiteLeaf::extract() const
{
    HermiteLeafData data;
    for (Index n = 0; n < Index(kLeafVoxels); ++n) data.material[n] = this->getValue(n);
    data.edgeBits = edgeBits_;
    data.samples = samples_;
    return data;
}

std::optional<BlockChange> HermiteLeaf::changeTo(const HermiteLeafData& data) const
{
    const MaterialValue* materials = this->buffer().data();
    if (edgeBits_ == data.edgeBits && samples_ == data.samples && std::equal(data.material.begin(), data.material.end(), materials))
        return std::nullopt;
    requireSamplesMatchMask(data, "HermiteLeaf::changeTo");
    // Bit v of word v / 64: voxel v changes.
    std::array<uint64_t, kLeafVoxels / 64> changed{};
    auto mark = [&](Index voxel) { changed[voxel >> 6] |= uint64_t(1) << (voxel & 63); };
    for (Index v = 0; v < Index(kLeafVoxels); ++v)
        if (!(materials[v] == data.material[v])) mark(v);
    // Both sample arrays in edge-bit order: an edge in one mask only changes, one in both changes if
    // its sample does.
    std::size_t mine = 0, theirs = 0;
    for (int w = 0; w < kEdgeWords; ++w) {
        const uint64_t ownBits = edgeBits_[w], newBits = data.edgeBits[w];
        for (uint64_t bits = ownBits | newBits; bits; bits &= bits - 1) {
            const int bit = __builtin_ctzll(bits);
            const bool inOwn = (ownBits >> bit) & 1u, inNew = (newBits >> bit) & 1u;
            const bool differs = !(inOwn && inNew) || samples_[mine] != data.samples[theirs];
            mine += inOwn;
            theirs += inNew;
            if (differs) mark(Index((w * 64 + bit) / 3));
        }
    }
    BlockChange change;
    change.origin = {this->origin().x(), this->origin().y(), this->origin().z()};
    change.min = {kLeafDim - 1, kLeafDim - 1, kLeafDim - 1};
    change.max = {0, 0, 0};
    for (int w = 0; w < int(changed.size()); ++w)
        for (uint64_t bits = changed[w]; bits; bits &= bits - 1) {
            const Coord c = BaseLeaf::offsetToLocalCoord(Index(w * 64 + __builtin_ctzll(bits)));
            for (int a = 0; a < 3; ++a) {
                change.min[a] = std::min(change.min[a], uint8_t(c[a]));
                change.max[a] = std::max(change.max[a], uint8_t(c[a]));
            }
        }
    return change;
}

void HermiteLeaf::writeBuffers(std::ostream& os, bool toHalf) const
{
    BaseLeaf::writeBuffers(os, toHalf);
    os.write(reinterpret_cast<const char*>(edgeBits_.data()), sizeof(edgeBits_));
    const uint32_t count = uint32_t(samples_.size());
    os.write(reinterpret_cast<const char*>(&count), sizeof(count));
    if (count > 0) {
        openvdb::io::writeData<uint16_t>(os, reinterpret_cast<const uint16_t*>(samples_.data()), count * 3,
                                         openvdb::io::getDataCompression(os));
    }
}

void HermiteLeaf::readBuffers(std::istream& is, bool fromHalf)
{
    BaseLeaf::readBuffers(is, CoordBBox::inf(), fromHalf);
    is.read(reinterpret_cast<char*>(edgeBits_.data()), sizeof(edgeBits_));
    uint32_t count = 0;
    is.read(reinterpret_cast<char*>(&count), sizeof(count));
    if (!is) throw openvdb::IoError("truncated Hermite leaf");
    std::size_t expected = 0;
    for (uint64_t w : edgeBits_) expected += std::size_t(bitCount(w));
    if (count != expected) throw openvdb::IoError("corrupt Hermite leaf: sample count does not match edge mask");
    samples_.assign(count, PackedSample{});
    if (count > 0) {
        openvdb::io::readData<uint16_t>(is, reinterpret_cast<uint16_t*>(samples_.data()), count * 3,
                                        openvdb::io::getDataCompression(is));
    }
    if (!is) throw openvdb::IoError("truncated Hermite leaf");
    const auto storedMask = this->getValueMask();
    rebuildPrefixAndMask();
    if (storedMask != this->getValueMask())
        throw openvdb::IoError("corrupt Hermite leaf: active voxels do not match edge mask");
}

void HermiteLeaf::readBuffers(std::istream& is, const CoordBBox& clipBBox, bool fromHalf)
{
    readBuffers(is, fromHalf);
    MaterialValue background{};
    if (const void* bg = openvdb::io::getGridBackgroundValuePtr(is)) background = *static_cast<const MaterialValue*>(bg);
    clip(clipBBox, background);
}

openvdb::Index64 HermiteLeaf::memUsage() const
{
    return BaseLeaf::memUsage() + sizeof(edgeBits_) + sizeof(prefix_) + sizeof(samples_) +
           samples_.capacity() * sizeof(PackedSample);
}

void HermiteLeaf::clip(const CoordBBox& clipBBox, const ValueType& background)
{
    const CoordBBox nodeBBox = this->getNodeBoundingBox();
    if (clipBBox.isInside(nodeBBox)) return;
    HermiteLeafData data = extract();
    HermiteLeafData clipped;
    clipped.material = data.material;
    std::size_t next = 0;
    for (Index n = 0; n < Index(kLeafVoxels); ++n) {
        const bool inside = clipBBox.isInside(this->offsetToGlobalCoord(n));
        if (!inside) clipped.material[n] = background;
        for (int a = 0; a < 3; ++a) {
            const int bit = edgeBit(n, a);
            if (!((data.edgeBits[bit >> 6] >> (bit & 63)) & 1u)) continue;
            if (inside) {
                clipped.edgeBits[bit >> 6] |= uint64_t(1) << (bit & 63);
                clipped.samples.push_back(data.samples[next]);
            }
            ++next;
        }
    }
    assign(std::move(clipped));
}

void initializeHermiteGrid()
{
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        if (!HermiteGrid::isRegistered()) HermiteGrid::registerGrid();
    });
}

void pruneNodes(HermiteTree& tree, const std::set<Coord>& lowers)
{
    std::set<Coord> uppers;
    for (const Coord& o : lowers) {
        uppers.insert(alignDown(o, kUpperDim));
        const HermiteLower* node = tree.probeConstNode<HermiteLower>(o);
        MaterialValue value;
        bool state = false;
        if (node && node->isConstant(value, state, MaterialValue{}) && !state) tree.addTile(2, o, value, false);
    }
    bool erased = false;
    for (const Coord& o : uppers) {
        const HermiteUpper* node = tree.probeConstNode<HermiteUpper>(o);
        MaterialValue value;
        bool state = false;
        if (node && node->isConstant(value, state, MaterialValue{}) && !state) {
            tree.addTile(3, o, value, false);
            erased = erased || !value.solid();
        }
    }
    if (erased) tree.root().eraseBackgroundTiles();
}


} // namespace vdbclay

namespace vdbclay {

bool uniformWithoutSamples(const HermiteLeafData& data, MaterialValue& value)
{
    if (!data.samples.empty()) return false;
    value = data.material[0];
    return std::all_of(data.material.begin(), data.material.end(), [&](MaterialValue m) { return m == value; });
}

namespace {

void placeTile(HermiteTree& tree, const Coord& origin, const MaterialValue& value, std::set<Coord>& lowers)
{
    if (tree.getValue(origin) == value && !tree.probeConstLeaf(origin)) return;
    tree.addTile(1, origin, value, false);
    lowers.insert(alignDown(origin, kLowerDim));
}

} // namespace

void placeLeaves(HermiteTree& tree, const std::vector<Coord>& origins, std::vector<HermiteLeafData>& data)
{
    std::set<Coord> lowers;
    for (std::size_t i = 0; i < origins.size(); ++i) {
        MaterialValue uniform;
        if (uniformWithoutSamples(data[i], uniform)) placeTile(tree, origins[i], uniform, lowers);
        else tree.touchLeaf(origins[i])->assign(std::move(data[i]));
    }
    pruneNodes(tree, lowers);
}

void placeUniformLeaves(HermiteTree& tree, const std::vector<Coord>& origins, const std::vector<MaterialValue>& values)
{
    std::set<Coord> lowers;
    for (std::size_t i = 0; i < origins.size(); ++i) placeTile(tree, origins[i], values[i], lowers);
    pruneNodes(tree, lowers);
}

} // namespace vdbclay
