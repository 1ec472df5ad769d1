// bench vr: the stroke-heavy session of bench editor in a headset: the VR editor (vr::runVrSession) through
// the fake OpenXR runtime of the test build (a 90 Hz headset scripted from JSON), on the synthetic terrain
// store of at least 10^9 voxels of bounds. The right hand draws r=32 strokes of every mode the
// thumbstick cycles through (mirror symmetry on), 8 steps of 12 voxels each at one step a frame. Reports
// the frame thread's CPU time per frame p50/p99 (the device's drawing apart, as bench editor counts),
// the display refreshes missed while stroking, edit-to-visible frames and pose-to-submit latency.
#include "BenchSuites.h"
#include "BenchUtil.h"

#include "editor/EditingSession.h"
#include "scene/SceneStore.h"
#include "vr/VrControls.h"
#include "vr/VrEditor.h"
#include "vr/WorldPlacement.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace vdbclay::bench {

namespace {

namespace fs = std::filesystem;

constexpr double kRadius = 32.0;
constexpr int kEye = 512;         // pixels per side of each eye (lavapipe's fill grows with pixels)
constexpr uint64_t kSettle = 270; // frames the view settles in before the strokes (3 s)

nlohmann::json handKey(uint64_t frame, const glm::dvec3& p, double trigger, double stickX = 0.0)
{
    return {{"frame", frame}, {"position", {p.x, p.y, p.z}}, {"trigger", trigger}, {"thumbstick", {stickX, 0.0}}};
}

} // namespace

