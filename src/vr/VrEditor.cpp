#include "vr/VrEditor.h"

#include "editor/BrushOverlay.h"
#include "editor/SessionWorker.h"
#include "render/Framing.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/ScenePicture.h"
#include "vr/VrControls.h"
#include "vr/XrControllers.h"
#include "vr/XrHeadset.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <thread>

namespace vdbclay::vr {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMeshThreads = 1;
/// The near plane's distance from an eye when nothing is closer (metres).
constexpr double kNearMetres = 0.02;

Pose toPose(const XrPosef& p)
{
    Pose out;
    out.orientation = glm::dquat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    out.position = glm::dvec3(p.position.x, p.position.y, p.position.z);
    return out;
}

std::array<double, 3> arr(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

/// An eye's camera in scene units: its pose carried into the scene, its own (asymmetric) field of view.
render::Camera eyeCamera(const XrView& view, const WorldTransform& world)
{
    const Pose pose = toPose(view.pose);
    render::Camera c;
    const glm::dvec3 eye = world.toScene(pose.position);
    c.eye = arr(eye);
    c.target = arr(eye + world.directionToScene(pose.forward()));
    c.up = arr(world.directionToScene(pose.up()));
    c.fovTangents = {std::tan(double(view.fov.angleLeft)), std::tan(double(view.fov.angleRight)), std::tan(double(view.fov.angleUp)),
                     std::tan(double(view.fov.angleDown))};
    c.fovYDegrees = 2.0 * std::atan(c.tanHalfFovY()) * 180.0 / M_PI;
    c.nearPlane = kNearMetres / world.scale;
    return c;
}

/// What the loaders stream for: one view from between the eyes wide enough for both.
render::Camera headCamera(const std::vector<XrView>& views, const WorldTransform& world, std::array<int, 2>* viewport, int eyeHeight)
{
    render::Camera head = eyeCamera(views.front(), world);
    glm::dvec3 middle(0.0);
    double tanX = 0.0, tanY = 0.0;
    for (const XrView& v : views) {
        middle += toPose(v.pose).position / double(views.size());
        tanX = std::max({tanX, -std::tan(double(v.fov.angleLeft)), std::tan(double(v.fov.angleRight))});
        tanY = std::max({tanY, -std::tan(double(v.fov.angleDown)), std::tan(double(v.fov.angleUp))});
    }
    const glm::dvec3 eye = world.toScene(middle);
    const glm::dvec3 forward(head.target[0] - head.eye[0], head.target[1] - head.eye[1], head.target[2] - head.eye[2]);
    head.eye = arr(eye);
    head.target = arr(eye + forward);
    head.fovTangents = {0, 0, 0, 0};
    head.fovYDegrees = std::clamp(2.0 * std::atan(tanY) * 180.0 / M_PI, 10.0, 170.0);
    *viewport = {std::max(1, int(std::lround(eyeHeight * tanX / std::max(tanY, 1e-6)))), eyeHeight};
    return head;
}

double percentile(std::vector<double> v, double p)
{
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, std::size_t(p * double(v.size() - 1) + 0.5))];
}

} // namespace

