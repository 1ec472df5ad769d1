// bench editor: the desktop editor's frame without the window. A stroke-heavy session (r=32 strokes of
// every mode, mirror symmetry on) replayed at 90 Hz on a synthetic terrain store of at least 10^9 voxels
// of bounds: each frame submits its commands to the edit worker as they arrive on the recorded clock
// (never waiting for them), then does what the editor's frame thread does: streaming, taking the meshes
// the mesh workers finished (asking them for the changed bricks), upload recording. Reports the frame thread's CPU time p50/p99 and the frames over
// 11.1 ms, edit-to-visible latency in frames per mode, the worker's time per stroke step and the most
// commands pending, triangles, upload bytes per frame and resident memory against the budget; the
// rotated 64^3 tool stamp; OpenVDB's stamp and re-mesh of the same region.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "editor/EditingSession.h"
#include "editor/SessionWorker.h"
#include "render/OffscreenTarget.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/VulkanContext.h"
#include "scene/SceneStore.h"
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/VolumeIO.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <thread>


namespace vdbclay::bench {

namespace {

namespace fs = std::filesystem;

constexpr std::array<int, 2> kViewport{1920, 1080};
constexpr double kRadius = 32.0;

constexpr double kFrameMs = 1000.0 / 90.0;
constexpr int kMeshThreads = 1; // as the window's (DesktopEditor)

struct FrameSample {
    double cpuMs = 0.0, submitMs = 0.0, streamMs = 0.0, meshMs = 0.0, recordMs = 0.0;
    uint64_t triangles = 0, uploadBytes = 0, residentBytes = 0, pendingEdits = 0;
};

struct EditorFigures {
    int extent = 0;
    uint64_t budget = 0;
    std::vector<FrameSample> frames;
    std::vector<double> latencyFrames; // per edit: frames until the view showed it (1 = the frame it was submitted in)
    std::map<std::string, std::vector<double>> latencyByMode;
    std::vector<double> appliedFrames; // per edit: frames until the worker had applied it (the rest is meshing and selection)
    std::map<std::string, std::vector<double>> appliedByMode;
    std::vector<double> currentFrames; // per edit: frames until the view was current at its points (later edits there meshed too)
    std::map<std::string, std::vector<double>> stampMsByMode; // the worker's time per stroke step
    /// Per mode: the worker's time over all its ops and the stroke points they applied (merged or not): a
    /// figure that does not move with how many points the worker happened to merge.
    std::map<std::string, std::pair<double, uint64_t>> msAndPointsByMode;
    std::vector<double> commandMs;                            // the worker's time per op it applied
    uint64_t mergedPoints = 0;                                // stroke points the worker merged into the next one's op
    double toolFrameMs = 0.0, toolEditMs = 0.0, toolMeshMs = 0.0, toolVisibleFrames = 0.0;
    uint64_t toolBricks = 0;
    double openvdbStampMs = 0.0, openvdbMeshMs = 0.0;
    std::string device;
};

Command brushCommand(const std::string& mode, double radius, const nlohmann::json& symmetry)
{
    Command c;
    c.kind = Command::Kind::SetBrush;
    c.brush.emplace();
    c.brush->mode = mode;
    c.brush->radius = radius;
    c.brush->strength = 0.6;
    c.brush->distance = 4.0;
    c.brush->symmetry = symmetry;
    return c;
}

/// OpenVDB on the region of the first stroke: a level set of our meshes of its bricks (untimed), then a
/// sphere of the brush's radius united in (the stamp) and volumeToMesh of the result (the re-mesh).
std::pair<double, double> openvdbStampAndRemesh(const StreamingScene& scene, const std::array<double, 3>& at)
{
    const double voxel = scene.voxelSize();
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    for (const BrickKey& key : scene.shownBricks()) {
        if (key.level != 0) continue;
        const auto box = brickBox(key.brick);
        bool near = true;
        for (std::size_t a = 0; a < 3; ++a) near = near && std::fabs((box.min[a] + 32) * voxel - at[a]) < kRadius * voxel + 48 * voxel;
        if (!near) continue;
        const auto m = scene.meshBrick(key);
        if (!m) continue;
        const uint32_t base = uint32_t(points.size());
        const Mesh mesh = m->mesh.decoded();
        for (const auto& p : mesh.positions) points.emplace_back(float(p[0] / voxel), float(p[1] / voxel), float(p[2] / voxel));
        for (const auto& t : mesh.triangles) triangles.emplace_back(t[0] + base, t[1] + base, t[2] + base);
    }
    if (triangles.empty()) return {0.0, 0.0};
    const auto transform = openvdb::math::Transform::createLinearTransform(1.0);
    openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
    const double stampMs = timeMs([&] {
        openvdb::FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
            float(kRadius), openvdb::Vec3f(float(at[0] / voxel), float(at[1] / voxel), float(at[2] / voxel)), 1.0f, 3.0f);
        openvdb::tools::csgUnion(*grid, *sphere);
    });
    std::vector<openvdb::Vec3s> outPoints;
    std::vector<openvdb::Vec3I> outTriangles;
    std::vector<openvdb::Vec4I> outQuads;
    const double meshMs = timeMs([&] { openvdb::tools::volumeToMesh(*grid, outPoints, outTriangles, outQuads, 0.0, 0.0); });
    return {stampMs, meshMs};
}

/// A 64^3 tool (a rounded box with a sphere carved out of one face), saved as a .vdb.
std::string makeTool(const fs::path& dir, double voxel)
{
    Volume tool(voxel);
    nlohmann::json box = {{"mode", "add"}, {"brush", {{"shape", "box"}, {"size", {30 * voxel, 30 * voxel, 30 * voxel}}, {"rounding", 4 * voxel}}}};
    nlohmann::json carve = {{"mode", "remove"}, {"brush", {{"shape", "sphere"}, {"radius", 16 * voxel}}}, {"at", {0.0, 30 * voxel, 0.0}}};
    nlohmann::json script;
    script["ops"] = nlohmann::json::array({box, carve});
    runStrokeScript(tool, parseStrokeScript(script.dump()));
    const std::string path = (dir / "tool64.vdb").string();
    saveVolume(tool, path);
    return path;
}

EditorFigures measure(int extent, bool quick, uint64_t budget, const fs::path& dir)
{
    EditorFigures f;
    f.extent = extent;
    f.budget = budget;
    const std::string store = terrainStoreWithLod(dir, extent);
    SessionOptions options;
    options.memoryBudgetBytes = budget;
    EditingSession session(store, options);
    const double voxel = session.scene().voxelSize();
    const double cx = extent * 0.5 * voxel, cz = extent * 0.5 * voxel;

    render::VulkanContext context;
    f.device = context.deviceName();
    render::RendererOptions interactive; // as the window's frames
    interactive.uploadBytesPerFrame = render::kInteractiveUploadBytesPerFrame;
    render::Renderer renderer(context, interactive);
    renderer.setMaterials(session.scene().materials());
    render::StreamedSceneChunks chunks(session.scene(), kMeshThreads);
    render::OffscreenTarget small(context, 480, 270); // lavapipe's fill grows with pixels; selection is 1080p's

    Command camera;
    camera.kind = Command::Kind::SetCamera;
    camera.camera.eye = {cx - 180 * voxel, 140 * voxel, cz};
    camera.camera.target = {cx, 20 * voxel, cz};
    camera.camera.fovYDegrees = 60.0;
    camera.camera.nearPlane = 0.5 * voxel;
    session.apply(camera);
    for (int i = 0; i < 200; ++i) { // settle the view
        const FrameReport r = session.frame(0.0, kViewport);
        const uint64_t meshesWaiting = chunks.sync(session.scene(), renderer).waiting;
        chunks.waitForMeshes();
        if (r.settled && r.pending == 0 && meshesWaiting == 0) break;
        session.scene().waitForLoads();
    }
    renderer.render({{session.camera(), &small, {}}});

    // The session: per mode, a stroke of 8 steps of 12 voxels across the surface, mirrored across x.
    static const char* modes[] = {"add", "remove", "paint", "smooth", "flatten", "inflate", "deflate", "move", "erode"};
    const nlohmann::json symmetry = {{"mirror", {"z"}}, {"center", {cx, 0.0, cz}}};
    std::vector<std::vector<Command>> plan; // commands per frame
    std::vector<std::string> planMode;
    const int strokes = quick ? 9 : 18;
    for (int s = 0; s < strokes; ++s) {
        const std::string mode = modes[s % 9];
        const double angle = 0.7 * s;
        double x = cx + 30 * voxel * std::cos(angle), z = cz + 20 * voxel + 30 * voxel * std::sin(angle);
        const auto surface = [&](double px, double pz) { return session.pick({px, 400 * voxel, pz}, {0, -1, 0}); };
        std::vector<Command> first{brushCommand(mode, kRadius * voxel, symmetry)};
        const auto start = surface(x, z);
        if (!start) continue;
        Command begin;
        begin.kind = Command::Kind::StrokeBegin;
        begin.point = start->point;
        first.push_back(begin);
        plan.push_back(first);
        planMode.push_back(mode);
        for (int k = 0; k < 8; ++k) {
            x += 12 * voxel;
            const auto p = surface(x, z);
            Command move;
            move.kind = Command::Kind::StrokeMove;
            move.point = p ? p->point : begin.point;
            if (mode == "move") move.point = {x, start->point[1] + 2 * voxel * (k + 1), z};
            plan.push_back({move});
            planMode.push_back(mode);
        }
        Command end;
        end.kind = Command::Kind::StrokeEnd;
        plan.push_back({end});
        planMode.push_back("");
        for (int idle = 0; idle < 3; ++idle) {
            plan.push_back({});
            planMode.push_back("");
        }
    }
    // The rotated tool stamp, alone in its frame, twice: the first builds the tool's fields (once per
    // session), the second is the stamp reported.
    const std::string tool = makeTool(dir, voxel);
    for (const double dz : {-40.0, -80.0}) {
        const auto toolAt = session.pick({cx + 40 * voxel, 400 * voxel, cz + dz * voxel}, {0, -1, 0});
        if (!toolAt) continue;
        Command stamp;
        stamp.kind = Command::Kind::ApplyOp;
        stamp.op = {{"mode", "add"}, {"brush", {{"shape", "grid"}, {"file", tool}}}, {"at", toolAt->point}, {"rotate", {20, 35, 10}}};
        plan.push_back({stamp});
        planMode.push_back("tool");
        plan.push_back({});
        planMode.push_back("");
    }

    // Frames at 90 Hz: each submits the commands that arrived by then and never waits for the worker.
    // An edit is visible once the worker applied it and the view shows level 0 at the points it was made
    // (and their mirror images) with meshes made from the bricks' content since it (a coarse brick shown
    // there still holds the data before it). Later edits of a stroke need not be meshed yet: that is when
    // the view is current there, reported apart.
    struct Waiting {
        std::size_t frame = 0; // submitted in
        uint64_t command = 0;  // its place in the order submitted, from 1: applied once the worker did that many
        std::string mode;
        std::vector<std::array<double, 3>> at;
        std::optional<std::size_t> appliedIn; // the first frame that found it applied
        std::vector<uint64_t> contentAt;      // per point, its brick's content then (StreamingScene::brickContent)
        std::optional<std::size_t> visibleIn;
    };
    std::vector<std::string> commandModes; // per command, in the order submitted: the stroke's mode, or ""
    for (std::size_t i = 0; i < plan.size(); ++i)
        for (const Command& c : plan[i])
            commandModes.push_back(c.kind == Command::Kind::StrokeBegin || c.kind == Command::Kind::StrokeMove || c.kind == Command::Kind::ApplyOp ? planMode[i] : "");
    // The worker's time per command, and the bricks the frame after the tool's second stamp changed.
    std::mutex timesMutex;
    std::size_t applied = 0;
    int toolsApplied = 0;
    bool toolFrameNext = false;
    SessionWorkerOptions workerOptions;
    workerOptions.afterTask = [&](const Command* command, double ms) {
        std::lock_guard<std::mutex> lock(timesMutex);
        if (!command) {
            if (toolFrameNext) f.toolBricks = session.stats().bricksChangedLastFrame; // on the worker: the session is its own
            toolFrameNext = false;
            return;
        }
        const std::string& mode = applied < commandModes.size() ? commandModes[applied] : std::string();
        ++applied;
        if (mode == "tool") {
            if (++toolsApplied == 2) { // the first built the tool's fields (once per session)
                f.toolEditMs = ms;
                toolFrameNext = true;
            }
        } else if (command->mergedWithNext) {
            ++f.mergedPoints; // its stamps go with the next point's op, timed there
            if (!mode.empty()) ++f.msAndPointsByMode[mode].second;
        } else if (!mode.empty()) {
            f.stampMsByMode[mode].push_back(ms);
            f.commandMs.push_back(ms);
            f.msAndPointsByMode[mode].first += ms;
            ++f.msAndPointsByMode[mode].second;
        }
    };
    std::vector<Waiting> waiting;
    // Not yet drawn as it is now at a point: shown at a coarse level, or by a mesh older than its brick.
    const auto level0Brick = [&](const std::array<double, 3>& world) {
        BrickKey key;
        for (std::size_t a = 0; a < 3; ++a) key.brick[a] = int32_t(std::floor(world[a] / (voxel * kBrickEdge)));
        return key;
    };
    // Not yet drawn as it is now at a point: shown at a coarse level, or by a mesh older than its brick.
    const auto notCurrentAt = [&](const std::array<double, 3>& world) {
        if (session.scene().shownLevelAt(world).value_or(0) > 0) return true;
        const BrickKey key = level0Brick(world);
        const std::optional<uint64_t> drawn = chunks.versionOf(key);
        return drawn && *drawn != session.scene().brickVersion(key);
    };
    // Drawn at level 0 with a mesh made from the brick's content `content` or later.
    const auto drawnSince = [&](const std::array<double, 3>& world, uint64_t content) {
        if (session.scene().shownLevelAt(world).value_or(0) > 0) return false;
        const std::optional<uint64_t> drawn = chunks.contentOf(level0Brick(world));
        return !drawn || *drawn >= content;
    };
    bool baselineDone = false;
    uint64_t submitted = 0;
    int toolsSubmitted = 0;
    {
        SessionWorker worker(session, workerOptions);
        const auto begin = std::chrono::steady_clock::now();
        // After the plan, frames go on until every edit has shown (at most ten seconds more).
        for (std::size_t i = 0; i < plan.size() + 900 && (i < plan.size() || !waiting.empty()); ++i) {
            std::this_thread::sleep_until(begin + std::chrono::microseconds(int64_t(double(i) * kFrameMs * 1000.0)));
            FrameSample s;
            const std::vector<Command> none;
            const std::vector<Command>& commands = i < plan.size() ? plan[i] : none;
            s.submitMs = timeMs([&] {
                for (const Command& c : commands) worker.submit(c);
            });
            for (const Command& c : commands) {
                ++submitted;
                std::array<double, 3> at = c.point.value_or(std::array<double, 3>{0, 0, 0});
                if (c.kind == Command::Kind::ApplyOp) at = c.op.at("at").get<std::array<double, 3>>();
                else if (c.kind != Command::Kind::StrokeBegin && c.kind != Command::Kind::StrokeMove) continue;
                // The tool's first stamp builds its fields: the second is the one reported.
                if (planMode[i] == "tool" && ++toolsSubmitted == 1) continue;
                Waiting& w = waiting.emplace_back();
                w.frame = i;
                w.command = submitted;
                w.mode = planMode[i];
                w.at = {at, {at[0], at[1], 2.0 * cz - at[2]}};
            }
            FrameReport report;
            s.streamMs = timeMs([&] { report = worker.frame(double(i) / 90.0, kViewport); });
            s.meshMs = timeMs([&] { chunks.sync(session.scene(), renderer); });
            const render::FrameStats stats = renderer.render({{worker.camera(), &small, {}}});
            s.recordMs = stats.cpuMs;
            s.cpuMs = s.submitMs + s.streamMs + s.meshMs + s.recordMs; // the device's work (lavapipe's too) is apart
            s.triangles = stats.triangles;
            s.uploadBytes = stats.uploadBytes;
            s.residentBytes = report.residentBytes;
            s.pendingEdits = worker.pending();
            f.frames.push_back(s);
            const uint64_t done = worker.snapshot().commandsApplied;
            for (auto it = waiting.begin(); it != waiting.end();) {
                if (done >= it->command && !it->appliedIn) {
                    it->appliedIn = i;
                    for (const auto& world : it->at) it->contentAt.push_back(session.scene().brickContent(level0Brick(world)).value_or(0));
                }
                if (it->appliedIn && !it->visibleIn) {
                    bool all = true;
                    for (std::size_t p = 0; p < it->at.size(); ++p) all = all && drawnSince(it->at[p], it->contentAt[p]);
                    if (all) it->visibleIn = i;
                }
                if (it->visibleIn && std::none_of(it->at.begin(), it->at.end(), notCurrentAt)) {
                    const double frames = double(*it->visibleIn - it->frame + 1);
                    if (it->mode == "tool") {
                        f.toolFrameMs = s.cpuMs; // the frame that re-meshed and drew it
                        f.toolMeshMs = s.meshMs;
                        f.toolVisibleFrames = frames;
                    } else {
                        f.latencyFrames.push_back(frames);
                        f.latencyByMode[it->mode].push_back(frames);
                        f.appliedFrames.push_back(double(*it->appliedIn - it->frame + 1));
                        f.appliedByMode[it->mode].push_back(f.appliedFrames.back());
                        f.currentFrames.push_back(double(i - it->frame + 1));
                    }
                    it = waiting.erase(it);
                } else {
                    ++it;
                }
            }
            if (!baselineDone && i < plan.size() && planMode[i] == "add" && plan[i].size() == 2) {
                const auto [stamp, mesh] = openvdbStampAndRemesh(session.scene(), *plan[i][1].point);
                f.openvdbStampMs = stamp;
                f.openvdbMeshMs = mesh;
                baselineDone = true;
            }
        }
        worker.waitIdle();
    }
    return f;
}

} // namespace

