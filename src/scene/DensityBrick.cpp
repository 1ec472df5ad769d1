#include "scene/DensityBrick.h"

#include "scene/BrickStore.h"

#include <blosc.h>

#include <cstring>

namespace vdbclay {

namespace {

constexpr char kMagic[4] = {'V', 'C', 'L', 'D'};
constexpr std::size_t kHeaderBytes = sizeof(kMagic) + sizeof(uint32_t);
constexpr std::size_t kSlotBytes = kBlocksPerBrick * sizeof(MaterialId);
constexpr std::size_t kBlockBytes = sizeof(wavelet::LodBlock::density) + sizeof(wavelet::LodBlock::material);
// The slot table marks a block that is stored in full with a material id no table can hold.
constexpr MaterialId kStoredBlock = 0xffff;

} // namespace

bool DensityBrick::sameSlot(const DensityBrick& other, int s) const
{
    const wavelet::LodBlock* a = block(s);
    const wavelet::LodBlock* b = other.block(s);
    if (!a || !b) return !a && !b && uniform[std::size_t(s)] == other.uniform[std::size_t(s)];
    return *a == *b;
}

std::string encodeDensityBrick(const DensityBrick& brick)
{
    std::string raw(kSlotBytes + brick.blocks.size() * kBlockBytes, '\0');
    char* at = raw.data();
    for (int s = 0; s < kBlocksPerBrick; ++s) {
        const MaterialId id = brick.slot[std::size_t(s)] < 0 ? brick.uniform[std::size_t(s)] : kStoredBlock;
        std::memcpy(at, &id, sizeof(id));
        at += sizeof(id);
    }
    for (int s = 0; s < kBlocksPerBrick; ++s) {
        const wavelet::LodBlock* b = brick.block(s);
        if (!b) continue;
        std::memcpy(at, b->density.data(), sizeof(b->density));
        at += sizeof(b->density);
        std::memcpy(at, b->material.data(), sizeof(b->material));
        at += sizeof(b->material);
    }
    std::string out(kHeaderBytes + raw.size() + BLOSC_MAX_OVERHEAD, '\0');
    std::memcpy(out.data(), kMagic, sizeof(kMagic));
    const uint32_t count = uint32_t(brick.blocks.size());
    std::memcpy(out.data() + sizeof(kMagic), &count, sizeof(count));
    // Typesize 1: densities are bytes, and the material ids' high bytes are mostly zero either way.
    const int size = blosc_compress_ctx(5, BLOSC_SHUFFLE, 1, raw.size(), raw.data(), out.data() + kHeaderBytes,
                                        out.size() - kHeaderBytes, "lz4", 0, 1);
    if (size <= 0) throw StoreError("could not compress a density brick");
    out.resize(kHeaderBytes + std::size_t(size));
    return out;
}

DensityBrick decodeDensityBrick(const std::string& bytes, std::size_t materialCount, const std::string& what)
{
    const auto damaged = [&](const std::string& why) { return StoreError("'" + what + "' is damaged: " + why); };
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
        throw damaged("it is not a density brick");
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + sizeof(kMagic), sizeof(count));
    if (count > uint32_t(kBlocksPerBrick)) throw damaged("it claims " + std::to_string(count) + " blocks");
    const std::size_t expected = kSlotBytes + count * kBlockBytes;
    std::size_t decoded = 0;
    if (blosc_cbuffer_validate(bytes.data() + kHeaderBytes, bytes.size() - kHeaderBytes, &decoded) != 0 || decoded != expected)
        throw damaged("its compressed data does not hold what its header says");
    std::string raw(expected, '\0');
    if (blosc_decompress_ctx(bytes.data() + kHeaderBytes, raw.data(), raw.size(), 1) != int(expected))
        throw damaged("its compressed data does not decompress");

    DensityBrick brick;
    const char* at = raw.data();
    for (int s = 0; s < kBlocksPerBrick; ++s) {
        MaterialId id = 0;
        std::memcpy(&id, at, sizeof(id));
        at += sizeof(id);
        if (id == kStoredBlock) {
            if (brick.blocks.size() == count) throw damaged("it has more stored blocks than its header says");
            brick.slot[std::size_t(s)] = int16_t(brick.blocks.size());
            brick.blocks.emplace_back();
        } else if (id > materialCount) {
            throw damaged("it uses an undefined material");
        } else {
            brick.uniform[std::size_t(s)] = id;
        }
    }
    if (brick.blocks.size() != count) throw damaged("it has fewer stored blocks than its header says");
    for (wavelet::LodBlock& b : brick.blocks) {
        std::memcpy(b.density.data(), at, sizeof(b.density));
        at += sizeof(b.density);
        std::memcpy(b.material.data(), at, sizeof(b.material));
        at += sizeof(b.material);
        for (MaterialId m : b.material)
            if (m > materialCount) throw damaged("it uses an undefined material");
    }
    return brick;
}

} // namespace vdbclay
