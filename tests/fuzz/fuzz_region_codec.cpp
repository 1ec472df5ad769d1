// The store's brick decoder on crafted bodies. The input is a region body (block table, then the
// leaves' serialization); the target seals it as encodeRegion would (header, Blosc, checksum), so
// every input reaches the leaf parser. decodeRegion must decode it or refuse it with a VolumeIOError of
// one printable line, and what it decodes must paste.
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/RegionCodec.h"
#include "vdb_hermite/VolumeIO.h"

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const vdbclay::LeafAlignedBox box{{64, -128, 0}, 64};
    const std::string body(reinterpret_cast<const char*>(data), size);
    try {
        vdbclay::DecodedRegion region =
            vdbclay::decodeRegion(vdbclay::sealRegion(body, box, 0.5), box, 0.5, 3, "fuzzed region");
        vdbclay::Volume volume(0.5);
        vdbclay::pasteRegion(volume, std::move(region));
        (void)volume.stats();
    } catch (const vdbclay::VolumeIOError& e) {
        if (!vdbclay::isPrintableName(e.what(), std::string::npos)) std::abort(); // raw bytes, control characters or several lines
    }
    return 0;
}
