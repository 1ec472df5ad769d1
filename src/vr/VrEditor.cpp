#include "vr/VrEditor.h"

#include "editor/BrushOverlay.h"
#include "editor/SessionWorker.h"
#include "render/Framing.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/ScenePicture.h"
#include "vr/VrComfort.h"
#include "vr/VrControls.h"
#include "vr/VrMenus.h"
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

namespace {

void extendBox(std::array<double, 3>& lo, std::array<double, 3>& hi, const glm::dvec3& p, double margin)
{
    for (int a = 0; a < 3; ++a) {
        lo[std::size_t(a)] = std::min(lo[std::size_t(a)], p[a] - margin);
        hi[std::size_t(a)] = std::max(hi[std::size_t(a)], p[a] + margin);
    }
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
    VrMenus menus(headset.vulkan(), headset.renderPass());
    const render::MaterialLook look =
        render::materialLook(session.scene().voxelSize(), std::filesystem::path(session.scenePath()).parent_path().string());
    MaterialTable drawnMaterials;
    {
        // Meshes and edits on workers; declared after what they use, so they stop first.
        render::StreamedSceneChunks chunks(session.scene(), kMeshThreads);
        SessionWorker worker(session);
        VrControls controls(options.dominantHand);
        VrComfort comfort;
        WorldTransform world;
        std::vector<render::RenderView> eyes;
        headset.setEyeRecorders([&](VkCommandBuffer cmd, uint32_t view) { if (view == 0) menus.recordPicture(cmd); },
                                [&](VkCommandBuffer cmd, uint32_t view) {
                                    const render::RenderView& eye = eyes.at(view);
                                    menus.recordQuads(cmd, eye.camera, world, eye.target->width(), eye.target->height());
                                });
        FrameFigures figures;
        // Stroke points given and not yet drawn: the frame they were given in, their place in the order
        // submitted (applied once the worker did that many), where they were made.
        struct Waiting {
            uint64_t frame, command;
            std::array<double, 3> at;
        };
        std::vector<Waiting> waiting;
        uint64_t submitted = 0;
        const double voxel = session.scene().voxelSize();
        const auto drawnAsItIs = [&](const std::array<double, 3>& at) {
            if (session.scene().shownLevelAt(at).value_or(0) > 0) return false;
            BrickKey key;
            for (std::size_t a = 0; a < 3; ++a) key.brick[a] = int32_t(std::floor(at[a] / (voxel * kBrickEdge)));
            const std::optional<uint64_t> drawn = chunks.versionOf(key);
            return !drawn || *drawn == session.scene().brickVersion(key);
        };
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
            figures.intervalMs = std::chrono::duration<double, std::milli>(begun - lastFrame).count();
            figures.averageIntervalMs = figures.averageIntervalMs > 0.0 ? 0.9 * figures.averageIntervalMs + 0.1 * figures.intervalMs : figures.intervalMs;
            lastFrame = begun;
            if (lastDisplayTime && frame.period > 0 && frame.displayTime - lastDisplayTime > frame.period + frame.period / 2)
                report.missedFrames += uint64_t((frame.displayTime - lastDisplayTime + frame.period / 2) / frame.period) - 1;
            lastDisplayTime = frame.displayTime;

            const std::vector<XrView> views = frame.shouldRender ? headset.locateViews(frame.displayTime) : std::vector<XrView>{};
            const Clock::time_point located = Clock::now();
            if (!views.empty() && !framed) {
                Pose head = toPose(views.front().pose);
                head.position = 0.5 * (toPose(views.front().pose).position + toPose(views.back().pose).position);
                const auto [lo, hi] = session.sceneBox();
                world = frameScene(lo, hi, head);
                controls.setScaleLimits(world.scale / kScaleRange, world.scale * kScaleRange);
                framed = true;
            }
            // Input: the menus first (where the pointer is decides what the trigger does), then the hands.
            ControllerFrame input = controllers.read(headset.stage(), frame.displayTime, headset.focused(), seconds);
            figures.missedFrames = report.missedFrames;
            figures.detail = comfort.detail();
            figures.pendingEdits = worker.pending();
            std::vector<Command> commands = menus.update(input, options.dominantHand, worker, figures, seconds);
            const VrControls::Output out = controls.update(input, worker.brush(), world);
            world = out.world;
            commands.insert(commands.end(), out.commands.begin(), out.commands.end());
            for (const Command& c : commands) {
                worker.submit(c);
                ++submitted;
                if ((c.kind == Command::Kind::StrokeBegin || c.kind == Command::Kind::StrokeMove) && c.point)
                    waiting.push_back({report.frames, submitted, *c.point});
            }
            report.commands += commands.size();
            if (out.toggleMenu) menus.toggleMenu();
            if (out.toggleHints) menus.toggleHints();
            if (out.frameAgain && !views.empty()) {
                const auto [lo, hi] = session.sceneBox();
                world = frameScene(lo, hi, toPose(views.front().pose));
            }
            // A pulse when the brush reaches the surface: from the resident data, and only when no load or
            // edit holds it (else the last frame's answer stands).
            bool touches = touching;
            if (out.brush && input.focused) {
                const glm::dvec3 dir = world.directionToScene(input.hands[std::size_t(options.dominantHand)].aim.forward());
                std::optional<SurfaceHit> ahead, behind;
                if (session.tryPick(arr(*out.brush), arr(dir), out.brushRadius, &ahead) &&
                    session.tryPick(arr(*out.brush), arr(-dir), out.brushRadius, &behind))
                    touches = ahead.has_value() || behind.has_value();
            } else {
                touches = false;
            }
            if (touches && !touching) {
                controllers.pulse(options.dominantHand);
                ++report.hapticPulses;
            }
            touching = touches;

            if (views.empty()) {
                headset.endFrame(frame, {}, 0.0, false);
            } else {
                std::vector<render::RenderTarget*> targets = headset.acquireEyes();
                // The loaders stream for the head at the frame's detail: fewer pixels, a coarser cut.
                std::array<int, 2> viewport{0, 0};
                const int streamedHeight = std::max(16, int(std::lround(targets.front()->height() * comfort.detail())));
                const render::Camera head = headCamera(views, world, &viewport, streamedHeight);
                figures.stream = worker.frame(std::chrono::duration<double>(begun - started).count(), viewport, head);
                for (const std::string& failure : worker.takeFailures()) std::cerr << "vdbclay: " << failure << "\n";
                figures.meshesWaiting = chunks.sync(session.scene(), renderer).waiting;
                for (const std::string& failure : chunks.takeMeshFailures()) std::cerr << "vdbclay: " << failure << "\n";
                const uint64_t applied = worker.snapshot().commandsApplied;
                for (auto it = waiting.begin(); it != waiting.end();) {
                    if (applied >= it->command && drawnAsItIs(it->at)) {
                        report.editToVisibleFrames.push_back(double(report.frames - it->frame + 1));
                        it = waiting.erase(it);
                    } else {
                        ++it;
                    }
                }
                figures.bricksShown = session.scene().shownBricks().size();
                MaterialTable materials = session.scene().materials();
                if (!(materials == drawnMaterials) || renderer.picturesReady()) {
                    for (const std::string& w : renderer.setMaterials(materials, look, render::Renderer::PictureLoading::Background))
                        std::cerr << "vdbclay: warning: " << w << "\n";
                    drawnMaterials = std::move(materials);
                }
                render::ShadingOptions shading = renderer.shading();
                if (shading.mode != menus.panels().look || shading.wireframe != menus.panels().wireframe) {
                    shading.mode = menus.panels().look;
                    shading.wireframe = menus.panels().wireframe;
                    renderer.setShading(shading);
                }
                BrushSettings shown = worker.brush();
                shown.radius = out.brushRadius;
                renderer.setBrush(out.brush ? std::optional<render::BrushOverlay>(brushOverlay(shown, arr(*out.brush))) : std::nullopt);

                // One near plane for both eyes (the depth both submit means the same), in front of all
                // they may draw: the bricks shown, the brush and the menus.
                auto [lo, hi] = session.shownBox();
                if (out.brush) extendBox(lo, hi, *out.brush, 2.0 * out.brushRadius);
                const MenuLayout& layout = menus.layout();
                auto panelCorners = [&](const MenuLayout::Panel& p) {
                    for (const glm::dvec3& c : p.corners()) extendBox(lo, hi, world.toScene(c), 0.0);
                };
                if (layout.menu) panelCorners(*layout.menu);
                for (const auto& h : layout.hints) panelCorners(h);
                eyes.clear();
                double nearMetres = 1e30;
                for (std::size_t i = 0; i < views.size(); ++i) {
                    render::RenderView v;
                    v.camera = eyeCamera(views[i], world);
                    render::fitNearPlane(v.camera, lo, hi);
                    nearMetres = std::min(nearMetres, v.camera.nearPlane * world.scale);
                    v.target = targets[i];
                    eyes.push_back(v);
                }
                for (auto& v : eyes) v.camera.nearPlane = nearMetres / world.scale;
                renderer.setUploadBytesPerFrame(uint64_t(double(render::kInteractiveUploadBytesPerFrame) * comfort.detail()));
                const double workMs = std::chrono::duration<double, std::milli>(Clock::now() - begun).count();
                figures.draw = renderer.render(eyes);
                // The wait for the device (the frame two back) is not the frame thread's work.
                const double recordMs = std::max(0.0, figures.draw.cpuMs - figures.draw.submitWaitMs);
                figures.uploadsWaiting = figures.draw.chunksWaitingUpload;
                headset.releaseEyes();
                headset.endFrame(frame, views, nearMetres, true);
                const Clock::time_point ended = Clock::now();
                const double cpuMs = workMs + recordMs;
                report.cpuMs.push_back(cpuMs);
                report.wallMs.push_back(std::chrono::duration<double, std::milli>(ended - begun).count());
                report.poseToSubmitMs.push_back(std::chrono::duration<double, std::milli>(ended - located).count());
                report.missedSoFar.push_back(report.missedFrames);
                comfort.frameTook(cpuMs, double(frame.period) * 1e-6);
                ++report.framesDrawn;
            }
            ++report.frames;
            if (options.frames && report.frames == *options.frames) headset.requestExit();
        }
        report.lost = headset.lost();
        report.menuWidgets = menus.panels().widgetRects;
        headset.setEyeRecorders({}, {});
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
            {"frame_wall_ms", {{"p50", percentile(report.wallMs, 0.5)}, {"p99", percentile(report.wallMs, 0.99)}}},
            {"pose_to_submit_ms", {{"p50", percentile(report.poseToSubmitMs, 0.5)}, {"p99", percentile(report.poseToSubmitMs, 0.99)}}},
            {"edit_to_visible_frames",
             {{"p50", percentile(report.editToVisibleFrames, 0.5)},
              {"p99", percentile(report.editToVisibleFrames, 0.99)},
              {"max", report.editToVisibleFrames.empty() ? 0.0 : *std::max_element(report.editToVisibleFrames.begin(), report.editToVisibleFrames.end())}}},
            {"states", report.states},
            {"commands", report.commands},
            {"haptic_pulses", report.hapticPulses},
            {"validation_messages", report.validationMessages},
            {"lost", report.lost},
            {"headset", report.headset},
            {"menu_widgets", report.menuWidgets}};
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
              << " display refreshes missed; frame thread's work p50 " << percentile(report.cpuMs, 0.5) << " ms, p99 "
              << percentile(report.cpuMs, 0.99) << " ms\n";
    if (report.lost) {
        std::cerr << "vdbclay: error: the headset's session was lost (the runtime ended it); every edit is autosaved: open the scene again\n";
        return 1;
    }
    return 0;
}

} // namespace vdbclay::vr
