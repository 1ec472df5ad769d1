#include "render/DrawnDepth.h"

#include "render/GpuMemory.h"
#include "render/OffscreenTarget.h"
#include "render/Pipelines.h"
#include "render/RenderTarget.h"
#include "render/Renderer.h"
#include "render/VulkanContext.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace vdbclay::render {

namespace {

const uint32_t kDepthTilesComp[] =
#include "shaders/depthtiles.comp.inc"
    ;

struct RegionConstants {
    int32_t viewport[4];
    int32_t columns;
};

/// Reversed depth is near / distance: a tile's least depth is its farthest surface (none: infinity).
std::vector<float> farthestOf(const float* least, std::size_t count, const Camera& camera)
{
    const double near = usableNearPlane(camera);
    std::vector<float> farthest(count);
    for (std::size_t i = 0; i < count; ++i)
        farthest[i] = least[i] > 0.0f ? float(near / double(least[i])) : std::numeric_limits<float>::infinity();
    return farthest;
}

} // namespace

OccluderDepth occluderDepthOf(const std::vector<float>& depth, int width, int height, const Camera& camera, int tile)
{
    if (width <= 0 || height <= 0 || depth.size() != std::size_t(width) * std::size_t(height))
        throw std::invalid_argument("a depth image's pixels do not match its size");
    if (tile <= 0) throw std::invalid_argument("occluder tiles must be at least a pixel wide");
    const int columns = (width + tile - 1) / tile, rows = (height + tile - 1) / tile;
    std::vector<float> least(std::size_t(columns) * std::size_t(rows), std::numeric_limits<float>::infinity());
    for (int y = 0; y < height; ++y) {
        const float* row = depth.data() + std::size_t(y) * std::size_t(width);
        float* tiles = least.data() + std::size_t(y / tile) * std::size_t(columns);
        for (int x = 0; x < width; ++x) tiles[x / tile] = std::min(tiles[x / tile], row[x]);
    }
    return OccluderDepth(viewProjectionExact(camera, double(width) / double(height)), columns, rows,
                         farthestOf(least.data(), least.size(), camera));
}

bool depthSampleable(const VulkanContext& context)
{
    VkFormatProperties properties{};
    vkGetPhysicalDeviceFormatProperties(context.physicalDevice(), kDepthFormat, &properties);
    return (properties.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT) != 0;
}

struct DepthTileReducer::Slot {
    struct Reduction {
        VkDescriptorSet set = VK_NULL_HANDLE;
        std::unique_ptr<HostBuffer> tiles;
        Camera camera;
        std::array<int, 4> viewport{};
        int columns = 0, rows = 0;
    };
    std::vector<Reduction> reductions; // sets allocated as views first ask for them
    std::size_t recorded = 0;          // of `reductions`, since the last take
};

DepthTileReducer::DepthTileReducer(const VulkanContext& context, int slots) : context_(context)
{
    VkDevice device = context.device();
    try {
        VkDescriptorSetLayoutBinding bindings[2]{};
        bindings[0].binding = 0;
        bindings[0].descriptorType = VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE;
        bindings[0].descriptorCount = 1;
        bindings[0].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
        bindings[1].binding = 1;
        bindings[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        bindings[1].descriptorCount = 1;
        bindings[1].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
        VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
        setInfo.bindingCount = 2;
        setInfo.pBindings = bindings;
        check(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");
        VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(RegionConstants)};
        VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        layoutInfo.setLayoutCount = 1;
        layoutInfo.pSetLayouts = &setLayout_;
        layoutInfo.pushConstantRangeCount = 1;
        layoutInfo.pPushConstantRanges = &push;
        check(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &layout_), "vkCreatePipelineLayout");
        const VkShaderModule module = shaderModule(device, kDepthTilesComp, sizeof(kDepthTilesComp));
        VkComputePipelineCreateInfo pipelineInfo{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
        pipelineInfo.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
        pipelineInfo.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        pipelineInfo.stage.module = module;
        pipelineInfo.stage.pName = "main";
        pipelineInfo.layout = layout_;
        const VkResult made = vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipelineInfo, nullptr, &pipeline_);
        vkDestroyShaderModule(device, module, nullptr);
        check(made, "vkCreateComputePipelines");
        const uint32_t sets = uint32_t(slots * kMaxKeptViews);
        VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE, sets}, {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, sets}};
        VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        poolInfo.maxSets = sets;
        poolInfo.poolSizeCount = 2;
        poolInfo.pPoolSizes = sizes;
        check(vkCreateDescriptorPool(device, &poolInfo, nullptr, &pool_), "vkCreateDescriptorPool");
        for (int i = 0; i < slots; ++i) slots_.push_back(std::make_unique<Slot>());
    } catch (...) {
        release();
        throw;
    }
}

DepthTileReducer::~DepthTileReducer() { release(); }

