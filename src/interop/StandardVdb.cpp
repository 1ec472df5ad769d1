#include "interop/StandardVdb.h"

#include "interop/StandardGridRead.h"
#include "vdb_hermite/NumberText.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeIO.h"

#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/util/logging.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <mutex>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

/// Runs `read` with OpenVDB's failures turned into one printable line.
template<typename Read>
auto guarded(const std::string& path, Read&& read)
{
    try {
        return read();
    } catch (const VolumeIOError&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw VolumeIOError("'" + path + "' is corrupt (implausible sizes)");
    } catch (const std::exception& e) {
        throw VolumeIOError("'" + path + "' cannot be read: " + printableText(e.what())); // libraries quote the file
    }
}

/// A transform resampling can invert: finite, not singular, with voxels VDBClay can hold.
bool usableTransform(const openvdb::math::Transform& xf)
{
    if (!xf.isLinear()) return false;
    const openvdb::Mat4d m = xf.baseMap()->getAffineMap()->getMat4();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (!std::isfinite(m(i, j))) return false;
    const openvdb::Vec3d voxel = xf.voxelSize();
    for (int i = 0; i < 3; ++i)
        if (!(voxel[i] >= kMinVoxelSize && voxel[i] <= kMaxVoxelSize)) return false;
    return std::fabs(m.getMat3().det()) > 1e-6 * voxel[0] * voxel[1] * voxel[2];
}

/// OpenVDB, with the delayed-load metadata that files of other tools carry read as opaque bytes: its
/// reader allocates arrays of whatever length the file states (found by fuzzing), and VDBClay never
/// loads lazily. Its bytes are checked like any other metadata value's (they must fit the file).
void initializeForForeignFiles()
{
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        // OpenVDB's warnings (a repeated grid name, ...) would reach stdout in colour; what matters is
        // said in VDBClay's own messages.
        openvdb::logging::setLevel(openvdb::logging::Level::Fatal);
        if (openvdb::Metadata::isRegisteredType(openvdb::io::DelayedLoadMetadata::staticTypeName()))
            openvdb::Metadata::unregisterType(openvdb::io::DelayedLoadMetadata::staticTypeName());
    });
}

} // namespace

StandardVdbInfo describeStandardVdb(const std::string& path)
{
    initializeForForeignFiles();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw VolumeIOError("'" + path + "' is not a regular file");
    const uint64_t size = fs::file_size(path, ec);
    PayloadSummary summary;
    {
        std::ifstream in(path, std::ios::binary);
        if (!in) throw VolumeIOError("cannot open '" + path + "': " + std::strerror(errno));
        summary = checkPayload(in, size, path, "", AcceptedGrids::Standard);
    }
    // What OpenVDB allocates is held to a small multiple of the file, as for VDBClay's own files.
    if (summary.estimatedMemoryBytes > 64 * size + (64u << 20))
        throw VolumeIOError("'" + path + "' is corrupt: its trees would take " + std::to_string(summary.estimatedMemoryBytes >> 20) +
                            " MiB for a " + std::to_string(size >> 10) + " KiB file");
    StandardVdbInfo info;
    guarded(path, [&] {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        const openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();
        file.close();
        if (grids->size() != summary.grids.size()) throw VolumeIOError("'" + path + "' holds grids its check did not see");
        for (std::size_t i = 0; i < grids->size(); ++i) {
            const openvdb::GridBase& grid = *(*grids)[i];
            StandardGridInfo g;
            g.header = summary.grids[i];
            g.name = openvdb::io::GridDescriptor::nameAsString(g.header.name);
            g.baseName = openvdb::io::GridDescriptor::stripSuffix(g.header.name);
            g.selectable = openvdb::io::GridDescriptor::stringAsUniqueName(g.name) == g.header.name;
            const openvdb::Vec3d voxel = grid.voxelSize();
            g.voxelSize = {voxel[0], voxel[1], voxel[2]};
            g.uniformVoxels = grid.hasUniformVoxels();
            g.axisAligned = axisAligned(grid.transform());
            g.usableTransform = usableTransform(grid.transform());
            if (const auto count = grid.getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_VOXEL_COUNT))
                g.activeVoxels = uint64_t(count->value());
            // A crafted file may repeat a unique name: OpenVDB then reads the first of them only.
            for (const StandardGridInfo& earlier : info.grids) g.selectable = g.selectable && earlier.name != g.name;
            info.grids.push_back(std::move(g));
        }
        return 0;
    });
    return info;
}

