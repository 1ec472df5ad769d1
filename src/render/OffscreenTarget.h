// A render target in device memory (colour RGBA8 + 32-bit depth) whose pixels can be read back: what
// `vdbclay render`, thumbnails and the tests draw into. The editor's swapchain images and the headset's
// eye images are targets of the same render pass shape.
#pragma once

#include "render/GpuMemory.h"
#include "render/RenderTarget.h"
#include "render/VulkanContext.h"

#include <cstdint>
#include <vector>

namespace vdbclay::render {

constexpr VkFormat kColourFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

/// An RGBA8 picture, rows top to bottom.
struct Image {
    int width = 0, height = 0;
    std::vector<uint8_t> rgba; // width * height * 4
    const uint8_t* pixel(int x, int y) const { return &rgba[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4]; }
};

/// The render pass every target uses: one colour attachment of `colourFormat` left in `finalLayout`,
/// and depth. Cleared on load.
VkRenderPass createRenderPass(VkDevice device, VkFormat colourFormat, VkImageLayout finalLayout);

/// A framebuffer of createRenderPass's shape over a colour and a depth view of `width` x `height`.
VkFramebuffer createFramebuffer(VkDevice device, VkRenderPass pass, VkImageView colour, VkImageView depth, uint32_t width, uint32_t height);

/// The depth of a pixel nothing was drawn on (the renderer's depth is reversed: 0 is infinitely far).
constexpr float kNothingDrawn = 0.0f;

class OffscreenTarget : public RenderTarget {
public:
    /// Throws std::invalid_argument for sizes outside 1 .. the device's image limit.
    OffscreenTarget(const VulkanContext& context, int width, int height);
    ~OffscreenTarget();
    OffscreenTarget(const OffscreenTarget&) = delete;
    OffscreenTarget& operator=(const OffscreenTarget&) = delete;

    int width() const override { return width_; }
    int height() const override { return height_; }
    VkRenderPass renderPass() const override { return renderPass_; }
    VkFramebuffer framebuffer() const override { return framebuffer_; }
    VkImage colourImage() const { return colour_; }
    VkImage depthImage() const override { return depthSampled_ ? depth_ : VK_NULL_HANDLE; }
    VkImageView depthView() const override { return depthSampled_ ? depthView_ : VK_NULL_HANDLE; }
    VkImageLayout depthLayoutAfterPass() const override { return VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL; }

    /// Records the copy of the colour and depth images into host memory (after the render pass).
    void recordReadback(VkCommandBuffer cmd) const;
    void recordAfterPass(VkCommandBuffer cmd) const override { recordReadback(cmd); }
    bool readsBack() const override { return true; }
    /// The pixels copied by the last readback that completed.
    Image colour() const;
    /// Depth per pixel, reversed (1 at the near plane, falling towards 0 with distance, exactly
    /// kNothingDrawn where nothing was drawn), rows top to bottom.
    std::vector<float> depth() const;

private:
    void release();

    const VulkanContext& context_;
    int width_, height_;
    bool depthSampled_; // made sampled (depthSampleable): RenderView::keepDepth reads it
    VkImage colour_ = VK_NULL_HANDLE, depth_ = VK_NULL_HANDLE;
    VkDeviceMemory colourMemory_ = VK_NULL_HANDLE, depthMemory_ = VK_NULL_HANDLE;
    VkImageView colourView_ = VK_NULL_HANDLE, depthView_ = VK_NULL_HANDLE;
    VkRenderPass renderPass_ = VK_NULL_HANDLE;
    VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
    std::unique_ptr<HostBuffer> colourReadback_, depthReadback_;
};

} // namespace vdbclay::render
