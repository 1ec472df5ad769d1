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
#include <tuple>

namespace vdbclay::vr {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMeshThreads = 1;
/// The near plane's distance from an eye when nothing is closer (metres).
constexpr double kNearMetres = 0.02;

std::array<double, 3> arr(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

/// An eye's camera in scene units: its pose carried into the scene, its own (asymmetric) field of view.
render::Camera eyeCamera(const XrView& view, const WorldTransform& world)
{
    const Pose pose = poseOf(view.pose);
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
        middle += poseOf(v.pose).position / double(views.size());
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

void extendBox(std::array<double, 3>& lo, std::array<double, 3>& hi, const glm::dvec3& p, double margin)
{
    for (int a = 0; a < 3; ++a) {
        lo[std::size_t(a)] = std::min(lo[std::size_t(a)], p[a] - margin);
        hi[std::size_t(a)] = std::max(hi[std::size_t(a)], p[a] + margin);
    }
}

/// One VR session: the headset, the renderer, the controllers and the menus, the session's workers, and
/// what the frames keep between them (where the world stands, the edits not yet seen, the figures).
class VrFrameLoop {
public:
    VrFrameLoop(EditingSession& session, const VrOptions& options, VrReport& report)
        : session_(session), options_(options), report_(report), headset_(XrHeadsetOptions{options.validation}),
          renderer_(headset_.vulkan(), rendererOptions(headset_)), controllers_(headset_.instance(), headset_.session()),
          menus_(headset_.vulkan(), headset_.renderPass()),
          look_(render::materialLook(session.scene().voxelSize(), std::filesystem::path(session.scenePath()).parent_path().string())),
          chunks_(session.scene(), kMeshThreads), worker_(session), controls_(options.dominantHand)
    {
        report_.headset = headset_.describe();
        headset_.setEyeRecorders(
            [this](VkCommandBuffer cmd, uint32_t view) {
                if (view == 0) menus_.recordPicture(cmd);
            },
            [this](VkCommandBuffer cmd, uint32_t view) {
                const render::RenderView& eye = eyes_.at(view);
                menus_.recordQuads(cmd, eye.camera, world_, eye.target->width(), eye.target->height());
            });
    }
    ~VrFrameLoop() { headset_.setEyeRecorders({}, {}); }

    /// Frames until the runtime ends the session (or options.frames are done); the edit worker then
    /// finishes every command the controllers gave.
    void run()
    {
        while (headset_.pollEvents()) {
            if (!headset_.running()) {
                std::this_thread::sleep_for(std::chrono::milliseconds(5)); // IDLE, or STOPPING handed on: wait for the runtime
                continue;
            }
            frame();
            ++report_.frames;
            if (options_.frames && report_.frames == *options_.frames) headset_.requestExit();
        }
        report_.lost = headset_.lost();
        report_.menuWidgets = menus_.panels().widgetRects;
        worker_.waitIdle();
        for (XrSessionState s : headset_.states()) report_.states.push_back(sessionStateName(s));
        report_.validationMessages = headset_.vulkan().validationMessages();
    }

private:
    static render::RendererOptions rendererOptions(const XrHeadset& headset)
    {
        render::RendererOptions o;
        o.colourFormat = headset.colourFormat();
        o.uploadBytesPerFrame = render::kInteractiveUploadBytesPerFrame;
        return o;
    }

    void frame()
    {
        const XrHeadset::Frame frame = headset_.beginFrame();
        const Clock::time_point begun = Clock::now();
        const double seconds = std::min(0.1, std::chrono::duration<double>(begun - lastFrame_).count());
        figures_.intervalMs = std::chrono::duration<double, std::milli>(begun - lastFrame_).count();
        figures_.averageIntervalMs = figures_.averageIntervalMs > 0.0 ? 0.9 * figures_.averageIntervalMs + 0.1 * figures_.intervalMs : figures_.intervalMs;
        lastFrame_ = begun;
        if (lastDisplayTime_ && frame.period > 0 && frame.displayTime - lastDisplayTime_ > frame.period + frame.period / 2)
            report_.missedFrames += uint64_t((frame.displayTime - lastDisplayTime_ + frame.period / 2) / frame.period) - 1;
        lastDisplayTime_ = frame.displayTime;

        const std::vector<XrView> views = frame.shouldRender ? headset_.locateViews(frame.displayTime) : std::vector<XrView>{};
        const Clock::time_point located = Clock::now();
        if (!views.empty() && !framed_) {
            Pose head = poseOf(views.front().pose);
            head.position = 0.5 * (poseOf(views.front().pose).position + poseOf(views.back().pose).position);
            frameScene(head);
            controls_.setScaleLimits(world_.scale / kScaleRange, world_.scale * kScaleRange);
            framed_ = true;
        }
        const VrControls::Output out = input(frame, views, seconds);
        if (views.empty()) {
            headset_.endFrame(frame, {}, 0.0, false);
            return;
        }
        std::vector<render::RenderTarget*> targets = headset_.acquireEyes();
        // The loaders stream for the head at the frame's detail: fewer pixels, a coarser cut.
        std::array<int, 2> viewport{0, 0};
        const int streamedHeight = std::max(16, int(std::lround(targets.front()->height() * comfort_.detail())));
        const render::Camera head = headCamera(views, world_, &viewport, streamedHeight);
        const std::shared_ptr<const OccluderDepth> drawnDepth = renderer_.drawnDepth();
        figures_.stream = worker_.frame(std::chrono::duration<double>(begun - started_).count(), viewport, head, drawnDepth.get());
        for (const std::string& failure : worker_.takeFailures()) std::cerr << "vdbclay: " << failure << "\n";
        figures_.meshesWaiting = chunks_.sync(session_.scene(), renderer_).waiting;
        for (const std::string& failure : chunks_.takeMeshFailures()) std::cerr << "vdbclay: " << failure << "\n";
        noteEditsSeen();
        prepareDrawing(out);
        const double nearMetres = placeEyes(views, targets, out);
        renderer_.setUploadBytesPerFrame(uint64_t(double(render::kInteractiveUploadBytesPerFrame) * comfort_.detail()));
        const double workMs = std::chrono::duration<double, std::milli>(Clock::now() - begun).count();
        figures_.draw = renderer_.render(eyes_);
        // The wait for the device (the frame two back) is not the frame thread's work.
        const double recordMs = std::max(0.0, figures_.draw.cpuMs - figures_.draw.submitWaitMs);
        figures_.uploadsWaiting = figures_.draw.chunksWaitingUpload;
        headset_.releaseEyes();
        headset_.endFrame(frame, views, nearMetres, true);
        const Clock::time_point ended = Clock::now();
        report_.cpuMs.push_back(workMs + recordMs);
        report_.wallMs.push_back(std::chrono::duration<double, std::milli>(ended - begun).count());
        report_.poseToSubmitMs.push_back(std::chrono::duration<double, std::milli>(ended - located).count());
        report_.missedSoFar.push_back(report_.missedFrames);
        comfort_.frameTook(workMs + recordMs, double(frame.period) * 1e-6);
        ++report_.framesDrawn;
    }

    void frameScene(const Pose& head)
    {
        const auto [lo, hi] = session_.sceneBox();
        world_ = vr::frameScene(lo, hi, head);
    }

    /// The controllers: the menus first (where the pointer is decides what the trigger does), then the
    /// hands; their commands to the worker, the world moved, the touch pulse.
    VrControls::Output input(const XrHeadset::Frame& frame, const std::vector<XrView>& views, double seconds)
    {
        ControllerFrame hands = controllers_.read(headset_.stage(), frame.displayTime, headset_.focused(), seconds);
        figures_.missedFrames = report_.missedFrames;
        figures_.detail = comfort_.detail();
        figures_.pendingEdits = worker_.pending();
        menus_.panels().brushPoint = brushOffMenu_;
        std::vector<Command> commands = menus_.update(hands, options_.dominantHand, worker_, figures_, seconds);
        const VrControls::Output out = controls_.update(hands, worker_.brush(), world_);
        // A model found in the menu goes where the brush was last while the hand did not point at the menu.
        if (out.brush && !hands.pointerOnMenu) brushOffMenu_ = arr(*out.brush);
        world_ = out.world;
        commands.insert(commands.end(), out.commands.begin(), out.commands.end());
        for (const Command& c : commands) {
            worker_.submit(c);
            ++submitted_;
            if ((c.kind == Command::Kind::StrokeBegin || c.kind == Command::Kind::StrokeMove) && c.point)
                unseen_.push_back({report_.frames, submitted_, *c.point});
        }
        report_.commands += commands.size();
        if (out.toggleMenu) menus_.toggleMenu();
        if (out.toggleHints) menus_.toggleHints();
        if (out.frameAgain && !views.empty()) frameScene(poseOf(views.front().pose));
        pulseOnTouch(out, hands);
        return out;
    }

    /// A pulse when the brush reaches the surface: from the resident data, and only when no load or edit
    /// holds it (else the last frame's answer stands).
    void pulseOnTouch(const VrControls::Output& out, const ControllerFrame& hands)
    {
        bool touches = false;
        if (out.brush && hands.focused) {
            touches = touching_;
            const glm::dvec3 dir = world_.directionToScene(hands.hands[std::size_t(options_.dominantHand)].aim.forward());
            std::optional<SurfaceHit> ahead, behind;
            if (session_.tryPick(arr(*out.brush), arr(dir), out.brushRadius, &ahead) &&
                session_.tryPick(arr(*out.brush), arr(-dir), out.brushRadius, &behind))
                touches = ahead.has_value() || behind.has_value();
        }
        if (touches && !touching_) {
            controllers_.pulse(options_.dominantHand);
            ++report_.hapticPulses;
        }
        touching_ = touches;
    }

    /// Stroke points the worker applied and the view now shows at level 0 with their bricks' new meshes.
    void noteEditsSeen()
    {
        const uint64_t applied = worker_.snapshot().commandsApplied;
        const double voxel = session_.scene().voxelSize();
        const auto drawnAsItIs = [&](const std::array<double, 3>& at) {
            if (session_.scene().shownLevelAt(at).value_or(0) > 0) return false;
            BrickKey key;
            for (std::size_t a = 0; a < 3; ++a) key.brick[a] = int32_t(std::floor(at[a] / (voxel * kBrickEdge)));
            const std::optional<uint64_t> drawn = chunks_.versionOf(key);
            return !drawn || *drawn == session_.scene().brickVersion(key);
        };
        for (auto it = unseen_.begin(); it != unseen_.end();) {
            if (applied >= it->command && drawnAsItIs(it->at)) {
                report_.editToVisibleFrames.push_back(double(report_.frames - it->frame + 1));
                it = unseen_.erase(it);
            } else {
                ++it;
            }
        }
    }

    /// Materials, the look the menu chose and the brush's overlay, for the renderer.
    void prepareDrawing(const VrControls::Output& out)
    {
        figures_.bricksShown = session_.scene().shownBricks().size();
        MaterialTable materials = session_.scene().materials();
        if (!(materials == drawnMaterials_) || renderer_.picturesReady()) {
            for (const std::string& w : renderer_.setMaterials(materials, look_, render::Renderer::PictureLoading::Background))
                std::cerr << "vdbclay: warning: " << w << "\n";
            drawnMaterials_ = std::move(materials);
        }
        render::ShadingOptions shading = renderer_.shading();
        if (shading.mode != menus_.panels().look || shading.wireframe != menus_.panels().wireframe) {
            shading.mode = menus_.panels().look;
            shading.wireframe = menus_.panels().wireframe;
            renderer_.setShading(shading);
        }
        BrushSettings shown = worker_.brush();
        shown.radius = out.brushRadius;
        renderer_.setBrush(out.brush ? std::optional<render::BrushOverlay>(brushOverlay(shown, arr(*out.brush))) : std::nullopt);
    }

    /// The eyes' views, with one near plane for both (the depth both submit means the same) in front of
    /// all they may draw: the bricks shown, the brush, the menus and the pointer. Returns it in metres.
    double placeEyes(const std::vector<XrView>& views, const std::vector<render::RenderTarget*>& targets, const VrControls::Output& out)
    {
        // (Not a structured binding: the lambda below captures the box, which C++17 does not allow of bindings.)
        std::array<double, 3> lo, hi;
        std::tie(lo, hi) = session_.shownBox();
        if (out.brush) extendBox(lo, hi, *out.brush, 2.0 * out.brushRadius);
        const MenuLayout& layout = menus_.layout();
        auto panelCorners = [&](const MenuLayout::Panel& p) {
            for (const glm::dvec3& c : p.corners()) extendBox(lo, hi, world_.toScene(c), 0.0);
        };
        if (layout.menu) panelCorners(*layout.menu);
        for (const auto& h : layout.hints) panelCorners(h);
        if (layout.pointer)
            for (const glm::dvec3& p : *layout.pointer) extendBox(lo, hi, world_.toScene(p), 0.0);
        eyes_.clear();
        double nearMetres = 1e30;
        for (std::size_t i = 0; i < views.size(); ++i) {
            render::RenderView v;
            v.camera = eyeCamera(views[i], world_);
            render::fitNearPlane(v.camera, lo, hi);
            nearMetres = std::min(nearMetres, v.camera.nearPlane * world_.scale);
            v.target = targets[i];
            v.keepDepth = true; // both eyes' depths: a brick is left coarse only when both hide it
            eyes_.push_back(v);
        }
        for (auto& v : eyes_) v.camera.nearPlane = nearMetres / world_.scale;
        return nearMetres;
    }

    EditingSession& session_;
    const VrOptions& options_;
    VrReport& report_;
    // Declared in the order they start: the workers last, so that they stop first.
    XrHeadset headset_;
    render::Renderer renderer_;
    XrControllers controllers_;
    VrMenus menus_;
    const render::MaterialLook look_;
    MaterialTable drawnMaterials_;
    render::StreamedSceneChunks chunks_;
    SessionWorker worker_;
    VrControls controls_;
    std::optional<std::array<double, 3>> brushOffMenu_;
    VrComfort comfort_;
    WorldTransform world_;
    std::vector<render::RenderView> eyes_;
    FrameFigures figures_;
    /// Stroke points given and not yet seen: the frame they were given in, their place in the order
    /// submitted (applied once the worker did that many), where they were made.
    struct Unseen {
        uint64_t frame, command;
        std::array<double, 3> at;
    };
    std::vector<Unseen> unseen_;
    uint64_t submitted_ = 0;
    bool framed_ = false, touching_ = false;
    XrTime lastDisplayTime_ = 0;
    const Clock::time_point started_ = Clock::now();
    Clock::time_point lastFrame_ = started_;
};

} // namespace

VrReport runVrSession(EditingSession& session, const VrOptions& options)
{
    VrReport report;
    VrFrameLoop(session, options, report).run();
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