const StandardGridInfo& chooseImportGrid(const StandardVdbInfo& info, const std::string& name, const std::string& path)
{
    if (!name.empty()) {
        std::vector<const StandardGridInfo*> sharing;
        for (const StandardGridInfo& g : info.grids)
            if (g.baseName == name) sharing.push_back(&g);
        if (sharing.size() > 1 && std::none_of(info.grids.begin(), info.grids.end(), [&](const auto& g) { return g.name == name; })) {
            std::string names;
            for (const StandardGridInfo* g : sharing) names += (names.empty() ? "'" : ", '") + printableText(g->name, 64) + "'";
            throw VolumeIOError("'" + path + "' holds " + std::to_string(sharing.size()) + " grids named '" + printableText(name, 64) +
                                "': " + names + "; pick one with --grid '" + printableText(sharing.back()->name, 64) + "'");
        }
        for (const StandardGridInfo& g : info.grids) {
            if (g.name != name && !(sharing.size() == 1 && &g == sharing.front())) continue;
            if (!g.selectable)
                throw VolumeIOError("grid '" + printableText(g.name, 64) + "' of '" + path +
                                    "' has a name OpenVDB cannot select it by; the file is damaged");
            if (g.header.treeChecked && !g.usableTransform)
                throw VolumeIOError("grid '" + printableText(name, 64) + "' of '" + path +
                                    "' has a transform that is singular, not finite, or of voxels outside VDBClay's range");
            if (!g.importable())
                throw VolumeIOError("grid '" + printableText(name, 64) + "' of '" + path + "' holds " + g.header.valueType +
                                    " values; VDBClay imports float and double grids");
            return g;
        }
        throw VolumeIOError("'" + path + "' has no grid named '" + printableText(name, 64) + "'; it holds: " + listGrids(info));
    }
    for (const auto& wanted : {&StandardGridInfo::levelSet, &StandardGridInfo::fogVolume})
        for (const StandardGridInfo& g : info.grids)
            if (g.importable() && (g.*wanted)()) return g;
    for (const StandardGridInfo& g : info.grids)
        if (g.importable()) return g;
    // Say why a float grid cannot be taken rather than that there is none.
    for (const StandardGridInfo& g : info.grids) {
        if (!g.header.treeChecked || (g.header.valueType != "float" && g.header.valueType != "double")) continue;
        if (!g.usableTransform)
            throw VolumeIOError("grid '" + printableText(g.name, 64) + "' of '" + path + "' has a transform VDBClay cannot use: " +
                                "voxels of " + formatNumber(g.voxelSize[0]) + " x " + formatNumber(g.voxelSize[1]) + " x " +
                                formatNumber(g.voxelSize[2]) + " (each must lie in " + formatNumber(kMinVoxelSize) + " .. " +
                                formatNumber(kMaxVoxelSize) + "), or a singular, non-finite or non-linear map");
        if (!g.selectable)
            throw VolumeIOError("grid '" + printableText(g.name, 64) + "' of '" + path + "' repeats another grid's unique name; the file is damaged");
    }
    throw VolumeIOError("'" + path + "' holds no float or double grid to import; it holds: " + listGrids(info));
}

std::string listGrids(const StandardVdbInfo& info)
{
    std::string out;
    for (const StandardGridInfo& g : info.grids) {
        if (!out.empty()) out += ", ";
        out += "'" + printableText(g.name, 64) + "' (" + (g.header.gridClass.empty() ? "no class" : printableText(g.header.gridClass, 32)) +
               ", " + (g.header.valueType.empty() ? printableText(g.header.type, 64) : g.header.valueType) + ")";
    }
    return out;
}

openvdb::GridBase::Ptr readStandardGrid(const std::string& path, const std::string& name)
{
    return guarded(path, [&] {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        openvdb::GridBase::Ptr grid = file.readGrid(name);
        file.close();
        return grid;
    });
}

} // namespace vdbclay
