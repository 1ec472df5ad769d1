// bench render: the renderer on streamed terrains. Per terrain extent (the 4096 one is bench stream's,
// about 10^10 voxels of bounds): triangles of a complete 1080p view at 1 px of error (with the last
// frame's depth as occluders, and without), the CPU time per frame of a 90 Hz flight for selection,
// culling and upload recording, upload bytes per frame, GPU time on this machine's Vulkan device, and
// the time from an r=32 stamp to its chunks uploaded, beside OpenVDB's volumeToMesh of the same bricks
// in the same run.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "mesher/Mesher.h"
#include "render/OffscreenTarget.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/VulkanContext.h"
#include "scene/SceneStore.h"
#include "scene/StreamingScene.h"
#include "sculpt/StrokeScript.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>


namespace vdbclay::bench {

namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 1920, kHeight = 1080;

/// A viewer `clearance` above the terrain's ground at (x, z), looking along +x `lookAhead` ahead and
/// down by 0.7 clearance there (about 16 degrees): a flight over the ground, whatever its height.
Viewer viewerAt(int extent, double x, double z, double clearance, double lookAhead)
{
    const double y = terrainGroundHeight(extent, x, z) + clearance;
    Viewer v;
    v.position = {x, y, z};
    v.target = {x + lookAhead, y - 0.7 * clearance, z};
    v.fovDegrees = 60.0;
    v.viewport = {kWidth, kHeight};
    return v;
}

render::Camera cameraOf(const Viewer& v)
{
    render::Camera c;
    c.eye = v.position;
    c.target = v.target;
    c.fovYDegrees = v.fovDegrees;
    c.nearPlane = 0.5;
    return c;
}

/// Frames and waits until the view is refined as far as the budget allows.
FrameReport settle(StreamingScene& scene, const Viewer& viewer, const OccluderDepth* drawn = nullptr)
{
    FrameReport r;
    for (int i = 0; i < 400; ++i) {
        r = scene.frame(viewer, drawn);
        if (r.settled && r.pending == 0) break;
        scene.waitForLoads();
    }
    return r;
}

/// An r=32 stamp from its sculpt to its chunks uploaded.
struct StampFigures {
    double sculptMs = 0.0, meshMs = 0.0, uploadMs = 0.0, totalMs = 0.0, gpuMs = 0.0;
    uint64_t bricks = 0, bricksMeshed = 0, chunksUploaded = 0;
};

struct TerrainFigures {
    int extent = 0;
    uint64_t storeBytes = 0;
    // Complete views at 1080p, 1 px of error, over several stations: with the last frame's depth as
    // occluders (drawn again until the selection holds), and without.
    std::vector<double> viewTriangles, unoccludedViewTriangles, hiddenBricks;
    struct LevelShare {
        uint64_t bricks = 0, triangles = 0;
    };
    std::vector<LevelShare> perLevel; // of the complete view with the most triangles
    uint64_t maxChunks = 0, maxGpuBytes = 0;
    // At the last station: resident bytes (bricks and the shown bricks' meshes) per voxel^2 of resident
    // surface, and the meshes' share of them.
    double residentPerSurfaceVoxel = 0.0, meshShare = 0.0;
    double gpuMs1080 = 0.0; // one complete view drawn at full size
    // The flight.
    std::vector<double> cpuMs, selectMs, lockWaitMs, recordMs, meshMs, uploadBytes, triangles;
    // The first stamp on untouched bricks, and a stroke's next stamp 12 voxels on (its bricks already
    // re-made for edits).
    StampFigures stamp, nextStamp;
    double openvdbMeshMs = 0.0;
};

/// OpenVDB's meshing of the same surface: a level set of our mesh of the bricks (meshToLevelSet, half
/// width 3), then volumeToMesh, timed alone.
double openvdbRemeshMs(const Mesh& mesh, double voxel)
{
    if (mesh.triangles.empty()) return 0.0;
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    for (const auto& p : mesh.positions) points.emplace_back(float(p[0] / voxel), float(p[1] / voxel), float(p[2] / voxel));
    for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    const auto transform = openvdb::math::Transform::createLinearTransform(1.0);
    const openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
    std::vector<openvdb::Vec3s> outPoints;
    std::vector<openvdb::Vec3I> outTriangles;
    std::vector<openvdb::Vec4I> outQuads;
    return timeMs([&] { openvdb::tools::volumeToMesh(*grid, outPoints, outTriangles, outQuads, 0.0, 0.0); });
}

TerrainFigures measureTerrain(render::VulkanContext& context, int extent, bool quick, uint64_t budget, const fs::path& dir)
{
    TerrainFigures f;
    f.extent = extent;
    const std::string store = terrainStoreWithLod(dir, extent);
    f.storeBytes = fs::file_size(store);

    StreamingOptions options;
    options.memoryBudgetBytes = budget;
    options.access = StoreAccess::ReadWrite;
    StreamingScene scene(store, options);
    render::RendererOptions interactive; // as a window's frames: the flight's uploads are spread over frames
    interactive.uploadBytesPerFrame = render::kInteractiveUploadBytesPerFrame;
    render::Renderer renderer(context, interactive);
    renderer.setMaterials(scene.materials());
    render::StreamedSceneChunks chunks;
    // Fill costs on lavapipe grow with the pixels; the selection is the 1080p view's whatever the target.
    render::OffscreenTarget small(context, 480, 270);
    // The complete views are drawn at 1080p: their depth, kept as tiles, hides bricks from the next selection.
    render::OffscreenTarget full(context, kWidth, kHeight);
    // Frames of a view until every queued chunk is up (the upload budget spreads a view over frames).
    const auto drawComplete = [&](const Viewer& v, render::OffscreenTarget& target) {
        const render::RenderView view{cameraOf(v), &target, {}, true};
        render::FrameStats s = renderer.render({view});
        while (renderer.uploadsWaiting() > 0) s = renderer.render({view});
        return s;
    };
    const double clearance = 80.0, lookAhead = 200.0;

    // Complete views at stations across the terrain.
    const int stations = quick ? 2 : 4;
    for (int i = 0; i < stations; ++i) {
        const double x = extent * (0.1 + 0.2 * i), z = extent * (0.3 + 0.1 * i);
        const Viewer v = viewerAt(extent, x, z, clearance, lookAhead);
        settle(scene, v);
        chunks.sync(scene, renderer);
        render::FrameStats s = drawComplete(v, full);
        f.unoccludedViewTriangles.push_back(double(s.triangles));
        // Then with the frame's depth as occluders, until the selection holds (a coarser brick drawn where
        // finer ones were changes the depth a little).
        FrameReport report;
        for (int pass = 0; pass < 6; ++pass) {
            const std::vector<BrickKey> before = scene.shownBricks();
            const std::shared_ptr<const OccluderDepth> drawn = renderer.drawnDepth();
            report = settle(scene, v, drawn.get());
            chunks.sync(scene, renderer);
            s = drawComplete(v, full);
            if (scene.shownBricks() == before) break;
        }
        f.hiddenBricks.push_back(double(report.hidden));
        f.viewTriangles.push_back(double(s.triangles));
        // Where the triangles of the view with the most lie, per level.
        if (double(s.triangles) >= maximum(f.viewTriangles)) {
            f.perLevel.assign(std::size_t(scene.levels()) + 1, {});
            for (const BrickKey& key : scene.shownBricks())
                if (const auto mesh = scene.meshBrick(key)) {
                    ++f.perLevel[std::size_t(key.level)].bricks;
                    f.perLevel[std::size_t(key.level)].triangles += mesh->mesh.triangleCount();
                }
        }
        f.maxChunks = std::max(f.maxChunks, s.chunksDrawn);
        f.maxGpuBytes = std::max(f.maxGpuBytes, s.gpuMemoryBytes);
        if (i == stations - 1) {
            // At the last station: the scene has learnt by then what meshes take beside their bricks.
            f.residentPerSurfaceVoxel = double(scene.residentBytes()) / double(std::max<uint64_t>(1, scene.residentActiveVoxels()));
            f.meshShare = double(scene.residentMeshBytes()) / double(std::max<uint64_t>(1, scene.residentBytes()));
        }
        if (i == 0) f.gpuMs1080 = renderer.render({{cameraOf(v), &full, {}}}).gpuMs;
    }

    // The flight: along x at 90 Hz of wall time (the loaders stream meanwhile), each frame selected,
    // synced and drawn.
    const double seconds = quick ? 1.5 : 4.0, speed = extent * 0.5 / seconds;
    const auto start = Clock::now();
    for (int frame = 0; frame < int(seconds * 90.0); ++frame) {
        const Viewer v = viewerAt(extent, extent * 0.15 + speed * frame / 90.0, extent * 0.5, clearance, lookAhead);
        FrameReport report;
        const std::shared_ptr<const OccluderDepth> drawn = renderer.drawnDepth(); // the last frame's
        const double select = timeMs([&] { report = scene.frame(v, drawn.get()); });
        const double mesh = timeMs([&] { chunks.sync(scene, renderer); });
        const render::FrameStats s = renderer.render({{cameraOf(v), &small, {}, true}});
        f.selectMs.push_back(select);
        f.lockWaitMs.push_back(report.lockWaitMs);
        f.recordMs.push_back(s.cpuMs);
        f.cpuMs.push_back(select + s.cpuMs);
        f.meshMs.push_back(mesh);
        f.uploadBytes.push_back(double(s.uploadBytes));
        f.triangles.push_back(double(s.triangles));
        const double due = (frame + 1) / 90.0 * 1000.0 - millisecondsSince(start);
        if (due > 0.0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(due));
    }

    // A stamp of radius 32 on the surface in front of the camera, then its bricks re-meshed and uploaded.
    const Viewer v = viewerAt(extent, extent * 0.5, extent * 0.5, clearance, lookAhead);
    settle(scene, v);
    chunks.sync(scene, renderer);
    drawComplete(v, small);
    const Volume resident = scene.residentLevel0();
    const double voxel = scene.voxelSize();
    const int32_t sx = int32_t((v.position[0] + lookAhead * 0.5) / voxel), sz = int32_t(v.position[2] / voxel);
    int32_t sy = 0;
    for (int32_t y = int32_t(extent); y > -int32_t(extent); --y)
        if (resident.materialAt({sx, y, sz}) != kEmptyMaterial) {
            sy = y;
            break;
        }
    const auto stampAt = [&](int32_t x) {
        char text[200];
        std::snprintf(text, sizeof text, R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 32}, "at": [%.1f, %.1f, %.1f]}]})",
                      x * voxel, sy * voxel, sz * voxel);
        const StrokeScript stamp = parseStrokeScript(text);
        StampFigures out;
        const auto stampStart = Clock::now();
        StreamingScene::EditReport edit;
        out.sculptMs = timeMs([&] { edit = scene.sculpt(stamp); });
        scene.frame(v);
        render::StreamedSceneChunks::SyncReport sync;
        out.meshMs = timeMs([&] { sync = chunks.sync(scene, renderer); });
        out.totalMs = millisecondsSince(stampStart);
        // Then the frame that uploads them: its recording (staging copies included) counts to the upload;
        // the device's copy and draw are apart (lavapipe's draw is all CPU).
        // Frames until every re-meshed chunk is up (one unless the uploads pass the frame's budget).
        do {
            const render::FrameStats after = renderer.render({{cameraOf(v), &small, {}}});
            out.uploadMs += after.cpuMs;
            out.gpuMs += after.gpuMs;
            out.chunksUploaded += after.chunksUploaded;
        } while (renderer.uploadsWaiting() > 0);
        out.totalMs += out.uploadMs;
        out.bricksMeshed = sync.meshed;
        out.bricks = edit.bricksChanged;
        return out;
    };
    f.stamp = stampAt(sx);
    f.nextStamp = stampAt(sx + 12);
    // OpenVDB on the same bricks: the union of their meshes as one surface.
    Mesh changed;
    for (const BrickKey& key : scene.shownBricks()) {
        if (key.level != 0) continue;
        const auto box = brickBox(key.brick);
        const double cx = (box.min[0] + 32) * voxel, cz = (box.min[2] + 32) * voxel;
        if (std::fabs(cx - sx * voxel) > 32 + 48 || std::fabs(cz - sz * voxel) > 32 + 48) continue;
        const auto m = scene.meshBrick(key);
        if (!m) continue;
        appendMesh(changed, m->mesh.decoded());
    }
    f.openvdbMeshMs = openvdbRemeshMs(changed, voxel);
    return f;
}

} // namespace

