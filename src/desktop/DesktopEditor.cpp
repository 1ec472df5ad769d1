#include "desktop/DesktopEditor.h"

#include "desktop/DesktopSettings.h"
#include "editor/BrushOverlay.h"
#include "editor/CameraControl.h"
#include "render/Framing.h"
#include "render/ImageFile.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/ScenePicture.h"
#include "render/SwapchainTarget.h"
#include "render/VulkanContext.h"
#include "scene/OutputCheck.h"
#include "vdb_hermite/AtomicFile.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <iostream>

namespace vdbclay {

bool desktopAvailable()
{
    const char* x = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    return (x && *x) || (wayland && *wayland);
}

std::string desktopShortcutsHelp(const Keymap& keymap)
{
    return "Mouse: left drag sculpts with the brush (Ctrl inverts it: add <-> remove, inflate <-> deflate, mask <-> unmask; Shift smooths);\n"
           "right drag (or Alt + left) orbits about the surface under the cursor; middle drag (or Shift + right) pans;\n"
           "the wheel zooms towards the surface under the cursor; hold the right button and use W A S D Q E to fly.\n"
           "Keys (keymap.json in $XDG_CONFIG_HOME/vdbclay or ~/.config/vdbclay rebinds them; docs/EDITOR.md):\n" +
           keymap.help();
}

Keymap loadKeymap(const std::string& configFolder, bool writeMissing, std::string* warning)
{
    if (configFolder.empty()) return Keymap::defaults();
    const std::string path = (std::filesystem::path(configFolder) / "keymap.json").string();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
        if (writeMissing) {
            try {
                std::filesystem::create_directories(configFolder);
                const std::string text = Keymap::defaults().json().dump(2) + "\n";
                writeFileAtomically(path, [&](std::ostream& o) { o << text; });
            } catch (const std::exception& e) {
                if (warning) *warning = std::string("could not write the default keymap: ") + e.what();
            }
        }
        return Keymap::defaults();
    }
    try {
        return Keymap::load(path);
    } catch (const KeymapError& e) {
        if (warning) *warning = std::string(e.what()) + "; the default keys are used";
        return Keymap::defaults();
    }
}

namespace {

using Clock = std::chrono::steady_clock;

/// Threads meshing the shown bricks (the frame only uploads what they finished): one leaves the other
/// core to the edit worker, and CMS spreads a brick's leaves over TBB's threads.
constexpr int kMeshThreads = 1;

double msBetween(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

void checkImgui(VkResult r)
{
    if (r != VK_SUCCESS) std::cerr << "vdbclay: ImGui's Vulkan backend: " << render::resultName(r) << "\n";
}

/// The brush a held modifier makes of `brush`: Ctrl inverts it, Shift smooths; nullopt when neither changes it.
std::optional<BrushSettings> modifiedBrush(const BrushSettings& brush, bool ctrl, bool shift)
{
    BrushSettings b = brush;
    if (shift) b.mode = "smooth";
    else if (ctrl) {
        static const std::pair<const char*, const char*> opposites[] = {{"add", "remove"}, {"inflate", "deflate"}, {"mask", "unmask"}};
        for (const auto& [one, other] : opposites) {
            if (brush.mode == one) b.mode = other;
            else if (brush.mode == other) b.mode = one;
        }
    }
    if (b.mode == brush.mode) return std::nullopt;
    return b;
}

/// The brush as the shaders preview it: its primitive at the pointer, sized by the brush's radius.

} // namespace

struct DesktopEditor::Impl {
    enum class Drag { None, Stroke, Orbit, Pan };
    enum class Adjust { None, Radius, Strength }; // F and Shift+F: the brush's size or strength follows the pointer

    DesktopEditor& self;
    EditingSession& session; // safe from this thread: its scene, pick() and paths; the rest goes through the worker
    DesktopOptions options;
    std::string configFolder;
    DesktopSettings settings;
    Keymap keymap = Keymap::defaults();
    std::string iniPath; // ImGui keeps a pointer to it
    GLFWwindow* window = nullptr;
    std::unique_ptr<render::VulkanContext> context;
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    std::unique_ptr<render::SwapchainTarget> swapchain;
    std::unique_ptr<render::Renderer> renderer;
    render::StreamedSceneChunks chunks; // meshes made on workers
    VkDescriptorPool imguiPool = VK_NULL_HANDLE;
    bool imguiReady = false;
    SessionPanels panels;
    FrameFigures figures;  // what the overlay shows: the last whole frame
    FrameFigures measured; // the parts of the frame under way, shown once its interval is known
    render::FrameStats lastStats;
    Clock::time_point started = Clock::now(), lastFrameStart = Clock::now();
    std::deque<std::pair<Clock::time_point, double>> recentIntervals; // the last second's frame intervals
    uint64_t frames = 0;
    bool firstFrame = true;

