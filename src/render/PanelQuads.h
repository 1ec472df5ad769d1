// Menus in the world: a picture of panels (what Dear ImGui draws into it each frame) shown on quads that
// stand in the scene, over what a view drew (a headset's menu held in the hand, the hints beside the
// controllers). The picture is drawn once per frame before the views' passes; each view then draws
// its quads, their corners given in that view's clip space.
#pragma once

#include "render/VulkanContext.h"

#include <array>
#include <functional>
#include <vector>

namespace vdbclay::render {

class PanelQuads {
public:
    /// A picture of `width` x `height` pixels, and the pipeline that shows parts of it in targets of
    /// `targetPass`'s shape. Throws VulkanError.
    PanelQuads(const VulkanContext& context, int width, int height, VkRenderPass targetPass);
    ~PanelQuads();
    PanelQuads(const PanelQuads&) = delete;
    PanelQuads& operator=(const PanelQuads&) = delete;

    int width() const { return width_; }
    int height() const { return height_; }
    /// The render pass the picture is drawn in (give it to the UI's Vulkan back end).
    VkRenderPass picturePass() const { return picturePass_; }

    /// Records the picture's pass (cleared transparent) with `draw` inside it; its quads sample it next.
    void recordPicture(VkCommandBuffer cmd, const std::function<void(VkCommandBuffer)>& draw);

    struct Quad {
        std::array<std::array<float, 4>, 4> clip; // corners in the view's clip space: lower left, lower right, upper right, upper left
        std::array<float, 4> uv{0, 0, 1, 1};      // the part of the picture: u0, v0 (upper left), u1, v1
    };
    /// Records `quads` inside a target's render pass, drawn over it (no depth test: menus stay in sight).
    void recordQuads(VkCommandBuffer cmd, const std::vector<Quad>& quads, int targetWidth, int targetHeight) const;

private:
    void release();

    const VulkanContext& context_;
    int width_, height_;
    VkImage colour_ = VK_NULL_HANDLE, depth_ = VK_NULL_HANDLE;
    VkDeviceMemory colourMemory_ = VK_NULL_HANDLE, depthMemory_ = VK_NULL_HANDLE;
    VkImageView colourView_ = VK_NULL_HANDLE, depthView_ = VK_NULL_HANDLE;
    VkRenderPass picturePass_ = VK_NULL_HANDLE;
    VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
    VkSampler sampler_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
};

} // namespace vdbclay::render
