#include "vdb_hermite/RegionCodec.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/RegionBlocks.h"
#include "vdb_hermite/VolumeIO.h"

#include <blosc.h>
#include <openvdb/io/io.h>
#include <zlib.h>

#include <cstring>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <streambuf>
#include <vector>

namespace vdbclay {

namespace {

constexpr char kMagic[4] = {'V', 'C', 'L', 'R'};
constexpr uint32_t kCodecVersion = 1;

/// The header: magic, codec version, box min (3 x int32), box edge, voxel size (double), leaf count and
/// body bytes once decompressed (uint32 each), packed in this order.
constexpr std::size_t kHeaderBytes = sizeof(kMagic) + 4 + 12 + 4 + 8 + 4 + 4;
constexpr std::size_t kTrailerBytes = 4; // CRC-32 of everything before it

/// The slot table marks a block stored as a leaf with a material id no table can hold.
constexpr MaterialId kLeafSlot = 0xffff;
/// A leaf's serialization never exceeds this: its value mask and flag byte, its materials, its edge
/// mask, a sample count and a sample per edge.
constexpr std::size_t kMaxLeafBytes =
    64 + 1 + kLeafVoxels * sizeof(MaterialValue) + kEdgeWords * 8 + 4 + 3 * kLeafVoxels * sizeof(PackedSample);

using region_blocks::blockCount;
using region_blocks::blockOrigin;

uint32_t checksum(const char* data, std::size_t size)
{
    uLong crc = crc32(0L, Z_NULL, 0);
    while (size > 0) {
        const uInt chunk = uInt(std::min<std::size_t>(size, 1u << 30));
        crc = crc32(crc, reinterpret_cast<const Bytef*>(data), chunk);
        data += chunk;
        size -= chunk;
    }
    return uint32_t(crc);
}

template<typename T>
void put(std::string& out, const T& value)
{
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}
template<typename T>
T take(const char*& at)
{
    T value;
    std::memcpy(&value, at, sizeof(T));
    at += sizeof(T);
    return value;
}

/// Reads a buffer in place (std::istringstream would copy it).
struct BufferSource : std::streambuf {
    BufferSource(char* data, std::size_t size) { setg(data, data, data + size); }
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override
    {
        if (off != 0 || dir != std::ios_base::cur) return pos_type(off_type(-1));
        return pos_type(gptr() - eback());
    }
};

} // namespace

struct DecodedRegion::Impl {
    LeafAlignedBox box;
    std::vector<MaterialId> tiles;                    // per block: its material where it has no leaf
    std::vector<std::unique_ptr<HermiteLeaf>> leaves; // per block: its leaf, or null
};

namespace {

using Damaged = std::function<VolumeIOError(const std::string&)>;

void requireDefinedMaterials(const HermiteLeaf& leaf, std::size_t materialCount, const Damaged& damaged)
{
    const MaterialValue* values = leaf.buffer().data();
    MaterialId largest = 0; // a reduction without an early exit: the loop vectorizes
    for (Index n = 0; n < Index(kLeafVoxels); ++n) largest = std::max(largest, values[n].id);
    if (largest > materialCount) throw damaged("it uses an undefined material");
}

/// The blocks of a region that came as a .vdb stream (stores of format version 1), taken out of its tree.
void takeFromVolume(Volume&& part, DecodedRegion::Impl& out, std::size_t materialCount, const Damaged& damaged)
{
    HermiteTree& tree = part.impl().grid->tree();
    for (std::size_t b = 0; b < out.tiles.size(); ++b) {
        const Coord o = blockOrigin(out.box, b);
        if (tree.probeConstLeaf(o)) {
            out.leaves[b].reset(tree.stealNode<HermiteLeaf>(o, MaterialValue{}, false));
            requireDefinedMaterials(*out.leaves[b], materialCount, damaged);
        } else {
            out.tiles[b] = tree.getValue(o).id;
            if (out.tiles[b] > materialCount) throw damaged("it uses an undefined material");
        }
    }
}

} // namespace

DecodedRegion::DecodedRegion(const LeafAlignedBox& box, MaterialId material) : impl_(std::make_unique<Impl>())
{
    impl_->box = box;
    impl_->tiles.assign(blockCount(box), material);
    impl_->leaves.resize(blockCount(box));
}
DecodedRegion::~DecodedRegion() = default;
DecodedRegion::DecodedRegion(DecodedRegion&&) noexcept = default;
DecodedRegion& DecodedRegion::operator=(DecodedRegion&&) noexcept = default;

uint64_t DecodedRegion::memoryBytes() const
{
    uint64_t bytes = nodeShareBytes(impl_->box);
    for (const auto& leaf : impl_->leaves)
        if (leaf) bytes += leaf->memUsage();
    return bytes;
}

std::string encodeRegionBody(const Volume& volume, const LeafAlignedBox& box)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    const std::size_t blocks = blockCount(box);
    std::vector<const HermiteLeaf*> leaves(blocks, nullptr);
    std::string body;
    body.reserve(blocks * sizeof(MaterialId));
    for (std::size_t b = 0; b < blocks; ++b) {
        const Coord o = blockOrigin(box, b);
        leaves[b] = tree.probeConstLeaf(o);
        put(body, leaves[b] ? kLeafSlot : tree.getValue(o).id);
    }
    std::ostringstream leafBytes(std::ios::binary); // uncompressed: Blosc takes the whole body
    openvdb::io::setDataCompression(leafBytes, openvdb::io::COMPRESS_NONE);
    for (const HermiteLeaf* leaf : leaves)
        if (leaf) leaf->writeBuffers(leafBytes);
    return body + leafBytes.str();
}