    Drag drag = Drag::None;
    double cursorX = 0.0, cursorY = 0.0;
    bool rightHeld = false;
    std::optional<std::array<double, 3>> orbitPivot; // the surface under the cursor when the orbit began
    std::optional<SurfaceHit> hover;
    std::optional<std::array<double, 3>> hoverOutsidePanels; // where a model found by the query panel goes
    std::optional<BrushSettings> brushBeforeModifier; // the brush to go back to after a Ctrl or Shift stroke
    Adjust adjust = Adjust::None;
    double adjustFromX = 0.0;
    BrushSettings adjusted; // what the brush becomes when the drag is kept
    bool turntable = false;
    std::optional<double> perspectiveFov; // in a parallel view: the field of view to go back to
    std::array<double, 2> lazy{0, 0}; // where a stabilized stroke is, trailing the pointer
    std::string title;

    const SessionRecord* replay = nullptr;
    std::size_t replayNext = 0;
    MaterialTable drawnMaterials; // what the renderer was last given
    uint64_t savesShown = 0;      // the worker's saves the status line has told of
    // Edits, undo, autosave and saves run here, in the order submitted: the frame never waits for them.
    SessionWorker worker;

    render::MaterialLook look() const
    {
        return render::materialLook(session.scene().voxelSize(), std::filesystem::path(session.scenePath()).parent_path().string());
    }

    Impl(DesktopEditor& editor, EditingSession& s, const DesktopOptions& o) : self(editor), session(s), options(o), chunks(s.scene(), kMeshThreads), worker(s)
    {
        configFolder = options.configFolder.value_or(defaultConfigFolder());
        std::string warning;
        settings = loadDesktopSettings(configFolder, &warning);
        if (!warning.empty()) std::cerr << "vdbclay: warning: " << warning << "\n";
        warning.clear();
        keymap = loadKeymap(configFolder, true, &warning);
        if (!warning.empty()) {
            std::cerr << "vdbclay: warning: " << warning << "\n";
            panels.status = warning;
        }
        panels.showStats = settings.showStats;
        panels.showHelp = settings.showHelp;
        panels.look = settings.look;
        panels.wireframe = settings.wireframe;
        panels.stabilizer = float(settings.stabilizerPixels);
        panels.helpText = desktopShortcutsHelp(keymap);
        panels.query.lightField = true; // a window has a renderer: searches draw the sculpture's silhouettes
    }

    std::array<int, 2> windowSize() const
    {
        int w = 0, h = 0;
        glfwGetWindowSize(window, &w, &h);
        return {std::max(w, 1), std::max(h, 1)};
    }

    double now() const { return std::chrono::duration<double>(Clock::now() - started).count(); }

    void apply(const Command& c)
    {
        try {
            worker.submit(c);
        } catch (const std::exception& e) {
            panels.status = std::string(commandName(c.kind)) + " failed: " + e.what();
            std::cerr << "vdbclay: " << panels.status << "\n";
        }
    }

    void setCamera(const render::Camera& camera)
    {
        Command c;
        c.kind = Command::Kind::SetCamera;
        c.camera = camera;
        apply(c);
    }

    void setBrush(const BrushSettings& brush)
    {
        Command c;
        c.kind = Command::Kind::SetBrush;
        c.brush = brush;
        apply(c);
    }

    Ray rayAt(double x, double y) const { return pointerRay(worker.camera(), windowSize(), x, y); }

    std::optional<SurfaceHit> pickAt(double x, double y) const
    {
        const Ray ray = rayAt(x, y);
        return session.pick(ray.origin, ray.direction);
    }

    /// The pointer's ray: the session places the brush on the surface as the stroke found it.
    void strokeTo(double x, double y, bool begin)
    {
        Command c;
        c.kind = begin ? Command::Kind::StrokeBegin : Command::Kind::StrokeMove;
        c.ray = rayAt(x, y);
        c.pressure = 1.0;
        apply(c);
    }

    void endStroke()
    {
        Command c;
        c.kind = Command::Kind::StrokeEnd;
        apply(c);
        drag = Drag::None;
        if (brushBeforeModifier) {
            setBrush(*brushBeforeModifier);
            brushBeforeModifier.reset();
        }
    }

    void beginAdjust(Adjust what)
    {
        adjust = what;
        adjustFromX = cursorX;
        adjusted = worker.brush();
    }