int benchVr(bool json, bool quick, double memoryBudgetMb)
{
    // The fake runtime the test build makes (or the one XR_RUNTIME_JSON names).
    const char* named = std::getenv("XR_RUNTIME_JSON");
    const std::string runtime = named && *named ? std::string(named) : std::string(VDBCLAY_FAKEXR_JSON);
    if (!fs::exists(runtime)) {
        std::cerr << "vdbclay: error: bench vr runs through the fake OpenXR runtime of the test build (" << runtime
                  << " is missing): build the tests (bash scripts/bootstrap.sh test), or set XR_RUNTIME_JSON\n";
        return 1;
    }
    const uint64_t budget = memoryBudgetMb > 0.0 ? uint64_t(memoryBudgetMb * double(1 << 20)) : 384ull << 20;
    const ScratchDir scratch("vr");
    const fs::path& dir = scratch.path();
    const int extent = quick ? 512 : 1024;
    if (!json) std::cerr << "bench vr: terrain of extent " << extent << " ..." << std::endl;
    const std::string store = terrainStoreWithLod(dir, extent);
    SessionOptions options;
    options.memoryBudgetBytes = budget;
    EditingSession session(store, options);
    const double voxel = session.scene().voxelSize();
    const double cx = extent * 0.5 * voxel, cz = extent * 0.5 * voxel;

    // The brush bench editor strokes with; the thumbstick then cycles its mode.
    Command brush;
    brush.kind = Command::Kind::SetBrush;
    brush.brush.emplace();
    brush.brush->mode = vr::vrBrushModes().front();
    brush.brush->radius = kRadius * voxel;
    brush.brush->strength = 0.6;
    brush.brush->distance = 4.0;
    brush.brush->symmetry = {{"mirror", {"z"}}, {"center", {cx, 0.0, cz}}};
    session.apply(brush);
    // The terrain under the strokes resident, so that they can be placed on its surface (picks read what
    // is resident): a view from above it, settled.
    Command camera;
    camera.kind = Command::Kind::SetCamera;
    camera.camera.eye = {cx - 180 * voxel, 140 * voxel, cz};
    camera.camera.target = {cx, 20 * voxel, cz};
    camera.camera.fovYDegrees = 60.0;
    session.apply(camera);
    for (int i = 0; i < 200; ++i) {
        const FrameReport r = session.frame(0.0, {1920, 1080});
        if (r.settled && r.pending == 0) break;
        session.scene().waitForLoads();
    }

    // Where the scene will stand: framed in front of the fake's head, as the editor frames it.
    vr::Pose head;
    head.position = glm::dvec3(0.0, 1.6, 0.0);
    const auto [lo, hi] = session.sceneBox();
    const vr::WorldTransform world = vr::frameScene(lo, hi, head);
    // The grip that puts the brush at a scene point (the brush sits kBrushReachMetres ahead of it).
    const auto gripFor = [&](const std::array<double, 3>& at) {
        return world.toStage(glm::dvec3(at[0], at[1], at[2])) + glm::dvec3(0.0, 0.0, vr::kBrushReachMetres);
    };
    const auto surface = [&](double x, double z) { return session.pick({x, 400 * voxel, z}, {0, -1, 0}); };

    nlohmann::json right = nlohmann::json::array();
    const glm::dvec3 rest(0.3, 0.8, -0.1);
    right.push_back(handKey(0, rest, 0.0));
    uint64_t frame = kSettle;
    const int strokes = quick ? 8 : 16;
    const std::size_t modes = vr::vrBrushModes().size();
    // Keys interpolate: the hand rests until each stroke's first key (a key holding it the frame before).
    right.push_back(handKey(frame - 1, rest, 0.0));
    for (int s = 0; s < strokes; ++s) {
        if (s > 0) { // flick to the next mode
            right.push_back(handKey(frame, rest, 0.0, 0.0));
            right.push_back(handKey(frame + 1, rest, 0.0, 1.0));
            right.push_back(handKey(frame + 3, rest, 0.0, 0.0));
            frame += 5;
        }
        const double angle = 0.7 * s;
        double x = cx + 30 * voxel * std::cos(angle), z = cz + 20 * voxel + 30 * voxel * std::sin(angle);
        const auto start = surface(x, z);
        if (!start) continue;
        const std::string mode = vr::vrBrushModes()[std::size_t(s) % modes];
        right.push_back(handKey(frame, gripFor(start->point), 0.0));
        right.push_back(handKey(frame + 2, gripFor(start->point), 1.0));
        frame += 2;
        for (int k = 1; k <= 8; ++k) {
            x += 12 * voxel;
            const auto p = surface(x, z);
            std::array<double, 3> at = p ? p->point : start->point;
            if (mode == "move") at = {x, start->point[1] + 2 * voxel * k, z};
            right.push_back(handKey(frame + uint64_t(k), gripFor(at), 1.0));
        }
        frame += 8;
        right.push_back(handKey(frame + 1, gripFor(start->point) + glm::dvec3(0.0, 0.1, 0.0), 0.0));
        right.push_back(handKey(frame + 3, rest, 0.0));
        frame += 4;
    }
    const uint64_t strokesEnd = frame;
    const nlohmann::json script = {{"width", kEye},
                                   {"height", kEye},
                                   {"left", nlohmann::json::array({handKey(0, glm::dvec3(-0.3, 0.8, -0.1), 0.0)})},
                                   {"right", right}};
    const std::string scriptPath = (dir / "headset.json").string();
    std::ofstream(scriptPath) << script.dump(1);
    setenv("XR_RUNTIME_JSON", runtime.c_str(), 1);
    setenv("FAKEXR_SCRIPT", scriptPath.c_str(), 1);

    vr::VrOptions vrOptions;
    vrOptions.frames = strokesEnd + 90; // a second after the last stroke for its meshes
    vr::VrReport report;
    try {
        report = vr::runVrSession(session, vrOptions);
    } catch (const std::exception& e) {
        std::cerr << "vdbclay: error: bench vr: " << e.what() << "\n";
        return 1;
    }
    // The stroking stretch: drawn frames from the settled view on (the runtime draws every frame here).
    const std::size_t from = std::min<std::size_t>(kSettle, report.cpuMs.size());
    const std::vector<double> cpu(report.cpuMs.begin() + std::ptrdiff_t(from), report.cpuMs.end());
    const std::vector<double> wall(report.wallMs.begin() + std::ptrdiff_t(from), report.wallMs.end());
    const std::vector<double> pose(report.poseToSubmitMs.begin() + std::ptrdiff_t(from), report.poseToSubmitMs.end());
    const uint64_t missed = report.missedSoFar.empty() ? 0 : report.missedSoFar.back() - (from > 0 ? report.missedSoFar[from - 1] : 0);
    uint64_t over = 0;
    for (double ms : cpu) over += ms > 1000.0 / 90.0;
    if (json) {
        nlohmann::json out = jsonPreamble("vr", quick);
        out["frame_ms"] = {{"p50", percentile(cpu, 0.5)}, {"p99", percentile(cpu, 0.99)}};
        out["missed_frames"] = missed;
        out["frames_over_11ms"] = over;
        out["edit_to_visible_frames"] = {{"p50", percentile(report.editToVisibleFrames, 0.5)},
                                         {"p99", percentile(report.editToVisibleFrames, 0.99)},
                                         {"max", maximum(report.editToVisibleFrames)}};
        out["pose_to_submit_ms"] = {{"p50", percentile(pose, 0.5)}, {"p99", percentile(pose, 0.99)}};
        out["frame_wall_ms"] = {{"p50", percentile(wall, 0.5)}, {"p99", percentile(wall, 0.99)}};
        out["frames"] = cpu.size();
        out["extent"] = extent;
        out["eye_pixels"] = {kEye, kEye};
        out["headset"] = report.headset;
        out["commands"] = report.commands;
        std::cout << out.dump(2) << std::endl;
        return 0;
    }
    std::cout << "bench vr: the editor in a headset (fake runtime, 90 Hz, two " << kEye << " x " << kEye << " eyes), terrain of extent "
              << extent << ", " << cpu.size() << " frames of strokes\n";
    std::cout << "  frame thread's work per frame   p50 " << percentile(cpu, 0.5) << " ms, p99 " << percentile(cpu, 0.99)
              << " ms (goal p99 <= 11; the device's drawing apart)\n";
    std::cout << "  frames over 11.1 ms of work     " << over << "\n";
    std::cout << "  display refreshes missed        " << missed << " (goal: none in steady strokes; lavapipe draws on the same 2 cores)\n";
    std::cout << "  edit to visible                 p50 " << percentile(report.editToVisibleFrames, 0.5) << ", p99 "
              << percentile(report.editToVisibleFrames, 0.99) << ", max " << maximum(report.editToVisibleFrames) << " frames\n";
    std::cout << "  pose to submit                  p50 " << percentile(pose, 0.5) << " ms, p99 " << percentile(pose, 0.99)
              << " ms (goal <= 20)\n";
    std::cout << "  frame wall time                 p50 " << percentile(wall, 0.5) << " ms, p99 " << percentile(wall, 0.99) << " ms\n";
    return 0;
}

} // namespace vdbclay::bench
