// Another tool's .vdb on crafted bytes: the input is the whole file (no VDBClay trailer), so every input
// reaches the standard-grid check (PayloadCheck with AcceptedGrids::Standard) and, when that passes,
// OpenVDB's parser and the level-set import. They must import it or refuse it with one printable line.
#include "vdb_hermite/PrintableText.h"
#include "interop/LevelSetImport.h"
#include "vdb_hermite/MemoryLimit.h"
#include "vdb_hermite/VolumeIO.h"

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace {

const std::string& scratchPath()
{
    static const std::string path = "/tmp/vdbclay-fuzz-standard-" + std::to_string(::getpid()) + ".vdb";
    return path;
}

void requirePrintable(const char* message)
{
    if (!vdbclay::isPrintableName(message, std::string::npos)) std::abort(); // raw bytes, control characters or several lines
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    {
        std::ofstream out(scratchPath(), std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    vdbclay::LevelSetImportOptions options;
    options.iso = 0.5; // fog volumes import too
    // OpenVDB's resampling runs about 25 times slower under ASan; what it reads was checked already.
    options.maxResampledVoxels = 1 << 16;
    // libFuzzer stops at 2 GB of memory: a few flipped tiles may hold a solid of gigabytes.
    options.memoryLimitBytes = double(512u << 20);
    try {
        (void)vdbclay::importLevelSet(scratchPath(), options);
    } catch (const vdbclay::VolumeIOError& e) {
        requirePrintable(e.what());
    } catch (const std::invalid_argument& e) {
        requirePrintable(e.what());
    } catch (const vdbclay::MemoryLimitError& e) { // a few tiles may hold a huge solid
        requirePrintable(e.what());
    }
    return 0;
}