    void onMouseButton(int button, int action, int mods)
    {
        if (action == GLFW_RELEASE) {
            if (button == GLFW_MOUSE_BUTTON_RIGHT) rightHeld = false;
            if (drag != Drag::Stroke) drag = Drag::None;
            else if (button == GLFW_MOUSE_BUTTON_LEFT) endStroke();
            return;
        }
        if (action != GLFW_PRESS) return;
        if (adjust != Adjust::None) { // a click keeps the on-screen drag, the right button cancels it
            if (button == GLFW_MOUSE_BUTTON_LEFT) setBrush(adjusted);
            adjust = Adjust::None;
            return;
        }
        if (drag != Drag::None) return;
        const bool alt = mods & GLFW_MOD_ALT, shift = mods & GLFW_MOD_SHIFT, ctrl = mods & GLFW_MOD_CONTROL;
        if (button == GLFW_MOUSE_BUTTON_LEFT && !alt) {
            // Ctrl and Shift change the brush for this stroke only: the commands say so, so a replay does too.
            if (const auto modified = modifiedBrush(worker.brush(), ctrl, shift)) {
                brushBeforeModifier = worker.brush();
                setBrush(*modified);
            }
            drag = Drag::Stroke;
            lazy = {cursorX, cursorY};
            strokeTo(cursorX, cursorY, true);
        } else if (button == GLFW_MOUSE_BUTTON_MIDDLE || (button == GLFW_MOUSE_BUTTON_RIGHT && shift)) {
            drag = Drag::Pan;
        } else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_LEFT) {
            drag = Drag::Orbit;
            rightHeld = button == GLFW_MOUSE_BUTTON_RIGHT;
            const auto hit = pickAt(cursorX, cursorY);
            orbitPivot = hit ? std::optional<std::array<double, 3>>(hit->point) : std::nullopt;
        }
    }

    void onCursor(double x, double y)
    {
        const double dx = x - cursorX, dy = y - cursorY;
        cursorX = x;
        cursorY = y;
        if (adjust == Adjust::Radius) {
            adjusted.radius = std::max(worker.brush().radius * std::exp((x - adjustFromX) / 150.0), 0.1 * session.scene().voxelSize());
        } else if (adjust == Adjust::Strength) {
            adjusted.strength = std::clamp(worker.brush().strength + (x - adjustFromX) / 300.0, 0.0, 1.0);
        }
        switch (drag) {
        case Drag::Stroke: {
            // The stabilizer: the stroke follows the pointer on a string, moving only once it is taut.
            const double string = panels.stabilizer, ex = x - lazy[0], ey = y - lazy[1], length = std::hypot(ex, ey);
            if (string <= 0.0) lazy = {x, y};
            else if (length > string) lazy = {lazy[0] + ex * (1.0 - string / length), lazy[1] + ey * (1.0 - string / length)};
            else break;
            strokeTo(lazy[0], lazy[1], false);
            break;
        }
        case Drag::Orbit:
            setCamera(orbitPivot ? orbitAbout(worker.camera(), *orbitPivot, dx * 0.3, dy * 0.3) : orbit(worker.camera(), dx * 0.3, dy * 0.3));
            break;
        case Drag::Pan: setCamera(pan(worker.camera(), windowSize(), dx, dy)); break;
        case Drag::None: break;
        }
    }

    void onScroll(double dy)
    {
        if (dy == 0.0) return;
        const auto hit = pickAt(cursorX, cursorY);
        const std::optional<std::array<double, 3>> toward = hit ? std::optional<std::array<double, 3>>(hit->point) : std::nullopt;
        // A parallel view zooms by narrowing: moving its far eye closer would bring perspective back.
        setCamera(perspectiveFov ? zoomByFieldOfView(worker.camera(), std::pow(1.15, dy), toward)
                                 : zoomToward(worker.camera(), std::pow(1.15, dy), toward));
    }

    void frameScene()
    {
        const auto [lo, hi] = session.sceneBox();
        const auto size = windowSize();
        perspectiveFov.reset();
        setCamera(render::framingCamera(lo, hi, double(size[0]) / double(size[1])));
    }

    void toggleParallel()
    {
        if (perspectiveFov) {
            setCamera(perspectiveView(worker.camera(), *perspectiveFov));
            perspectiveFov.reset();
        } else {
            perspectiveFov = worker.camera().fovYDegrees;
            setCamera(parallelView(worker.camera()));
        }
    }

    void frameCursor()
    {
        const auto hit = pickAt(cursorX, cursorY);
        if (!hit) {
            panels.status = "no surface under the cursor to centre the view on";
            return;
        }
        const render::Camera& c = worker.camera();
        const double distance = std::sqrt(std::pow(c.target[0] - c.eye[0], 2) + std::pow(c.target[1] - c.eye[1], 2) + std::pow(c.target[2] - c.eye[2], 2));
        // A parallel view keeps its far eye (its scale is its field of view).
        setCamera(frameOn(c, hit->point, perspectiveFov ? distance : std::min(distance, 12.0 * worker.brush().radius)));
    }

