// The .vdb reader on crafted bytes. The input is a payload; the target seals it with a valid VDBClay
// trailer (as anyone can), so every input reaches the structural check and, when that passes, OpenVDB's
// parser. loadVolume must load the file or refuse it with a VolumeIOError of one printable line.
#include "vdb_hermite/PrintableText.h"
#include "support/HermiteProbe.h"
#include "vdb_hermite/VolumeIO.h"

#include <cstdint>
#include <cstdlib>
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
    }
    vdbclay::test::appendIntegrityTrailer(scratchPath()); // the trailer saveVolume writes
    try {
        (void)vdbclay::loadVolume(scratchPath());
    } catch (const vdbclay::VolumeIOError& e) {
        if (!vdbclay::isPrintableName(e.what(), std::string::npos)) std::abort(); // raw bytes, control characters or several lines
    }
    return 0;
}
