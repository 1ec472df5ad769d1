#include "FakeXrVulkan.h"

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace fakexr {

namespace {

void check(VkResult r, const char* what)
{
    if (r != VK_SUCCESS) throw std::runtime_error(std::string(what) + " failed (" + std::to_string(int(r)) + ")");
}

bool isDepth(VkFormat f)
{
    return f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D16_UNORM || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT;
}

uint32_t memoryType(VkPhysicalDevice physical, uint32_t bits, VkMemoryPropertyFlags flags)
{
    VkPhysicalDeviceMemoryProperties props;
    vkGetPhysicalDeviceMemoryProperties(physical, &props);
    for (uint32_t i = 0; i < props.memoryTypeCount; ++i)
        if ((bits & (1u << i)) && (props.memoryTypes[i].propertyFlags & flags) == flags) return i;
    throw std::runtime_error("no suitable memory type");
}

/// Records with `record` into a one-time command buffer on the application's queue and waits for it.
template <typename Record>
void submitAndWait(const VulkanBinding& v, Record record)
{
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = v.pool;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    VkCommandBuffer cmd;
    check(vkAllocateCommandBuffers(v.device, &alloc, &cmd), "vkAllocateCommandBuffers");
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    vkBeginCommandBuffer(cmd, &begin);
    record(cmd);
    vkEndCommandBuffer(cmd);
    VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    check(vkCreateFence(v.device, &fenceInfo, nullptr, &fence), "vkCreateFence");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    const VkResult r = vkQueueSubmit(v.queue, 1, &submit, fence);
    if (r == VK_SUCCESS) vkWaitForFences(v.device, 1, &fence, VK_TRUE, UINT64_MAX);
    vkDestroyFence(v.device, fence, nullptr);
    vkFreeCommandBuffers(v.device, v.pool, 1, &cmd);
    check(r, "vkQueueSubmit");
}

VkImageLayout attachmentLayout(bool depth)
{
    return depth ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
}

} // namespace

VkResult createAppInstance(PFN_vkGetInstanceProcAddr getProcAddr, const VkInstanceCreateInfo& info, const VkAllocationCallbacks* allocator,
                           VkInstance* out)
{
    auto create = reinterpret_cast<PFN_vkCreateInstance>(getProcAddr(VK_NULL_HANDLE, "vkCreateInstance"));
    if (!create) return VK_ERROR_INITIALIZATION_FAILED;
    return create(&info, allocator, out);
}

VkPhysicalDevice choosePhysicalDevice(VkInstance instance)
{
    uint32_t count = 0;
    vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::vector<VkPhysicalDevice> devices(count);
    vkEnumeratePhysicalDevices(instance, &count, devices.data());
    VkPhysicalDevice best = VK_NULL_HANDLE;
    for (VkPhysicalDevice d : devices) {
        uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(d, &families, nullptr);
        std::vector<VkQueueFamilyProperties> props(families);
        vkGetPhysicalDeviceQueueFamilyProperties(d, &families, props.data());
        bool graphics = false;
        for (const auto& f : props) graphics = graphics || (f.queueFlags & VK_QUEUE_GRAPHICS_BIT);
        if (!graphics) continue;
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(d, &p);
        if (!best || p.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU) best = d;
    }
    return best;
}

VkResult createAppDevice(VkPhysicalDevice physical, const VkDeviceCreateInfo& info, const VkAllocationCallbacks* allocator, VkDevice* out)
{
    return vkCreateDevice(physical, &info, allocator, out);
}

VulkanBinding bindVulkan(VkInstance instance, VkPhysicalDevice physical, VkDevice device, uint32_t queueFamily, uint32_t queueIndex)
{
    if (!instance || !physical || !device) throw std::runtime_error("the graphics binding names no Vulkan instance, device or physical device");
    VulkanBinding v;
    v.instance = instance;
    v.physical = physical;
    v.device = device;
    v.queueFamily = queueFamily;
    vkGetDeviceQueue(device, queueFamily, queueIndex, &v.queue);
    if (!v.queue) throw std::runtime_error("the graphics binding's queue does not exist");
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.queueFamilyIndex = queueFamily;
    pool.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    check(vkCreateCommandPool(device, &pool, nullptr, &v.pool), "vkCreateCommandPool");
    return v;
}

void unbindVulkan(VulkanBinding& v)
{
    if (v.pool) vkDestroyCommandPool(v.device, v.pool, nullptr);
    v.pool = VK_NULL_HANDLE;
}

SwapchainImages createImages(const VulkanBinding& v, const XrSwapchainCreateInfo& info, uint32_t count)
{
    SwapchainImages out;
    out.format = VkFormat(info.format);
    out.depth = isDepth(out.format);
    VkImageUsageFlags usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT; // the runtime reads what it composes
    if (info.usageFlags & XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT) usage |= VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
    if (info.usageFlags & XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT) usage |= VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
    if (info.usageFlags & XR_SWAPCHAIN_USAGE_SAMPLED_BIT) usage |= VK_IMAGE_USAGE_SAMPLED_BIT;
    if (info.usageFlags & XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT) usage |= VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    if (info.usageFlags & XR_SWAPCHAIN_USAGE_UNORDERED_ACCESS_BIT) usage |= VK_IMAGE_USAGE_STORAGE_BIT;
    if (info.usageFlags & XR_SWAPCHAIN_USAGE_INPUT_ATTACHMENT_BIT_MND) usage |= VK_IMAGE_USAGE_INPUT_ATTACHMENT_BIT;
    if (out.depth) usage |= VK_IMAGE_USAGE_SAMPLED_BIT;
    try {
        for (uint32_t i = 0; i < count; ++i) {
            VkImageCreateInfo image{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
            image.flags = (info.usageFlags & XR_SWAPCHAIN_USAGE_MUTABLE_FORMAT_BIT) ? VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT : 0;
            image.imageType = VK_IMAGE_TYPE_2D;
            image.format = out.format;
            image.extent = {info.width, info.height, 1};
            image.mipLevels = info.mipCount;
            image.arrayLayers = info.arraySize;
            image.samples = VK_SAMPLE_COUNT_1_BIT;
            image.tiling = VK_IMAGE_TILING_OPTIMAL;
            image.usage = usage;
            image.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
            image.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
            VkImage img;
            check(vkCreateImage(v.device, &image, nullptr, &img), "vkCreateImage");
            out.images.push_back(img);
            VkMemoryRequirements req;
            vkGetImageMemoryRequirements(v.device, img, &req);
            VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
            alloc.allocationSize = req.size;
            alloc.memoryTypeIndex = memoryType(v.physical, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
            VkDeviceMemory mem;
            check(vkAllocateMemory(v.device, &alloc, nullptr, &mem), "vkAllocateMemory");
            out.memory.push_back(mem);
            check(vkBindImageMemory(v.device, img, mem, 0), "vkBindImageMemory");
        }
        // The application finds its images in the attachment layout (it may render with initialLayout
        // UNDEFINED or with the attachment layout).
        submitAndWait(v, [&](VkCommandBuffer cmd) {
            for (VkImage img : out.images) {
                VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
                b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
                b.newLayout = attachmentLayout(out.depth);
                b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
                b.image = img;
                b.subresourceRange = {VkImageAspectFlags(out.depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT), 0, info.mipCount, 0,
                                      info.arraySize};
                b.dstAccessMask = out.depth ? VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT : VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
                vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
            }
        });
    } catch (...) {
        releaseImages(v, out);
        throw;
    }
    return out;
}

void releaseImages(const VulkanBinding& v, SwapchainImages& images)
{
    if (!images.images.empty()) vkQueueWaitIdle(v.queue);
    for (VkImage i : images.images) vkDestroyImage(v.device, i, nullptr);
    for (VkDeviceMemory m : images.memory) vkFreeMemory(v.device, m, nullptr);
    images.images.clear();
    images.memory.clear();
}

void captureImage(const VulkanBinding& v, const SwapchainImages& images, uint32_t index, const XrSwapchainSubImage& sub, const std::string& path)
{
    if (images.depth) throw std::runtime_error("only colour images are captured");
    const uint32_t w = uint32_t(sub.imageRect.extent.width), h = uint32_t(sub.imageRect.extent.height);
    VkBufferCreateInfo bufferInfo{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bufferInfo.size = VkDeviceSize(w) * h * 4;
    bufferInfo.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    VkBuffer buffer;
    check(vkCreateBuffer(v.device, &bufferInfo, nullptr, &buffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(v.device, buffer, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = memoryType(v.physical, req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    VkDeviceMemory mem;
    check(vkAllocateMemory(v.device, &alloc, nullptr, &mem), "vkAllocateMemory");
    vkBindBufferMemory(v.device, buffer, mem, 0);
    const VkImage image = images.images.at(index);
    submitAndWait(v, [&](VkCommandBuffer cmd) {
        VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.oldLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
        b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        b.image = image;
        b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, sub.imageArrayIndex, 1};
        b.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
        VkBufferImageCopy copy{};
        copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, sub.imageArrayIndex, 1};
        copy.imageOffset = {sub.imageRect.offset.x, sub.imageRect.offset.y, 0};
        copy.imageExtent = {w, h, 1};
        vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer, 1, &copy);
        b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        b.newLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
        b.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        b.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
    });
    void* mapped = nullptr;
    vkMapMemory(v.device, mem, 0, bufferInfo.size, 0, &mapped);
    const bool bgr = images.format == VK_FORMAT_B8G8R8A8_SRGB || images.format == VK_FORMAT_B8G8R8A8_UNORM;
    std::vector<uint8_t> rgb(std::size_t(w) * h * 3);
    const auto* px = static_cast<const uint8_t*>(mapped);
    for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
        rgb[i * 3 + 0] = px[i * 4 + (bgr ? 2 : 0)];
        rgb[i * 3 + 1] = px[i * 4 + 1];
        rgb[i * 3 + 2] = px[i * 4 + (bgr ? 0 : 2)];
    }
    vkUnmapMemory(v.device, mem);
    vkDestroyBuffer(v.device, buffer, nullptr);
    vkFreeMemory(v.device, mem, nullptr);
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error("cannot write " + path);
    std::fprintf(f, "P6\n%u %u\n255\n", w, h);
    std::fwrite(rgb.data(), 1, rgb.size(), f);
    std::fclose(f);
}

} // namespace fakexr