int benchEditor(bool json, bool quick, double memoryBudgetMb)
{
    const uint64_t budget = memoryBudgetMb > 0.0 ? uint64_t(memoryBudgetMb * double(1 << 20)) : 384ull << 20;
    const ScratchDir scratch("editor");
    const fs::path& dir = scratch.path();
    const int extent = quick ? 512 : 1024;
    if (!json) std::cerr << "bench editor: terrain of extent " << extent << " ..." << std::endl;
    const EditorFigures f = measure(extent, quick, budget, dir);

    std::vector<double> cpu, stream, mesh, record, triangles, upload, resident;
    const std::vector<double>& edit = f.commandMs;
    uint64_t missed = 0, pendingMax = 0;
    for (const FrameSample& s : f.frames) {
        missed += s.cpuMs > kFrameMs;
        pendingMax = std::max(pendingMax, s.pendingEdits);
        cpu.push_back(s.cpuMs);
        stream.push_back(s.streamMs);
        mesh.push_back(s.meshMs);
        record.push_back(s.recordMs);
        triangles.push_back(double(s.triangles));
        upload.push_back(double(s.uploadBytes));
        resident.push_back(double(s.residentBytes));
    }
    if (json) {
        nlohmann::json out = jsonPreamble("editor", quick);
        out["frame_ms"] = {{"p50", percentile(cpu, 0.5)}, {"p99", percentile(cpu, 0.99)}};
        out["missed_frames"] = missed;
        out["pending_edits_max"] = pendingMax;
        out["merged_stroke_points"] = f.mergedPoints;
        const auto spread = [](const std::vector<double>& v) {
            return nlohmann::json{{"p50", percentile(v, 0.5)}, {"p99", percentile(v, 0.99)}, {"max", maximum(v)}};
        };
        nlohmann::json visible = spread(f.latencyFrames), byMode = nlohmann::json::object(), steps = nlohmann::json::object();
        for (const auto& [mode, frames] : f.latencyByMode) byMode[mode] = spread(frames);
        visible["by_mode"] = byMode;
        out["edit_to_visible_frames"] = visible;
        nlohmann::json applied = spread(f.appliedFrames), appliedModes = nlohmann::json::object();
        for (const auto& [mode, frames] : f.appliedByMode) appliedModes[mode] = spread(frames);
        applied["by_mode"] = appliedModes;
        out["edit_to_applied_frames"] = applied;
        out["edit_to_current_frames"] = spread(f.currentFrames);
        for (const auto& [mode, ms] : f.stampMsByMode) steps[mode] = spread(ms);
        out["step_ms"] = steps;
        nlohmann::json perPoint = nlohmann::json::object();
        for (const auto& [mode, total] : f.msAndPointsByMode)
            if (total.second > 0) perPoint[mode] = total.first / double(total.second);
        out["ms_per_stroke_point"] = perPoint;
        out["triangles"] = uint64_t(mean(triangles));
        out["upload_bytes_per_frame"] = uint64_t(mean(upload));
        out["resident_bytes"] = uint64_t(maximum(resident));
        out["budget_bytes"] = f.budget;
        out["extent"] = f.extent;
        out["frames"] = f.frames.size();
        out["device"] = f.device;
        out["edit_ms"] = {{"p50", percentile(edit, 0.5)}, {"p99", percentile(edit, 0.99)}};
        out["stream_ms_p99"] = percentile(stream, 0.99);
        out["mesh_ms"] = {{"p50", percentile(mesh, 0.5)}, {"p99", percentile(mesh, 0.99)}};
        out["record_ms_p99"] = percentile(record, 0.99);
        nlohmann::json modes = nlohmann::json::object();
        for (const auto& [mode, ms] : f.stampMsByMode) modes[mode] = {{"median", median(ms)}, {"max", maximum(ms)}};
        out["stroke_step_ms_by_mode"] = modes;
        out["tool_stamp_64_rotated"] = {{"frame_ms", f.toolFrameMs}, {"edit_ms", f.toolEditMs}, {"mesh_ms", f.toolMeshMs}, {"bricks", f.toolBricks},
                                        {"visible_frames", f.toolVisibleFrames}};
        out["openvdb"] = {{"sphere_stamp_ms", f.openvdbStampMs}, {"volume_to_mesh_ms", f.openvdbMeshMs}};
        std::cout << out.dump(2) << std::endl;
        return 0;
    }
    printPreamble(std::cout, "editor", quick);
    std::cout << "device: " << f.device << "; terrain of extent " << f.extent << " (" << fixed(std::pow(double(f.extent), 3) / 1e9, 2)
              << " x 10^9 voxels of bounds), views selected for 1920x1080; " << f.frames.size() << " frames; r=" << kRadius
              << " strokes of every mode mirrored; memory budget " << megabytes(double(f.budget)) << "\n\n";
    Table t;
    t.header = {"figure", "value", "goal / baseline"};
    t.rows.push_back({"frame thread CPU p50 / p99 (submit + stream + re-mesh + record)", fixed(percentile(cpu, 0.5), 1) + " / " + fixed(percentile(cpu, 0.99), 1) + " ms", "p99 <= 11 ms"});
    t.rows.push_back({"  frames over 11.1 ms", std::to_string(missed) + " of " + std::to_string(f.frames.size()), "none"});
    t.rows.push_back({"  edit worker per op applied p50 / p99", fixed(percentile(edit, 0.5), 1) + " / " + fixed(percentile(edit, 0.99), 1) + " ms", ""});
    t.rows.push_back({"  commands pending (most); stroke points merged into the next one's op", std::to_string(pendingMax) + "; " + std::to_string(f.mergedPoints), ""});
    t.rows.push_back({"  re-mesh p50 / p99", fixed(percentile(mesh, 0.5), 1) + " / " + fixed(percentile(mesh, 0.99), 1) + " ms", ""});
    t.rows.push_back({"  stream / record p99", fixed(percentile(stream, 0.99), 2) + " / " + fixed(percentile(record, 0.99), 2) + " ms", ""});
    t.rows.push_back({"edit to visible p50 / p99 / max", fixed(percentile(f.latencyFrames, 0.5), 0) + " / " + fixed(percentile(f.latencyFrames, 0.99), 0) + " / " +
                                                              fixed(maximum(f.latencyFrames), 0) + " frames",
                      "CSG <= 2, reshaping <= 4"});
    t.rows.push_back({"  until the view is current there too (the stroke's later edits meshed), p50 / p99 / max",
                      fixed(percentile(f.currentFrames, 0.5), 0) + " / " + fixed(percentile(f.currentFrames, 0.99), 0) + " / " +
                          fixed(maximum(f.currentFrames), 0) + " frames",
                      ""});
    t.rows.push_back({"  of which until the worker applied it, p50 / p99 / max", fixed(percentile(f.appliedFrames, 0.5), 0) + " / " +
                                                                                      fixed(percentile(f.appliedFrames, 0.99), 0) + " / " +
                                                                                      fixed(maximum(f.appliedFrames), 0) + " frames",
                      ""});
    for (const auto& [mode, frames] : f.latencyByMode) {
        const std::vector<double>& applied = f.appliedByMode.at(mode);
        t.rows.push_back({"  edit to visible, " + mode + " (p50 / max; applied p50 / max)",
                          fixed(percentile(frames, 0.5), 0) + " / " + fixed(maximum(frames), 0) + "; " + fixed(percentile(applied, 0.5), 0) + " / " +
                              fixed(maximum(applied), 0) + " frames",
                          ""});
    }
    t.rows.push_back({"triangles drawn (mean)", fixed(mean(triangles) / 1e6, 2) + " M", ""});
    t.rows.push_back({"upload per frame (mean / max)", megabytes(mean(upload)) + " / " + megabytes(maximum(upload)), ""});
    t.rows.push_back({"resident (max) / budget", megabytes(maximum(resident)) + " / " + megabytes(double(f.budget)), "within the budget"});
    for (const auto& [mode, ms] : f.stampMsByMode)
        t.rows.push_back({"  op on the worker (a stroke step, or merged steps), " + mode + " (median / max)", fixed(median(ms), 1) + " / " + fixed(maximum(ms), 1) + " ms",
                          mode == "add" || mode == "remove" || mode == "paint" || mode == "erode" ? "<= 3 ms" : "<= 15 ms"});
    for (const auto& [mode, total] : f.msAndPointsByMode)
        if (total.second > 0)
            t.rows.push_back({"  worker time per stroke point, " + mode + " (all its ops / points)", fixed(total.first / double(total.second), 1) + " ms", ""});
    t.rows.push_back({"64^3 rotated tool stamp: worker edit; frame that drew it (its re-mesh); frames until shown",
                      fixed(f.toolEditMs, 1) + " ms; " + fixed(f.toolFrameMs, 1) + " ms (" + fixed(f.toolMeshMs, 1) + "); " + fixed(f.toolVisibleFrames, 0),
                      "edit <= 2 ms"});
    t.rows.push_back({"OpenVDB: r=32 sphere csgUnion / volumeToMesh of the region", fixed(f.openvdbStampMs, 1) + " / " + fixed(f.openvdbMeshMs, 1) + " ms", "baseline"});
    t.print(std::cout);
    return 0;
}

} // namespace vdbclay::bench