    /// F12: the view as drawn, into SCENE-shot-N.png beside the scene (the first N not taken).
    void screenshot()
    {
        try {
            const std::filesystem::path scene = std::filesystem::absolute(session.scenePath());
            std::string path;
            for (int n = 1; n < 100000 && path.empty(); ++n) {
                char name[64];
                std::snprintf(name, sizeof name, "-shot-%03d.png", n);
                const std::filesystem::path candidate = scene.parent_path() / (scene.stem().string() + name);
                if (!std::filesystem::exists(candidate)) path = candidate.string();
            }
            if (path.empty()) throw std::runtime_error("no free name beside the scene");
            checkOutput(path, OutputForm::Png, {session.scenePath()});
            render::PictureRequest request;
            const auto size = windowSize();
            request.width = size[0];
            request.height = size[1];
            request.textureFolder = scene.parent_path().string();
            request.shading = renderer->shading();
            render::Camera camera = worker.camera();
            const auto [lo, hi] = session.shownBox();
            render::fitNearPlane(camera, lo, hi);
            render::writePng(render::renderStreamed(*context, session.scene(), camera, request).image, path);
            panels.status = "wrote the view to " + path;
        } catch (const std::exception& e) {
            panels.status = std::string("could not write the screenshot: ") + e.what();
        }
    }

    void toggleMirrorX(BrushSettings b)
    {
        nlohmann::json s = b.symmetry.is_object() ? b.symmetry : nlohmann::json::object();
        nlohmann::json mirror = s.value("mirror", nlohmann::json::array());
        const auto it = std::find(mirror.begin(), mirror.end(), "x");
        if (it != mirror.end()) mirror.erase(it);
        else mirror.push_back("x");
        if (mirror.empty()) s.erase("mirror");
        else s["mirror"] = mirror;
        b.symmetry = s.empty() || (s.size() == 1 && s.contains("center")) ? nlohmann::json() : s;
        setBrush(b);
    }

    void onKey(int key, int action, int mods)
    {
        if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
        const bool ctrl = mods & GLFW_MOD_CONTROL;
        static const int flyKeys[] = {GLFW_KEY_W, GLFW_KEY_A, GLFW_KEY_S, GLFW_KEY_D, GLFW_KEY_Q, GLFW_KEY_E};
        if (rightHeld && !ctrl && std::find(std::begin(flyKeys), std::end(flyKeys), key) != std::end(flyKeys)) return; // flying (per frame)
        const std::optional<KeyAction> bound = keymap.actionFor(key, mods);
        if (!bound) return;
        BrushSettings b = worker.brush();
        Command c;
        const auto mode = [&](const char* m) {
            b.mode = m;
            setBrush(b);
        };
        switch (*bound) {
        case KeyAction::Undo: c.kind = Command::Kind::Undo; return apply(c);
        case KeyAction::Redo: c.kind = Command::Kind::Redo; return apply(c);
        case KeyAction::Save:
            c.kind = Command::Kind::Save;
            apply(c); // the status line shows it under way, then saved (or why not)
            return;
        case KeyAction::Screenshot: return screenshot();
        case KeyAction::ModeAdd: return mode("add");
        case KeyAction::ModeRemove: return mode("remove");
        case KeyAction::ModePaint: return mode("paint");
        case KeyAction::ModeErode: return mode("erode");
        case KeyAction::ModeSmooth: return mode("smooth");
        case KeyAction::ModeFlatten: return mode("flatten");
        case KeyAction::ModeInflate: return mode("inflate");
        case KeyAction::ModeDeflate: return mode("deflate");
        case KeyAction::ModeMove: return mode("move");
        case KeyAction::ModeMask: return mode("mask");
        case KeyAction::MaskInvert:
        case KeyAction::MaskClear:
            c.kind = Command::Kind::ApplyOp;
            c.op = {{"mode", *bound == KeyAction::MaskInvert ? "mask_invert" : "mask_clear"}};
            return apply(c);
        case KeyAction::BrushSmaller:
        case KeyAction::BrushLarger:
            b.radius = std::max(b.radius * (*bound == KeyAction::BrushLarger ? 1.15 : 1.0 / 1.15), 0.1 * session.scene().voxelSize());
            return setBrush(b);
        case KeyAction::BrushWeaker:
        case KeyAction::BrushStronger:
            b.strength = std::clamp(b.strength + (*bound == KeyAction::BrushStronger ? 0.05 : -0.05), 0.0, 1.0);
            return setBrush(b);
        case KeyAction::RadiusDrag: return beginAdjust(Adjust::Radius);
        case KeyAction::StrengthDrag: return beginAdjust(Adjust::Strength);
        case KeyAction::MirrorX: return toggleMirrorX(b);
        case KeyAction::FrameAll: return frameScene();
        case KeyAction::FrameCursor: return frameCursor();
        case KeyAction::ViewFront: return setCamera(axisView(worker.camera(), AxisView::Front));
        case KeyAction::ViewBack: return setCamera(axisView(worker.camera(), AxisView::Back));
        case KeyAction::ViewRight: return setCamera(axisView(worker.camera(), AxisView::Right));
        case KeyAction::ViewLeft: return setCamera(axisView(worker.camera(), AxisView::Left));
        case KeyAction::ViewTop: return setCamera(axisView(worker.camera(), AxisView::Top));
        case KeyAction::ViewBottom: return setCamera(axisView(worker.camera(), AxisView::Bottom));
        case KeyAction::Parallel: return toggleParallel();
        case KeyAction::Turntable: turntable = !turntable; return;
        case KeyAction::ShadingNext:
            panels.look = panels.look == render::ViewMode::Shaded ? render::ViewMode::Clay
                          : panels.look == render::ViewMode::Clay ? render::ViewMode::Normals
                                                                  : render::ViewMode::Shaded;
            return;
        case KeyAction::Wireframe: panels.wireframe = !panels.wireframe; return;
        case KeyAction::Help: panels.showHelp = !panels.showHelp; return;
        case KeyAction::Stats: panels.showStats = !panels.showStats; return;
        case KeyAction::EndStroke:
            if (adjust != Adjust::None) adjust = Adjust::None;
            else if (drag == Drag::Stroke || worker.snapshot().strokeActive) endStroke();
            return;
        }
    }

