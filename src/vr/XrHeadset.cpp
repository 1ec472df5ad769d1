#include "vr/XrHeadset.h"

#include "render/DrawnDepth.h"
#include "render/GpuMemory.h"
#include "render/OffscreenTarget.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace vdbclay::vr {

const char* sessionStateName(XrSessionState state)
{
    switch (state) {
    case XR_SESSION_STATE_IDLE: return "IDLE";
    case XR_SESSION_STATE_READY: return "READY";
    case XR_SESSION_STATE_SYNCHRONIZED: return "SYNCHRONIZED";
    case XR_SESSION_STATE_VISIBLE: return "VISIBLE";
    case XR_SESSION_STATE_FOCUSED: return "FOCUSED";
    case XR_SESSION_STATE_STOPPING: return "STOPPING";
    case XR_SESSION_STATE_LOSS_PENDING: return "LOSS_PENDING";
    case XR_SESSION_STATE_EXITING: return "EXITING";
    default: return "UNKNOWN";
    }
}

namespace {

template <typename Fn>
Fn proc(XrInstance instance, const char* name)
{
    PFN_xrVoidFunction f = nullptr;
    check(xrGetInstanceProcAddr(instance, name, &f), name, instance);
    if (!f) throw XrError(std::string("the OpenXR runtime returned no ") + name);
    return reinterpret_cast<Fn>(f);
}

bool isUnorm(int64_t f) { return f == VK_FORMAT_R8G8B8A8_UNORM || f == VK_FORMAT_B8G8R8A8_UNORM; }
bool isSrgb(int64_t f) { return f == VK_FORMAT_R8G8B8A8_SRGB || f == VK_FORMAT_B8G8R8A8_SRGB; }
VkFormat unormOf(int64_t f)
{
    return f == VK_FORMAT_B8G8R8A8_SRGB || f == VK_FORMAT_B8G8R8A8_UNORM ? VK_FORMAT_B8G8R8A8_UNORM : VK_FORMAT_R8G8B8A8_UNORM;
}

std::vector<VkImage> swapchainImages(XrSwapchain swapchain, XrInstance instance)
{
    uint32_t count = 0;
    check(xrEnumerateSwapchainImages(swapchain, 0, &count, nullptr), "xrEnumerateSwapchainImages", instance);
    std::vector<XrSwapchainImageVulkan2KHR> images(count, {XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR});
    check(xrEnumerateSwapchainImages(swapchain, count, &count, reinterpret_cast<XrSwapchainImageBaseHeader*>(images.data())),
          "xrEnumerateSwapchainImages", instance);
    std::vector<VkImage> out;
    for (const auto& i : images) out.push_back(i.image);
    return out;
}

/// Why no runtime can be loaded, or empty when the loader will find a manifest: the OpenXR loader's
/// search on Linux (XR_RUNTIME_JSON, then active_runtime.json under XDG_CONFIG_HOME, XDG_CONFIG_DIRS and
/// /etc). Checked first, so that a machine with no runtime gets one line, not the loader's log.
std::string missingRuntime()
{
    namespace fs = std::filesystem;
    std::error_code ec;
    if (const char* named = std::getenv("XR_RUNTIME_JSON"); named && *named)
        return fs::is_regular_file(named, ec) ? std::string() : std::string("XR_RUNTIME_JSON names ") + named + ", which does not exist";
    std::vector<fs::path> folders;
    const char* home = std::getenv("HOME");
    if (const char* config = std::getenv("XDG_CONFIG_HOME"); config && *config) folders.emplace_back(config);
    else if (home && *home) folders.push_back(fs::path(home) / ".config");
    const char* dirs = std::getenv("XDG_CONFIG_DIRS");
    std::string list = dirs && *dirs ? dirs : "/etc/xdg";
    for (std::size_t at = 0; at <= list.size();) {
        const std::size_t colon = std::min(list.find(':', at), list.size());
        if (colon > at) folders.emplace_back(list.substr(at, colon - at));
        at = colon + 1;
    }
    folders.emplace_back("/etc");
    for (const fs::path& folder : folders)
        if (fs::is_regular_file(folder / "openxr/1/active_runtime.json", ec)) return {};
    return "no openxr/1/active_runtime.json under ~/.config, /etc/xdg or /etc";
}

} // namespace

