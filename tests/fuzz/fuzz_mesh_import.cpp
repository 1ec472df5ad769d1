// A mesh file of another tool on crafted bytes: the first byte picks the format (obj, ply, stl, off,
// glb), the rest is the file. Assimp reads it and the voxelizer turns it into Hermite data at a small
// resolution (soups of at most 2000 triangles); every input must be imported or refused with one
// printable line.
#include "vdb_hermite/PrintableText.h"
#include "voxelize/TriangleMesh.h"
#include "voxelize/Voxelizer.h"

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace {

const char* const kExtensions[] = {".obj", ".ply", ".stl", ".off", ".glb"};

std::string scratchPath(const char* extension)
{
    return "/tmp/vdbclay-fuzz-mesh-" + std::to_string(::getpid()) + extension;
}

void requirePrintable(const char* message)
{
    if (!vdbclay::isPrintableName(message, std::string::npos)) std::abort(); // raw bytes, control characters or several lines
}

} // namespace

// libFuzzer runs one thread: a fork of it is safe, and ten times faster than starting the reader
// program for each input.
extern "C" int LLVMFuzzerInitialize(int*, char***)
{
    ::setenv("VDBCLAY_MESH_READER", "fork", 1);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 2) return 0;
    const std::string path = scratchPath(kExtensions[data[0] % 5]);
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 2), std::streamsize(size - 2));
    }
    try {
        // A reading stopped at its time limit is a refusal like any other; it must stay well below
        // libFuzzer's -timeout, which would report the input as a hang.
        vdbclay::MeshReadLimits limits;
        limits.time = std::chrono::seconds(5);
        const vdbclay::TriangleSoup soup = vdbclay::loadTriangleMesh(path, limits);
        // Thousands of large triangles at once cost seconds under the sanitizers (hits grow with the
        // triangles times the rays each covers); the voxelizer's own fuzz (test_voxelize) takes soups.
        if (soup.triangles.size() <= 2000) {
            vdbclay::VoxelizeOptions options;
            options.resolution = 4 + data[1] % 16;
            vdbclay::VoxelizeReport report;
            const vdbclay::Volume volume = vdbclay::voxelizeMesh(soup, options, &report);
            if (report.triangles == 0) std::abort(); // loaded, so it held a triangle
        }
    } catch (const vdbclay::MeshImportError& e) {
        requirePrintable(e.what());
    } catch (const std::invalid_argument& e) {
        requirePrintable(e.what());
    }
    std::remove(path.c_str());
    return 0;
}
