#include "render/SwapchainTarget.h"

#include "render/DrawnDepth.h"
#include "render/GpuMemory.h"
#include "render/OffscreenTarget.h"

#include <algorithm>

namespace vdbclay::render {

struct SwapchainTarget::Image : RenderTarget {
    SwapchainTarget* owner = nullptr;
    VkImageView view = VK_NULL_HANDLE;
    VkFramebuffer framebufferHandle = VK_NULL_HANDLE;
    VkSemaphore finished = VK_NULL_HANDLE; // the frame drawn into it is done: its present waits for it
    VkSemaphore acquired = VK_NULL_HANDLE; // of its last acquire: the frame's submission waits for it
    int width() const override { return owner->width_; }
    VkSemaphore finishedSemaphore() const override { return finished; }
    VkSemaphore readySemaphore() const override { return acquired; }
    int height() const override { return owner->height_; }
    VkRenderPass renderPass() const override { return owner->renderPass_; }
    VkFramebuffer framebuffer() const override { return framebufferHandle; }
    VkImage depthImage() const override { return owner->depthSampled_ ? owner->depth_ : VK_NULL_HANDLE; }
    VkImageView depthView() const override { return owner->depthSampled_ ? owner->depthView_ : VK_NULL_HANDLE; }
    void recordOverlay(VkCommandBuffer cmd) override
    {
        if (owner->overlay_) owner->overlay_(cmd);
    }
};

SwapchainTarget::SwapchainTarget(const VulkanContext& context, VkSurfaceKHR surface, int width, int height)
    : context_(context), surface_(surface), depthSampled_(depthSampleable(context))
{
    VkBool32 supported = VK_FALSE;
    check(vkGetPhysicalDeviceSurfaceSupportKHR(context.physicalDevice(), context.queueFamily(), surface, &supported),
          "vkGetPhysicalDeviceSurfaceSupportKHR");
    if (!supported) throw VulkanError("the Vulkan device cannot present to this window");
    uint32_t count = 0;
    check(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface, &count, nullptr), "vkGetPhysicalDeviceSurfaceFormatsKHR");
    std::vector<VkSurfaceFormatKHR> formats(count);
    check(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface, &count, formats.data()), "vkGetPhysicalDeviceSurfaceFormatsKHR");
    // The shaders write display-ready (sRGB-encoded) values, as into offscreen RGBA8 images: a UNORM format.
    for (VkFormat wanted : {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_UNORM})
        for (const VkSurfaceFormatKHR& f : formats)
            if (format_ == VK_FORMAT_UNDEFINED && f.format == wanted && f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) format_ = wanted;
    if (format_ == VK_FORMAT_UNDEFINED) throw VulkanError("the window offers no RGBA8 or BGRA8 UNORM surface format");
    renderPass_ = createRenderPass(context.device(), format_, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR);
    create(width, height);
}

SwapchainTarget::~SwapchainTarget()
{
    vkDeviceWaitIdle(context_.device());
    destroy();
    vkDestroyRenderPass(context_.device(), renderPass_, nullptr);
}