/// One eye: its colour swapchain (and depth swapchain, or a depth image of its own), the views and
/// framebuffers of its images, and the target the renderer draws the current pair into.
struct XrHeadset::Eye : render::RenderTarget {
    VkDevice device = VK_NULL_HANDLE;
    VkRenderPass pass = VK_NULL_HANDLE;
    int w = 0, h = 0;
    XrSwapchain colour = XR_NULL_HANDLE, depth = XR_NULL_HANDLE;
    std::vector<VkImageView> colourViews, depthViews;
    // A depth image of its own when depth is not submitted.
    VkImage ownDepth = VK_NULL_HANDLE;
    VkDeviceMemory ownDepthMemory = VK_NULL_HANDLE;
    std::vector<VkImage> depthImages; // of the depth swapchain, or the own depth image
    bool depthSampled = false;        // its depth images can be sampled (the renderer keeps their tiles)
    std::map<std::pair<uint32_t, uint32_t>, VkFramebuffer> framebuffers; // (colour, depth) image indices
    uint32_t colourIndex = 0, depthIndex = 0;
    bool acquired = false;
    uint32_t view = 0;
    std::function<void(VkCommandBuffer, uint32_t)> beforePass, overlay;

    void recordBeforePass(VkCommandBuffer cmd) override
    {
        if (beforePass) beforePass(cmd, view);
    }
    void recordOverlay(VkCommandBuffer cmd) override
    {
        if (overlay) overlay(cmd, view);
    }

    int width() const override { return w; }
    int height() const override { return h; }
    VkRenderPass renderPass() const override { return pass; }
    VkImage depthImage() const override
    {
        const uint32_t i = depth ? depthIndex : 0;
        return depthSampled && i < depthImages.size() ? depthImages[i] : VK_NULL_HANDLE;
    }
    VkImageView depthView() const override
    {
        const uint32_t i = depth ? depthIndex : 0;
        return depthSampled && i < depthViews.size() ? depthViews[i] : VK_NULL_HANDLE;
    }
    VkFramebuffer framebuffer() const override
    {
        auto it = framebuffers.find({colourIndex, depth ? depthIndex : 0});
        return it == framebuffers.end() ? VK_NULL_HANDLE : it->second;
    }
    void makeFramebuffers()
    {
        for (uint32_t c = 0; c < colourViews.size(); ++c)
            for (uint32_t d = 0; d < depthViews.size(); ++d) {
                framebuffers[{c, d}] = render::createFramebuffer(device, pass, colourViews[c], depthViews[d], uint32_t(w), uint32_t(h));
            }
    }
    void release()
    {
        for (auto& [key, fb] : framebuffers) vkDestroyFramebuffer(device, fb, nullptr);
        framebuffers.clear();
        for (VkImageView v : colourViews) vkDestroyImageView(device, v, nullptr);
        for (VkImageView v : depthViews) vkDestroyImageView(device, v, nullptr);
        colourViews.clear();
        depthViews.clear();
        depthImages.clear();
        if (ownDepth) vkDestroyImage(device, ownDepth, nullptr);
        if (ownDepthMemory) vkFreeMemory(device, ownDepthMemory, nullptr);
        ownDepth = VK_NULL_HANDLE;
        ownDepthMemory = VK_NULL_HANDLE;
        if (colour) xrDestroySwapchain(colour);
        if (depth) xrDestroySwapchain(depth);
        colour = depth = XR_NULL_HANDLE;
    }
};

XrHeadset::XrHeadset(const XrHeadsetOptions& options)
{
    try {
        createInstance();
        createSession(options);
        createSwapchains();
    } catch (...) {
        destroy();
        throw;
    }
}

XrHeadset::~XrHeadset() { destroy(); }

void XrHeadset::destroy()
{
    if (vulkan_) vkDeviceWaitIdle(vulkan_->device());
    for (auto& eye : eyes_) eye->release();
    eyes_.clear();
    if (renderPass_) vkDestroyRenderPass(vulkan_->device(), renderPass_, nullptr);
    renderPass_ = VK_NULL_HANDLE;
    if (stage_) xrDestroySpace(stage_);
    stage_ = XR_NULL_HANDLE;
    if (session_) xrDestroySession(session_);
    session_ = XR_NULL_HANDLE;
    vulkan_.reset(); // after the session: the runtime let go of the device
    if (instance_) xrDestroyInstance(instance_);
    instance_ = XR_NULL_HANDLE;
}

