#include "render/GpuMemory.h"

#include <algorithm>

namespace vdbclay::render {

namespace {
VkDeviceSize alignUp(VkDeviceSize v, VkDeviceSize a) { return (v + a - 1) / a * a; }
} // namespace

GpuHeap::GpuHeap(const VulkanContext& context, VkMemoryPropertyFlags properties, VkDeviceSize blockSize)
    : context_(context), properties_(properties), blockSize_(blockSize)
{
}

GpuHeap::~GpuHeap()
{
    for (auto& b : blocks_) vkFreeMemory(context_.device(), b.memory, nullptr);
}

GpuAllocation GpuHeap::allocate(const VkMemoryRequirements& req)
{
    const VkDeviceSize alignment = std::max<VkDeviceSize>(req.alignment, 16);
    for (uint32_t bi = 0; bi < blocks_.size(); ++bi) {
        Block& b = blocks_[bi];
        if (!(req.memoryTypeBits & (1u << b.memoryType))) continue;
        for (auto it = b.free.begin(); it != b.free.end(); ++it) {
            const VkDeviceSize start = alignUp(it->first, alignment);
            const VkDeviceSize end = it->first + it->second;
            if (start + req.size > end) continue;
            const VkDeviceSize freeStart = it->first;
            b.free.erase(it);
            if (start > freeStart) b.free.emplace(freeStart, start - freeStart);
            if (end > start + req.size) b.free.emplace(start + req.size, end - (start + req.size));
            used_ += req.size;
            return {b.memory, start, req.size, bi};
        }
    }
    Block b;
    b.size = std::max(blockSize_, alignUp(req.size, 1 << 16));
    b.memoryType = context_.memoryType(req.memoryTypeBits, properties_);
    VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    info.allocationSize = b.size;
    info.memoryTypeIndex = b.memoryType;
    check(vkAllocateMemory(context_.device(), &info, nullptr, &b.memory), "vkAllocateMemory");
    if (req.size < b.size) b.free.emplace(req.size, b.size - req.size);
    reserved_ += b.size;
    used_ += req.size;
    blocks_.push_back(std::move(b));
    return {blocks_.back().memory, 0, req.size, uint32_t(blocks_.size() - 1)};
}

void GpuHeap::free(const GpuAllocation& a)
{
    if (!a.memory || a.block >= blocks_.size()) return;
    auto& list = blocks_[a.block].free;
    auto [it, inserted] = list.emplace(a.offset, a.size);
    if (!inserted) return; // freed twice: ignore rather than corrupt the list
    used_ -= a.size;
    auto next = std::next(it);
    if (next != list.end() && it->first + it->second == next->first) {
        it->second += next->second;
        list.erase(next);
    }
    if (it != list.begin()) {
        auto prev = std::prev(it);
        if (prev->first + prev->second == it->first) {
            prev->second += it->second;
            list.erase(it);
        }
    }
}

HostBuffer::HostBuffer(const VulkanContext& context, VkDeviceSize size, VkBufferUsageFlags usage)
    : context_(context), size_(size)
{
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = size;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(vkCreateBuffer(context.device(), &info, nullptr, &buffer_), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(context.device(), buffer_, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = context.memoryType(req.memoryTypeBits,
                                               VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    VkResult r = vkAllocateMemory(context.device(), &alloc, nullptr, &memory_);
    if (r != VK_SUCCESS) {
        vkDestroyBuffer(context.device(), buffer_, nullptr);
        check(r, "vkAllocateMemory");
    }
    vkBindBufferMemory(context.device(), buffer_, memory_, 0);
    void* mapped = nullptr;
    check(vkMapMemory(context.device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    data_ = static_cast<uint8_t*>(mapped);
}

HostBuffer::~HostBuffer()
{
    if (memory_) vkFreeMemory(context_.device(), memory_, nullptr);
    if (buffer_) vkDestroyBuffer(context_.device(), buffer_, nullptr);
}

void createDeviceImage(const VulkanContext& context, const VkImageCreateInfo& info, VkImage& image, VkDeviceMemory& memory)
{
    check(vkCreateImage(context.device(), &info, nullptr, &image), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(context.device(), image, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = context.memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    check(vkAllocateMemory(context.device(), &alloc, nullptr, &memory), "vkAllocateMemory");
    check(vkBindImageMemory(context.device(), image, memory, 0), "vkBindImageMemory");
}

VkImageView createImageView(VkDevice device, VkImage image, VkFormat format, VkImageAspectFlags aspect)
{
    VkImageViewCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    info.image = image;
    info.viewType = VK_IMAGE_VIEW_TYPE_2D;
    info.format = format;
    info.subresourceRange = {aspect, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    check(vkCreateImageView(device, &info, nullptr, &view), "vkCreateImageView");
    return view;
}

void createImage2D(const VulkanContext& context, int w, int h, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect,
                   VkImage& image, VkDeviceMemory& memory, VkImageView& view)
{
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {uint32_t(w), uint32_t(h), 1};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    createDeviceImage(context, info, image, memory);
    view = createImageView(context.device(), image, format, aspect);
}

} // namespace vdbclay::render
