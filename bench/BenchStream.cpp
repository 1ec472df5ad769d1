// bench stream: a terrain store several times larger than the memory budget, generated, given its
// levels of detail (in a child process, so this one's memory stays the flight's), then flown over at
// 90 Hz with strokes along the way. Reports peak resident memory against the budget, the time to a
// first coarse view of a new region and to its full refinement, stroke latency on bricks not resident,
// bytes read per frame and the sustained read rate next to the disk's speed measured in the same run,
// and resident bytes per voxel^2 of surface next to an OpenVDB FloatGrid level set.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "scene/SceneStore.h"
#include "scene/StreamingScene.h"
#include "scene/Synthesize.h"
#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "sculpt/StrokeScript.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <thread>

#include <fcntl.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>

namespace vdbclay::bench {

namespace {

namespace fs = std::filesystem;

/// A field of /proc/self/status in bytes ("VmRSS", "VmHWM").
uint64_t procStatusBytes(const char* field)
{
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind(field, 0) == 0) return std::stoull(line.substr(line.find(':') + 1)) * 1024;
    return 0;
}

void resetPeakRss()
{
    std::ofstream("/proc/self/clear_refs") << "5";
}

/// Drops the file's pages from the page cache, so the next reads come from the disk.
void dropCache(const std::string& path)
{
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) return;
    ::fdatasync(fd);
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
}

/// Sequential read speed of a file just dropped from the cache, bytes per second.
double diskReadSpeed(const std::string& path)
{
    dropCache(path);
    std::ifstream in(path, std::ios::binary);
    std::vector<char> buffer(4 << 20);
    uint64_t total = 0;
    const auto start = Clock::now();
    while (in.read(buffer.data(), std::streamsize(buffer.size())) || in.gcount() > 0) total += uint64_t(in.gcount());
    return double(total) / (millisecondsSince(start) / 1000.0);
}