void XrHeadset::createInstance()
{
    if (const std::string missing = missingRuntime(); !missing.empty())
        throw NoXrRuntime("no OpenXR runtime is installed or active (" + missing +
                          "): install one (Monado, SteamVR) or point XR_RUNTIME_JSON at its manifest");
    uint32_t count = 0;
    XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr);
    if (XR_FAILED(r))
        throw NoXrRuntime("no OpenXR runtime is installed or active (" + resultName(r) +
                          "): install one (Monado, SteamVR) or point XR_RUNTIME_JSON at its manifest");
    std::vector<XrExtensionProperties> offered(count, {XR_TYPE_EXTENSION_PROPERTIES});
    check(xrEnumerateInstanceExtensionProperties(nullptr, count, &count, offered.data()), "xrEnumerateInstanceExtensionProperties");
    auto has = [&](const char* name) {
        return std::any_of(offered.begin(), offered.end(), [&](const XrExtensionProperties& p) { return std::strcmp(p.extensionName, name) == 0; });
    };
    if (!has(XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME))
        throw NoXrRuntime("the OpenXR runtime does not offer Vulkan (XR_KHR_vulkan_enable2), which the VR editor draws with");
    std::vector<const char*> extensions{XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME};
    depthExtension_ = has(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
    if (depthExtension_) extensions.push_back(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);

    XrInstanceCreateInfo info{XR_TYPE_INSTANCE_CREATE_INFO};
    std::snprintf(info.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "vdbclay");
    std::snprintf(info.applicationInfo.engineName, XR_MAX_ENGINE_NAME_SIZE, "vdbclay");
    info.applicationInfo.applicationVersion = 1;
    info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
    info.enabledExtensionCount = uint32_t(extensions.size());
    info.enabledExtensionNames = extensions.data();
    r = xrCreateInstance(&info, &instance_);
    if (XR_FAILED(r)) throw NoXrRuntime("the OpenXR runtime refused an instance (" + resultName(r) + ")");
    XrInstanceProperties props{XR_TYPE_INSTANCE_PROPERTIES};
    check(xrGetInstanceProperties(instance_, &props), "xrGetInstanceProperties", instance_);
    runtimeName_ = props.runtimeName;

    XrSystemGetInfo systemInfo{XR_TYPE_SYSTEM_GET_INFO};
    systemInfo.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
    r = xrGetSystem(instance_, &systemInfo, &system_);
    if (XR_FAILED(r)) throw NoXrRuntime("the OpenXR runtime '" + runtimeName_ + "' has no headset (" + resultName(r, instance_) + ")");
    XrSystemProperties system{XR_TYPE_SYSTEM_PROPERTIES};
    check(xrGetSystemProperties(instance_, system_, &system), "xrGetSystemProperties", instance_);
    systemName_ = system.systemName;

    // Stereo where offered, else the runtime's first view configuration.
    check(xrEnumerateViewConfigurations(instance_, system_, 0, &count, nullptr), "xrEnumerateViewConfigurations", instance_);
    std::vector<XrViewConfigurationType> configurations(count);
    check(xrEnumerateViewConfigurations(instance_, system_, count, &count, configurations.data()), "xrEnumerateViewConfigurations", instance_);
    if (configurations.empty()) throw NoXrRuntime("the headset offers no view configuration");
    viewConfiguration_ = std::find(configurations.begin(), configurations.end(), XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) != configurations.end()
                             ? XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO
                             : configurations.front();
    check(xrEnumerateEnvironmentBlendModes(instance_, system_, viewConfiguration_, 0, &count, nullptr), "xrEnumerateEnvironmentBlendModes", instance_);
    std::vector<XrEnvironmentBlendMode> modes(count);
    check(xrEnumerateEnvironmentBlendModes(instance_, system_, viewConfiguration_, count, &count, modes.data()), "xrEnumerateEnvironmentBlendModes",
          instance_);
    if (modes.empty()) throw NoXrRuntime("the headset offers no environment blend mode");
    blendMode_ = std::find(modes.begin(), modes.end(), XR_ENVIRONMENT_BLEND_MODE_OPAQUE) != modes.end() ? XR_ENVIRONMENT_BLEND_MODE_OPAQUE : modes.front();
}

