// bench io: save/load time and file size of our sphere against the same sphere as an OpenVDB FloatGrid
// level set written with io::File and Blosc, in a temporary directory removed afterwards.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/VolumeIO.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>

namespace vdbclay::bench {

namespace {

namespace fs = std::filesystem;

constexpr double kVoxelSize = 1.0;
constexpr float kHalfWidth = 3.0f;
constexpr int kRepeats = 3;

/// A fresh directory under the system temp dir, removed (with its content) when this goes away.
class TempDir {
public:
    TempDir()
    {
        std::string pattern = (fs::temp_directory_path() / "vdbclay-bench-XXXXXX").string();
        if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a temporary directory: " + std::string(std::strerror(errno)));
        path_ = pattern;
    }
    ~TempDir()
    {
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const fs::path& path() const { return path_; }

private:
    fs::path path_;
};

void writeLevelSet(const openvdb::FloatGrid::Ptr& grid, const std::string& path)
{
    openvdb::io::File file(path);
    file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write(openvdb::GridCPtrVec{grid});
    file.close();
}

openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& name)
{
    openvdb::io::File file(path);
    file.setCopyMaxBytes(0);
    file.open(/*delayLoad=*/false);
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(name));
    file.close();
    if (!grid) throw std::runtime_error("bench io: the level set did not read back");
    return grid;
}

} // namespace

int benchIo(bool json, bool quick)
{
    const double radius = quick ? 40.0 : 100.0;
    TempDir dir;
    const std::string oursPath = (dir.path() / "ours.vdb").string();
    const std::string vdbPath = (dir.path() / "levelset.vdb").string();

    Volume volume(kVoxelSize);
    {
        Primitive p;
        p.shape = Shape::Sphere;
        p.radius = radius * kVoxelSize;
        CsgOp add;
        add.mode = CsgMode::Add;
        applyCsg(volume, Brush(p, Placement{}), add);
    }
    openvdb::FloatGrid::Ptr levelSet = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        float(radius * kVoxelSize), openvdb::Vec3f(0.0f), float(kVoxelSize), kHalfWidth);
    levelSet->setName("level_set");

    std::vector<double> oursSave, oursLoad, vdbSave, vdbSaveSync, vdbLoad;
    bool roundTrip = true;
    for (int i = 0; i < kRepeats; ++i) {
        oursSave.push_back(timeMs([&] { saveVolume(volume, oursPath); }));
        Volume loaded(kVoxelSize);
        oursLoad.push_back(timeMs([&] { loaded = loadVolume(oursPath); }));
        roundTrip = roundTrip && identical(volume, loaded);

        vdbSave.push_back(timeMs([&] { writeLevelSet(levelSet, vdbPath); }));
        vdbSaveSync.push_back(timeMs([&] {
            writeLevelSet(levelSet, vdbPath);
            syncFileToDisk(vdbPath);
        }));
        openvdb::FloatGrid::Ptr back;
        vdbLoad.push_back(timeMs([&] { back = readLevelSet(vdbPath, "level_set"); }));
        roundTrip = roundTrip && back->activeVoxelCount() == levelSet->activeVoxelCount();
    }
    if (!roundTrip) throw std::runtime_error("bench io: a file did not read back identical to what was written");

    const uint64_t oursBytes = fs::file_size(oursPath);
    const uint64_t vdbBytes = fs::file_size(vdbPath);
    const VolumeStats stats = volume.stats();

    if (json) {
        nlohmann::json out = jsonPreamble("io", quick);
        out["voxel_size"] = kVoxelSize;
        out["sphere_radius_voxels"] = radius;
        out["repeats"] = kRepeats;
        out["ours"] = {{"save_ms", median(oursSave)},
                       {"load_ms", median(oursLoad)},
                       {"file_bytes", oursBytes},
                       {"active_voxels", stats.activeVoxels}};
        out["openvdb"] = {{"save_ms", median(vdbSave)},
                          {"save_fsync_ms", median(vdbSaveSync)},
                          {"load_ms", median(vdbLoad)},
                          {"file_bytes", vdbBytes},
                          {"active_voxels", levelSet->activeVoxelCount()}};
        out["file_size_ratio_ours_to_openvdb"] = vdbBytes ? double(oursBytes) / double(vdbBytes) : 0.0;
        std::cout << out.dump() << std::endl;
        return 0;
    }

    printPreamble(std::cout, "io", quick);
    std::cout << "Sphere of radius " << radius << " voxels, Blosc-compressed .vdb files, median of " << kRepeats
              << " runs. Our save is atomic (temporary file, fsync, rename);\nthe OpenVDB row is a plain "
                 "io::File write, shown also with an fsync added:\n\n";
    Table t;
    t.header = {"file", "save ms", "save + fsync ms", "load ms", "file size", "active voxels"};
    t.rows.push_back({"ours (saveVolume/loadVolume)", "-", fixed(median(oursSave), 1), fixed(median(oursLoad), 1),
                      megabytes(double(oursBytes)), std::to_string(stats.activeVoxels)});
    t.rows.push_back({"OpenVDB FloatGrid level set (half-width 3)", fixed(median(vdbSave), 1),
                      fixed(median(vdbSaveSync), 1), fixed(median(vdbLoad), 1), megabytes(double(vdbBytes)),
                      std::to_string(levelSet->activeVoxelCount())});
    t.print(std::cout);
    std::cout << "\nfile size ours/OpenVDB: " << fixed(vdbBytes ? double(oursBytes) / double(vdbBytes) : 0.0, 2)
              << '\n';
    return 0;
}

} // namespace vdbclay::bench
