#include "vr/VrMenus.h"

#include "render/Renderer.h"

#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace vdbclay::vr {

namespace {

// The picture: the menu on the left half (512 x 768, as tall as a phone held upright), the two hands'
// hints at the top of the right half (512 x 256 each).
constexpr int kPictureSize = 1024;
constexpr int kMenuPixelsWide = 512, kMenuPixelsHigh = 768;
constexpr int kHintPixelsWide = 512, kHintPixelsHigh = 256;
// A white square in the picture's free lower right corner: what the pointer's ray is drawn with.
constexpr float kWhiteFrom = 1016.0f, kWhiteTo = 1024.0f;
constexpr double kRayWidthMetres = 0.003;

void checkImgui(VkResult r)
{
    if (r != VK_SUCCESS) render::check(r, "Dear ImGui's Vulkan back end");
}

const char* const kHintLines[2][5] = {
    // The off hand.
    {"Grip: hold the world (both grips: turn and scale it)", "Thumbstick: fly", "X: frame the scene again", "Y: the menu on / off",
     "Menu: these hints on / off"},
    // The dominant hand.
    {"Trigger: sculpt (pressure sets size or strength)", "Thumbstick up / down: brush size", "Thumbstick left / right: brush mode",
     "A: undo     B: redo", "Point at the menu, trigger: click"},
};

} // namespace

std::array<glm::dvec3, 4> MenuLayout::Panel::corners() const
{
    const glm::dvec3 r = right * (0.5 * width), u = up * (0.5 * height);
    return {centre - r - u, centre + r - u, centre + r + u, centre - r + u};
}

std::optional<glm::dvec3> MenuLayout::meet(const Pose& ray) const
{
    if (!menu) return std::nullopt;
    const glm::dvec3 normal = glm::cross(menu->right, menu->up);
    const glm::dvec3 dir = ray.forward();
    const double facing = glm::dot(dir, normal);
    if (std::fabs(facing) < 1e-6) return std::nullopt;
    const double t = glm::dot(menu->centre - ray.position, normal) / facing;
    if (t <= 0.0) return std::nullopt;
    const glm::dvec3 hit = ray.position + t * dir;
    const glm::dvec3 local = hit - menu->centre;
    if (std::fabs(glm::dot(local, menu->right)) > 0.5 * menu->width || std::fabs(glm::dot(local, menu->up)) > 0.5 * menu->height) return std::nullopt;
    return hit;
}

std::optional<glm::dvec2> MenuLayout::pointAt(const Pose& ray, int pictureWidth, int pictureHeight) const
{
    const std::optional<glm::dvec3> hit = meet(ray);
    if (!hit) return std::nullopt;
    const glm::dvec3 local = *hit - menu->centre;
    const double u = glm::dot(local, menu->right) / menu->width + 0.5, v = 0.5 - glm::dot(local, menu->up) / menu->height;
    const double x = (menu->uv[0] + u * (menu->uv[2] - menu->uv[0])) * pictureWidth;
    const double y = (menu->uv[1] + v * (menu->uv[3] - menu->uv[1])) * pictureHeight;
    return glm::dvec2(x, y);
}

MenuLayout layoutMenus(const ControllerFrame& frame, int dominantHand, bool menuShown, bool hintsShown)
{
    MenuLayout layout;
    const HandInput& off = frame.hands[std::size_t(1 - dominantHand)];
    if (menuShown && off.tracked) {
        // Above the hand that holds it, its face turned back along the grip toward the user.
        MenuLayout::Panel p;
        p.right = off.grip.orientation * glm::dvec3(1, 0, 0);
        p.up = off.grip.orientation * glm::dvec3(0, 1, 0);
        p.centre = off.grip.position + p.up * (0.5 * MenuLayout::kMenuHeight + 0.06) + off.grip.orientation * glm::dvec3(0, 0, -0.04);
        p.width = MenuLayout::kMenuWidth;
        p.height = MenuLayout::kMenuHeight;
        p.uv = {0.0f, 0.0f, float(kMenuPixelsWide) / kPictureSize, float(kMenuPixelsHigh) / kPictureSize};
        layout.menu = p;
    }
    if (hintsShown) {
        for (int h = 0; h < 2; ++h) {
            const HandInput& hand = frame.hands[std::size_t(h)];
            if (!hand.tracked) continue;
            // Beside the hand, on its outer side.
            MenuLayout::Panel p;
            p.right = hand.grip.orientation * glm::dvec3(1, 0, 0);
            p.up = hand.grip.orientation * glm::dvec3(0, 1, 0);
            const double side = h == 0 ? -1.0 : 1.0;
            p.centre = hand.grip.position + p.right * (side * (0.5 * MenuLayout::kHintWidth + 0.05)) + p.up * 0.03;
            p.width = MenuLayout::kHintWidth;
            p.height = MenuLayout::kHintHeight;
            const float top = float(h * kHintPixelsHigh) / kPictureSize;
            p.uv = {float(kMenuPixelsWide) / kPictureSize, top, float(kMenuPixelsWide + kHintPixelsWide) / kPictureSize,
                    top + float(kHintPixelsHigh) / kPictureSize};
            layout.hints.push_back(p);
        }
    }
    return layout;
}