std::string sealRegion(const std::string& body, const LeafAlignedBox& box, double voxelSize, uint32_t* leafCount)
{
    uint32_t leaves = 0; // the block table's leaf slots (as many of the table as the body holds)
    for (std::size_t b = 0; b < blockCount(box) && (b + 1) * sizeof(MaterialId) <= body.size(); ++b) {
        const char* at = body.data() + b * sizeof(MaterialId);
        leaves += take<MaterialId>(at) == kLeafSlot;
    }
    if (leafCount) *leafCount = leaves;
    std::string out;
    out.append(kMagic, sizeof(kMagic));
    put(out, kCodecVersion);
    for (int a = 0; a < 3; ++a) put(out, box.min[a]);
    put(out, box.edge);
    put(out, voxelSize);
    put(out, leaves);
    put(out, uint32_t(body.size()));
    out.resize(kHeaderBytes + body.size() + BLOSC_MAX_OVERHEAD);
    // Typesize 1: the ids' high bytes and the samples' fields line up badly with any larger one.
    const int size = blosc_compress_ctx(5, BLOSC_SHUFFLE, 1, body.size(), body.data(), out.data() + kHeaderBytes,
                                        out.size() - kHeaderBytes, "lz4", 0, 1);
    if (size <= 0) throw VolumeIOError("could not compress a region of " + std::to_string(body.size()) + " bytes");
    out.resize(kHeaderBytes + std::size_t(size));
    put(out, checksum(out.data(), out.size()));
    return out;
}

std::string encodeRegion(const Volume& volume, const LeafAlignedBox& box, uint32_t* leafCount)
{
    return sealRegion(encodeRegionBody(volume, box), box, volume.voxelSize(), leafCount);
}

