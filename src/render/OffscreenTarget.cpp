#include "render/OffscreenTarget.h"

#include "render/DrawnDepth.h"

#include <cstring>
#include <string>

namespace vdbclay::render {

VkRenderPass createRenderPass(VkDevice device, VkFormat colourFormat, VkImageLayout finalLayout)
{
    VkAttachmentDescription attachments[2]{};
    attachments[0].format = colourFormat;
    attachments[0].samples = VK_SAMPLE_COUNT_1_BIT;
    attachments[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    attachments[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    attachments[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    attachments[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    attachments[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    attachments[0].finalLayout = finalLayout;
    attachments[1] = attachments[0];
    attachments[1].format = kDepthFormat;
    attachments[1].finalLayout = finalLayout == VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
                                     ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
                                     : VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    VkAttachmentReference colourRef{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depthRef{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &colourRef;
    subpass.pDepthStencilAttachment = &depthRef;
    // Earlier frames' reads of the images (readback, presentation, the depth's reduction to tiles) and
    // their writes (frames in flight share a depth image) finish before this pass writes them; this
    // pass's writes finish before a readback copies them.
    VkSubpassDependency deps[2]{};
    deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    deps[0].dstSubpass = 0;
    deps[0].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                           VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT |
                           VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                           VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    deps[0].srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
    deps[1].srcSubpass = 0;
    deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
    deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
    VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    info.attachmentCount = 2;
    info.pAttachments = attachments;
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = 2;
    info.pDependencies = deps;
    VkRenderPass pass = VK_NULL_HANDLE;
    check(vkCreateRenderPass(device, &info, nullptr, &pass), "vkCreateRenderPass");
    return pass;
}


VkFramebuffer createFramebuffer(VkDevice device, VkRenderPass pass, VkImageView colour, VkImageView depth, uint32_t width, uint32_t height)
{
    VkImageView attachments[2] = {colour, depth};
    VkFramebufferCreateInfo info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    info.renderPass = pass;
    info.attachmentCount = 2;
    info.pAttachments = attachments;
    info.width = width;
    info.height = height;
    info.layers = 1;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    check(vkCreateFramebuffer(device, &info, nullptr, &framebuffer), "vkCreateFramebuffer");
    return framebuffer;
}

OffscreenTarget::OffscreenTarget(const VulkanContext& context, int width, int height)
    : context_(context), width_(width), height_(height), depthSampled_(depthSampleable(context))
{
    const int limit = int(context.properties().limits.maxImageDimension2D);
    if (width < 1 || height < 1 || width > limit || height > limit)
        throw std::invalid_argument("image size " + std::to_string(width) + "x" + std::to_string(height) +
                                    " is outside 1 .. " + std::to_string(limit) + " (the device's limit)");
    try {
        createImage2D(context, width, height, kColourFormat,
                    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                    colour_, colourMemory_, colourView_);
        createImage2D(context, width, height, kDepthFormat,
                    VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                        (depthSampled_ ? VK_IMAGE_USAGE_SAMPLED_BIT : 0),
                    VK_IMAGE_ASPECT_DEPTH_BIT, depth_, depthMemory_, depthView_);
        renderPass_ = createRenderPass(context.device(), kColourFormat, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
        framebuffer_ = createFramebuffer(context.device(), renderPass_, colourView_, depthView_, uint32_t(width), uint32_t(height));
        const VkDeviceSize pixels = VkDeviceSize(width) * VkDeviceSize(height);
        colourReadback_ = std::make_unique<HostBuffer>(context, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
        depthReadback_ = std::make_unique<HostBuffer>(context, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
        std::memset(colourReadback_->data(), 0, pixels * 4);
        std::memset(depthReadback_->data(), 0, pixels * 4);
    } catch (...) {
        release();
        throw;
    }
}

OffscreenTarget::~OffscreenTarget() { release(); }

void OffscreenTarget::release()
{
    VkDevice d = context_.device();
    colourReadback_.reset();
    depthReadback_.reset();
    if (framebuffer_) vkDestroyFramebuffer(d, framebuffer_, nullptr);
    if (renderPass_) vkDestroyRenderPass(d, renderPass_, nullptr);
    if (colourView_) vkDestroyImageView(d, colourView_, nullptr);
    if (depthView_) vkDestroyImageView(d, depthView_, nullptr);
    if (colour_) vkDestroyImage(d, colour_, nullptr);
    if (depth_) vkDestroyImage(d, depth_, nullptr);
    if (colourMemory_) vkFreeMemory(d, colourMemory_, nullptr);
    if (depthMemory_) vkFreeMemory(d, depthMemory_, nullptr);
    framebuffer_ = VK_NULL_HANDLE;
    renderPass_ = VK_NULL_HANDLE;
    colourView_ = depthView_ = VK_NULL_HANDLE;
    colour_ = depth_ = VK_NULL_HANDLE;
    colourMemory_ = depthMemory_ = VK_NULL_HANDLE;
}

void OffscreenTarget::recordReadback(VkCommandBuffer cmd) const
{
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {uint32_t(width_), uint32_t(height_), 1};
    vkCmdCopyImageToBuffer(cmd, colour_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, colourReadback_->buffer(), 1, &region);
    region.imageSubresource.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
    vkCmdCopyImageToBuffer(cmd, depth_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, depthReadback_->buffer(), 1, &region);
    VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toHost.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0, nullptr, 0,
                         nullptr);
}

Image OffscreenTarget::colour() const
{
    Image image;
    image.width = width_;
    image.height = height_;
    image.rgba.assign(colourReadback_->data(), colourReadback_->data() + colourReadback_->size());
    return image;
}

std::vector<float> OffscreenTarget::depth() const
{
    std::vector<float> d(std::size_t(width_) * std::size_t(height_));
    std::memcpy(d.data(), depthReadback_->data(), d.size() * sizeof(float));
    return d;
}

} // namespace vdbclay::render
