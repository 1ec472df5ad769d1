// The .vdb reader on crafted bytes. The input is a payload; the target seals it with a valid VDBClay
// trailer (as anyone can), so every input reaches the structural check and, when that passes, OpenVDB's
// parser. loadVolume must load the file or refuse it with a VolumeIOError of one printable line.
#include "vdb_hermite/VolumeIO.h"

#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <unistd.h>

namespace {

const std::string& scratchPath()
{
    static const std::string path = "/tmp/vdbclay-fuzz-" + std::to_string(::getpid()) + ".vdb";
    return path;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    {
        std::ofstream out(scratchPath(), std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        // The trailer saveVolume writes: magic, payload size, CRC-32 of the payload, format version.
        const char magic[8] = {'V', 'D', 'B', 'C', 'L', 'A', 'Y', '\0'};
        const uint64_t bytes = size;
        const uint32_t crc = uint32_t(crc32(crc32(0L, Z_NULL, 0), data, uInt(size)));
        const uint32_t version = 1;
        out.write(magic, 8);
        out.write(reinterpret_cast<const char*>(&bytes), 8);
        out.write(reinterpret_cast<const char*>(&crc), 4);
        out.write(reinterpret_cast<const char*>(&version), 4);
    }
    try {
        (void)vdbclay::loadVolume(scratchPath());
    } catch (const vdbclay::VolumeIOError& e) {
        for (const char* c = e.what(); *c; ++c)
            if (*c < 32 || *c > 126) std::abort(); // a message with raw bytes or several lines
    }
    return 0;
}