DecodedRegion decodeRegion(const std::string& bytes, const LeafAlignedBox& box, double voxelSize,
                           std::size_t materialCount, const std::string& name)
{
    const Damaged damaged = [&](const std::string& why) { return VolumeIOError("'" + name + "' is damaged: " + why); };
    DecodedRegion region(box, kEmptyMaterial);
    DecodedRegion::Impl& out = region.impl();

    constexpr char kVdbMagic[4] = {0x20, 0x42, 0x44, 0x56}; // OpenVDB's, as a little-endian int64
    if (bytes.size() >= sizeof(kVdbMagic) && std::memcmp(bytes.data(), kVdbMagic, sizeof(kVdbMagic)) == 0) {
        Volume part = decodeVolume(bytes, name);
        if (part.voxelSize() != voxelSize) throw damaged("its voxel size does not match its level");
        takeFromVolume(std::move(part), out, materialCount, damaged);
        return region;
    }

    if (bytes.size() < kHeaderBytes + kTrailerBytes || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
        throw damaged("it is not a VDBClay region");
    const std::size_t sealed = bytes.size() - kTrailerBytes;
    const char* at = bytes.data() + sealed;
    if (take<uint32_t>(at) != checksum(bytes.data(), sealed)) throw damaged("its checksum does not match");
    at = bytes.data() + sizeof(kMagic);
    const uint32_t version = take<uint32_t>(at);
    if (version != kCodecVersion)
        throw VolumeIOError("'" + name + "' has region format version " + std::to_string(version) +
                            "; this build reads version " + std::to_string(kCodecVersion));
    bool sameBox = true;
    for (int a = 0; a < 3; ++a) sameBox = take<int32_t>(at) == box.min[a] && sameBox;
    sameBox = take<int32_t>(at) == box.edge && sameBox;
    if (!sameBox) throw damaged("it holds another region");
    if (take<double>(at) != voxelSize) throw damaged("its voxel size does not match its level");
    const uint32_t leafCount = take<uint32_t>(at);
    const uint32_t rawBytes = take<uint32_t>(at);
    const std::size_t blocks = out.tiles.size();
    if (leafCount > blocks) throw damaged("it claims " + std::to_string(leafCount) + " leaves");
    const std::size_t slotBytes = blocks * sizeof(MaterialId);
    if (rawBytes < slotBytes || rawBytes > slotBytes + leafCount * kMaxLeafBytes)
        throw damaged("its size does not fit its leaves");

    const char* compressed = bytes.data() + kHeaderBytes;
    const std::size_t compressedBytes = sealed - kHeaderBytes;
    std::size_t decoded = 0;
    if (blosc_cbuffer_validate(compressed, compressedBytes, &decoded) != 0 || decoded != rawBytes)
        throw damaged("its compressed data does not hold what its header says");
    // One buffer per thread, kept: a fresh one per brick would leave holes that the leaves decoded into
    // them pin, so a streaming process would grow past its budget.
    thread_local std::vector<char> raw;
    raw.resize(rawBytes);
    if (blosc_decompress_ctx(compressed, raw.data(), raw.size(), 1) != int(rawBytes))
        throw damaged("its compressed data does not decompress");

    at = raw.data();
    uint32_t leaves = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
        const MaterialId id = take<MaterialId>(at);
        if (id == kLeafSlot) {
            out.leaves[b] = std::make_unique<HermiteLeaf>(blockOrigin(box, b));
            ++leaves;
        } else if (id > materialCount) {
            throw damaged("it uses an undefined material");
        } else {
            out.tiles[b] = id;
        }
    }
    if (leaves != leafCount) throw damaged("its block table does not match its leaf count");

    BufferSource source(raw.data() + slotBytes, raw.size() - slotBytes);
    std::istream in(&source);
    openvdb::io::setCurrentVersion(in);
    openvdb::io::setDataCompression(in, openvdb::io::COMPRESS_NONE);
    try {
        for (auto& leaf : out.leaves) {
            if (!leaf) continue;
            leaf->readBuffers(in);
            requireDefinedMaterials(*leaf, materialCount, damaged);
        }
    } catch (const openvdb::Exception& e) {
        throw damaged(e.what());
    }
    if (!in || in.tellg() != std::streamoff(raw.size() - slotBytes)) throw damaged("its leaves do not end where its header says");
    return region;
}

void pasteRegion(Volume& volume, DecodedRegion&& region)
{
    DecodedRegion::Impl& r = region.impl();
    region_blocks::replaceBlocks(volume.impl().grid->tree(), r.box, [&](std::size_t b, const Coord&) {
        return std::pair(r.leaves[b].release(), MaterialValue{r.tiles[b]});
    });
    r.tiles.assign(r.tiles.size(), kEmptyMaterial);
}

} // namespace vdbclay