void SwapchainTarget::create(int width, int height)
{
    VkSurfaceCapabilitiesKHR caps{};
    check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(context_.physicalDevice(), surface_, &caps), "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
    VkExtent2D extent = caps.currentExtent;
    if (extent.width == UINT32_MAX) {
        extent.width = std::clamp(uint32_t(std::max(width, 1)), caps.minImageExtent.width, caps.maxImageExtent.width);
        extent.height = std::clamp(uint32_t(std::max(height, 1)), caps.minImageExtent.height, caps.maxImageExtent.height);
    }
    width_ = int(extent.width);
    height_ = int(extent.height);
    if (width_ == 0 || height_ == 0) return; // minimized
    VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
    info.surface = surface_;
    info.minImageCount = caps.maxImageCount ? std::min(caps.minImageCount + 1, caps.maxImageCount) : caps.minImageCount + 1;
    info.imageFormat = format_;
    info.imageColorSpace = VK_COLOR_SPACE_SRGB_NONLINEAR_KHR;
    info.imageExtent = extent;
    info.imageArrayLayers = 1;
    info.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
    info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.preTransform = caps.currentTransform;
    info.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
    info.presentMode = VK_PRESENT_MODE_FIFO_KHR; // always there; paces the editor to the display
    info.clipped = VK_TRUE;
    check(vkCreateSwapchainKHR(context_.device(), &info, nullptr, &swapchain_), "vkCreateSwapchainKHR");
    uint32_t count = 0;
    check(vkGetSwapchainImagesKHR(context_.device(), swapchain_, &count, nullptr), "vkGetSwapchainImagesKHR");
    std::vector<VkImage> images(count);
    check(vkGetSwapchainImagesKHR(context_.device(), swapchain_, &count, images.data()), "vkGetSwapchainImagesKHR");

    // Sampled too: the renderer reduces the frame's depth to tiles, the next selection's occluders.
    createImage2D(context_, int(extent.width), int(extent.height), kDepthFormat,
                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | (depthSampled_ ? VK_IMAGE_USAGE_SAMPLED_BIT : 0), VK_IMAGE_ASPECT_DEPTH_BIT,
                  depth_, depthMemory_, depthView_);

    for (VkImage image : images) {
        auto target = std::make_unique<Image>();
        target->owner = this;
        target->view = createImageView(context_.device(), image, format_, VK_IMAGE_ASPECT_COLOR_BIT);
        target->framebufferHandle = createFramebuffer(context_.device(), renderPass_, target->view, depthView_, extent.width, extent.height);
        VkSemaphoreCreateInfo semaphore{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        check(vkCreateSemaphore(context_.device(), &semaphore, nullptr, &target->finished), "vkCreateSemaphore");
        images_.push_back(std::move(target));
    }
    for (std::size_t i = 0; i <= images_.size(); ++i) {
        VkSemaphoreCreateInfo semaphore{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        VkSemaphore s = VK_NULL_HANDLE;
        check(vkCreateSemaphore(context_.device(), &semaphore, nullptr, &s), "vkCreateSemaphore");
        acquireSemaphores_.push_back(s);
    }
    nextAcquire_ = 0;
}

void SwapchainTarget::destroy()
{
    const VkDevice device = context_.device();
    for (auto& image : images_) {
        vkDestroyFramebuffer(device, image->framebufferHandle, nullptr);
        vkDestroyImageView(device, image->view, nullptr);
        vkDestroySemaphore(device, image->finished, nullptr);
    }
    images_.clear();
    for (VkSemaphore s : acquireSemaphores_) vkDestroySemaphore(device, s, nullptr);
    acquireSemaphores_.clear();
    if (depthView_) vkDestroyImageView(device, depthView_, nullptr);
    if (depth_) vkDestroyImage(device, depth_, nullptr);
    if (depthMemory_) vkFreeMemory(device, depthMemory_, nullptr);
    depthView_ = VK_NULL_HANDLE;
    depth_ = VK_NULL_HANDLE;
    depthMemory_ = VK_NULL_HANDLE;
    if (swapchain_) vkDestroySwapchainKHR(device, swapchain_, nullptr);
    swapchain_ = VK_NULL_HANDLE;
}

RenderTarget* SwapchainTarget::acquire()
{
    if (!swapchain_) return nullptr;
    const VkSemaphore ready = acquireSemaphores_[nextAcquire_];
    const VkResult r = vkAcquireNextImageKHR(context_.device(), swapchain_, UINT64_MAX, ready, VK_NULL_HANDLE, &current_);
    if (r == VK_ERROR_OUT_OF_DATE_KHR) return nullptr;
    if (r != VK_SUBOPTIMAL_KHR) check(r, "vkAcquireNextImageKHR");
    nextAcquire_ = (nextAcquire_ + 1) % acquireSemaphores_.size();
    images_[current_]->acquired = ready;
    return images_[current_].get();
}

bool SwapchainTarget::present()
{
    VkPresentInfoKHR info{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    info.swapchainCount = 1;
    info.pSwapchains = &swapchain_;
    info.waitSemaphoreCount = 1;
    info.pWaitSemaphores = &images_[current_]->finished;
    info.pImageIndices = &current_;
    const VkResult r = vkQueuePresentKHR(context_.queue(), &info);
    if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) return false;
    check(r, "vkQueuePresentKHR");
    return true;
}

void SwapchainTarget::resize(int width, int height)
{
    vkDeviceWaitIdle(context_.device());
    destroy();
    create(width, height);
}

} // namespace vdbclay::render
