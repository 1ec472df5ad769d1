// A headset through OpenXR (XR_KHR_vulkan_enable2): the instance with the extensions the runtime offers
// and we use, the system, the Vulkan device the runtime names (made through it), the session and its
// states, the stage space, a swapchain per eye (colour, and depth where XR_KHR_composition_layer_depth
// is offered) and the frame loop (wait, begin, locate views, end on the predicted display time). Every
// choice (view configuration, blend mode, formats, sizes) is made from what the runtime enumerates.
#pragma once

#include "render/RenderTarget.h"
#include "render/VulkanContext.h"
#include "vr/XrCheck.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace vdbclay::vr {

struct XrHeadsetOptions {
    bool validation = false; // the Vulkan validation layer on the device the runtime names
};

class XrHeadset {
public:
    /// Throws NoXrRuntime when no runtime answers (or it has no headset or no Vulkan), XrError and
    /// render::VulkanError on failures.
    explicit XrHeadset(const XrHeadsetOptions& options);
    ~XrHeadset();
    XrHeadset(const XrHeadset&) = delete;
    XrHeadset& operator=(const XrHeadset&) = delete;

    XrInstance instance() const { return instance_; }
    XrSession session() const { return session_; }
    XrSpace stage() const { return stage_; }
    render::VulkanContext& vulkan() { return *vulkan_; }
    /// The format the eyes are drawn in (a UNORM view, also of an sRGB swapchain: the shaders encode).
    VkFormat colourFormat() const { return viewFormat_; }
    uint32_t viewCount() const { return uint32_t(eyes_.size()); }
    bool submitsDepth() const { return depthSubmitted_; }
    /// The eyes' render pass (what pipelines drawing into them are made for).
    VkRenderPass renderPass() const { return renderPass_; }
    /// What each eye records before its pass and over the scene inside it (the menus), by view index.
    void setEyeRecorders(std::function<void(VkCommandBuffer, uint32_t)> beforePass, std::function<void(VkCommandBuffer, uint32_t)> overlay);
    std::string describe() const; // runtime, system, view configuration, eye size, formats

    // --- session states ---
    /// Reads the runtime's events and follows its state: begins the session when READY, ends it when
    /// STOPPING. Returns false once the session is over (EXITING, LOSS_PENDING, the instance lost).
    bool pollEvents();
    XrSessionState state() const { return state_; }
    bool running() const { return running_; }
    bool focused() const { return state_ == XR_SESSION_STATE_FOCUSED; }
    /// Whether the session ended because the runtime lost it (LOSS_PENDING or the instance lost).
    bool lost() const { return lost_; }
    /// Asks the runtime to stop the session (it goes STOPPING, then EXITING).
    void requestExit();
    /// Every state the session went through, in order (tests, bug reports).
    const std::vector<XrSessionState>& states() const { return states_; }

    // --- the frame ---
    struct Frame {
        XrTime displayTime = 0;
        XrDuration period = 0;
        bool shouldRender = false;
    };
    /// xrWaitFrame then xrBeginFrame.
    Frame beginFrame();
    /// The eyes' poses (stage) and fields of view at `time`; empty when the runtime cannot track them.
    std::vector<XrView> locateViews(XrTime time);
    /// Acquires and waits for each eye's images: the targets to draw the eyes into, in view order.
    std::vector<render::RenderTarget*> acquireEyes();
    /// Releases them (after the frame's drawing is submitted).
    void releaseEyes();
    /// Ends the frame: the projection layer of `views` (as drawn, with depth where submitted and
    /// `nearMetres` is the near plane of the reversed depth) when `drawn`, else no layer.
    void endFrame(const Frame& frame, const std::vector<XrView>& views, double nearMetres, bool drawn);

private:
    struct Eye;
    void createInstance();
    void createSession(const XrHeadsetOptions& options);
    void createSwapchains();
    void destroy();

    XrInstance instance_ = XR_NULL_HANDLE;
    XrSystemId system_ = XR_NULL_SYSTEM_ID;
    XrSession session_ = XR_NULL_HANDLE;
    XrSpace stage_ = XR_NULL_HANDLE;
    XrViewConfigurationType viewConfiguration_ = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
    XrEnvironmentBlendMode blendMode_ = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    bool depthExtension_ = false, depthSubmitted_ = false;
    std::string runtimeName_, systemName_;
    std::unique_ptr<render::VulkanContext> vulkan_;
    VkRenderPass renderPass_ = VK_NULL_HANDLE;
    int64_t swapchainFormat_ = 0;
    VkFormat viewFormat_ = VK_FORMAT_UNDEFINED;
    std::vector<std::unique_ptr<Eye>> eyes_;
    XrSessionState state_ = XR_SESSION_STATE_UNKNOWN;
    std::vector<XrSessionState> states_;
    bool running_ = false, over_ = false, lost_ = false;
};

const char* sessionStateName(XrSessionState state);

} // namespace vdbclay::vr