VrMenus::VrMenus(const render::VulkanContext& vulkan, VkRenderPass eyePass) : vulkan_(vulkan)
{
    quads_ = std::make_unique<render::PanelQuads>(vulkan, kPictureSize, kPictureSize, eyePass);
    IMGUI_CHECKVERSION();
    ImGuiContext* context = ImGui::CreateContext();
    imgui_ = context;
    ImGui::SetCurrentContext(context);
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;
    io.DisplaySize = ImVec2(float(kPictureSize), float(kPictureSize));
    io.MouseDrawCursor = true; // the pointer's spot on the menu
    ImGui::StyleColorsDark();
    VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16}};
    VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
    pool.maxSets = 16;
    pool.poolSizeCount = 1;
    pool.pPoolSizes = sizes;
    render::check(vkCreateDescriptorPool(vulkan.device(), &pool, nullptr, &imguiPool_), "vkCreateDescriptorPool");
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = vulkan.instance();
    info.PhysicalDevice = vulkan.physicalDevice();
    info.Device = vulkan.device();
    info.QueueFamily = vulkan.queueFamily();
    info.Queue = vulkan.queue();
    info.DescriptorPool = imguiPool_;
    info.MinImageCount = 2;
    info.ImageCount = 4; // its vertex buffers: one per frame that may be in flight, and a spare
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = checkImgui;
    ImGui_ImplVulkan_Init(&info, quads_->picturePass());
    vulkan.submitAndWait([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
    ImGui_ImplVulkan_DestroyFontUploadObjects();
    panels_.canvas = std::array<float, 2>{float(kMenuPixelsWide), float(kMenuPixelsHigh)};
    panels_.panelWidth = float(kMenuPixelsWide - 20);
    panels_.showStats = false;
    panels_.query.lightField = true; // a headset has a renderer: searches draw the sculpture's silhouettes
}

VrMenus::~VrMenus()
{
    vkDeviceWaitIdle(vulkan_.device());
    ImGui::SetCurrentContext(static_cast<ImGuiContext*>(imgui_));
    ImGui_ImplVulkan_Shutdown();
    ImGui::DestroyContext(static_cast<ImGuiContext*>(imgui_));
    if (imguiPool_) vkDestroyDescriptorPool(vulkan_.device(), imguiPool_, nullptr);
}

std::vector<Command> VrMenus::update(ControllerFrame& frame, int dominantHand, SessionWorker& worker, const FrameFigures& figures, double seconds)
{
    ImGui::SetCurrentContext(static_cast<ImGuiContext*>(imgui_));
    layout_ = layoutMenus(frame, dominantHand, menuShown_, hintsShown_);
    ImGuiIO& io = ImGui::GetIO();
    const HandInput& hand = frame.hands[std::size_t(dominantHand)];
    std::optional<glm::dvec2> pointer;
    if (frame.focused && hand.tracked) pointer = layout_.pointAt(hand.aim, kPictureSize, kPictureSize);
    frame.pointerOnMenu = pointer.has_value();
    if (layout_.menu && frame.focused && hand.tracked)
        layout_.pointer = std::array<glm::dvec3, 2>{hand.aim.position, layout_.meet(hand.aim).value_or(hand.aim.position + 0.5 * hand.aim.forward())};
    io.DeltaTime = float(std::max(seconds, 1e-4));
    io.MousePos = pointer ? ImVec2(float(pointer->x), float(pointer->y)) : ImVec2(-FLT_MAX, -FLT_MAX);
    io.MouseDown[0] = pointer && hand.trigger > 0.5;
    io.MouseWheel = pointer ? float(hand.thumbstick.y * seconds * 10.0) : 0.0f;

    std::vector<Command> out;
    ImGui_ImplVulkan_NewFrame();
    ImGui::NewFrame();
    if (layout_.menu) out = panels_.draw(worker, figures);
    if (hintsShown_) {
        for (int h = 0; h < 2; ++h) {
            const bool dominant = h == dominantHand;
            ImGui::SetNextWindowPos(ImVec2(float(kMenuPixelsWide), float(h * kHintPixelsHigh)));
            ImGui::SetNextWindowSize(ImVec2(float(kHintPixelsWide), float(kHintPixelsHigh)));
            ImGui::SetNextWindowBgAlpha(0.8f);
            const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs | ImGuiWindowFlags_NoSavedSettings |
                                           ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoFocusOnAppearing;
            if (ImGui::Begin(h == 0 ? "hints left" : "hints right", nullptr, flags)) {
                ImGui::SetWindowFontScale(1.4f);
                for (const char* line : kHintLines[dominant ? 1 : 0]) ImGui::TextWrapped("%s", line);
                if (dominant) ImGui::TextWrapped("Brush: %s, radius %.1f", worker.brush().mode.c_str(), worker.brush().radius);
            }
            ImGui::End();
        }
    }
    ImGui::GetForegroundDrawList()->AddRectFilled(ImVec2(kWhiteFrom, kWhiteFrom), ImVec2(kWhiteTo, kWhiteTo), IM_COL32_WHITE);
    ImGui::Render();
    drawn_ = true;
    return out;
}

void VrMenus::recordPicture(VkCommandBuffer cmd)
{
    if (!drawn_ || (!layout_.menu && layout_.hints.empty())) return;
    ImGui::SetCurrentContext(static_cast<ImGuiContext*>(imgui_));
    quads_->recordPicture(cmd, [](VkCommandBuffer c) {
        if (ImDrawData* data = ImGui::GetDrawData()) ImGui_ImplVulkan_RenderDrawData(data, c);
    });
}

void VrMenus::recordQuads(VkCommandBuffer cmd, const render::Camera& eye, const WorldTransform& world, int width, int height) const
{
    if (!drawn_) return;
    const std::array<float, 16> m = render::viewProjection(eye, double(width) / double(height));
    auto clip = [&](const glm::dvec3& stage) {
        const glm::dvec3 p = world.toScene(stage);
        std::array<float, 4> c{};
        for (int r = 0; r < 4; ++r)
            c[std::size_t(r)] = float(m[std::size_t(r)] * p.x + m[std::size_t(4 + r)] * p.y + m[std::size_t(8 + r)] * p.z + m[std::size_t(12 + r)]);
        return c;
    };
    std::vector<render::PanelQuads::Quad> quads;
    auto add = [&](const MenuLayout::Panel& panel) {
        render::PanelQuads::Quad q;
        const auto corners = panel.corners();
        for (std::size_t i = 0; i < 4; ++i) q.clip[i] = clip(corners[i]);
        // A corner behind the eye would fold the quad across the view: such a panel is not drawn.
        for (const auto& c : q.clip)
            if (c[3] <= 0.0f) return;
        q.uv = panel.uv;
        quads.push_back(q);
    };
    if (layout_.menu) add(*layout_.menu);
    for (const auto& h : layout_.hints) add(h);
    if (layout_.pointer) {
        // The ray as a thin strip turned toward the eye.
        const auto& [from, to] = *layout_.pointer;
        const glm::dvec3 eyeAt = world.toStage(glm::dvec3(eye.eye[0], eye.eye[1], eye.eye[2]));
        const glm::dvec3 across = glm::cross(to - from, eyeAt - from);
        if (glm::length(across) > 1e-12) {
            MenuLayout::Panel strip;
            strip.centre = 0.5 * (from + to);
            strip.right = glm::normalize(to - from);
            strip.up = glm::normalize(across);
            strip.width = glm::length(to - from);
            strip.height = kRayWidthMetres;
            const float a = (kWhiteFrom + 2.0f) / kPictureSize, b = (kWhiteTo - 2.0f) / kPictureSize;
            strip.uv = {a, a, b, b};
            add(strip);
        }
    }
    quads_->recordQuads(cmd, quads, width, height);
}

} // namespace vdbclay::vr