    void flyKeys(double seconds)
    {
        if (!rightHeld) return;
        const auto held = [&](int k) { return glfwGetKey(window, k) == GLFW_PRESS ? 1.0 : 0.0; };
        const double f = held(GLFW_KEY_W) - held(GLFW_KEY_S), r = held(GLFW_KEY_D) - held(GLFW_KEY_A), u = held(GLFW_KEY_E) - held(GLFW_KEY_Q);
        if (f == 0.0 && r == 0.0 && u == 0.0) return;
        const render::Camera& c = worker.camera();
        const double dist = std::sqrt(std::pow(c.target[0] - c.eye[0], 2) + std::pow(c.target[1] - c.eye[1], 2) + std::pow(c.target[2] - c.eye[2], 2));
        const double speed = 0.5 * dist * seconds; // half the distance to the target per second
        setCamera(fly(c, f * speed, r * speed, u * speed));
    }

    void open()
    {
        if (!glfwInit()) throw NoDisplay("no display to open a window on (GLFW could not reach it)");
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
        title = windowTitle();
        const std::array<int, 2> size = options.windowSize.value_or(settings.windowSize);
        window = glfwCreateWindow(size[0], size[1], title.c_str(), nullptr, nullptr);
        if (!window) throw NoDisplay("the window could not be opened on this display");
        glfwSetWindowUserPointer(window, &self);
        glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int b, int a, int m) { static_cast<DesktopEditor*>(glfwGetWindowUserPointer(w))->mouseButton(b, a, m); });
        glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) { static_cast<DesktopEditor*>(glfwGetWindowUserPointer(w))->cursorMoved(x, y); });
        glfwSetScrollCallback(window, [](GLFWwindow* w, double x, double y) { static_cast<DesktopEditor*>(glfwGetWindowUserPointer(w))->scrolled(x, y); });
        glfwSetKeyCallback(window, [](GLFWwindow* w, int k, int, int a, int m) { static_cast<DesktopEditor*>(glfwGetWindowUserPointer(w))->key(k, a, m); });
        glfwSetCharCallback(window, [](GLFWwindow* w, unsigned int c) { ImGui_ImplGlfw_CharCallback(w, c); });
        glfwSetCursorEnterCallback(window, [](GLFWwindow* w, int entered) { ImGui_ImplGlfw_CursorEnterCallback(w, entered); });
        glfwSetWindowFocusCallback(window, [](GLFWwindow* w, int focused) { ImGui_ImplGlfw_WindowFocusCallback(w, focused); });

        render::ContextOptions co;
        co.validation = options.validation;
        co.swapchain = true;
        uint32_t count = 0;
        const char** extensions = glfwGetRequiredInstanceExtensions(&count);
        if (!extensions) throw render::NoVulkanDevice("GLFW finds no Vulkan surface support on this display");
        co.instanceExtensions.assign(extensions, extensions + count);
        context = std::make_unique<render::VulkanContext>(co);
        render::check(glfwCreateWindowSurface(context->instance(), window, nullptr, &surface), "glfwCreateWindowSurface");
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window, &fw, &fh);
        swapchain = std::make_unique<render::SwapchainTarget>(*context, surface, fw, fh);
        render::RendererOptions ro;
        ro.colourFormat = swapchain->format();
        ro.uploadBytesPerFrame = render::kInteractiveUploadBytesPerFrame;
        renderer = std::make_unique<render::Renderer>(*context, ro);
        drawnMaterials = session.scene().materials();
        for (const std::string& w : renderer->setMaterials(drawnMaterials, look(), render::Renderer::PictureLoading::Background))
            std::cerr << "vdbclay: warning: " << w << "\n";

        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        // The panels' layout is kept with the other settings (nowhere when there is no config folder).
        iniPath = configFolder.empty() ? std::string() : (std::filesystem::path(configFolder) / "imgui.ini").string();
        ImGui::GetIO().IniFilename = iniPath.empty() ? nullptr : iniPath.c_str();
        ImGui::StyleColorsDark();
        ImGui_ImplGlfw_InitForVulkan(window, false);
        VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16}};
        VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pool.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
        pool.maxSets = 16;
        pool.poolSizeCount = 1;
        pool.pPoolSizes = sizes;
        render::check(vkCreateDescriptorPool(context->device(), &pool, nullptr, &imguiPool), "vkCreateDescriptorPool");
        ImGui_ImplVulkan_InitInfo info{};
        info.Instance = context->instance();
        info.PhysicalDevice = context->physicalDevice();
        info.Device = context->device();
        info.QueueFamily = context->queueFamily();
        info.Queue = context->queue();
        info.DescriptorPool = imguiPool;
        info.MinImageCount = 2;
        info.ImageCount = std::max(2u, swapchain->imageCount());
        info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
        info.CheckVkResultFn = checkImgui;
        ImGui_ImplVulkan_Init(&info, swapchain->renderPass());
        context->submitAndWait([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
        ImGui_ImplVulkan_DestroyFontUploadObjects();
        imguiReady = true;
        swapchain->setOverlay([](VkCommandBuffer cmd) {
            if (ImDrawData* data = ImGui::GetDrawData()) ImGui_ImplVulkan_RenderDrawData(data, cmd);
        });
    }

    std::string windowTitle() const
    {
        return "VDBClay - " + std::filesystem::path(session.scenePath()).filename().string() + (worker.snapshot().unsaved ? " *" : "");
    }

    /// What the next session starts with: the brush, the window's size, the panels and the look.
    void keepSettings()
    {
        if (!window || configFolder.empty()) return;
        settings.brush = brushBeforeModifier.value_or(worker.brush());
        settings.windowSize = windowSize();
        settings.showStats = panels.showStats;
        settings.showHelp = panels.showHelp;
        settings.look = panels.look;
        settings.wireframe = panels.wireframe;
        settings.stabilizerPixels = panels.stabilizer;
        try {
            saveDesktopSettings(settings, configFolder);
        } catch (const std::exception& e) {
            std::cerr << "vdbclay: warning: the editor's settings were not kept: " << e.what() << "\n";
        }
    }

    void close()
    {
        keepSettings();
        if (imguiReady && !iniPath.empty()) ImGui::SaveIniSettingsToDisk(iniPath.c_str());
        if (context) vkDeviceWaitIdle(context->device());
        if (imguiReady) {
            ImGui_ImplVulkan_Shutdown();
            ImGui_ImplGlfw_Shutdown();
            ImGui::DestroyContext();
        }
        if (imguiPool) vkDestroyDescriptorPool(context->device(), imguiPool, nullptr);
        renderer.reset();
        swapchain.reset();
        if (surface) vkDestroySurfaceKHR(context->instance(), surface, nullptr);
        context.reset();
        if (window) glfwDestroyWindow(window);
        glfwTerminate();
    }

    bool frame()
    {
        // The frame starts before the events are read: strokes they make are part of it.
        const auto start = Clock::now();
        const double seconds = std::chrono::duration<double>(start - lastFrameStart).count();
        if (!firstFrame) {
            // The frame that just ended: its interval, and the parts measured in it.
            const FrameFigures parts = measured;
            figures.inputMs = parts.inputMs;
            figures.sculptMs = parts.sculptMs;
            figures.streamMs = parts.streamMs;
            figures.meshMs = parts.meshMs;
            figures.drawMs = parts.drawMs;
            figures.presentMs = parts.presentMs;
            figures.intervalMs = seconds * 1000.0;
            recentIntervals.emplace_back(start, figures.intervalMs);
            while (recentIntervals.size() > 1 && recentIntervals.front().first < start - std::chrono::seconds(1)) recentIntervals.pop_front();
            double sum = 0.0;
            for (const auto& [at, ms] : recentIntervals) sum += ms;
            figures.averageIntervalMs = sum / double(recentIntervals.size());
        }
        lastFrameStart = start;
        glfwPollEvents();
        if (glfwWindowShouldClose(window)) return false;
        if (firstFrame) {
            firstFrame = false;
            // The brush kept from the last session, unless a replay sets its own.
            if (!replay && settings.brush) setBrush(*settings.brush);
        }
        flyKeys(std::min(seconds, 0.1));
        if (turntable) setCamera(orbit(worker.camera(), 20.0 * std::min(seconds, 0.1), 0.0)); // 20 degrees a second
        if (replay) {
            try {
                replayNext = submitRecordedFrame(worker, *replay, replayNext, frames);
            } catch (const std::exception& e) {
                panels.status = std::string("the replay stopped: ") + e.what();
                std::cerr << "vdbclay: " << panels.status << "\n";
                replay = nullptr;
            }
        }

        ImGui_ImplVulkan_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        if (options.beforeUi) options.beforeUi(frames);
        ImGui::NewFrame();
        panels.brushPoint = hoverOutsidePanels;
        for (const Command& c : panels.draw(worker, figures)) apply(c);
        ImGui::Render();
        if (!panels.openRequested.empty() || panels.discardRecoveryRequested) return false;
        // The brush follows the pointer every frame, whatever the worker has still to do.
        if (drag == Drag::None || drag == Drag::Stroke) {
            // Never waits: while a load or an edit holds the data, the last frame's hover stands.
            const Ray ray = rayAt(cursorX, cursorY);
            std::optional<SurfaceHit> hit;
            if (session.tryPick(ray.origin, ray.direction, 1e30, &hit)) hover = hit;
            if (hover && !ImGui::GetIO().WantCaptureMouse) hoverOutsidePanels = hover->point;
        }
        const auto inputDone = Clock::now();

        // Bricks behind what the last finished frame drew stay coarse (their detail cannot show).
        const std::shared_ptr<const OccluderDepth> drawnDepth = renderer->drawnDepth();
        const FrameReport stream = worker.frame(now(), windowSize(), drawnDepth.get());
        const SessionSnapshot done = worker.snapshot();
        for (const std::string& failure : worker.takeFailures()) {
            panels.status = failure;
            std::cerr << "vdbclay: " << failure << "\n";
        }
        if (done.saves > savesShown) {
            savesShown = done.saves;
            panels.status = "saved " + done.lastSavedPath;
        } else if (!done.busy.empty()) {
            panels.status = done.busy + " ...";
        }
        figures.pendingEdits = worker.pending();
        const auto streamed = Clock::now();
        figures.meshesWaiting = chunks.sync(session.scene(), *renderer).waiting;
        for (const std::string& failure : chunks.takeMeshFailures()) {
            panels.status = failure;
            std::cerr << "vdbclay: " << failure << "\n";
        }
        figures.bricksShown = session.scene().shownBricks().size();
        MaterialTable materials = session.scene().materials();
        // A material defined or changed: its colour at once, its picture once a worker has read it.
        if (!(materials == drawnMaterials) || renderer->picturesReady()) {
            for (const std::string& w : renderer->setMaterials(materials, look(), render::Renderer::PictureLoading::Background))
                std::cerr << "vdbclay: warning: " << w << "\n";
            drawnMaterials = std::move(materials);
        }
        render::ShadingOptions shading = renderer->shading();
        if (shading.mode != panels.look || shading.wireframe != panels.wireframe) {
            shading.mode = panels.look;
            shading.wireframe = panels.wireframe;
            renderer->setShading(shading);
        }
        const BrushSettings& shownBrush = adjust != Adjust::None ? adjusted : worker.brush();
        const std::optional<std::array<double, 3>> brushAt =
            worker.brush().mode == "move" && done.strokeActive ? std::optional<std::array<double, 3>>(done.strokePoint)
            : hover                                             ? std::optional<std::array<double, 3>>(hover->point)
                                                                : std::nullopt;
        renderer->setBrush(brushAt ? std::optional<render::BrushOverlay>(brushOverlay(shownBrush, *brushAt)) : std::nullopt);
        if (const std::string t = windowTitle(); t != title) {
            title = t;
            glfwSetWindowTitle(window, title.c_str());
        }
        const auto meshed = Clock::now();

        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window, &fw, &fh);
        if (fw == 0 || fh == 0) return true; // minimized
        if (fw != swapchain->width() || fh != swapchain->height()) swapchain->resize(fw, fh);
        render::RenderTarget* target = swapchain->acquire();
        if (!target) {
            swapchain->resize(fw, fh);
            return true;
        }
        const auto acquired = Clock::now();
        render::RenderView view;
        view.camera = worker.camera();
        // The near plane follows the camera every frame: zooming up to the surface never cuts it open.
        const auto [lo, hi] = session.shownBox();
        render::fitNearPlane(view.camera, lo, hi);
        view.target = target;
        view.keepDepth = true;
        lastStats = renderer->render({view});
        figures.uploadsWaiting = lastStats.chunksWaitingUpload;
        const auto drawn = Clock::now();
        if (!swapchain->present()) swapchain->resize(fw, fh);
        const auto presented = Clock::now();

        figures.stream = stream;
        figures.draw = lastStats;
        measured.sculptMs = 0.0; // the edit worker sculpts, not this thread
        measured.inputMs = msBetween(start, inputDone) - measured.sculptMs;
        measured.streamMs = msBetween(inputDone, streamed);
        measured.meshMs = msBetween(streamed, meshed);
        measured.drawMs = msBetween(acquired, drawn);
        measured.presentMs = msBetween(meshed, acquired) + msBetween(drawn, presented);
        ++frames;
        return true;
    }
};

