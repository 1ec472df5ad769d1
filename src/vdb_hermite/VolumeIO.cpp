#include "vdb_hermite/VolumeIO.h"

#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/io/File.h>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <unistd.h>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

void syncPath(const std::string& path, bool directory)
{
    const int fd = ::open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0) {
        if (directory) return; // some filesystems do not allow opening directories; the rename still stands
        throw VolumeIOError("cannot reopen '" + path + "' to flush it: " + std::strerror(errno));
    }
    const int rc = ::fsync(fd);
    const int err = errno;
    ::close(fd);
    if (rc != 0 && !directory) throw VolumeIOError("cannot flush '" + path + "' to disk: " + std::strerror(err));
}

} // namespace

void saveVolume(const Volume& volume, const std::string& path)
{
    initializeHermiteGrid();
    const fs::path target(path);
    if (target.filename().empty()) throw VolumeIOError("'" + path + "' is not a file name");
    if (fs::is_directory(target)) throw VolumeIOError("'" + path + "' is a directory");
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(dir)) throw VolumeIOError("directory '" + dir.string() + "' does not exist");

    HermiteGrid::Ptr out = openvdb::gridPtrCast<HermiteGrid>(volume.impl().grid->copyGrid()); // shares the tree
    out->insertMeta(kFormatVersionKey, openvdb::Int32Metadata(kFormatVersion));
    out->insertMeta(kMaterialsKey, openvdb::StringMetadata(volume.materials().toJson()));

    const std::string temp = (dir / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()))).string();
    try {
        openvdb::io::File file(temp);
        file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write(openvdb::GridCPtrVec{out});
        file.close();
        syncPath(temp, false);
        fs::rename(temp, target);
    } catch (const VolumeIOError&) {
        std::error_code ec;
        fs::remove(temp, ec);
        throw;
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(temp, ec);
        throw VolumeIOError("cannot write '" + path + "': " + e.what());
    }
    syncPath(dir.string(), true);
}

Volume loadVolume(const std::string& path)
{
    initializeHermiteGrid();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw VolumeIOError("'" + path + "' does not exist");
    if (!fs::is_regular_file(path, ec)) throw VolumeIOError("'" + path + "' is not a regular file");

    try {
        openvdb::io::File file(path);
        file.setCopyMaxBytes(0);
        file.open(/*delayLoad=*/false);
        std::string name;
        openvdb::GridBase::Ptr meta;
        openvdb::GridPtrVecPtr all = file.readAllGridMetadata();
        for (const auto& g : *all) {
            if (g->type() != HermiteGrid::gridType()) continue;
            if (!meta || g->getName() == "hermite") {
                meta = g;
                name = g->getName();
            }
        }
        if (!meta) {
            std::string found;
            for (const auto& g : *all) found += (found.empty() ? "" : ", ") + g->getName() + " (" + g->type() + ")";
            throw VolumeIOError("'" + path + "' is a .vdb file without a VDBClay Hermite grid" +
                                (found.empty() ? std::string() : "; it holds: " + found));
        }
        const auto version = meta->metaValue<int32_t>(kFormatVersionKey);
        if (version > kFormatVersion || version < 1) {
            throw VolumeIOError("'" + path + "' has VDBClay format version " + std::to_string(version) +
                                "; this build reads versions 1 to " + std::to_string(kFormatVersion));
        }
        MaterialTable materials = MaterialTable::fromJson(meta->metaValue<std::string>(kMaterialsKey));

        auto grid = openvdb::gridPtrCast<HermiteGrid>(file.readGrid(name));
        file.close();
        if (!grid) throw VolumeIOError("'" + path + "': grid '" + name + "' could not be read");
        if (!grid->hasUniformVoxels() || !grid->transform().isLinear())
            throw VolumeIOError("'" + path + "': the Hermite grid needs a linear transform with cubic voxels");
        if (grid->background().id != kEmptyMaterial)
            throw VolumeIOError("'" + path + "': the Hermite grid's background must be empty");
        for (auto leaf = grid->constTree().cbeginLeaf(); leaf; ++leaf) {
            for (Index n = 0; n < Index(kLeafVoxels); ++n) {
                if (leaf->getValue(n).id > materials.size())
                    throw VolumeIOError("'" + path + "' is corrupt: a voxel uses an undefined material id");
            }
        }
        grid->removeMeta(kFormatVersionKey);
        grid->removeMeta(kMaterialsKey);
        Volume volume(grid->voxelSize()[0]);
        volume.impl().grid = grid;
        volume.materials() = std::move(materials);
        return volume;
    } catch (const VolumeIOError&) {
        throw;
    } catch (const openvdb::TypeError&) {
        throw VolumeIOError("'" + path + "' lacks the VDBClay metadata (format version, materials)");
    } catch (const openvdb::LookupError&) {
        throw VolumeIOError("'" + path + "' lacks the VDBClay metadata (format version, materials)");
    } catch (const std::bad_alloc&) {
        throw VolumeIOError("'" + path + "' is corrupt (implausible sizes)");
    } catch (const std::exception& e) {
        std::string what = e.what();
        if (what.find("not a VDB file") != std::string::npos || what.find("magic number") != std::string::npos)
            throw VolumeIOError("'" + path + "' is not a .vdb file");
        throw VolumeIOError("'" + path + "' cannot be read: " + what);
    }
}

} // namespace vdbclay
