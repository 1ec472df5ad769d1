// The Vulkan instance, the device the renderer draws on and its one graphics queue. Optionally with
// the Khronos validation layer, whose messages are counted (tests require zero) and printed.
#pragma once

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay::render {

/// No Vulkan loader, instance or device on this machine: the caller reports one line and exits 1.
struct NoVulkanDevice : std::runtime_error {
    using std::runtime_error::runtime_error;
};
/// A Vulkan call failed.
struct VulkanError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Throws VulkanError naming the call and the result unless `result` is VK_SUCCESS.
void check(VkResult result, const char* what);
const char* resultName(VkResult result);

struct ContextOptions {
    /// Enable VK_LAYER_KHRONOS_validation (also when the environment sets VDBCLAY_VULKAN_VALIDATION=1).
    bool validation = false;
    /// Instance extensions a window system needs (GLFW's), and whether to enable the swapchain.
    std::vector<const char*> instanceExtensions;
    bool swapchain = false;
    /// Where a headset's runtime makes the instance and the device and names the physical device it is
    /// wired to (XR_KHR_vulkan_enable2): each returns the handle or throws. Absent: made here.
    struct Creation {
        std::function<VkInstance(const VkInstanceCreateInfo&)> instance;
        std::function<VkPhysicalDevice(VkInstance)> physicalDevice;
        std::function<VkDevice(VkPhysicalDevice, const VkDeviceCreateInfo&)> device;
    };
    std::optional<Creation> creation;
};

class VulkanContext {
public:
    /// Throws NoVulkanDevice when there is no usable device, VulkanError on other failures.
    explicit VulkanContext(const ContextOptions& options = {});
    ~VulkanContext();
    VulkanContext(const VulkanContext&) = delete;
    VulkanContext& operator=(const VulkanContext&) = delete;

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physicalDevice() const { return physical_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    uint32_t queueFamily() const { return queueFamily_; }
    const VkPhysicalDeviceProperties& properties() const { return properties_; }
    std::string deviceName() const { return properties_.deviceName; }
    bool supportsWireframe() const { return fillModeNonSolid_; }
    /// Whether one indirect draw call may draw many chunks (multiDrawIndirect, enabled where offered).
    bool supportsMultiDrawIndirect() const { return multiDrawIndirect_; }
    /// Nanoseconds per timestamp tick, 0 when the queue has no timestamps.
    double timestampPeriodNs() const { return timestampPeriod_; }

    /// A memory type index with `required` flags among `typeBits`; throws VulkanError when none.
    uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags required) const;

    /// Records with `record` into a one-time command buffer, submits it and waits.
    void submitAndWait(const std::function<void(VkCommandBuffer)>& record) const;
    VkCommandPool commandPool() const { return pool_; }

    bool validationEnabled() const { return validation_; }
    /// Validation messages (warnings and errors) reported so far.
    uint64_t validationMessages() const { return messages_.load(); }

private:
    /// Picks the device with a graphics queue (among all, or `given`); throws NoVulkanDevice when none.
    void choosePhysicalDevice(VkPhysicalDevice given);
    void createDevice(const ContextOptions& options);
    void release();
    static VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT types,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* self);

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    uint32_t queueFamily_ = 0;
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memory_{};
    bool fillModeNonSolid_ = false;
    bool multiDrawIndirect_ = false;
    double timestampPeriod_ = 0.0;
    bool validation_ = false;
    std::atomic<uint64_t> messages_{0};
};

} // namespace vdbclay::render
