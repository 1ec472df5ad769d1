// The controllers through OpenXR actions: one action set (poses, trigger, squeeze, thumbstick, buttons,
// haptics) with suggested bindings for the khr/simple, oculus/touch, valve/index and htc/vive
// profiles, read each frame into a ControllerFrame (VrControls.h) at the predicted display time.
#pragma once

#include "vr/VrControls.h"
#include "vr/XrCheck.h"

#include <array>
#include <string>

namespace vdbclay::vr {

/// An OpenXR pose as the front end's.
Pose poseOf(const XrPosef& pose);

class XrControllers {
public:
    /// Creates the actions, suggests the bindings and attaches them to the session.
    XrControllers(XrInstance instance, XrSession session);
    ~XrControllers();
    XrControllers(const XrControllers&) = delete;
    XrControllers& operator=(const XrControllers&) = delete;

    /// Syncs the actions (when the session has focus) and reads both hands, posed in `space` at `time`.
    ControllerFrame read(XrSpace space, XrTime time, bool focused, double seconds);
    /// A short pulse on a hand (0 left, 1 right): the brush touched the surface.
    void pulse(int hand, double amplitude = 0.5);
    /// The profile the runtime bound for a hand ("/interaction_profiles/oculus/touch_controller"), or empty.
    std::string profile(int hand) const;

private:
    XrInstance instance_;
    XrSession session_;
    XrActionSet set_ = XR_NULL_HANDLE;
    XrAction gripPose_ = XR_NULL_HANDLE, aimPose_ = XR_NULL_HANDLE, trigger_ = XR_NULL_HANDLE, squeeze_ = XR_NULL_HANDLE,
             thumbstick_ = XR_NULL_HANDLE, primary_ = XR_NULL_HANDLE, secondary_ = XR_NULL_HANDLE, menu_ = XR_NULL_HANDLE,
             haptic_ = XR_NULL_HANDLE;
    std::array<XrPath, 2> hands_{XR_NULL_PATH, XR_NULL_PATH};
    std::array<XrSpace, 2> gripSpaces_{XR_NULL_HANDLE, XR_NULL_HANDLE}, aimSpaces_{XR_NULL_HANDLE, XR_NULL_HANDLE};
};

} // namespace vdbclay::vr
