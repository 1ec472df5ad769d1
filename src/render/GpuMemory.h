// Device memory for mesh chunks: a few large blocks sub-allocated first-fit (drivers limit the number of
// allocations to a few thousand, a scene has more chunks), and host-visible buffers for staging,
// uniforms and readback.
#pragma once

#include "render/VulkanContext.h"

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

namespace vdbclay::render {

struct GpuAllocation {
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkDeviceSize offset = 0;
    VkDeviceSize size = 0;
    uint32_t block = 0;
};

class GpuHeap {
public:
    GpuHeap(const VulkanContext& context, VkMemoryPropertyFlags properties, VkDeviceSize blockSize = 32ull << 20);
    ~GpuHeap();
    GpuHeap(const GpuHeap&) = delete;
    GpuHeap& operator=(const GpuHeap&) = delete;

    /// Room for `requirements`; a new block when no block has it.
    GpuAllocation allocate(const VkMemoryRequirements& requirements);
    void free(const GpuAllocation& allocation);

    VkDeviceSize usedBytes() const { return used_; }
    VkDeviceSize reservedBytes() const { return reserved_; }
    std::size_t blockCount() const { return blocks_.size(); }
    VkDeviceMemory blockMemory(uint32_t block) const { return blocks_[block].memory; }
    VkDeviceSize blockSize(uint32_t block) const { return blocks_[block].size; }

private:
    struct Block {
        VkDeviceMemory memory = VK_NULL_HANDLE;
        VkDeviceSize size = 0;
        uint32_t memoryType = 0;
        std::map<VkDeviceSize, VkDeviceSize> free; // offset -> size, coalesced
    };
    const VulkanContext& context_;
    VkMemoryPropertyFlags properties_;
    VkDeviceSize blockSize_;
    std::vector<Block> blocks_;
    VkDeviceSize used_ = 0, reserved_ = 0;
};

/// Creates the image `info` describes in device-local memory of its own, bound to it.
void createDeviceImage(const VulkanContext& context, const VkImageCreateInfo& info, VkImage& image, VkDeviceMemory& memory);
/// A 2D view of one level and layer of `image`.
VkImageView createImageView(VkDevice device, VkImage image, VkFormat format, VkImageAspectFlags aspect);
/// A 2D image of `w` x `h` (one level, one layer, optimal tiling) in device-local memory, and a view of it.
void createImage2D(const VulkanContext& context, int w, int h, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect,
                   VkImage& image, VkDeviceMemory& memory, VkImageView& view);

/// A buffer in host-visible, coherent memory, mapped for its whole life.
class HostBuffer {
public:
    HostBuffer(const VulkanContext& context, VkDeviceSize size, VkBufferUsageFlags usage);
    ~HostBuffer();
    HostBuffer(const HostBuffer&) = delete;
    HostBuffer& operator=(const HostBuffer&) = delete;

    VkBuffer buffer() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    uint8_t* data() const { return data_; }

private:
    const VulkanContext& context_;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceSize size_ = 0;
    uint8_t* data_ = nullptr;
};

} // namespace vdbclay::render