/// Runs this program's `lod build` on the store in a child process; returns the child's peak RSS.
uint64_t buildLodInChild(const std::string& store)
{
    const pid_t child = ::fork();
    if (child == 0) {
        const int devnull = ::open("/dev/null", O_WRONLY);
        ::dup2(devnull, 1);
        ::execl("/proc/self/exe", "vdbclay", "lod", "build", store.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    int status = 0;
    struct rusage usage {};
    ::wait4(child, &status, 0, &usage);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error("vdbclay lod build failed in the child process");
    return uint64_t(usage.ru_maxrss) * 1024; // kilobytes on Linux
}

Viewer viewer(double x, double z, double height, double lookAhead)
{
    Viewer v;
    v.position = {x, height, z};
    v.target = {x + lookAhead, height * 0.3, z};
    return v;
}

std::string strokeAt(double x, double y, double z)
{
    char text[256];
    std::snprintf(text, sizeof(text),
                  R"({"ops": [{"mode": "remove", "brush": {"shape": "sphere", "radius": 5}, "path": [[%.1f, %.1f, %.1f], [%.1f, %.1f, %.1f]]}]})",
                  x, y, z, x + 12.0, y, z + 6.0);
    return text;
}

/// OpenVDB's bytes per surface voxel: a FloatGrid level set (half-width 3) of a sphere, divided by the
/// surface voxels of our volume of the same sphere (as bench memory does).
std::pair<double, double> sphereBytesPerSurfaceVoxel()
{
    Volume v(1.0);
    Primitive p;
    p.shape = Shape::Sphere;
    p.radius = 100.0;
    CsgOp add;
    add.mode = CsgMode::Add;
    applyCsg(v, Brush(p, Placement{}), add);
    const auto levelSet = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(100.0f, openvdb::Vec3f(0.0f), 1.0f, 3.0f);
    const double surface = double(v.stats().activeVoxels);
    return {double(v.stats().memoryBytes) / surface, double(levelSet->memUsage()) / surface};
}

} // namespace

int benchStream(bool json, bool quick, double memoryBudgetMb)
{
    const int extent = quick ? 768 : 4096;
    const uint64_t budget = memoryBudgetMb > 0.0 ? uint64_t(memoryBudgetMb * double(1 << 20)) : (quick ? 2ull : 192ull) << 20;
    const ScratchDir scratch("stream");
    const fs::path& dir = scratch.path();
    const std::string store = (dir / "terrain.vdbclay").string();

    SynthOptions synth;
    synth.kind = SynthKind::Terrain;
    synth.extent = extent;
    synth.seed = 7;
    SynthReport generated;
    const double generateMs = timeMs([&] { generated = synthesizeStore(synth, store); });
    const uint64_t storeBytes = fs::file_size(store);
    uint64_t lodPeakRss = 0;
    const double lodMs = timeMs([&] { lodPeakRss = buildLodInChild(store); });
    const double diskSpeed = diskReadSpeed(store);
    dropCache(store);

    // What the generation freed goes back to the system first: the flight would otherwise reuse it
    // without its RSS showing, and the figure would depend on how much the generation happened to keep.
    ::malloc_trim(0);
    const uint64_t baselineRss = procStatusBytes("VmRSS");
    resetPeakRss();
    StreamingOptions options;
    options.memoryBudgetBytes = budget;
    options.access = StoreAccess::ReadWrite;
    options.pixelTolerance = 1.0;
    StreamingScene scene(store, options);
    const double height = 80.0, lookAhead = 200.0;

    // A new region: teleport there and count the time to a complete coarse view and to full refinement.
    struct Arrival {
        double coarseMs = -1.0, refinedMs = -1.0, settledMs = -1.0;
        uint64_t bytesRead = 0; // until settled
    };
    const auto arrive = [&](StreamingScene& in, double x, double z) {
        Arrival a;
        const auto start = Clock::now();
        for (int frame = 0; frame < 90 * 5; ++frame) {
            const FrameReport r = in.frame(viewer(x, z, height, lookAhead));
            if (r.coarseComplete && a.coarseMs < 0.0) a.coarseMs = millisecondsSince(start);
            if (a.settledMs < 0.0) a.bytesRead += r.bytesRead;
            if (r.settled && a.settledMs < 0.0) a.settledMs = millisecondsSince(start);
            if (r.complete) {
                a.refinedMs = millisecondsSince(start);
                break;
            }
            if (r.budgetLimited && a.settledMs >= 0.0) break; // as refined as the budget allows
            std::this_thread::sleep_for(std::chrono::microseconds(11111));
        }
        return a;
    };
    std::vector<Arrival> arrivals;
    const auto arrivalX = [&](int i) { return extent * (0.15 + 0.3 * i); };
    const auto arrivalZ = [&](int i) { return extent * (0.8 - 0.25 * i); };
    for (int i = 0; i < 3; ++i) arrivals.push_back(arrive(scene, arrivalX(i), arrivalZ(i)));

    // The flight: along x at 90 Hz, a stroke every second somewhere not resident (ahead, off to the side).
    const double seconds = quick ? 2.0 : 6.0, speed = extent * 0.6 / seconds;
    std::vector<double> strokeMs, readPerFrame;
    uint64_t flightRead = 0, flightFrames = 0;
    const auto flightStart = Clock::now();
    for (int frame = 0; frame < int(seconds * 90.0); ++frame) {
        const double x = extent * 0.2 + speed * frame / 90.0, z = extent * 0.5;
        const FrameReport r = scene.frame(viewer(x, z, height, lookAhead));
        flightRead += r.bytesRead;
        readPerFrame.push_back(double(r.bytesRead));
        ++flightFrames;
        if (frame % 90 == 45) {
            const double sx = std::fmod(x + extent * 0.4, double(extent - 64)) + 32.0, sz = extent * 0.15;
            const StrokeScript script = parseStrokeScript(strokeAt(sx, 40.0, sz));
            strokeMs.push_back(timeMs([&] { scene.sculpt(script); }));
        }
        const double due = (frame + 1) / 90.0 * 1000.0 - millisecondsSince(flightStart);
        if (due > 0.0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(due));
    }
    const double flightSeconds = millisecondsSince(flightStart) / 1000.0;
    scene.autosave();
    const uint64_t peakRss = procStatusBytes("VmHWM");
    // The first arrival again, read-only, with a budget large enough to hold the whole view.
    StreamingOptions roomy = options;
    roomy.memoryBudgetBytes = 4 * budget;
    roomy.access = StoreAccess::ReadOnly;
    Arrival roomyArrival;
    {
        StreamingScene fresh(store, roomy);
        roomyArrival = arrive(fresh, arrivalX(0), arrivalZ(0));
    }
    uint64_t arrivalBytes = roomyArrival.bytesRead;
    double arrivalMs = roomyArrival.settledMs;
    for (const Arrival& a : arrivals) arrivalBytes += a.bytesRead, arrivalMs += a.settledMs;
    const double loadRate = double(arrivalBytes) / (arrivalMs / 1000.0);
    const Volume resident = scene.residentLevel0();
    // Every resident level's bytes over every resident level's surface voxels (each level's voxel^2 on
    // its own lattice): what the representation costs. Coarse bricks kept beside the fine ones (LRU
    // evicts only over the budget) would otherwise count in the bytes but not in the surface.
    const double residentPerSurfaceVoxel = double(scene.residentBytes()) / double(std::max<uint64_t>(1, scene.residentActiveVoxels()));
    const double residentPerLevel0SurfaceVoxel = double(scene.residentBytes()) / double(std::max<uint64_t>(1, resident.stats().activeVoxels));
    const auto [ourSphere, vdbSphere] = sphereBytesPerSurfaceVoxel();

    double worstCoarse = 0.0, worstRefined = 0.0, worstSettled = 0.0;
    bool allRefined = true, allSettled = true;
    for (const Arrival& a : arrivals) {
        worstCoarse = std::max(worstCoarse, a.coarseMs);
        worstRefined = std::max(worstRefined, a.refinedMs);
        worstSettled = std::max(worstSettled, a.settledMs);
        allRefined = allRefined && a.refinedMs >= 0.0;
        allSettled = allSettled && a.settledMs >= 0.0;
    }
    const double generatedVoxels = double(generated.bricksVisited) * double(kBrickEdge) * kBrickEdge * kBrickEdge;

    if (json) {
        nlohmann::json out = jsonPreamble("stream", quick);
        out["extent"] = extent;
        out["store_bytes"] = storeBytes;
        out["memory_budget_bytes"] = budget;
        out["store_to_budget"] = double(storeBytes) / double(budget);
        out["generate_seconds"] = generateMs / 1000.0;
        out["generate_bytes_per_second"] = double(storeBytes) / (generateMs / 1000.0);
        out["generate_voxels_per_second"] = generatedVoxels / (generateMs / 1000.0);
        out["lod_build_seconds"] = lodMs / 1000.0;
        out["lod_build_peak_rss_bytes"] = lodPeakRss;
        out["baseline_rss_bytes"] = baselineRss;
        out["peak_rss_bytes"] = peakRss;
        out["overhead_bytes"] = peakRss > baselineRss + budget ? peakRss - baselineRss - budget : 0;
        nlohmann::json a = nlohmann::json::array();
        for (const Arrival& x : arrivals)
            a.push_back({{"coarse_ms", x.coarseMs}, {"refined_ms", x.refinedMs}, {"refined_within_budget_ms", x.settledMs}});
        out["arrivals"] = a;
        out["roomy_budget_bytes"] = roomy.memoryBudgetBytes;
        out["roomy_refined_ms"] = roomyArrival.refinedMs;
        out["load_bytes_per_second"] = loadRate;
        out["stroke_ms"] = strokeMs;
        out["stroke_max_ms"] = maximum(strokeMs);
        out["read_bytes_per_frame_mean"] = double(flightRead) / double(flightFrames);
        out["read_bytes_per_second"] = double(flightRead) / flightSeconds;
        out["disk_read_bytes_per_second"] = diskSpeed;
        out["resident_bytes_per_surface_voxel"] = residentPerSurfaceVoxel;
        out["resident_bytes_per_level0_surface_voxel"] = residentPerLevel0SurfaceVoxel;
        out["sphere_bytes_per_surface_voxel"] = ourSphere;
        out["openvdb_level_set_bytes_per_surface_voxel"] = vdbSphere;
        std::cout << out.dump() << std::endl;
        return 0;
    }
    printPreamble(std::cout, "stream", quick);
    const auto ms = [](double v) { return v < 0.0 ? std::string("not within 5 s") : fixed(v, 1) + " ms"; };
    Table t;
    t.header = {"figure", "measured", "goal"};
    t.rows = {
        {"terrain store (extent " + std::to_string(extent) + ")", megabytes(double(storeBytes)) + ", " +
                                                                      fixed(double(storeBytes) / double(budget), 1) + "x the budget", ">= 4x"},
        {"generation", fixed(generateMs / 1000.0, 1) + " s, " + megabytes(double(storeBytes) / (generateMs / 1000.0)) + "/s, " +
                           fixed(generatedVoxels / (generateMs / 1000.0) / 1e6, 1) + " M voxels/s", ""},
        {"lod build (child process)", fixed(lodMs / 1000.0, 1) + " s, peak RSS " + megabytes(double(lodPeakRss)), "out of core: RSS << store"},
        {"peak RSS over the baseline", megabytes(double(peakRss - std::min(peakRss, baselineRss))) + " for a budget of " + megabytes(double(budget)),
         "budget + documented overhead"},
        {"first coarse view of a new region (worst of 3)", ms(worstCoarse), "<= 100 ms"},
        {"full refinement of the view (worst of 3)", allRefined ? ms(worstRefined) : ms(-1.0), "<= 1 s"},
        {"refined as far as the budget allows (worst of 3)", allSettled ? ms(worstSettled) : ms(-1.0), ""},
        {"full refinement of the first view, budget " + megabytes(double(roomy.memoryBudgetBytes)), ms(roomyArrival.refinedMs), "<= 1 s"},
        {"stroke on bricks not resident (worst)", fixed(maximum(strokeMs), 1) + " ms over " + std::to_string(strokeMs.size()) + " strokes", "<= 50 ms"},
        {"read per frame (mean)", megabytes(double(flightRead) / double(flightFrames)), ""},
        {"sustained read rate / disk speed", megabytes(double(flightRead) / flightSeconds) + "/s / " + megabytes(diskSpeed) + "/s", "disk speed"},
        {"loading rate while refining (4 arrivals)", megabytes(loadRate) + "/s of payload", "disk speed"},
        {"resident bytes per voxel^2 of surface", fixed(residentPerSurfaceVoxel, 1) + " (one tree: " + fixed(ourSphere, 1) +
                                                      "; OpenVDB level set: " + fixed(vdbSphere, 1) + ")", "<= 25"},
        {"  the same over level 0's surface only", fixed(residentPerLevel0SurfaceVoxel, 1) + " (coarse bricks' bytes, fine surface)", ""},
    };
    t.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
