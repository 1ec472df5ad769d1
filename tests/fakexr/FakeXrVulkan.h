// The fake runtime's Vulkan side (XR_KHR_vulkan_enable2): the application's instance and device made
// on its behalf, swapchain images allocated on the application's own device, and the readback of a
// submitted eye image.
#pragma once

#include <vulkan/vulkan.h>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <string>
#include <vector>

namespace fakexr {

VkResult createAppInstance(PFN_vkGetInstanceProcAddr getProcAddr, const VkInstanceCreateInfo& info, const VkAllocationCallbacks* allocator,
                           VkInstance* out);
/// The device a headset would be wired to: a discrete GPU first, else the first with a graphics queue.
VkPhysicalDevice choosePhysicalDevice(VkInstance instance);
VkResult createAppDevice(VkPhysicalDevice physical, const VkDeviceCreateInfo& info, const VkAllocationCallbacks* allocator, VkDevice* out);

/// The session's graphics binding, and a command pool of the fake's own on the application's queue family.
struct VulkanBinding {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queueFamily = 0;
    VkCommandPool pool = VK_NULL_HANDLE;
};
/// Throws std::runtime_error for a binding that names no device or queue.
VulkanBinding bindVulkan(VkInstance instance, VkPhysicalDevice physical, VkDevice device, uint32_t queueFamily, uint32_t queueIndex);
void unbindVulkan(VulkanBinding& binding);

struct SwapchainImages {
    std::vector<VkImage> images;
    std::vector<VkDeviceMemory> memory;
    VkFormat format = VK_FORMAT_UNDEFINED;
    bool depth = false;
};
/// `count` images as the create info asks, in the layout an application finds them in (colour or
/// depth attachment optimal). Throws std::runtime_error.
SwapchainImages createImages(const VulkanBinding& vulkan, const XrSwapchainCreateInfo& info, uint32_t count);
void releaseImages(const VulkanBinding& vulkan, SwapchainImages& images);

/// Writes the sub-image of image `index` as a binary PPM (RGB) at `path`. Throws std::runtime_error.
void captureImage(const VulkanBinding& vulkan, const SwapchainImages& images, uint32_t index, const XrSwapchainSubImage& sub,
                  const std::string& path);

} // namespace fakexr