DesktopEditor::DesktopEditor(EditingSession& session, const DesktopOptions& options)
    : impl_(std::make_unique<Impl>(*this, session, options))
{
    try {
        impl_->open();
    } catch (...) {
        impl_->close();
        throw;
    }
}

DesktopEditor::~DesktopEditor() { impl_->close(); }

bool DesktopEditor::frame() { return impl_->frame(); }

void DesktopEditor::run()
{
    while (frame()) {
    }
}

void DesktopEditor::mouseButton(int button, int action, int mods)
{
    ImGui_ImplGlfw_MouseButtonCallback(impl_->window, button, action, mods);
    if (action == GLFW_PRESS && ImGui::GetIO().WantCaptureMouse) return;
    impl_->onMouseButton(button, action, mods);
}

void DesktopEditor::cursorMoved(double x, double y) { impl_->onCursor(x, y); }

void DesktopEditor::scrolled(double dx, double dy)
{
    ImGui_ImplGlfw_ScrollCallback(impl_->window, dx, dy);
    if (!ImGui::GetIO().WantCaptureMouse) impl_->onScroll(dy);
}

void DesktopEditor::key(int key, int action, int mods)
{
    ImGui_ImplGlfw_KeyCallback(impl_->window, key, 0, action, mods);
    if (!ImGui::GetIO().WantCaptureKeyboard) impl_->onKey(key, action, mods);
}

