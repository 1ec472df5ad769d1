// The menus in the headset: the editor's panels (SessionPanels) on a quad the off hand holds, pointed at
// by a ray from the dominant hand (its trigger clicks, its thumbstick scrolls), and controller hints
// beside each hand (seed 004's appendix: what each control does, shown until the user turns them off).
// Dear ImGui draws them all into one picture each frame (PanelQuads), which every eye shows on its quads.
#pragma once

#include "panels/SessionPanels.h"
#include "render/PanelQuads.h"
#include "render/RenderTypes.h"
#include "vr/VrControls.h"

#include <array>
#include <memory>
#include <optional>
#include <vector>

namespace vdbclay::vr {

/// Where the menus stand in the room (stage metres), from the hands; device-free.
struct MenuLayout {
    static constexpr double kMenuWidth = 0.24, kMenuHeight = 0.36; // metres
    static constexpr double kHintWidth = 0.16, kHintHeight = 0.08;
    struct Panel {
        glm::dvec3 centre{0.0}, right{1, 0, 0}, up{0, 1, 0}; // right and up: unit vectors of its plane
        double width = 0.0, height = 0.0;
        std::array<float, 4> uv{0, 0, 1, 1}; // its part of the picture
        /// Corners, as PanelQuads reads them: lower left, lower right, upper right, upper left.
        std::array<glm::dvec3, 4> corners() const;
    };
    std::optional<Panel> menu;
    std::vector<Panel> hints;
    /// The pointer's ray while the menu is shown: from the pointing hand to where it meets the menu (or
    /// half a metre ahead).
    std::optional<std::array<glm::dvec3, 2>> pointer;
    /// Where a ray meets the menu, in its picture's pixels (x right, y down); none when it misses.
    std::optional<glm::dvec2> pointAt(const Pose& ray, int pictureWidth, int pictureHeight) const;
    /// Where a ray meets the menu's plane within it (stage metres); none when it misses.
    std::optional<glm::dvec3> meet(const Pose& ray) const;
};

/// The menu above the off hand's grip, facing back along it; the hints beside each tracked hand.
MenuLayout layoutMenus(const ControllerFrame& frame, int dominantHand, bool menuShown, bool hintsShown);

class VrMenus {
public:
    /// Dear ImGui on `vulkan`, drawing the panels' picture; `eyePass` is the eyes' render pass shape.
    VrMenus(const render::VulkanContext& vulkan, VkRenderPass eyePass);
    ~VrMenus();
    VrMenus(const VrMenus&) = delete;
    VrMenus& operator=(const VrMenus&) = delete;

    /// One frame: places the menus, feeds the pointer to ImGui and builds the panels and hints; returns
    /// the panels' commands. `frame.pointerOnMenu` is set when the dominant hand points at the menu.
    std::vector<Command> update(ControllerFrame& frame, int dominantHand, SessionWorker& worker, const FrameFigures& figures, double seconds);
    void toggleMenu() { menuShown_ = !menuShown_; }
    void toggleHints() { hintsShown_ = !hintsShown_; }
    bool menuShown() const { return menuShown_; }
    bool hintsShown() const { return hintsShown_; }
    const MenuLayout& layout() const { return layout_; }
    SessionPanels& panels() { return panels_; }

    /// Records the picture (before the first eye's pass).
    void recordPicture(VkCommandBuffer cmd);
    /// Records the quads of the shown menus for an eye whose camera (scene units) is `eye`.
    void recordQuads(VkCommandBuffer cmd, const render::Camera& eye, const WorldTransform& world, int width, int height) const;

private:
    const render::VulkanContext& vulkan_;
    std::unique_ptr<render::PanelQuads> quads_;
    VkDescriptorPool imguiPool_ = VK_NULL_HANDLE;
    void* imgui_ = nullptr; // the ImGui context
    SessionPanels panels_;
    MenuLayout layout_;
    bool menuShown_ = false, hintsShown_ = true;
    bool drawn_ = false; // ImGui rendered a frame whose draw data the picture may record
};

} // namespace vdbclay::vr
