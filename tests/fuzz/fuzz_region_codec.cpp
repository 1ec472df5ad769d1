// The store's brick decoder on crafted bodies. The input is a region body (block table, then the
// leaves' serialization); the target seals it as encodeRegion would (header with the leaf count its
// table announces, Blosc, checksum), so every input reaches the leaf parser. decodeRegion must decode
// it or refuse it with a VolumeIOError of one printable line, and what it decodes must paste.
#include "vdb_hermite/RegionCodec.h"
#include "vdb_hermite/VolumeIO.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const vdbclay::LeafAlignedBox box{{64, -128, 0}, 64};
    constexpr std::size_t kBlocks = 8 * 8 * 8;
    const std::string body(reinterpret_cast<const char*>(data), size);
    uint32_t leaves = 0;
    for (std::size_t b = 0; b < kBlocks && 2 * b + 1 < size; ++b) {
        uint16_t id;
        std::memcpy(&id, data + 2 * b, sizeof(id));
        leaves += id == 0xffff;
    }
    try {
        vdbclay::DecodedRegion region =
            vdbclay::decodeRegion(vdbclay::sealRegion(body, box, 0.5, leaves), box, 0.5, 3, "fuzzed region");
        vdbclay::Volume volume(0.5);
        vdbclay::pasteRegion(volume, std::move(region));
        (void)volume.stats();
    } catch (const vdbclay::VolumeIOError& e) {
        for (const char* c = e.what(); *c; ++c)
            if (*c < 32 || *c > 126) std::abort(); // a message with raw bytes or several lines
    }
    return 0;
}
