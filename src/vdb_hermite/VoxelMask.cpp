#include "vdb_hermite/VoxelMask.h"

#include <cstring>

namespace vdbclay {

namespace {

int voxelBit(const IndexCoord& voxel)
{
    const int m = kLeafDim - 1;
    return ((voxel[0] & m) << (2 * kLeafLog2Dim)) | ((voxel[1] & m) << kLeafLog2Dim) | (voxel[2] & m);
}

constexpr char kMagic[4] = {'V', 'C', 'M', 'K'};
constexpr uint8_t kMaskFormat = 1;
constexpr std::size_t kHeaderBytes = sizeof kMagic + 1 + 1 + 8; // magic, format, flag, leaf count
constexpr std::size_t kLeafBytes = 3 * 4 + sizeof(VoxelMask::LeafBits);

template<typename T> void put(std::string& out, T value)
{
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    out.append(raw, sizeof(T));
}

template<typename T> T take(const std::string& in, std::size_t& at)
{
    T value;
    std::memcpy(&value, in.data() + at, sizeof(T));
    at += sizeof(T);
    return value;
}

} // namespace

bool VoxelMask::masked(const IndexCoord& voxel) const
{
    const auto it = leaves_.find(leafOriginOf(voxel));
    const int bit = voxelBit(voxel);
    const bool listed = it != leaves_.end() && ((it->second[std::size_t(bit >> 6)] >> (bit & 63)) & 1u);
    return listed != inverted_;
}

void VoxelMask::set(const IndexCoord& voxel, bool mask)
{
    const bool listed = mask != inverted_;
    const IndexCoord origin = leafOriginOf(voxel);
    const int bit = voxelBit(voxel);
    const uint64_t flag = uint64_t(1) << (bit & 63);
    if (listed) {
        leaves_[origin][std::size_t(bit >> 6)] |= flag;
        return;
    }
    const auto it = leaves_.find(origin);
    if (it == leaves_.end()) return;
    it->second[std::size_t(bit >> 6)] &= ~flag;
    for (uint64_t w : it->second)
        if (w) return;
    leaves_.erase(it);
}

void VoxelMask::setLeaf(const IndexCoord& leafOrigin, bool mask)
{
    const IndexCoord origin = leafOriginOf(leafOrigin);
    if (mask != inverted_) leaves_[origin].fill(~uint64_t(0));
    else leaves_.erase(origin);
}

void VoxelMask::clear()
{
    inverted_ = false;
    leaves_.clear();
}

std::string VoxelMask::encode() const
{
    std::string out(kMagic, sizeof kMagic);
    put<uint8_t>(out, kMaskFormat);
    put<uint8_t>(out, inverted_ ? 1 : 0);
    put<uint64_t>(out, leaves_.size());
    for (const auto& [origin, bits] : leaves_) {
        for (int32_t c : origin) put<int32_t>(out, c);
        for (uint64_t w : bits) put<uint64_t>(out, w);
    }
    return out;
}

VoxelMask VoxelMask::decode(const std::string& bytes)
{
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
        throw MaskFormatError("the mask is damaged (not a VDBClay mask)");
    std::size_t at = sizeof kMagic;
    const uint8_t format = take<uint8_t>(bytes, at);
    if (format != kMaskFormat)
        throw MaskFormatError("the mask has format " + std::to_string(format) + "; this build reads format " + std::to_string(kMaskFormat));
    const uint8_t flag = take<uint8_t>(bytes, at);
    if (flag > 1) throw MaskFormatError("the mask is damaged (its inverted flag is neither 0 nor 1)");
    const uint64_t count = take<uint64_t>(bytes, at);
    if (count > (bytes.size() - kHeaderBytes) / kLeafBytes || kHeaderBytes + count * kLeafBytes != bytes.size())
        throw MaskFormatError("the mask is damaged (its size does not match its " + std::to_string(count) + " leaves)");
    VoxelMask mask;
    mask.inverted_ = flag == 1;
    for (uint64_t i = 0; i < count; ++i) {
        IndexCoord origin;
        for (int32_t& c : origin) c = take<int32_t>(bytes, at);
        LeafBits bits;
        bool anyBit = false;
        for (uint64_t& w : bits) anyBit |= (w = take<uint64_t>(bytes, at)) != 0;
        if (origin != leafOriginOf(origin) || !anyBit || (!mask.leaves_.empty() && !(mask.leaves_.rbegin()->first < origin)))
            throw MaskFormatError("the mask is damaged (leaf " + std::to_string(i) + " is off the leaf lattice, empty or out of order)");
        mask.leaves_.emplace_hint(mask.leaves_.end(), origin, bits);
    }
    return mask;
}

} // namespace vdbclay
