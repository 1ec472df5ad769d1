// OpenXR results as exceptions, and the Vulkan flavour of the OpenXR headers every file of the VR front
// end includes (XR_USE_GRAPHICS_API_VULKAN before openxr_platform.h).
#pragma once

#include <vulkan/vulkan.h>
#ifndef XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_GRAPHICS_API_VULKAN
#endif
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <stdexcept>
#include <string>

namespace vdbclay::vr {

/// No OpenXR runtime is installed or active (or it offers no headset, or no Vulkan): the caller says
/// so in one line and exits 1.
struct NoXrRuntime : std::runtime_error {
    using std::runtime_error::runtime_error;
};
/// An OpenXR call failed.
struct XrError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The result's name ("XR_ERROR_SESSION_LOST"), from the runtime when `instance` is given.
std::string resultName(XrResult result, XrInstance instance = XR_NULL_HANDLE);
/// Throws XrError naming the call and the result unless the result is a success code.
void check(XrResult result, const char* what, XrInstance instance = XR_NULL_HANDLE);

} // namespace vdbclay::vr
