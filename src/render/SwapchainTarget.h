// A window's swapchain as render targets: one per image (colour from the swapchain, one depth image the
// frames in flight share: the render pass orders their writes), acquired without waiting (the frame's
// submission waits on the device for the image's acquire semaphore) and presented once drawn (the
// present waits on the image's semaphore, which the frame's submission signals).
#pragma once

#include "render/RenderTarget.h"
#include "render/VulkanContext.h"

#include <functional>
#include <memory>
#include <vector>

namespace vdbclay::render {

class SwapchainTarget {
public:
    /// `surface` stays the caller's. Throws VulkanError when the device cannot present to it.
    SwapchainTarget(const VulkanContext& context, VkSurfaceKHR surface, int width, int height);
    ~SwapchainTarget();
    SwapchainTarget(const SwapchainTarget&) = delete;
    SwapchainTarget& operator=(const SwapchainTarget&) = delete;

    /// The colour format of its images (give it to RendererOptions::colourFormat) and its render pass.
    VkFormat format() const { return format_; }
    VkRenderPass renderPass() const { return renderPass_; }
    uint32_t imageCount() const { return uint32_t(images_.size()); }
    int width() const { return width_; }
    int height() const { return height_; }

    /// What every target draws over the scene, inside its render pass (the menus).
    void setOverlay(std::function<void(VkCommandBuffer)> overlay) { overlay_ = std::move(overlay); }

    /// The next image as a target (the device waits for it, not the caller); nullptr when the swapchain
    /// no longer matches the window (call resize). A target acquired must be drawn before the next
    /// acquire, and a renderer keeps fewer frames in flight than the swapchain has images.
    RenderTarget* acquire();
    /// Presents the image acquired last, once the frame drawn into it is done. False when the swapchain
    /// must be resized.
    bool present();
    /// Makes the swapchain again for the window's new size (0 x 0 while minimized: nothing to draw).
    void resize(int width, int height);

private:
    struct Image;
    void create(int width, int height);
    void destroy();

    const VulkanContext& context_;
    VkSurfaceKHR surface_;
    VkFormat format_ = VK_FORMAT_UNDEFINED;
    VkRenderPass renderPass_ = VK_NULL_HANDLE;
    VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
    std::vector<VkSemaphore> acquireSemaphores_; // a ring, one more than the images: a semaphore is used
                                                 // again only once the frame that waited on it is done
    std::size_t nextAcquire_ = 0;
    bool depthSampled_; // made sampled (depthSampleable): RenderView::keepDepth reads it
    VkImage depth_ = VK_NULL_HANDLE;
    VkDeviceMemory depthMemory_ = VK_NULL_HANDLE;
    VkImageView depthView_ = VK_NULL_HANDLE;
    std::vector<std::unique_ptr<Image>> images_;
    uint32_t current_ = 0;
    int width_ = 0, height_ = 0;
    std::function<void(VkCommandBuffer)> overlay_;
};

} // namespace vdbclay::render