int benchRender(bool json, bool quick, double memoryBudgetMb, const std::vector<int>& extents)
{
    const uint64_t budget = memoryBudgetMb > 0.0 ? uint64_t(memoryBudgetMb * double(1 << 20)) : 384ull << 20;
    const ScratchDir scratch("render");
    const fs::path& dir = scratch.path();

    render::VulkanContext context;
    std::vector<TerrainFigures> terrains;
    for (int extent : !extents.empty() ? extents : quick ? std::vector<int>{512, 768} : std::vector<int>{1024, 4096}) {
        if (!json) std::cerr << "bench render: terrain of extent " << extent << " ..." << std::endl;
        terrains.push_back(measureTerrain(context, extent, quick, budget, dir));
    }

    if (json) {
        nlohmann::json out = jsonPreamble("render", quick);
        out["device"] = context.deviceName();
        out["memory_budget_bytes"] = budget;
        out["viewport"] = {kWidth, kHeight};
        nlohmann::json list = nlohmann::json::array();
        for (const TerrainFigures& f : terrains)
            list.push_back({{"extent", f.extent},
                            {"store_bytes", f.storeBytes},
                            {"complete_view_triangles_max", maximum(f.viewTriangles)},
                            {"complete_view_triangles_mean", mean(f.viewTriangles)},
                            {"complete_view_chunks_max", f.maxChunks},
                            {"complete_view_triangles_unoccluded_max", maximum(f.unoccludedViewTriangles)},
                            {"complete_view_hidden_bricks_max", maximum(f.hiddenBricks)},
                            {"complete_view_per_level", [&] {
                                 nlohmann::json levels = nlohmann::json::array();
                                 for (const auto& l : f.perLevel) levels.push_back({{"bricks", l.bricks}, {"triangles", l.triangles}});
                                 return levels;
                             }()},
                            {"gpu_memory_bytes_max", f.maxGpuBytes},
                            {"resident_bytes_per_surface_voxel", f.residentPerSurfaceVoxel},
                            {"resident_mesh_share", f.meshShare},
                            {"gpu_ms_1080p", f.gpuMs1080},
                            {"flight_frames", f.cpuMs.size()},
                            {"cpu_ms_p50", percentile(f.cpuMs, 0.5)},
                            {"cpu_ms_p99", percentile(f.cpuMs, 0.99)},
                            {"select_ms_p99", percentile(f.selectMs, 0.99)},
                            {"select_lock_wait_ms_p50", percentile(f.lockWaitMs, 0.5)},
                            {"select_lock_wait_ms_p99", percentile(f.lockWaitMs, 0.99)},
                            {"record_ms_p99", percentile(f.recordMs, 0.99)},
                            {"mesh_ms_per_frame_mean", mean(f.meshMs)},
                            {"mesh_ms_per_frame_p99", percentile(f.meshMs, 0.99)},
                            {"upload_bytes_per_frame_mean", mean(f.uploadBytes)},
                            {"upload_bytes_per_frame_max", maximum(f.uploadBytes)},
                            {"triangles_per_frame_mean", mean(f.triangles)},
                            {"triangles_per_frame_max", maximum(f.triangles)},
                            {"stamp_bricks", f.stamp.bricks},
                            {"stamp_bricks_meshed", f.stamp.bricksMeshed},
                            {"stamp_chunks_uploaded", f.stamp.chunksUploaded},
                            {"stamp_gpu_ms", f.stamp.gpuMs},
                            {"stamp_sculpt_ms", f.stamp.sculptMs},
                            {"stamp_mesh_ms", f.stamp.meshMs},
                            {"stamp_upload_ms", f.stamp.uploadMs},
                            {"stamp_to_uploaded_ms", f.stamp.totalMs},
                            {"next_stamp_bricks", f.nextStamp.bricks},
                            {"next_stamp_bricks_meshed", f.nextStamp.bricksMeshed},
                            {"next_stamp_sculpt_ms", f.nextStamp.sculptMs},
                            {"next_stamp_mesh_ms", f.nextStamp.meshMs},
                            {"next_stamp_upload_ms", f.nextStamp.uploadMs},
                            {"next_stamp_to_uploaded_ms", f.nextStamp.totalMs},
                            {"openvdb_volume_to_mesh_ms", f.openvdbMeshMs}});
        out["terrains"] = list;
        std::cout << out.dump(2) << std::endl;
        return 0;
    }
    printPreamble(std::cout, "render", quick);
    std::cout << "device: " << context.deviceName() << "; views selected for " << kWidth << "x" << kHeight
              << " at 1 px of error; memory budget " << megabytes(double(budget)) << "\n\n";
    Table t;
    t.header = {"figure"};
    for (const TerrainFigures& f : terrains) t.header.push_back("extent " + std::to_string(f.extent));
    t.header.push_back("goal / baseline");
    const auto row = [&](const std::string& name, auto value, const std::string& goal) {
        std::vector<std::string> r{name};
        for (const TerrainFigures& f : terrains) r.push_back(value(f));
        r.push_back(goal);
        t.rows.push_back(r);
    };
    row("triangles of a complete view (max)", [](const TerrainFigures& f) { return fixed(maximum(f.viewTriangles) / 1e6, 2) + " M"; }, "<= 2 M");
    row("  without occluders (the last frame's depth)", [](const TerrainFigures& f) { return fixed(maximum(f.unoccludedViewTriangles) / 1e6, 2) + " M"; }, "");
    row("  bricks left coarse behind drawn surfaces (max)", [](const TerrainFigures& f) { return fixed(maximum(f.hiddenBricks), 0); }, "");
    row("  per level: bricks / triangles (the view with the most)", [](const TerrainFigures& f) {
        std::string out;
        for (std::size_t k = 0; k < f.perLevel.size(); ++k)
            if (f.perLevel[k].bricks)
                out += (out.empty() ? "" : ", ") + std::to_string(k) + ": " + std::to_string(f.perLevel[k].bricks) + " / " +
                       fixed(double(f.perLevel[k].triangles) / 1e6, 2) + " M";
        return out;
    }, "");
    row("chunks drawn (max) / GPU memory", [](const TerrainFigures& f) { return std::to_string(f.maxChunks) + " / " + megabytes(double(f.maxGpuBytes)); }, "");
    row("resident bytes per voxel^2 of surface (meshes' share)", [](const TerrainFigures& f) { return fixed(f.residentPerSurfaceVoxel, 1) + " (" + fixed(100.0 * f.meshShare, 0) + " %)"; }, "<= 25");
    row("CPU per frame p50 / p99 (select + record)", [](const TerrainFigures& f) { return fixed(percentile(f.cpuMs, 0.5), 2) + " / " + fixed(percentile(f.cpuMs, 0.99), 2) + " ms"; }, "p99 <= 2 ms");
    row("  selection p99; of it waiting for the scene's lock p50 / p99", [](const TerrainFigures& f) {
        return fixed(percentile(f.selectMs, 0.99), 2) + "; " + fixed(percentile(f.lockWaitMs, 0.5), 2) + " / " + fixed(percentile(f.lockWaitMs, 0.99), 2) + " ms";
    }, "");
    row("meshing per frame mean / p99 (workers' share)", [](const TerrainFigures& f) { return fixed(mean(f.meshMs), 1) + " / " + fixed(percentile(f.meshMs, 0.99), 1) + " ms"; }, "");
    row("upload per frame mean / max", [](const TerrainFigures& f) { return megabytes(mean(f.uploadBytes)) + " / " + megabytes(maximum(f.uploadBytes)); }, "");
    row("triangles per flight frame mean / max", [](const TerrainFigures& f) { return fixed(mean(f.triangles) / 1e6, 2) + " / " + fixed(maximum(f.triangles) / 1e6, 2) + " M"; }, "");
    for (const auto& [title, of] : {std::pair<const char*, StampFigures TerrainFigures::*>{"r=32 stamp to chunks uploaded", &TerrainFigures::stamp},
                                    {"a stroke's next stamp (12 voxels on)", &TerrainFigures::nextStamp}}) {
        const auto which = of;
        row(title, [which](const TerrainFigures& f) { return fixed((f.*which).totalMs, 1) + " ms (" + std::to_string((f.*which).bricks) + " bricks)"; }, "<= 3 ms");
        row("  sculpt / re-mesh / upload recorded", [which](const TerrainFigures& f) {
            const StampFigures& s = f.*which;
            return fixed(s.sculptMs, 1) + " / " + fixed(s.meshMs, 1) + " / " + fixed(s.uploadMs, 1) + " ms";
        }, "");
        row("  bricks meshed again / chunks uploaded", [which](const TerrainFigures& f) {
            return std::to_string((f.*which).bricksMeshed) + " / " + std::to_string((f.*which).chunksUploaded);
        }, "");
    }
    row("  the first stamp's frame on the device (copy + draw)", [](const TerrainFigures& f) { return fixed(f.stamp.gpuMs, 1) + " ms"; }, "informational");
    row("  OpenVDB volumeToMesh of those bricks", [](const TerrainFigures& f) { return fixed(f.openvdbMeshMs, 1) + " ms"; }, "baseline");
    row("GPU, one complete view at 1080p", [](const TerrainFigures& f) { return fixed(f.gpuMs1080, 1) + " ms"; }, "<= 5 ms on a GPU");
    t.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
