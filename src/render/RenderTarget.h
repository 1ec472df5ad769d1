// What a frame draws into: an offscreen image read back to the host, a window's swapchain image, one eye
// of a headset. All share the render pass shape of createRenderPass (colour + 32-bit depth, cleared).
#pragma once

#include <vulkan/vulkan.h>

namespace vdbclay::render {

class RenderTarget {
public:
    virtual ~RenderTarget() = default;
    virtual int width() const = 0;
    virtual int height() const = 0;
    virtual VkRenderPass renderPass() const = 0;
    virtual VkFramebuffer framebuffer() const = 0;
    /// Recorded before the target's render pass (outside any pass): what its overlay reads, drawn first
    /// (the picture of a headset's menus).
    virtual void recordBeforePass(VkCommandBuffer) {}
    /// Recorded inside the render pass after the scene's views: what the target draws over them (menus).
    virtual void recordOverlay(VkCommandBuffer) {}
    /// Recorded after the render pass (a readback of the pixels).
    virtual void recordAfterPass(VkCommandBuffer) const {}
    /// Whether the caller reads the drawn pixels once Renderer::render returns (the frame is then waited
    /// for); else the frame runs on while the next one is prepared.
    virtual bool readsBack() const { return false; }
    /// Signalled when the frame drawn into it is finished (a swapchain image's present waits for it);
    /// none by default.
    virtual VkSemaphore finishedSemaphore() const { return VK_NULL_HANDLE; }
    /// Waited for on the device before the frame writes its pixels (a swapchain image, until the
    /// presentation engine lets go of it): the CPU records meanwhile. None by default.
    virtual VkSemaphore readySemaphore() const { return VK_NULL_HANDLE; }
    /// The depth image its pass draws (made with VK_IMAGE_USAGE_SAMPLED_BIT), a view of it, and the
    /// layout the target leaves it in after the pass: what RenderView::keepDepth reduces to tiles. None
    /// by default (such a target's depth is not kept).
    virtual VkImage depthImage() const { return VK_NULL_HANDLE; }
    virtual VkImageView depthView() const { return VK_NULL_HANDLE; }
    virtual VkImageLayout depthLayoutAfterPass() const { return VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL; }
};

} // namespace vdbclay::render