void DepthTileReducer::release()
{
    VkDevice device = context_.device();
    slots_.clear(); // the sets go with the pool
    if (pool_) vkDestroyDescriptorPool(device, pool_, nullptr);
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
    if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
    pool_ = VK_NULL_HANDLE;
    pipeline_ = VK_NULL_HANDLE;
    layout_ = VK_NULL_HANDLE;
    setLayout_ = VK_NULL_HANDLE;
}

bool DepthTileReducer::record(VkCommandBuffer cmd, std::size_t index, const RenderTarget& target, const std::array<int, 4>& viewport,
                              const Camera& camera)
{
    const VkImage image = target.depthImage();
    const VkImageView view = target.depthView();
    if (!image || !view || viewport[2] <= 0 || viewport[3] <= 0) return false;
    Slot& frame = *slots_.at(index);
    if (frame.recorded == frame.reductions.size()) {
        if (frame.reductions.size() == std::size_t(kMaxKeptViews)) return false;
        Slot::Reduction added;
        VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        alloc.descriptorPool = pool_;
        alloc.descriptorSetCount = 1;
        alloc.pSetLayouts = &setLayout_;
        check(vkAllocateDescriptorSets(context_.device(), &alloc, &added.set), "vkAllocateDescriptorSets");
        frame.reductions.push_back(std::move(added));
    }
    Slot::Reduction& slot = frame.reductions[frame.recorded];
    slot.columns = (viewport[2] + kDepthTile - 1) / kDepthTile;
    slot.rows = (viewport[3] + kDepthTile - 1) / kDepthTile;
    const VkDeviceSize bytes = VkDeviceSize(slot.columns) * VkDeviceSize(slot.rows) * sizeof(float);
    if (!slot.tiles || slot.tiles->size() < bytes) slot.tiles = std::make_unique<HostBuffer>(context_, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    // The slot's last frame is done (the caller's fence): its set may be written again.
    VkDescriptorImageInfo imageInfo{VK_NULL_HANDLE, view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkDescriptorBufferInfo bufferInfo{slot.tiles->buffer(), 0, bytes};
    VkWriteDescriptorSet writes[2]{};
    for (VkWriteDescriptorSet& w : writes) {
        w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        w.dstSet = slot.set;
        w.descriptorCount = 1;
    }
    writes[0].dstBinding = 0;
    writes[0].descriptorType = VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE;
    writes[0].pImageInfo = &imageInfo;
    writes[1].dstBinding = 1;
    writes[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[1].pBufferInfo = &bufferInfo;
    vkUpdateDescriptorSets(context_.device(), 2, writes, 0, nullptr);

    // The pass's depth writes (and a readback's copy) before the shader reads it.
    VkImageMemoryBarrier toRead{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    toRead.srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    toRead.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    toRead.oldLayout = target.depthLayoutAfterPass();
    toRead.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    toRead.srcQueueFamilyIndex = toRead.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    toRead.image = image;
    toRead.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0,
                         nullptr, 0, nullptr, 1, &toRead);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &slot.set, 0, nullptr);
    const RegionConstants region{{viewport[0], viewport[1], viewport[2], viewport[3]}, slot.columns};
    vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof region, &region);
    vkCmdDispatch(cmd, uint32_t(slot.columns), uint32_t(slot.rows), 1);
    // The tiles to the host; the image back in the layout the target leaves it in (a headset's runtime
    // reads its depth images in that layout), written by a next pass only once the shader has read it.
    VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toHost.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    VkImageMemoryBarrier back = toRead;
    back.srcAccessMask = VK_ACCESS_SHADER_READ_BIT;
    back.dstAccessMask = 0;
    back.oldLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    back.newLayout = target.depthLayoutAfterPass();
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT |
                             VK_PIPELINE_STAGE_TRANSFER_BIT,
                         0, 1, &toHost, 0, nullptr, 1, &back);
    ++frame.recorded;
    slot.camera = camera;
    slot.viewport = viewport;
    return true;
}

std::shared_ptr<const OccluderDepth> DepthTileReducer::take(std::size_t index)
{
    Slot& frame = *slots_.at(index);
    const auto depthOf = [](const Slot::Reduction& r) {
        const auto* least = reinterpret_cast<const float*>(r.tiles->data());
        const std::size_t count = std::size_t(r.columns) * std::size_t(r.rows);
        return OccluderDepth(viewProjectionExact(r.camera, double(r.viewport[2]) / double(r.viewport[3])), r.columns, r.rows,
                             farthestOf(least, count, r.camera));
    };
    if (frame.recorded == 0) return nullptr;
    OccluderDepth depth = depthOf(frame.reductions[0]);
    for (std::size_t i = 1; i < frame.recorded; ++i) depth.alsoSeenFrom(depthOf(frame.reductions[i]));
    frame.recorded = 0;
    return std::make_shared<const OccluderDepth>(std::move(depth));
}

} // namespace vdbclay::render