GLFWwindow* DesktopEditor::window() const { return impl_->window; }
std::optional<std::array<float, 4>> DesktopEditor::widgetRect(const std::string& label) const
{
    const auto it = impl_->panels.widgetRects.find(label);
    if (it == impl_->panels.widgetRects.end()) return std::nullopt;
    return it->second;
}
const render::FrameStats& DesktopEditor::lastFrame() const { return impl_->lastStats; }
const FrameFigures& DesktopEditor::figures() const { return impl_->figures; }
const Keymap& DesktopEditor::keymap() const { return impl_->keymap; }
const std::string& DesktopEditor::title() const { return impl_->title; }
uint64_t DesktopEditor::validationMessages() const { return impl_->context ? impl_->context->validationMessages() : 0; }
EditingSession& DesktopEditor::session() { return impl_->session; }

void DesktopEditor::finishEdits()
{
    impl_->worker.waitIdle();
    impl_->chunks.waitForMeshes();
}

void DesktopEditor::submit(const Command& command) { impl_->apply(command); }
void DesktopEditor::replay(const SessionRecord* record)
{
    impl_->replay = record;
    impl_->replayNext = 0;
    // The record says which stroke points went together; the worker adds none of its own.
    impl_->worker.setMergeStrokePoints(record == nullptr);
}
std::string DesktopEditor::openRequested() const { return impl_->panels.openRequested; }

bool DesktopEditor::discardRecoveryRequested() const { return impl_->panels.discardRecoveryRequested; }

int runDesktopEditor(const SessionOptions& options, std::unique_ptr<EditingSession> session, const SessionRecord* replay)
{
    while (true) {
        std::string open;
        bool discard = false;
        try {
            DesktopEditor editor(*session);
            editor.replay(replay);
            editor.run();
            open = editor.openRequested();
            discard = editor.discardRecoveryRequested();
        } catch (const NoDisplay& e) {
            std::cerr << "vdbclay: error: " << e.what() << ": draw pictures with 'vdbclay render', or replay a session with "
                      << "'vdbclay edit SCENE --replay SESSION.json --headless'\n";
            return 1;
        } catch (const render::NoVulkanDevice& e) {
            std::cerr << "vdbclay: error: cannot open the editor: " << e.what() << "\n";
            return 1;
        }
        SessionOptions next = options;
        if (discard) {
            // The same scene again, as last saved.
            open = session->scenePath();
            next.discardRecovery = true;
        }
        if (open.empty()) return 0;
        replay = nullptr;
        session.reset();
        session = std::make_unique<EditingSession>(open, next);
    }
}

} // namespace vdbclay
