#include "editor/DesktopEditor.h"

#include "editor/CameraControl.h"
#include "editor/DesktopPanels.h"
#include "render/Framing.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/ScenePicture.h"
#include "render/SwapchainTarget.h"
#include "render/VulkanContext.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

namespace vdbclay {

bool desktopAvailable()
{
    const char* x = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    return (x && *x) || (wayland && *wayland);
}

const char* desktopShortcutsHelp()
{
    return "Mouse: left drag sculpts with the brush; right drag (or Alt + left) orbits; middle drag (or Shift + right)\n"
           "pans; the wheel zooms towards the surface under the cursor; hold the right button and use W A S D Q E to fly.\n"
           "Keys:\n"
           "  Ctrl+Z undo         Ctrl+Shift+Z / Ctrl+Y redo      Ctrl+S save\n"
           "  [ / ]  brush smaller / larger     Shift+[ / Shift+]  weaker / stronger\n"
           "  X      mirror across x on/off     F  frame the scene          H  help panel\n"
           "  A add   R remove   P paint   E erode   S smooth   L flatten   I inflate   D deflate   G move (grab)\n"
           "  Tab    stats overlay on/off       Esc  end the stroke\n";
}

namespace {

using Clock = std::chrono::steady_clock;

void checkImgui(VkResult r)
{
    if (r != VK_SUCCESS) std::cerr << "vdbclay: ImGui's Vulkan backend: " << render::resultName(r) << "\n";
}

/// The brush as the shaders preview it: its primitive at the pointer, sized by the brush's radius.
render::BrushOverlay overlayFor(const BrushSettings& brush, const std::array<double, 3>& at)
{
    using Shape = render::BrushOverlay::Shape;
    render::BrushOverlay o;
    const float r = float(brush.radius);
    const std::string shape = brush.shape.value("shape", std::string("sphere"));
    const auto value = [&](const char* key, double fallback) { return float(brush.shape.value(key, fallback)) * r; };
    o.shape = Shape::Sphere;
    o.params = {r, r, r, 0.0f};
    if (shape == "sphere") o.params[0] = value("radius", 1.0);
    else if (shape == "box" && brush.shape.contains("size") && brush.shape.at("size").is_array()) {
        o.shape = Shape::Box;
        for (std::size_t a = 0; a < 3; ++a) o.params[a] = float(brush.shape.at("size")[a].get<double>()) * r;
        o.params[3] = value("rounding", 0.0);
    } else if (shape == "cylinder" || shape == "cone" || shape == "capsule") {
        o.shape = shape == "cylinder" ? Shape::Cylinder : shape == "cone" ? Shape::Cone : Shape::Capsule;
        o.params[0] = value("radius", 1.0);
        o.height = shape == "capsule" ? value("length", 1.0) : value("height", 2.0);
    } else if (shape == "torus") {
        o.shape = Shape::Torus;
        o.params = {value("radius", 0.75), value("minor_radius", 0.25), 0.0f, 0.0f};
    }
    o.worldToLocal = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float(-at[0]), float(-at[1]), float(-at[2]), 1};
    const float reach = 2.0f * r;
    for (std::size_t a = 0; a < 3; ++a) {
        o.worldBoundsMin[a] = float(at[a]) - reach;
        o.worldBoundsMax[a] = float(at[a]) + reach;
    }
    return o;
}

} // namespace

struct DesktopEditor::Impl {
    enum class Drag { None, Stroke, Orbit, Pan };

    DesktopEditor& self;
    EditingSession& session;
    DesktopOptions options;
    GLFWwindow* window = nullptr;
    std::unique_ptr<render::VulkanContext> context;
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    std::unique_ptr<render::SwapchainTarget> swapchain;
    std::unique_ptr<render::Renderer> renderer;
    render::StreamedSceneChunks chunks;
    VkDescriptorPool imguiPool = VK_NULL_HANDLE;
    bool imguiReady = false;
    DesktopPanels panels;
    FrameFigures figures;
    render::FrameStats lastStats;
    Clock::time_point started = Clock::now(), lastFrame = Clock::now();
    uint64_t frames = 0;

    Drag drag = Drag::None;
    double cursorX = 0.0, cursorY = 0.0;
    bool rightHeld = false;
    std::optional<SurfaceHit> hover;

    const SessionRecord* replay = nullptr;
    std::size_t replayNext = 0;
    MaterialTable drawnMaterials; // what the renderer was last given

    render::MaterialLook look() const
    {
        return render::materialLook(session.scene().store().voxelSize(), std::filesystem::path(session.scenePath()).parent_path().string());
    }

    Impl(DesktopEditor& editor, EditingSession& s, const DesktopOptions& o) : self(editor), session(s), options(o) {}

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
            session.apply(c);
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