void XrHeadset::createSession(const XrHeadsetOptions& options)
{
    auto requirements = proc<PFN_xrGetVulkanGraphicsRequirements2KHR>(instance_, "xrGetVulkanGraphicsRequirements2KHR");
    auto createInstance = proc<PFN_xrCreateVulkanInstanceKHR>(instance_, "xrCreateVulkanInstanceKHR");
    auto graphicsDevice = proc<PFN_xrGetVulkanGraphicsDevice2KHR>(instance_, "xrGetVulkanGraphicsDevice2KHR");
    auto createDevice = proc<PFN_xrCreateVulkanDeviceKHR>(instance_, "xrCreateVulkanDeviceKHR");
    XrGraphicsRequirementsVulkan2KHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
    check(requirements(instance_, system_, &req), "xrGetVulkanGraphicsRequirements2KHR", instance_);
    if (XR_VERSION_MAJOR(req.minApiVersionSupported) > 1 || (XR_VERSION_MAJOR(req.minApiVersionSupported) == 1 && XR_VERSION_MINOR(req.minApiVersionSupported) > 3))
        throw NoXrRuntime("the OpenXR runtime needs a newer Vulkan than 1.3");

    const XrInstance xr = instance_;
    const XrSystemId system = system_;
    render::ContextOptions vk;
    vk.validation = options.validation;
    render::ContextOptions::Creation creation;
    creation.instance = [=](const VkInstanceCreateInfo& info) {
        XrVulkanInstanceCreateInfoKHR create{XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR};
        create.systemId = system;
        create.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
        create.vulkanCreateInfo = &info;
        VkInstance instance = VK_NULL_HANDLE;
        VkResult result = VK_SUCCESS;
        check(createInstance(xr, &create, &instance, &result), "xrCreateVulkanInstanceKHR", xr);
        if (result == VK_ERROR_INCOMPATIBLE_DRIVER || result == VK_ERROR_INITIALIZATION_FAILED)
            throw render::NoVulkanDevice(std::string("no Vulkan driver is installed (") + render::resultName(result) + ")");
        render::check(result, "vkCreateInstance (through the OpenXR runtime)");
        return instance;
    };
    creation.physicalDevice = [=](VkInstance instance) {
        XrVulkanGraphicsDeviceGetInfoKHR get{XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR};
        get.systemId = system;
        get.vulkanInstance = instance;
        VkPhysicalDevice device = VK_NULL_HANDLE;
        check(graphicsDevice(xr, &get, &device), "xrGetVulkanGraphicsDevice2KHR", xr);
        return device;
    };
    creation.device = [=](VkPhysicalDevice physical, const VkDeviceCreateInfo& info) {
        XrVulkanDeviceCreateInfoKHR create{XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR};
        create.systemId = system;
        create.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
        create.vulkanPhysicalDevice = physical;
        create.vulkanCreateInfo = &info;
        VkDevice device = VK_NULL_HANDLE;
        VkResult result = VK_SUCCESS;
        check(createDevice(xr, &create, &device, &result), "xrCreateVulkanDeviceKHR", xr);
        render::check(result, "vkCreateDevice (through the OpenXR runtime)");
        return device;
    };
    vk.creation = creation;
    vulkan_ = std::make_unique<render::VulkanContext>(vk);

    XrGraphicsBindingVulkan2KHR binding{XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR};
    binding.instance = vulkan_->instance();
    binding.physicalDevice = vulkan_->physicalDevice();
    binding.device = vulkan_->device();
    binding.queueFamilyIndex = vulkan_->queueFamily();
    binding.queueIndex = 0;
    XrSessionCreateInfo info{XR_TYPE_SESSION_CREATE_INFO};
    info.next = &binding;
    info.systemId = system_;
    check(xrCreateSession(instance_, &info, &session_), "xrCreateSession", instance_);

    // The stage (the floor of the room) where offered, else the local space.
    uint32_t count = 0;
    check(xrEnumerateReferenceSpaces(session_, 0, &count, nullptr), "xrEnumerateReferenceSpaces", instance_);
    std::vector<XrReferenceSpaceType> spaces(count);
    check(xrEnumerateReferenceSpaces(session_, count, &count, spaces.data()), "xrEnumerateReferenceSpaces", instance_);
    XrReferenceSpaceCreateInfo space{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
    space.referenceSpaceType = std::find(spaces.begin(), spaces.end(), XR_REFERENCE_SPACE_TYPE_STAGE) != spaces.end() ? XR_REFERENCE_SPACE_TYPE_STAGE
                                                                                                                       : XR_REFERENCE_SPACE_TYPE_LOCAL;
    space.poseInReferenceSpace.orientation.w = 1.0f;
    check(xrCreateReferenceSpace(session_, &space, &stage_), "xrCreateReferenceSpace", instance_);
}

void XrHeadset::createSwapchains()
{
    uint32_t count = 0;
    check(xrEnumerateSwapchainFormats(session_, 0, &count, nullptr), "xrEnumerateSwapchainFormats", instance_);
    std::vector<int64_t> formats(count);
    check(xrEnumerateSwapchainFormats(session_, count, &count, formats.data()), "xrEnumerateSwapchainFormats", instance_);
    // The shaders write display-encoded colour (as into a window's UNORM image): a UNORM format where
    // offered, else an sRGB one viewed as UNORM (a mutable-format swapchain).
    auto pick = [&](bool (*accept)(int64_t)) {
        auto it = std::find_if(formats.begin(), formats.end(), accept);
        return it == formats.end() ? int64_t(0) : *it;
    };
    swapchainFormat_ = pick(isUnorm);
    const bool mutableFormat = swapchainFormat_ == 0;
    if (mutableFormat) swapchainFormat_ = pick(isSrgb);
    if (swapchainFormat_ == 0) throw XrError("the OpenXR runtime offers no RGBA8 or BGRA8 swapchain format");
    viewFormat_ = unormOf(swapchainFormat_);
    depthSubmitted_ = depthExtension_ && std::find(formats.begin(), formats.end(), int64_t(render::kDepthFormat)) != formats.end();
    renderPass_ = render::createRenderPass(vulkan_->device(), viewFormat_, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);

    check(xrEnumerateViewConfigurationViews(instance_, system_, viewConfiguration_, 0, &count, nullptr), "xrEnumerateViewConfigurationViews", instance_);
    std::vector<XrViewConfigurationView> views(count, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
    check(xrEnumerateViewConfigurationViews(instance_, system_, viewConfiguration_, count, &count, views.data()),
          "xrEnumerateViewConfigurationViews", instance_);
    const VkDevice device = vulkan_->device();
    for (const XrViewConfigurationView& v : views) {
        auto eye = std::make_unique<Eye>();
        eye->view = uint32_t(eyes_.size());
        eye->device = device;
        eye->pass = renderPass_;
        eye->w = int(std::min(v.recommendedImageRectWidth, v.maxImageRectWidth));
        eye->h = int(std::min(v.recommendedImageRectHeight, v.maxImageRectHeight));
        if (eye->w <= 0 || eye->h <= 0) throw XrError("the OpenXR runtime recommends an empty eye image");
        XrSwapchainCreateInfo info{XR_TYPE_SWAPCHAIN_CREATE_INFO};
        info.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | (mutableFormat ? XR_SWAPCHAIN_USAGE_MUTABLE_FORMAT_BIT : 0);
        info.format = swapchainFormat_;
        info.sampleCount = 1;
        info.width = uint32_t(eye->w);
        info.height = uint32_t(eye->h);
        info.faceCount = 1;
        info.arraySize = 1;
        info.mipCount = 1;
        Eye* e = eye.get();
        eyes_.push_back(std::move(eye));
        check(xrCreateSwapchain(session_, &info, &e->colour), "xrCreateSwapchain", instance_);
        for (VkImage image : swapchainImages(e->colour, instance_)) e->colourViews.push_back(render::createImageView(device, image, viewFormat_, VK_IMAGE_ASPECT_COLOR_BIT));
        // Sampled too where the device can: the renderer reduces each eye's depth to tiles, the next
        // selection's occluders.
        e->depthSampled = render::depthSampleable(*vulkan_);
        if (depthSubmitted_) {
            info.usageFlags = XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | (e->depthSampled ? XR_SWAPCHAIN_USAGE_SAMPLED_BIT : 0);
            info.format = render::kDepthFormat;
            check(xrCreateSwapchain(session_, &info, &e->depth), "xrCreateSwapchain (depth)", instance_);
            for (VkImage image : swapchainImages(e->depth, instance_)) {
                e->depthImages.push_back(image);
                e->depthViews.push_back(render::createImageView(device, image, render::kDepthFormat, VK_IMAGE_ASPECT_DEPTH_BIT));
            }
        } else {
            VkImageView view = VK_NULL_HANDLE;
            render::createImage2D(*vulkan_, e->w, e->h, render::kDepthFormat,
                                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | (e->depthSampled ? VK_IMAGE_USAGE_SAMPLED_BIT : 0),
                                  VK_IMAGE_ASPECT_DEPTH_BIT, e->ownDepth, e->ownDepthMemory, view);
            e->depthImages.push_back(e->ownDepth);
            e->depthViews.push_back(view);
        }
        e->makeFramebuffers();
    }
    if (eyes_.empty()) throw XrError("the OpenXR runtime's view configuration has no views");
}

void XrHeadset::setEyeRecorders(std::function<void(VkCommandBuffer, uint32_t)> beforePass, std::function<void(VkCommandBuffer, uint32_t)> overlay)
{
    for (auto& eye : eyes_) {
        eye->beforePass = beforePass;
        eye->overlay = overlay;
    }
}

std::string XrHeadset::describe() const
{
    std::ostringstream s;
    s << runtimeName_ << ", " << systemName_ << ": " << eyes_.size() << (eyes_.size() == 1 ? " view" : " views") << " of "
      << eyes_.front()->w << " x " << eyes_.front()->h << ", "
      << (swapchainFormat_ == viewFormat_ ? "UNORM" : "sRGB viewed as UNORM") << " colour, depth "
      << (depthSubmitted_ ? "submitted" : "kept");
    return s.str();
}

bool XrHeadset::pollEvents()
{
    XrEventDataBuffer event{XR_TYPE_EVENT_DATA_BUFFER};
    while (xrPollEvent(instance_, &event) == XR_SUCCESS) {
        switch (event.type) {
        case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
            lost_ = over_ = true;
            break;
        case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
            const auto& changed = reinterpret_cast<const XrEventDataSessionStateChanged&>(event);
            if (changed.session != session_) break;
            state_ = changed.state;
            states_.push_back(state_);
            if (state_ == XR_SESSION_STATE_READY && !running_) {
                XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
                begin.primaryViewConfigurationType = viewConfiguration_;
                check(xrBeginSession(session_, &begin), "xrBeginSession", instance_);
                running_ = true;
            } else if (state_ == XR_SESSION_STATE_STOPPING && running_) {
                check(xrEndSession(session_), "xrEndSession", instance_);
                running_ = false;
            } else if (state_ == XR_SESSION_STATE_EXITING) {
                over_ = true;
            } else if (state_ == XR_SESSION_STATE_LOSS_PENDING) {
                over_ = lost_ = true;
                running_ = false;
            }
            break;
        }
        default: break;
        }
        event = XrEventDataBuffer{XR_TYPE_EVENT_DATA_BUFFER};
    }
    return !over_;
}

void XrHeadset::requestExit()
{
    if (running_) check(xrRequestExitSession(session_), "xrRequestExitSession", instance_);
    else over_ = true;
}

XrHeadset::Frame XrHeadset::beginFrame()
{
    XrFrameWaitInfo wait{XR_TYPE_FRAME_WAIT_INFO};
    XrFrameState state{XR_TYPE_FRAME_STATE};
    check(xrWaitFrame(session_, &wait, &state), "xrWaitFrame", instance_);
    XrFrameBeginInfo begin{XR_TYPE_FRAME_BEGIN_INFO};
    check(xrBeginFrame(session_, &begin), "xrBeginFrame", instance_);
    return Frame{state.predictedDisplayTime, state.predictedDisplayPeriod, state.shouldRender == XR_TRUE};
}

std::vector<XrView> XrHeadset::locateViews(XrTime time)
{
    XrViewLocateInfo info{XR_TYPE_VIEW_LOCATE_INFO};
    info.viewConfigurationType = viewConfiguration_;
    info.displayTime = time;
    info.space = stage_;
    XrViewState state{XR_TYPE_VIEW_STATE};
    std::vector<XrView> views(eyes_.size(), {XR_TYPE_VIEW});
    uint32_t count = 0;
    check(xrLocateViews(session_, &info, &state, uint32_t(views.size()), &count, views.data()), "xrLocateViews", instance_);
    const XrViewStateFlags needed = XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT;
    if ((state.viewStateFlags & needed) != needed || count != views.size()) return {};
    return views;
}

std::vector<render::RenderTarget*> XrHeadset::acquireEyes()
{
    std::vector<render::RenderTarget*> targets;
    XrSwapchainImageAcquireInfo acquire{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
    XrSwapchainImageWaitInfo wait{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
    wait.timeout = XR_INFINITE_DURATION;
    for (auto& eye : eyes_) {
        check(xrAcquireSwapchainImage(eye->colour, &acquire, &eye->colourIndex), "xrAcquireSwapchainImage", instance_);
        eye->acquired = true;
        check(xrWaitSwapchainImage(eye->colour, &wait), "xrWaitSwapchainImage", instance_);
        if (eye->depth) {
            check(xrAcquireSwapchainImage(eye->depth, &acquire, &eye->depthIndex), "xrAcquireSwapchainImage (depth)", instance_);
            check(xrWaitSwapchainImage(eye->depth, &wait), "xrWaitSwapchainImage (depth)", instance_);
        }
        targets.push_back(eye.get());
    }
    return targets;
}

void XrHeadset::releaseEyes()
{
    XrSwapchainImageReleaseInfo release{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
    for (auto& eye : eyes_) {
        if (!eye->acquired) continue;
        check(xrReleaseSwapchainImage(eye->colour, &release), "xrReleaseSwapchainImage", instance_);
        if (eye->depth) check(xrReleaseSwapchainImage(eye->depth, &release), "xrReleaseSwapchainImage (depth)", instance_);
        eye->acquired = false;
    }
}

void XrHeadset::endFrame(const Frame& frame, const std::vector<XrView>& views, double nearMetres, bool drawn)
{
    std::vector<XrCompositionLayerProjectionView> projected(views.size(), {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW});
    std::vector<XrCompositionLayerDepthInfoKHR> depth(views.size(), {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR});
    XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
    const XrCompositionLayerBaseHeader* layers[1] = {reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
    XrFrameEndInfo end{XR_TYPE_FRAME_END_INFO};
    end.displayTime = frame.displayTime;
    end.environmentBlendMode = blendMode_;
    if (drawn && views.size() == eyes_.size()) {
        for (std::size_t i = 0; i < views.size(); ++i) {
            const Eye& eye = *eyes_[i];
            projected[i].pose = views[i].pose;
            projected[i].fov = views[i].fov;
            projected[i].subImage.swapchain = eye.colour;
            projected[i].subImage.imageRect = {{0, 0}, {eye.w, eye.h}};
            if (eye.depth) {
                // Reversed depth with no far plane: 1 at the near plane, 0 at infinity.
                depth[i].subImage.swapchain = eye.depth;
                depth[i].subImage.imageRect = {{0, 0}, {eye.w, eye.h}};
                depth[i].minDepth = 0.0f;
                depth[i].maxDepth = 1.0f;
                depth[i].nearZ = std::numeric_limits<float>::infinity();
                depth[i].farZ = float(nearMetres);
                projected[i].next = &depth[i];
            }
        }
        layer.space = stage_;
        layer.viewCount = uint32_t(projected.size());
        layer.views = projected.data();
        end.layerCount = 1;
        end.layers = layers;
    }
    const XrResult r = xrEndFrame(session_, &end);
    if (r == XR_SESSION_LOSS_PENDING) lost_ = true;
    check(r, "xrEndFrame", instance_);
}

} // namespace vdbclay::vr