VrReport runVrSession(EditingSession& session, const VrOptions& options)
{
    VrReport report;
    XrHeadsetOptions headsetOptions;
    headsetOptions.validation = options.validation;
    XrHeadset headset(headsetOptions);
    report.headset = headset.describe();
    render::RendererOptions rendererOptions;
    rendererOptions.colourFormat = headset.colourFormat();
    rendererOptions.uploadBytesPerFrame = render::kInteractiveUploadBytesPerFrame;
    render::Renderer renderer(headset.vulkan(), rendererOptions);
    XrControllers controllers(headset.instance(), headset.session());
    const render::MaterialLook look =
        render::materialLook(session.scene().voxelSize(), std::filesystem::path(session.scenePath()).parent_path().string());
    MaterialTable drawnMaterials;
    {
        // Meshes and edits on workers; declared after what they use, so they stop first.
        render::StreamedSceneChunks chunks(session.scene(), kMeshThreads);
        SessionWorker worker(session);
        VrControls controls(options.dominantHand);
        WorldTransform world;
        bool framed = false;
        bool touching = false;
        XrTime lastDisplayTime = 0;
        const Clock::time_point started = Clock::now();
        Clock::time_point lastFrame = started;

        while (headset.pollEvents()) {
            if (!headset.running()) {
                std::this_thread::sleep_for(std::chrono::milliseconds(5)); // IDLE, or STOPPING handed on: wait for the runtime
                continue;
            }
            const XrHeadset::Frame frame = headset.beginFrame();
            const Clock::time_point begun = Clock::now();
            const double seconds = std::min(0.1, std::chrono::duration<double>(begun - lastFrame).count());
            lastFrame = begun;
            if (lastDisplayTime && frame.period > 0 && frame.displayTime - lastDisplayTime > frame.period + frame.period / 2)
                report.missedFrames += uint64_t((frame.displayTime - lastDisplayTime + frame.period / 2) / frame.period) - 1;
            lastDisplayTime = frame.displayTime;

            const std::vector<XrView> views = frame.shouldRender ? headset.locateViews(frame.displayTime) : std::vector<XrView>{};
            if (!framed && !views.empty()) {
                Pose head = toPose(views.front().pose);
                head.position = 0.5 * (toPose(views.front().pose).position + toPose(views.back().pose).position);
                const auto [lo, hi] = session.sceneBox();
                world = frameScene(lo, hi, head);
                controls.setScaleLimits(world.scale / kScaleRange, world.scale * kScaleRange);
                framed = true;
            }
            const ControllerFrame input = controllers.read(headset.stage(), frame.displayTime, headset.focused(), seconds);
            const VrControls::Output out = controls.update(input, worker.brush(), world);
            world = out.world;
            for (const Command& c : out.commands) worker.submit(c);
            report.commands += out.commands.size();
            if (out.frameAgain && !views.empty()) {
                Pose head = toPose(views.front().pose);
                const auto [lo, hi] = session.sceneBox();
                world = frameScene(lo, hi, head);
            }
            // A pulse when the brush reaches the surface (from the resident data, never a load).
            bool touches = false;
            if (out.brush && input.focused) {
                const glm::dvec3 dir = world.directionToScene(input.hands[std::size_t(options.dominantHand)].aim.forward());
                for (double sign : {1.0, -1.0})
                    touches = touches || session.pick(arr(*out.brush), arr(sign * dir), out.brushRadius).has_value();
            }
            if (touches && !touching) {
                controllers.pulse(options.dominantHand);
                ++report.hapticPulses;
            }
            touching = touches;

            if (views.empty()) {
                headset.endFrame(frame, {}, 0.0, false);
            } else {
                std::array<int, 2> viewport{0, 0};
                std::vector<render::RenderTarget*> targets = headset.acquireEyes();
                const render::Camera head = headCamera(views, world, &viewport, targets.front()->height());
                const double time = std::chrono::duration<double>(begun - started).count();
                worker.frame(time, viewport, head);
                for (const std::string& failure : worker.takeFailures()) std::cerr << "vdbclay: " << failure << "\n";
                chunks.sync(session.scene(), renderer);
                for (const std::string& failure : chunks.takeMeshFailures()) std::cerr << "vdbclay: " << failure << "\n";
                MaterialTable materials = session.scene().materials();
                if (!(materials == drawnMaterials) || renderer.picturesReady()) {
                    for (const std::string& w : renderer.setMaterials(materials, look, render::Renderer::PictureLoading::Background))
                        std::cerr << "vdbclay: warning: " << w << "\n";
                    drawnMaterials = std::move(materials);
                }
                BrushSettings shown = worker.brush();
                shown.radius = out.brushRadius;
                renderer.setBrush(out.brush ? std::optional<render::BrushOverlay>(brushOverlay(shown, arr(*out.brush))) : std::nullopt);

                // Each eye's near plane in front of what it may draw: the bricks shown and the brush.
                auto [lo, hi] = session.shownBox();
                if (out.brush)
                    for (int a = 0; a < 3; ++a) {
                        lo[std::size_t(a)] = std::min(lo[std::size_t(a)], (*out.brush)[a] - 2.0 * out.brushRadius);
                        hi[std::size_t(a)] = std::max(hi[std::size_t(a)], (*out.brush)[a] + 2.0 * out.brushRadius);
                    }
                std::vector<render::RenderView> eyes;
                double nearMetres = 1e30;
                for (std::size_t i = 0; i < views.size(); ++i) {
                    render::RenderView v;
                    v.camera = eyeCamera(views[i], world);
                    render::fitNearPlane(v.camera, lo, hi);
                    nearMetres = std::min(nearMetres, v.camera.nearPlane * world.scale);
                    v.target = targets[i];
                    eyes.push_back(v);
                }
                // One near plane for both eyes: the depth both submit means the same.
                for (auto& v : eyes) v.camera.nearPlane = nearMetres / world.scale;
                renderer.render(eyes);
                headset.releaseEyes();
                headset.endFrame(frame, views, nearMetres, true);
                report.cpuMs.push_back(std::chrono::duration<double, std::milli>(Clock::now() - begun).count());
                ++report.framesDrawn;
            }
            ++report.frames;
            if (options.frames && report.frames == *options.frames) headset.requestExit();
        }
        report.lost = headset.lost();
        // The worker finishes every command the controllers gave (nothing sculpted is dropped), then
        // the mesh workers stop.
    }
    for (XrSessionState s : headset.states()) report.states.push_back(sessionStateName(s));
    report.validationMessages = headset.vulkan().validationMessages();
    return report;
}

nlohmann::json vrReportJson(const VrReport& report)
{
    return {{"frames", report.frames},
            {"frames_drawn", report.framesDrawn},
            {"missed_frames", report.missedFrames},
            {"frame_ms", {{"p50", percentile(report.cpuMs, 0.5)}, {"p99", percentile(report.cpuMs, 0.99)}}},
            {"states", report.states},
            {"commands", report.commands},
            {"haptic_pulses", report.hapticPulses},
            {"validation_messages", report.validationMessages},
            {"lost", report.lost},
            {"headset", report.headset}};
}

int runVrEditor(std::unique_ptr<EditingSession> session, const VrOptions& options)
{
    VrReport report;
    try {
        report = runVrSession(*session, options);
    } catch (const NoXrRuntime& e) {
        std::cerr << "vdbclay: error: cannot start VR: " << e.what() << "\n";
        return 1;
    } catch (const render::NoVulkanDevice& e) {
        std::cerr << "vdbclay: error: cannot start VR: " << e.what() << "\n";
        return 1;
    }
    session->autosave();
    if (options.json) std::cout << vrReportJson(report).dump() << std::endl;
    std::cerr << "vdbclay: vr: " << report.frames << " frames on " << report.headset << "; " << report.missedFrames
              << " display refreshes missed; CPU per drawn frame p50 " << percentile(report.cpuMs, 0.5) << " ms, p99 "
              << percentile(report.cpuMs, 0.99) << " ms\n";
    if (report.lost) {
        std::cerr << "vdbclay: error: the headset's session was lost (the runtime ended it); every edit is autosaved: open the scene again\n";
        return 1;
    }
    return 0;
}

} // namespace vdbclay::vr