    Ray rayAt(double x, double y) const { return pointerRay(session.camera(), windowSize(), x, y); }

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

    void onMouseButton(int button, int action, int mods)
    {
        if (action == GLFW_RELEASE) {
            if (button == GLFW_MOUSE_BUTTON_RIGHT) rightHeld = false;
            if (drag == Drag::Stroke && button == GLFW_MOUSE_BUTTON_LEFT) {
                Command c;
                c.kind = Command::Kind::StrokeEnd;
                apply(c);
            }
            drag = Drag::None;
            return;
        }
        if (action != GLFW_PRESS || drag != Drag::None) return;
        const bool alt = mods & GLFW_MOD_ALT, shift = mods & GLFW_MOD_SHIFT;
        if (button == GLFW_MOUSE_BUTTON_LEFT && !alt) {
            drag = Drag::Stroke;
            strokeTo(cursorX, cursorY, true);
        } else if (button == GLFW_MOUSE_BUTTON_MIDDLE || (button == GLFW_MOUSE_BUTTON_RIGHT && shift)) {
            drag = Drag::Pan;
        } else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_LEFT) {
            drag = Drag::Orbit;
            rightHeld = button == GLFW_MOUSE_BUTTON_RIGHT;
        }
    }

    void onCursor(double x, double y)
    {
        const double dx = x - cursorX, dy = y - cursorY;
        cursorX = x;
        cursorY = y;
        switch (drag) {
        case Drag::Stroke: strokeTo(x, y, false); break;
        case Drag::Orbit: setCamera(orbit(session.camera(), dx * 0.3, dy * 0.3)); break;
        case Drag::Pan: setCamera(pan(session.camera(), windowSize(), dx, dy)); break;
        case Drag::None: break;
        }
    }

    void onScroll(double dy)
    {
        if (dy == 0.0) return;
        const auto hit = pickAt(cursorX, cursorY);
        setCamera(zoomToward(session.camera(), std::pow(1.15, dy), hit ? std::optional<std::array<double, 3>>(hit->point) : std::nullopt));
    }

    void frameScene()
    {
        const auto [lo, hi] = session.sceneBox();
        const auto size = windowSize();
        setCamera(render::framingCamera(lo, hi, double(size[0]) / double(size[1])));
    }

    void onKey(int key, int action, int mods)
    {
        if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
        const bool ctrl = mods & GLFW_MOD_CONTROL, shift = mods & GLFW_MOD_SHIFT;
        Command c;
        BrushSettings b = session.brush();
        if (ctrl) {
            if (key == GLFW_KEY_Z) c.kind = shift ? Command::Kind::Redo : Command::Kind::Undo;
            else if (key == GLFW_KEY_Y) c.kind = Command::Kind::Redo;
            else if (key == GLFW_KEY_S) c.kind = Command::Kind::Save;
            else return;
            apply(c);
            if (key == GLFW_KEY_S) panels.status = "saved " + session.scenePath();
            return;
        }
        if (rightHeld) return; // W A S D Q E fly (handled per frame)
        static const std::pair<int, const char*> modeKeys[] = {{GLFW_KEY_A, "add"},     {GLFW_KEY_R, "remove"},  {GLFW_KEY_P, "paint"},
                                                               {GLFW_KEY_E, "erode"},   {GLFW_KEY_S, "smooth"},  {GLFW_KEY_L, "flatten"},
                                                               {GLFW_KEY_I, "inflate"}, {GLFW_KEY_D, "deflate"}, {GLFW_KEY_G, "move"}};
        for (const auto& [k, mode] : modeKeys)
            if (key == k) {
                b.mode = mode;
                return setBrush(b);
            }
        switch (key) {
        case GLFW_KEY_LEFT_BRACKET:
        case GLFW_KEY_RIGHT_BRACKET: {
            const bool up = key == GLFW_KEY_RIGHT_BRACKET;
            if (shift) b.strength = std::clamp(b.strength + (up ? 0.05 : -0.05), 0.0, 1.0);
            else b.radius = std::max(b.radius * (up ? 1.15 : 1.0 / 1.15), 0.1 * session.scene().store().voxelSize());
            return setBrush(b);
        }
        case GLFW_KEY_X: {
            nlohmann::json s = b.symmetry.is_object() ? b.symmetry : nlohmann::json::object();
            nlohmann::json mirror = s.value("mirror", nlohmann::json::array());
            const auto it = std::find(mirror.begin(), mirror.end(), "x");
            if (it != mirror.end()) mirror.erase(it);
            else mirror.push_back("x");
            if (mirror.empty()) s.erase("mirror");
            else s["mirror"] = mirror;
            b.symmetry = s.empty() || (s.size() == 1 && s.contains("center")) ? nlohmann::json() : s;
            return setBrush(b);
        }
        case GLFW_KEY_F: return frameScene();
        case GLFW_KEY_H: panels.showHelp = !panels.showHelp; return;
        case GLFW_KEY_TAB: panels.showStats = !panels.showStats; return;
        case GLFW_KEY_ESCAPE:
            if (session.strokeActive()) {
                c.kind = Command::Kind::StrokeEnd;
                apply(c);
                drag = Drag::None;
            }
            return;
        default: return;
        }
    }

    void flyKeys(double seconds)
    {
        if (!rightHeld) return;
        const auto held = [&](int k) { return glfwGetKey(window, k) == GLFW_PRESS ? 1.0 : 0.0; };
        const double f = held(GLFW_KEY_W) - held(GLFW_KEY_S), r = held(GLFW_KEY_D) - held(GLFW_KEY_A), u = held(GLFW_KEY_E) - held(GLFW_KEY_Q);
        if (f == 0.0 && r == 0.0 && u == 0.0) return;
        const render::Camera& c = session.camera();
        const double dist = std::sqrt(std::pow(c.target[0] - c.eye[0], 2) + std::pow(c.target[1] - c.eye[1], 2) + std::pow(c.target[2] - c.eye[2], 2));
        const double speed = 0.5 * dist * seconds; // half the distance to the target per second
        setCamera(fly(c, f * speed, r * speed, u * speed));
    }

    void open()
    {
        if (!glfwInit()) throw NoDisplay("no display to open a window on (GLFW could not reach it)");
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
        const std::string title = "VDBClay - " + std::filesystem::path(session.scenePath()).filename().string();
        window = glfwCreateWindow(options.windowSize[0], options.windowSize[1], title.c_str(), nullptr, nullptr);
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
        renderer = std::make_unique<render::Renderer>(*context, ro);
        drawnMaterials = session.scene().materials();
        for (const std::string& w : renderer->setMaterials(drawnMaterials, look(), render::Renderer::PictureLoading::Background))
            std::cerr << "vdbclay: warning: " << w << "\n";

        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;
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

    void close()
    {
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
        glfwPollEvents();
        if (glfwWindowShouldClose(window)) return false;
        const auto start = Clock::now();
        const double seconds = std::chrono::duration<double>(start - lastFrame).count();
        lastFrame = start;
        flyKeys(std::min(seconds, 0.1));
        if (replay) {
            try {
                replayNext = applyRecordedFrame(session, *replay, replayNext, frames);
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
        for (const Command& c : panels.draw(session, figures)) apply(c);
        ImGui::Render();
        if (!panels.openRequested.empty() || panels.discardRecoveryRequested) return false;

        figures.stream = session.frame(now(), windowSize());
        chunks.sync(session.scene(), *renderer);
        figures.bricksShown = session.scene().shownBricks().size();
        MaterialTable materials = session.scene().materials();
        // A material defined or changed: its colour at once, its picture once a worker has read it.
        if (!(materials == drawnMaterials) || renderer->picturesReady()) {
            for (const std::string& w : renderer->setMaterials(materials, look(), render::Renderer::PictureLoading::Background))
                std::cerr << "vdbclay: warning: " << w << "\n";
            drawnMaterials = std::move(materials);
        }
        if (drag == Drag::None) hover = pickAt(cursorX, cursorY);
        const std::optional<std::array<double, 3>> brushAt =
            session.strokeActive() ? std::optional<std::array<double, 3>>(session.strokePoint()) : hover ? std::optional<std::array<double, 3>>(hover->point) : std::nullopt;
        renderer->setBrush(brushAt ? std::optional<render::BrushOverlay>(overlayFor(session.brush(), *brushAt)) : std::nullopt);

        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window, &fw, &fh);
        if (fw == 0 || fh == 0) return true; // minimized
        if (fw != swapchain->width() || fh != swapchain->height()) swapchain->resize(fw, fh);
        render::RenderTarget* target = swapchain->acquire();
        if (!target) {
            swapchain->resize(fw, fh);
            return true;
        }
        render::RenderView view;
        view.camera = session.camera();
        // The near plane follows the camera every frame: zooming up to the surface never cuts it open.
        const auto [lo, hi] = session.shownBox();
        render::fitNearPlane(view.camera, lo, hi);
        view.target = target;
        lastStats = renderer->render({view});
        if (!swapchain->present()) swapchain->resize(fw, fh);
        figures.draw = lastStats;
        figures.editMs = session.stats().editMsLastFrame;
        figures.frameMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count() - lastStats.submitWaitMs;
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
uint64_t DesktopEditor::validationMessages() const { return impl_->context ? impl_->context->validationMessages() : 0; }
EditingSession& DesktopEditor::session() { return impl_->session; }
void DesktopEditor::replay(const SessionRecord* record) { impl_->replay = record; impl_->replayNext = 0; }
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
