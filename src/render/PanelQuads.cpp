#include "render/PanelQuads.h"

#include "render/GpuMemory.h"
#include "render/OffscreenTarget.h"
#include "render/Pipelines.h"

#include <stdexcept>

namespace vdbclay::render {

namespace {

const uint32_t kPanelVert[] =
#include "shaders/panel.vert.inc"
    ;
const uint32_t kPanelFrag[] =
#include "shaders/panel.frag.inc"
    ;

struct PushQuad {
    float corners[4][4];
    float uvRect[4];
};

} // namespace

PanelQuads::PanelQuads(const VulkanContext& context, int width, int height, VkRenderPass targetPass)
    : context_(context), width_(width), height_(height)
{
    if (width <= 0 || height <= 0) throw std::invalid_argument("a panel picture needs a positive size");
    const VkDevice device = context.device();
    try {
        createImage2D(context, width, height, kColourFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                      colour_, colourMemory_, colourView_);
        createImage2D(context, width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT, depth_,
                      depthMemory_, depthView_);
        picturePass_ = createRenderPass(device, kColourFormat, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        framebuffer_ = createFramebuffer(device, picturePass_, colourView_, depthView_, uint32_t(width), uint32_t(height));

        VkSamplerCreateInfo sampler{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
        sampler.magFilter = sampler.minFilter = VK_FILTER_LINEAR;
        sampler.addressModeU = sampler.addressModeV = sampler.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        sampler.maxLod = 0.0f;
        check(vkCreateSampler(device, &sampler, nullptr, &sampler_), "vkCreateSampler");
        VkDescriptorSetLayoutBinding binding{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr};
        VkDescriptorSetLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
        layoutInfo.bindingCount = 1;
        layoutInfo.pBindings = &binding;
        check(vkCreateDescriptorSetLayout(device, &layoutInfo, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");
        VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1};
        VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        poolInfo.maxSets = 1;
        poolInfo.poolSizeCount = 1;
        poolInfo.pPoolSizes = &size;
        check(vkCreateDescriptorPool(device, &poolInfo, nullptr, &pool_), "vkCreateDescriptorPool");
        VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        alloc.descriptorPool = pool_;
        alloc.descriptorSetCount = 1;
        alloc.pSetLayouts = &setLayout_;
        check(vkAllocateDescriptorSets(device, &alloc, &set_), "vkAllocateDescriptorSets");
        VkDescriptorImageInfo imageInfo{sampler_, colourView_, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
        VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        write.dstSet = set_;
        write.descriptorCount = 1;
        write.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        write.pImageInfo = &imageInfo;
        vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);

        VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(PushQuad)};
        VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        pl.setLayoutCount = 1;
        pl.pSetLayouts = &setLayout_;
        pl.pushConstantRangeCount = 1;
        pl.pPushConstantRanges = &push;
        check(vkCreatePipelineLayout(device, &pl, nullptr, &layout_), "vkCreatePipelineLayout");

        PipelineShape shape;
        shape.vert = shaderModule(device, kPanelVert, sizeof(kPanelVert));
        shape.frag = shaderModule(device, kPanelFrag, sizeof(kPanelFrag));
        shape.meshInput = false;
        shape.depthTest = false; // menus stay in sight over the scene
        shape.depthWrite = false;
        shape.blend = PipelineShape::Blend::Premultiplied; // as Dear ImGui leaves a cleared, transparent picture
        try {
            pipeline_ = createPipeline(device, targetPass, layout_, shape);
        } catch (...) {
            vkDestroyShaderModule(device, shape.vert, nullptr);
            vkDestroyShaderModule(device, shape.frag, nullptr);
            throw;
        }
        vkDestroyShaderModule(device, shape.vert, nullptr);
        vkDestroyShaderModule(device, shape.frag, nullptr);
    } catch (...) {
        release();
        throw;
    }
}

PanelQuads::~PanelQuads() { release(); }

void PanelQuads::release()
{
    const VkDevice device = context_.device();
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
    if (pool_) vkDestroyDescriptorPool(device, pool_, nullptr);
    if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
    if (sampler_) vkDestroySampler(device, sampler_, nullptr);
    if (framebuffer_) vkDestroyFramebuffer(device, framebuffer_, nullptr);
    if (picturePass_) vkDestroyRenderPass(device, picturePass_, nullptr);
    if (colourView_) vkDestroyImageView(device, colourView_, nullptr);
    if (depthView_) vkDestroyImageView(device, depthView_, nullptr);
    if (colour_) vkDestroyImage(device, colour_, nullptr);
    if (depth_) vkDestroyImage(device, depth_, nullptr);
    if (colourMemory_) vkFreeMemory(device, colourMemory_, nullptr);
    if (depthMemory_) vkFreeMemory(device, depthMemory_, nullptr);
    pipeline_ = VK_NULL_HANDLE;
    layout_ = VK_NULL_HANDLE;
    pool_ = VK_NULL_HANDLE;
    setLayout_ = VK_NULL_HANDLE;
    sampler_ = VK_NULL_HANDLE;
    framebuffer_ = VK_NULL_HANDLE;
    picturePass_ = VK_NULL_HANDLE;
    colourView_ = depthView_ = VK_NULL_HANDLE;
    colour_ = depth_ = VK_NULL_HANDLE;
    colourMemory_ = depthMemory_ = VK_NULL_HANDLE;
}

void PanelQuads::recordPicture(VkCommandBuffer cmd, const std::function<void(VkCommandBuffer)>& draw)
{
    // The last frame's quads read the picture before this pass writes it again.
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0, nullptr, 0, nullptr, 0,
                         nullptr);
    VkClearValue clears[2]{};
    clears[0].color = {{0.0f, 0.0f, 0.0f, 0.0f}};
    clears[1].depthStencil = {0.0f, 0};
    VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    begin.renderPass = picturePass_;
    begin.framebuffer = framebuffer_;
    begin.renderArea = {{0, 0}, {uint32_t(width_), uint32_t(height_)}};
    begin.clearValueCount = 2;
    begin.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    draw(cmd);
    vkCmdEndRenderPass(cmd);
    // Its pixels are read by the quads' fragment shaders next.
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0, 1, &barrier, 0, nullptr, 0,
                         nullptr);
}

void PanelQuads::recordQuads(VkCommandBuffer cmd, const std::vector<Quad>& quads, int targetWidth, int targetHeight) const
{
    if (quads.empty()) return;
    VkViewport viewport{0.0f, 0.0f, float(targetWidth), float(targetHeight), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {uint32_t(targetWidth), uint32_t(targetHeight)}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout_, 0, 1, &set_, 0, nullptr);
    for (const Quad& q : quads) {
        PushQuad push;
        for (int c = 0; c < 4; ++c)
            for (int i = 0; i < 4; ++i) push.corners[c][i] = q.clip[std::size_t(c)][std::size_t(i)];
        for (int i = 0; i < 4; ++i) push.uvRect[i] = q.uv[std::size_t(i)];
        vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof push, &push);
        vkCmdDraw(cmd, 6, 1, 0, 0);
    }
}

} // namespace vdbclay::render
