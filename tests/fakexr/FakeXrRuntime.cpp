// A fake OpenXR runtime for the VR tests: a headset at 90 Hz whose head and controllers follow a script
// (FakeXrScript.h), drawn into swapchain images it allocates on the application's own Vulkan device.
// Besides answering every call, it enforces what no Khronos layer checks (the frame loop's order,
// swapchain image acquire / wait / release, session-state rules, predicted display times used, every
// view submitted each frame): a violation is one line appended to FAKEXR_ERRORS (and stderr) and an
// error result. FAKEXR_CAPTURE names a folder for the eye images of the script's capture frames (PPM),
// FAKEXR_LOG a file for one JSON line of timings per frame.
#include "FakeXrScript.h"
#include "FakeXrVulkan.h"

#include <vulkan/vulkan.h>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#include <openxr/openxr_reflection.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

// The loader's negotiation structs (loader_interfaces.h is not installed by Debian's libopenxr-dev).
extern "C" {
enum XrLoaderInterfaceStructs {
    XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
    XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
    XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
    XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
};
struct XrNegotiateLoaderInfo {
    XrLoaderInterfaceStructs structType;
    uint32_t structVersion;
    size_t structSize;
    uint32_t minInterfaceVersion;
    uint32_t maxInterfaceVersion;
    XrVersion minApiVersion;
    XrVersion maxApiVersion;
};
struct XrNegotiateRuntimeRequest {
    XrLoaderInterfaceStructs structType;
    uint32_t structVersion;
    size_t structSize;
    uint32_t runtimeInterfaceVersion;
    XrVersion runtimeApiVersion;
    PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};
}

namespace fakexr {
namespace {

using Clock = std::chrono::steady_clock;

// --- the runtime's state ---------------------------------------------------------------------------

struct Instance;
struct Session;
struct ActionSet {
    Instance* instance;
    std::string name;
    bool attached = false;
};
struct Action {
    ActionSet* set;
    std::string name;
    XrActionType type;
    std::vector<XrPath> subactionPaths;
};
struct Space {
    Session* session;
    XrReferenceSpaceType reference = XrReferenceSpaceType(0); // 0: an action space
    Action* action = nullptr;
    XrPath subaction = XR_NULL_PATH;
    XrPosef offset{{0, 0, 0, 1}, {0, 0, 0}};
};
struct Swapchain {
    Session* session;
    XrSwapchainCreateInfo info{};
    SwapchainImages images;
    std::deque<uint32_t> acquired; // in order; the front one is waited next
    std::optional<uint32_t> waited;
    uint32_t nextAcquire = 0;
    std::optional<uint32_t> lastReleased;
    uint64_t releasedInFrame = UINT64_MAX; // the frame (xrBeginFrame count) an image was last released in
};
struct Session {
    Instance* instance;
    VulkanBinding vulkan;
    XrSessionState state = XR_SESSION_STATE_IDLE;
    bool running = false;
    bool exitRequested = false;
    XrViewConfigurationType viewConfiguration{};
    // The frame loop.
    uint64_t framesWaited = 0, framesBegun = 0, framesEnded = 0;
    bool waitedNotBegun = false, begun = false;
    XrTime predicted = 0;            // of the frame waited last
    XrTime begunPredicted = 0;       // of the frame begun
    std::map<XrTime, uint64_t> frameOfTime; // predicted display time -> frame index (recent)
    Clock::time_point waitReturned, beginAt, locateAt;
    XrTime locateTime = 0;
    std::vector<ActionSet*> attachedSets;
    std::map<std::pair<Action*, XrPath>, std::array<float, 2>> lastSynced; // value; changed flag kept apart
    std::map<std::pair<Action*, XrPath>, bool> changed;
    std::map<std::pair<Action*, XrPath>, XrTime> changeTime;
    uint64_t syncedFrame = 0;
    bool focused() const { return state == XR_SESSION_STATE_FOCUSED; }
};
struct Instance {
    std::set<std::string> extensions;
    bool requirementsQueried = false;
    std::deque<XrEventDataBuffer> events;
    std::map<XrPath, std::vector<std::pair<Action*, XrPath>>> bindings; // profile -> (action, input path)
};

struct Runtime {
    std::mutex mutex;
    HeadsetScript script;
    std::vector<std::string> paths{""}; // XrPath n is paths[n]
    std::set<Instance*> instances;
    std::set<Session*> sessions;
    std::set<Space*> spaces;
    std::set<ActionSet*> actionSets;
    std::set<Action*> actions;
    std::set<Swapchain*> swapchains;
    Clock::time_point epoch = Clock::now();
    FILE* log = nullptr;
    std::string captureFolder;
    uint64_t violations = 0;
    uint64_t hapticPulses = 0;

    Runtime()
    {
        if (const char* s = std::getenv("FAKEXR_SCRIPT"); s && *s) {
            try {
                script = loadHeadsetScript(s);
            } catch (const std::exception& e) {
                violation("%s", e.what());
            }
        }
        if (script.formats.empty())
            script.formats = {VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB, VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_UNORM,
                              VK_FORMAT_D32_SFLOAT, VK_FORMAT_D16_UNORM};
        if (const char* l = std::getenv("FAKEXR_LOG"); l && *l) log = std::fopen(l, "w");
        if (const char* c = std::getenv("FAKEXR_CAPTURE"); c && *c) captureFolder = c;
    }

    XrTime now() const { return XrTime(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - epoch).count()) + 1000000000; }
    XrDuration period() const { return XrDuration(1e9 / script.refreshHz); }

    void violation(const char* format, ...)
    {
        char text[1024];
        va_list args;
        va_start(args, format);
        std::vsnprintf(text, sizeof text, format, args);
        va_end(args);
        ++violations;
        std::fprintf(stderr, "fakexr: %s\n", text);
        if (const char* f = std::getenv("FAKEXR_ERRORS"); f && *f) {
            if (FILE* out = std::fopen(f, "a")) {
                std::fprintf(out, "%s\n", text);
                std::fclose(out);
            }
        }
    }

    XrPath path(const std::string& s)
    {
        for (std::size_t i = 1; i < paths.size(); ++i)
            if (paths[i] == s) return XrPath(i);
        paths.push_back(s);
        return XrPath(paths.size() - 1);
    }
    std::string name(XrPath p) const { return p < paths.size() ? paths[p] : std::string(); }
};

Runtime& runtime()
{
    static Runtime r;
    return r;
}

#define LOCK std::lock_guard<std::mutex> lock(runtime().mutex)

template <typename T>
bool live(const std::set<T*>& set, T* object)
{
    return object && set.count(object);
}

void pushEvent(Instance* instance, const XrEventDataBuffer& e) { instance->events.push_back(e); }

void setState(Session* s, XrSessionState state)
{
    s->state = state;
    XrEventDataBuffer buffer{XR_TYPE_EVENT_DATA_BUFFER};
    auto* e = reinterpret_cast<XrEventDataSessionStateChanged*>(&buffer);
    e->type = XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED;
    e->next = nullptr;
    e->session = reinterpret_cast<XrSession>(s);
    e->state = state;
    e->time = runtime().now();
    pushEvent(s->instance, buffer);
}

XrResult copyString(const std::string& s, uint32_t capacity, uint32_t* count, char* buffer)
{
    if (!count) return XR_ERROR_VALIDATION_FAILURE;
    *count = uint32_t(s.size() + 1);
    if (capacity == 0) return XR_SUCCESS;
    if (capacity < *count) return XR_ERROR_SIZE_INSUFFICIENT;
    std::memcpy(buffer, s.c_str(), s.size() + 1);
    return XR_SUCCESS;
}

template <typename T>
XrResult copyArray(const std::vector<T>& items, uint32_t capacity, uint32_t* count, T* out)
{
    if (!count) return XR_ERROR_VALIDATION_FAILURE;
    *count = uint32_t(items.size());
    if (capacity == 0) return XR_SUCCESS;
    if (capacity < items.size()) return XR_ERROR_SIZE_INSUFFICIENT;
    std::copy(items.begin(), items.end(), out);
    return XR_SUCCESS;
}

constexpr XrSystemId kSystem = 1;

std::vector<XrViewConfigurationType> viewConfigurations()
{
    if (runtime().script.stereo) return {XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_MONO};
    return {XR_VIEW_CONFIGURATION_TYPE_PRIMARY_MONO};
}
uint32_t viewCount(XrViewConfigurationType type) { return type == XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO ? 2 : 1; }

/// The frame whose predicted display time is nearest `time`.
uint64_t frameAt(const Session* s, XrTime time)
{
    if (s->frameOfTime.empty()) return 0;
    auto it = s->frameOfTime.lower_bound(time);
    if (it == s->frameOfTime.end()) return std::prev(it)->second;
    if (it != s->frameOfTime.begin() && time - std::prev(it)->first < it->first - time) return std::prev(it)->second;
    return it->second;
}

XrPosef headPose(const Session* s, XrTime time) { return runtime().script.headAt(frameAt(s, time)); }

int handOf(XrPath subaction)
{
    const std::string n = runtime().name(subaction);
    if (n == "/user/hand/left") return 0;
    if (n == "/user/hand/right") return 1;
    return -1;
}

/// A space's pose in the stage, at `time`; false when it is not tracked (an action space whose action
/// has no pose binding).
bool spacePose(const Space* space, XrTime time, XrPosef* pose)
{
    const Session* s = space->session;
    XrPosef base{{0, 0, 0, 1}, {0, 0, 0}};
    if (space->action) {
        if (!s->focused()) return false;
        int hand = handOf(space->subaction);
        if (hand < 0) {
            // No subaction path: the first hand the action is bound to.
            for (const auto& [action, input] : space->session->instance->bindings[runtime().path(runtime().script.profile)])
                if (action == space->action) {
                    hand = runtime().name(input).rfind("/user/hand/left", 0) == 0 ? 0 : 1;
                    break;
                }
            if (hand < 0) return false;
        }
        base = runtime().script.handAt(hand, frameAt(s, time)).pose;
    } else if (space->reference == XR_REFERENCE_SPACE_TYPE_VIEW) {
        base = headPose(s, time);
    } else if (space->reference == XR_REFERENCE_SPACE_TYPE_LOCAL) {
        base = XrPosef{{0, 0, 0, 1}, {0, 0, 0}}; // the local space is the stage's origin, at floor level
    }
    *pose = multiply(base, space->offset);
    return true;
}

// --- input: what a bound input path reads on the scripted controllers --------------------------------

/// The value of `input` ("/user/hand/right/input/trigger/value") now, as a float (buttons 0 or 1), and for
/// a thumbstick its y in `y`. False when the path names nothing the emulated controller has.
bool readInput(const Session* s, const std::string& input, float* x, float* y)
{
    const int hand = input.rfind("/user/hand/left/", 0) == 0 ? 0 : input.rfind("/user/hand/right/", 0) == 0 ? 1 : -1;
    if (hand < 0) return false;
    const HandState h = runtime().script.handAt(hand, s->syncedFrame);
    const std::string rest = input.substr(input.find("/input/") == std::string::npos ? input.size() : input.find("/input/") + 7);
    *y = 0.0f;
    auto button = [&](const std::string& name) {
        auto it = h.buttons.find(name);
        return it != h.buttons.end() && it->second ? 1.0f : 0.0f;
    };
    if (rest == "trigger/value" || rest == "trigger") *x = h.trigger;
    else if (rest == "trigger/click" || rest == "select/click") *x = h.trigger > 0.5f ? 1.0f : 0.0f;
    else if (rest == "squeeze/value" || rest == "squeeze") *x = h.squeeze;
    else if (rest == "squeeze/click") *x = h.squeeze > 0.5f ? 1.0f : 0.0f;
    // A Vive's trackpad is the script's thumbstick.
    else if (rest == "thumbstick" || rest == "trackpad") *x = h.thumbstick.x, *y = h.thumbstick.y;
    else if (rest == "thumbstick/x" || rest == "trackpad/x") *x = h.thumbstick.x;
    else if (rest == "thumbstick/y" || rest == "trackpad/y") *x = h.thumbstick.y;
    else if (rest == "trackpad/click" || rest == "trackpad/touch") *x = button("thumbstick");
    else if (rest.size() > 6 && rest.substr(rest.size() - 6) == "/click") *x = button(rest.substr(0, rest.size() - 6));
    else if (rest.size() > 6 && rest.substr(rest.size() - 6) == "/touch") *x = button(rest.substr(0, rest.size() - 6));
    else return false;
    return true;
}

/// An action's value for a subaction path (XR_NULL_PATH: every hand), combined over its bindings in the
/// emulated profile (the largest); false when none is bound.
bool actionValue(const Session* s, Action* action, XrPath subaction, float* x, float* y)
{
    bool any = false;
    *x = *y = 0.0f;
    const std::string prefix = subaction ? runtime().name(subaction) + "/" : std::string();
    auto it = s->instance->bindings.find(runtime().path(runtime().script.profile));
    if (it == s->instance->bindings.end()) return false;
    for (const auto& [a, input] : it->second) {
        if (a != action) continue;
        const std::string in = runtime().name(input);
        if (!prefix.empty() && in.rfind(prefix, 0) != 0) continue;
        float vx = 0, vy = 0;
        if (!readInput(s, in, &vx, &vy)) continue;
        if (!any || std::fabs(vx) + std::fabs(vy) > std::fabs(*x) + std::fabs(*y)) *x = vx, *y = vy;
        any = true;
    }
    return any;
}

bool knownSubaction(const Action* a, XrPath subaction)
{
    return subaction == XR_NULL_PATH || std::find(a->subactionPaths.begin(), a->subactionPaths.end(), subaction) != a->subactionPaths.end();
}

// --- the API ---------------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL enumerateApiLayerProperties(uint32_t capacity, uint32_t* count, XrApiLayerProperties*)
{
    if (!count) return XR_ERROR_VALIDATION_FAILURE;
    (void)capacity;
    *count = 0;
    return XR_SUCCESS;
}

std::vector<XrExtensionProperties> offeredExtensions()
{
    std::vector<XrExtensionProperties> out;
    auto add = [&](const char* name, uint32_t version) {
        XrExtensionProperties p{XR_TYPE_EXTENSION_PROPERTIES};
        std::snprintf(p.extensionName, sizeof p.extensionName, "%s", name);
        p.extensionVersion = version;
        out.push_back(p);
    };
    add(XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME, XR_KHR_vulkan_enable2_SPEC_VERSION);
    if (runtime().script.depthExtension) add(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME, XR_KHR_composition_layer_depth_SPEC_VERSION);
    return out;
}

XRAPI_ATTR XrResult XRAPI_CALL enumerateInstanceExtensionProperties(const char* layerName, uint32_t capacity, uint32_t* count,
                                                                    XrExtensionProperties* properties)
{
    if (layerName && *layerName) return XR_ERROR_API_LAYER_NOT_PRESENT;
    const auto offered = offeredExtensions();
    if (!count) return XR_ERROR_VALIDATION_FAILURE;
    *count = uint32_t(offered.size());
    if (capacity == 0) return XR_SUCCESS;
    if (capacity < offered.size()) return XR_ERROR_SIZE_INSUFFICIENT;
    for (std::size_t i = 0; i < offered.size(); ++i) {
        std::memcpy(properties[i].extensionName, offered[i].extensionName, sizeof offered[i].extensionName);
        properties[i].extensionVersion = offered[i].extensionVersion;
    }
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL createInstance(const XrInstanceCreateInfo* info, XrInstance* out)
{
    LOCK;
    if (!info || !out || info->type != XR_TYPE_INSTANCE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    auto instance = std::make_unique<Instance>();
    const auto offered = offeredExtensions();
    for (uint32_t i = 0; i < info->enabledExtensionCount; ++i) {
        const std::string name = info->enabledExtensionNames[i];
        const bool known = std::any_of(offered.begin(), offered.end(), [&](const XrExtensionProperties& p) { return name == p.extensionName; });
        if (!known) return XR_ERROR_EXTENSION_NOT_PRESENT;
        instance->extensions.insert(name);
    }
    *out = reinterpret_cast<XrInstance>(instance.get());
    runtime().instances.insert(instance.release());
    return XR_SUCCESS;
}

Instance* instanceOf(XrInstance handle)
{
    auto* i = reinterpret_cast<Instance*>(handle);
    return live(runtime().instances, i) ? i : nullptr;
}
Session* sessionOf(XrSession handle)
{
    auto* s = reinterpret_cast<Session*>(handle);
    return live(runtime().sessions, s) ? s : nullptr;
}

void destroySessionLocked(Session* s);

XRAPI_ATTR XrResult XRAPI_CALL destroyInstance(XrInstance handle)
{
    LOCK;
    Instance* instance = instanceOf(handle);
    if (!instance) return XR_ERROR_HANDLE_INVALID;
    std::vector<Session*> owned;
    for (Session* s : runtime().sessions)
        if (s->instance == instance) owned.push_back(s);
    for (Session* s : owned) destroySessionLocked(s);
    for (auto it = runtime().actionSets.begin(); it != runtime().actionSets.end();) {
        if ((*it)->instance == instance) {
            for (auto a = runtime().actions.begin(); a != runtime().actions.end();) {
                if ((*a)->set == *it) {
                    delete *a;
                    a = runtime().actions.erase(a);
                } else {
                    ++a;
                }
            }
            delete *it;
            it = runtime().actionSets.erase(it);
        } else {
            ++it;
        }
    }
    runtime().instances.erase(instance);
    delete instance;
    if (runtime().log) std::fflush(runtime().log);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getInstanceProperties(XrInstance handle, XrInstanceProperties* p)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (!p) return XR_ERROR_VALIDATION_FAILURE;
    p->runtimeVersion = XR_MAKE_VERSION(1, 0, 0);
    std::snprintf(p->runtimeName, sizeof p->runtimeName, "FakeXR (vdbclay tests)");
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL pollEvent(XrInstance handle, XrEventDataBuffer* event)
{
    LOCK;
    Instance* instance = instanceOf(handle);
    if (!instance) return XR_ERROR_HANDLE_INVALID;
    if (!event) return XR_ERROR_VALIDATION_FAILURE;
    if (instance->events.empty()) return XR_EVENT_UNAVAILABLE;
    *event = instance->events.front();
    instance->events.pop_front();
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL resultToString(XrInstance, XrResult value, char buffer[XR_MAX_RESULT_STRING_SIZE])
{
#define FAKEXR_RESULT(name, number) \
    case name: std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "%s", #name); return XR_SUCCESS;
    switch (value) {
        XR_LIST_ENUM_XrResult(FAKEXR_RESULT)
    default: std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "XR_UNKNOWN_%s_%d", value < 0 ? "FAILURE" : "SUCCESS", int(value));
    }
#undef FAKEXR_RESULT
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL structureTypeToString(XrInstance, XrStructureType value, char buffer[XR_MAX_STRUCTURE_NAME_SIZE])
{
#define FAKEXR_TYPE(name, number) \
    case name: std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "%s", #name); return XR_SUCCESS;
    switch (value) {
        XR_LIST_ENUM_XrStructureType(FAKEXR_TYPE)
    default: std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "XR_UNKNOWN_STRUCTURE_TYPE_%d", int(value));
    }
#undef FAKEXR_TYPE
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getSystem(XrInstance handle, const XrSystemGetInfo* info, XrSystemId* system)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (!info || !system || info->type != XR_TYPE_SYSTEM_GET_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY) return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
    *system = kSystem;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getSystemProperties(XrInstance handle, XrSystemId system, XrSystemProperties* p)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
    if (!p) return XR_ERROR_VALIDATION_FAILURE;
    p->systemId = kSystem;
    p->vendorId = 0xfa4e;
    std::snprintf(p->systemName, sizeof p->systemName, "FakeXR headset");
    p->graphicsProperties.maxSwapchainImageWidth = 4096;
    p->graphicsProperties.maxSwapchainImageHeight = 4096;
    p->graphicsProperties.maxLayerCount = 16;
    p->trackingProperties.orientationTracking = XR_TRUE;
    p->trackingProperties.positionTracking = XR_TRUE;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL enumerateEnvironmentBlendModes(XrInstance handle, XrSystemId system, XrViewConfigurationType,
                                                              uint32_t capacity, uint32_t* count, XrEnvironmentBlendMode* modes)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
    return copyArray(std::vector<XrEnvironmentBlendMode>{XR_ENVIRONMENT_BLEND_MODE_OPAQUE}, capacity, count, modes);
}

XRAPI_ATTR XrResult XRAPI_CALL enumerateViewConfigurations(XrInstance handle, XrSystemId system, uint32_t capacity, uint32_t* count,
                                                           XrViewConfigurationType* types)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
    return copyArray(viewConfigurations(), capacity, count, types);
}

bool offeredConfiguration(XrViewConfigurationType type)
{
    const auto all = viewConfigurations();
    return std::find(all.begin(), all.end(), type) != all.end();
}

XRAPI_ATTR XrResult XRAPI_CALL getViewConfigurationProperties(XrInstance handle, XrSystemId system, XrViewConfigurationType type,
                                                              XrViewConfigurationProperties* p)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
    if (!offeredConfiguration(type)) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    if (!p) return XR_ERROR_VALIDATION_FAILURE;
    p->viewConfigurationType = type;
    p->fovMutable = XR_FALSE;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL enumerateViewConfigurationViews(XrInstance handle, XrSystemId system, XrViewConfigurationType type,
                                                               uint32_t capacity, uint32_t* count, XrViewConfigurationView* views)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
    if (!offeredConfiguration(type)) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    const HeadsetScript& s = runtime().script;
    if (!count) return XR_ERROR_VALIDATION_FAILURE;
    *count = viewCount(type);
    if (capacity == 0) return XR_SUCCESS;
    if (capacity < *count) return XR_ERROR_SIZE_INSUFFICIENT;
    for (uint32_t i = 0; i < *count; ++i) {
        views[i].recommendedImageRectWidth = uint32_t(s.width);
        views[i].recommendedImageRectHeight = uint32_t(s.height);
        views[i].maxImageRectWidth = 4096;
        views[i].maxImageRectHeight = 4096;
        views[i].recommendedSwapchainSampleCount = 1;
        views[i].maxSwapchainSampleCount = 1;
    }
    return XR_SUCCESS;
}

// --- Vulkan (XR_KHR_vulkan_enable2) -----------------------------------------------------------------

bool enabled(const Instance* i, const char* extension) { return i->extensions.count(extension) > 0; }

XRAPI_ATTR XrResult XRAPI_CALL getVulkanGraphicsRequirements2(XrInstance handle, XrSystemId system, XrGraphicsRequirementsVulkanKHR* r)
{
    LOCK;
    Instance* instance = instanceOf(handle);
    if (!instance) return XR_ERROR_HANDLE_INVALID;
    if (!enabled(instance, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME)) return XR_ERROR_FUNCTION_UNSUPPORTED;
    if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
    if (!r) return XR_ERROR_VALIDATION_FAILURE;
    r->minApiVersionSupported = XR_MAKE_VERSION(1, 0, 0);
    r->maxApiVersionSupported = XR_MAKE_VERSION(1, 3, 0);
    instance->requirementsQueried = true;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL createVulkanInstance(XrInstance handle, const XrVulkanInstanceCreateInfoKHR* info, VkInstance* out,
                                                    VkResult* vkResult)
{
    {
        LOCK;
        Instance* instance = instanceOf(handle);
        if (!instance) return XR_ERROR_HANDLE_INVALID;
        if (!enabled(instance, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME)) return XR_ERROR_FUNCTION_UNSUPPORTED;
        if (!info || !out || !vkResult || !info->vulkanCreateInfo || !info->pfnGetInstanceProcAddr) return XR_ERROR_VALIDATION_FAILURE;
        if (info->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
    }
    *vkResult = createAppInstance(info->pfnGetInstanceProcAddr, *info->vulkanCreateInfo, info->vulkanAllocator, out);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getVulkanGraphicsDevice2(XrInstance handle, const XrVulkanGraphicsDeviceGetInfoKHR* info, VkPhysicalDevice* out)
{
    {
        LOCK;
        Instance* instance = instanceOf(handle);
        if (!instance) return XR_ERROR_HANDLE_INVALID;
        if (!enabled(instance, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME)) return XR_ERROR_FUNCTION_UNSUPPORTED;
        if (!info || !out || !info->vulkanInstance) return XR_ERROR_VALIDATION_FAILURE;
        if (info->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
    }
    *out = choosePhysicalDevice(info->vulkanInstance);
    return *out ? XR_SUCCESS : XR_ERROR_RUNTIME_FAILURE;
}

XRAPI_ATTR XrResult XRAPI_CALL createVulkanDevice(XrInstance handle, const XrVulkanDeviceCreateInfoKHR* info, VkDevice* out, VkResult* vkResult)
{
    {
        LOCK;
        Instance* instance = instanceOf(handle);
        if (!instance) return XR_ERROR_HANDLE_INVALID;
        if (!enabled(instance, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME)) return XR_ERROR_FUNCTION_UNSUPPORTED;
        if (!info || !out || !vkResult || !info->vulkanCreateInfo || !info->vulkanPhysicalDevice || !info->pfnGetInstanceProcAddr)
            return XR_ERROR_VALIDATION_FAILURE;
        if (info->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
    }
    *vkResult = createAppDevice(info->vulkanPhysicalDevice, *info->vulkanCreateInfo, info->vulkanAllocator, out);
    return XR_SUCCESS;
}

// --- sessions ---------------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL createSession(XrInstance handle, const XrSessionCreateInfo* info, XrSession* out)
{
    LOCK;
    Instance* instance = instanceOf(handle);
    if (!instance) return XR_ERROR_HANDLE_INVALID;
    if (!info || !out || info->type != XR_TYPE_SESSION_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (info->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
    const XrGraphicsBindingVulkanKHR* binding = nullptr;
    for (const auto* next = static_cast<const XrBaseInStructure*>(info->next); next && !binding; next = next->next)
        if (next->type == XR_TYPE_GRAPHICS_BINDING_VULKAN_KHR) binding = reinterpret_cast<const XrGraphicsBindingVulkanKHR*>(next);
    if (!binding) return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    if (!instance->requirementsQueried) return XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
    auto session = std::make_unique<Session>();
    session->instance = instance;
    try {
        session->vulkan = bindVulkan(binding->instance, binding->physicalDevice, binding->device, binding->queueFamilyIndex, binding->queueIndex);
    } catch (const std::exception& e) {
        runtime().violation("xrCreateSession: %s", e.what());
        return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    }
    Session* s = session.release();
    runtime().sessions.insert(s);
    *out = reinterpret_cast<XrSession>(s);
    setState(s, XR_SESSION_STATE_IDLE);
    setState(s, XR_SESSION_STATE_READY);
    return XR_SUCCESS;
}

void destroySwapchainLocked(Swapchain* sc)
{
    releaseImages(sc->session->vulkan, sc->images);
    runtime().swapchains.erase(sc);
    delete sc;
}

void destroySessionLocked(Session* s)
{
    std::vector<Swapchain*> chains;
    for (Swapchain* sc : runtime().swapchains)
        if (sc->session == s) chains.push_back(sc);
    for (Swapchain* sc : chains) destroySwapchainLocked(sc);
    for (auto it = runtime().spaces.begin(); it != runtime().spaces.end();) {
        if ((*it)->session == s) {
            delete *it;
            it = runtime().spaces.erase(it);
        } else {
            ++it;
        }
    }
    unbindVulkan(s->vulkan);
    // Events about it that were not read are dropped with it.
    auto& events = s->instance->events;
    events.erase(std::remove_if(events.begin(), events.end(),
                                [&](const XrEventDataBuffer& e) {
                                    return e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED &&
                                           reinterpret_cast<const XrEventDataSessionStateChanged&>(e).session == reinterpret_cast<XrSession>(s);
                                }),
                 events.end());
    runtime().sessions.erase(s);
    delete s;
}

XRAPI_ATTR XrResult XRAPI_CALL destroySession(XrSession handle)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (s->running && s->state != XR_SESSION_STATE_LOSS_PENDING)
        runtime().violation("xrDestroySession: the session is running (state %d): end it first", int(s->state));
    destroySessionLocked(s);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL beginSession(XrSession handle, const XrSessionBeginInfo* info)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_SESSION_BEGIN_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (s->running) return XR_ERROR_SESSION_RUNNING;
    if (s->state != XR_SESSION_STATE_READY) {
        runtime().violation("xrBeginSession in state %d (the session must be READY)", int(s->state));
        return XR_ERROR_SESSION_NOT_READY;
    }
    if (!offeredConfiguration(info->primaryViewConfigurationType)) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    s->viewConfiguration = info->primaryViewConfigurationType;
    s->running = true;
    setState(s, XR_SESSION_STATE_SYNCHRONIZED);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL endSession(XrSession handle)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    if (s->state != XR_SESSION_STATE_STOPPING) {
        runtime().violation("xrEndSession in state %d (the session must be STOPPING)", int(s->state));
        return XR_ERROR_SESSION_NOT_STOPPING;
    }
    for (Swapchain* sc : runtime().swapchains)
        if (sc->session == s && (!sc->acquired.empty() || sc->waited))
            runtime().violation("xrEndSession: a swapchain still holds an acquired image");
    s->running = false;
    s->waitedNotBegun = s->begun = false;
    setState(s, XR_SESSION_STATE_IDLE);
    if (s->exitRequested || runtime().script.stopAfterFrames) setState(s, XR_SESSION_STATE_EXITING);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL requestExitSession(XrSession handle)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    s->exitRequested = true;
    if (s->state != XR_SESSION_STATE_STOPPING && s->state != XR_SESSION_STATE_LOSS_PENDING) {
        if (s->state == XR_SESSION_STATE_FOCUSED) setState(s, XR_SESSION_STATE_VISIBLE);
        if (s->state == XR_SESSION_STATE_VISIBLE) setState(s, XR_SESSION_STATE_SYNCHRONIZED);
        setState(s, XR_SESSION_STATE_STOPPING);
    }
    return XR_SUCCESS;
}

// --- spaces -----------------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL enumerateReferenceSpaces(XrSession handle, uint32_t capacity, uint32_t* count, XrReferenceSpaceType* types)
{
    LOCK;
    if (!sessionOf(handle)) return XR_ERROR_HANDLE_INVALID;
    return copyArray(std::vector<XrReferenceSpaceType>{XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL, XR_REFERENCE_SPACE_TYPE_STAGE},
                     capacity, count, types);
}

XRAPI_ATTR XrResult XRAPI_CALL createReferenceSpace(XrSession handle, const XrReferenceSpaceCreateInfo* info, XrSpace* out)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || !out || info->type != XR_TYPE_REFERENCE_SPACE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_VIEW && info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_LOCAL &&
        info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE)
        return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
    auto* space = new Space{s, info->referenceSpaceType, nullptr, XR_NULL_PATH, info->poseInReferenceSpace};
    runtime().spaces.insert(space);
    *out = reinterpret_cast<XrSpace>(space);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getReferenceSpaceBoundsRect(XrSession handle, XrReferenceSpaceType type, XrExtent2Df* bounds)
{
    LOCK;
    if (!sessionOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (!bounds) return XR_ERROR_VALIDATION_FAILURE;
    if (type == XR_REFERENCE_SPACE_TYPE_STAGE) {
        *bounds = {3.0f, 3.0f};
        return XR_SUCCESS;
    }
    *bounds = {0, 0};
    return XR_SPACE_BOUNDS_UNAVAILABLE;
}

Action* actionOf(XrAction handle)
{
    auto* a = reinterpret_cast<Action*>(handle);
    return live(runtime().actions, a) ? a : nullptr;
}

XRAPI_ATTR XrResult XRAPI_CALL createActionSpace(XrSession handle, const XrActionSpaceCreateInfo* info, XrSpace* out)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || !out || info->type != XR_TYPE_ACTION_SPACE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    Action* a = actionOf(info->action);
    if (!a) return XR_ERROR_HANDLE_INVALID;
    if (a->type != XR_ACTION_TYPE_POSE_INPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
    if (!knownSubaction(a, info->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
    auto* space = new Space{s, XrReferenceSpaceType(0), a, info->subactionPath, info->poseInActionSpace};
    runtime().spaces.insert(space);
    *out = reinterpret_cast<XrSpace>(space);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL locateSpace(XrSpace spaceHandle, XrSpace baseHandle, XrTime time, XrSpaceLocation* location)
{
    LOCK;
    auto* space = reinterpret_cast<Space*>(spaceHandle);
    auto* base = reinterpret_cast<Space*>(baseHandle);
    if (!live(runtime().spaces, space) || !live(runtime().spaces, base)) return XR_ERROR_HANDLE_INVALID;
    if (!location || location->type != XR_TYPE_SPACE_LOCATION) return XR_ERROR_VALIDATION_FAILURE;
    if (time <= 0) return XR_ERROR_TIME_INVALID;
    XrPosef a, b;
    if (!spacePose(space, time, &a) || !spacePose(base, time, &b)) {
        location->locationFlags = 0;
        return XR_SUCCESS;
    }
    location->pose = multiply(inverse(b), a);
    location->locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
                              XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL destroySpace(XrSpace handle)
{
    LOCK;
    auto* space = reinterpret_cast<Space*>(handle);
    if (!live(runtime().spaces, space)) return XR_ERROR_HANDLE_INVALID;
    runtime().spaces.erase(space);
    delete space;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL locateViews(XrSession handle, const XrViewLocateInfo* info, XrViewState* state, uint32_t capacity,
                                           uint32_t* count, XrView* views)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || !state || !count || info->type != XR_TYPE_VIEW_LOCATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (!offeredConfiguration(info->viewConfigurationType)) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    auto* base = reinterpret_cast<Space*>(info->space);
    if (!live(runtime().spaces, base)) return XR_ERROR_HANDLE_INVALID;
    if (info->displayTime <= 0) return XR_ERROR_TIME_INVALID;
    const uint32_t n = viewCount(info->viewConfigurationType);
    *count = n;
    if (capacity == 0) return XR_SUCCESS;
    if (capacity < n) return XR_ERROR_SIZE_INSUFFICIENT;
    XrPosef basePose;
    if (!spacePose(base, info->displayTime, &basePose)) {
        state->viewStateFlags = 0;
        return XR_SUCCESS;
    }
    const XrPosef head = headPose(s, info->displayTime);
    const double ipd = runtime().script.ipd;
    for (uint32_t i = 0; i < n; ++i) {
        const float side = n == 1 ? 0.0f : (i == 0 ? -0.5f : 0.5f);
        const XrPosef eye = multiply(head, XrPosef{{0, 0, 0, 1}, {float(side * ipd), 0, 0}});
        views[i].pose = multiply(inverse(basePose), eye);
        views[i].fov = runtime().script.fov;
    }
    state->viewStateFlags = XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT |
                            XR_VIEW_STATE_ORIENTATION_TRACKED_BIT | XR_VIEW_STATE_POSITION_TRACKED_BIT;
    if (info->displayTime == s->predicted) {
        s->locateAt = Clock::now();
        s->locateTime = info->displayTime;
    }
    return XR_SUCCESS;
}

// --- swapchains -------------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL enumerateSwapchainFormats(XrSession handle, uint32_t capacity, uint32_t* count, int64_t* formats)
{
    LOCK;
    if (!sessionOf(handle)) return XR_ERROR_HANDLE_INVALID;
    return copyArray(runtime().script.formats, capacity, count, formats);
}

XRAPI_ATTR XrResult XRAPI_CALL createSwapchain(XrSession handle, const XrSwapchainCreateInfo* info, XrSwapchain* out)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || !out || info->type != XR_TYPE_SWAPCHAIN_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    const auto& formats = runtime().script.formats;
    if (std::find(formats.begin(), formats.end(), info->format) == formats.end()) return XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED;
    if (info->width == 0 || info->height == 0 || info->width > 4096 || info->height > 4096 || info->arraySize == 0 ||
        info->mipCount == 0 || info->faceCount != 1 || info->sampleCount != 1)
        return XR_ERROR_VALIDATION_FAILURE;
    auto sc = std::make_unique<Swapchain>();
    sc->session = s;
    sc->info = *info;
    try {
        sc->images = createImages(s->vulkan, *info, 3);
    } catch (const std::exception& e) {
        runtime().violation("xrCreateSwapchain: %s", e.what());
        return XR_ERROR_RUNTIME_FAILURE;
    }
    *out = reinterpret_cast<XrSwapchain>(sc.get());
    runtime().swapchains.insert(sc.release());
    return XR_SUCCESS;
}

Swapchain* swapchainOf(XrSwapchain handle)
{
    auto* sc = reinterpret_cast<Swapchain*>(handle);
    return live(runtime().swapchains, sc) ? sc : nullptr;
}

XRAPI_ATTR XrResult XRAPI_CALL destroySwapchain(XrSwapchain handle)
{
    LOCK;
    Swapchain* sc = swapchainOf(handle);
    if (!sc) return XR_ERROR_HANDLE_INVALID;
    destroySwapchainLocked(sc);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL enumerateSwapchainImages(XrSwapchain handle, uint32_t capacity, uint32_t* count, XrSwapchainImageBaseHeader* images)
{
    LOCK;
    Swapchain* sc = swapchainOf(handle);
    if (!sc) return XR_ERROR_HANDLE_INVALID;
    if (!count) return XR_ERROR_VALIDATION_FAILURE;
    const uint32_t n = uint32_t(sc->images.images.size());
    *count = n;
    if (capacity == 0) return XR_SUCCESS;
    if (capacity < n) return XR_ERROR_SIZE_INSUFFICIENT;
    auto* vk = reinterpret_cast<XrSwapchainImageVulkanKHR*>(images);
    for (uint32_t i = 0; i < n; ++i) {
        if (vk[i].type != XR_TYPE_SWAPCHAIN_IMAGE_VULKAN_KHR) return XR_ERROR_VALIDATION_FAILURE;
        vk[i].image = sc->images.images[i];
    }
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL acquireSwapchainImage(XrSwapchain handle, const XrSwapchainImageAcquireInfo*, uint32_t* index)
{
    LOCK;
    Swapchain* sc = swapchainOf(handle);
    if (!sc) return XR_ERROR_HANDLE_INVALID;
    if (!index) return XR_ERROR_VALIDATION_FAILURE;
    const std::size_t held = sc->acquired.size() + (sc->waited ? 1 : 0);
    if (held >= sc->images.images.size()) {
        runtime().violation("xrAcquireSwapchainImage: every image of the swapchain is acquired already");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    *index = sc->nextAcquire;
    sc->acquired.push_back(*index);
    sc->nextAcquire = (sc->nextAcquire + 1) % uint32_t(sc->images.images.size());
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL waitSwapchainImage(XrSwapchain handle, const XrSwapchainImageWaitInfo* info)
{
    LOCK;
    Swapchain* sc = swapchainOf(handle);
    if (!sc) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (sc->waited) {
        runtime().violation("xrWaitSwapchainImage: an image was waited for and not released yet");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    if (sc->acquired.empty()) {
        runtime().violation("xrWaitSwapchainImage: no image is acquired");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    sc->waited = sc->acquired.front();
    sc->acquired.pop_front();
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL releaseSwapchainImage(XrSwapchain handle, const XrSwapchainImageReleaseInfo*)
{
    LOCK;
    Swapchain* sc = swapchainOf(handle);
    if (!sc) return XR_ERROR_HANDLE_INVALID;
    if (!sc->waited) {
        runtime().violation("xrReleaseSwapchainImage: no image was waited for");
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    sc->lastReleased = sc->waited;
    sc->waited.reset();
    sc->releasedInFrame = sc->session->framesBegun;
    return XR_SUCCESS;
}

// --- the frame loop ---------------------------------------------------------------------------------

/// Runtime-side events tied to frames: focus lost and back, asked to stop, the session lost.
void scriptedEvents(Session* s)
{
    const HeadsetScript& script = runtime().script;
    const uint64_t f = s->framesWaited;
    if (s->state == XR_SESSION_STATE_STOPPING || s->state == XR_SESSION_STATE_LOSS_PENDING) return;
    if (script.lossPendingAt && f == *script.lossPendingAt) {
        setState(s, XR_SESSION_STATE_LOSS_PENDING);
        return;
    }
    if (script.stopAfterFrames && f >= script.stopAfterFrames) {
        if (s->state == XR_SESSION_STATE_FOCUSED) setState(s, XR_SESSION_STATE_VISIBLE);
        if (s->state == XR_SESSION_STATE_VISIBLE) setState(s, XR_SESSION_STATE_SYNCHRONIZED);
        setState(s, XR_SESSION_STATE_STOPPING);
        return;
    }
    if (script.focusLostAt && f == *script.focusLostAt && s->state == XR_SESSION_STATE_FOCUSED) setState(s, XR_SESSION_STATE_VISIBLE);
    if (script.focusBackAt && f == *script.focusBackAt && s->state == XR_SESSION_STATE_VISIBLE) setState(s, XR_SESSION_STATE_FOCUSED);
}

XRAPI_ATTR XrResult XRAPI_CALL waitFrame(XrSession handle, const XrFrameWaitInfo* info, XrFrameState* state)
{
    Clock::time_point wakeAt;
    {
        LOCK;
        Session* s = sessionOf(handle);
        if (!s) return XR_ERROR_HANDLE_INVALID;
        if (!state || state->type != XR_TYPE_FRAME_STATE || (info && info->type != XR_TYPE_FRAME_WAIT_INFO)) return XR_ERROR_VALIDATION_FAILURE;
        if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
        if (s->waitedNotBegun) {
            runtime().violation("xrWaitFrame called again before xrBeginFrame (frame %llu)", (unsigned long long)s->framesWaited);
            return XR_ERROR_CALL_ORDER_INVALID;
        }
        // The display refreshes at t0 + k P: the frame shows at the refresh after the next one, and a
        // paced runtime lets the application start it at the next refresh.
        const XrDuration P = runtime().period();
        const XrTime now = runtime().now();
        XrTime next = (now / P + 1) * P;
        if (runtime().script.pace && s->predicted && next < s->predicted) next = s->predicted; // one frame per refresh
        s->predicted = next + P;
        s->frameOfTime[s->predicted] = s->framesWaited;
        while (s->frameOfTime.size() > 64) s->frameOfTime.erase(s->frameOfTime.begin());
        state->predictedDisplayTime = s->predicted;
        state->predictedDisplayPeriod = P;
        state->shouldRender = (s->state == XR_SESSION_STATE_VISIBLE || s->state == XR_SESSION_STATE_FOCUSED) ? XR_TRUE : XR_FALSE;
        s->waitedNotBegun = true;
        wakeAt = Clock::now() + std::chrono::nanoseconds(runtime().script.pace ? std::max<XrTime>(0, next - now) : 0);
        ++s->framesWaited;
    }
    std::this_thread::sleep_until(wakeAt);
    LOCK;
    if (Session* s = sessionOf(handle)) s->waitReturned = Clock::now();
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL beginFrame(XrSession handle, const XrFrameBeginInfo* info)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (info && info->type != XR_TYPE_FRAME_BEGIN_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    if (!s->waitedNotBegun) {
        runtime().violation("xrBeginFrame without a preceding xrWaitFrame (frame %llu)", (unsigned long long)s->framesBegun);
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    s->waitedNotBegun = false;
    const bool discarded = s->begun;
    s->begun = true;
    s->begunPredicted = s->predicted;
    s->beginAt = Clock::now();
    ++s->framesBegun;
    return discarded ? XR_FRAME_DISCARDED : XR_SUCCESS;
}

void logFrame(Session* s, const XrFrameEndInfo* info, bool missed)
{
    FILE* log = runtime().log;
    if (!log) return;
    auto ms = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
    const Clock::time_point end = Clock::now();
    const bool located = s->locateTime == info->displayTime;
    std::fprintf(log,
                 "{\"frame\": %llu, \"predicted_display_ns\": %lld, \"layers\": %u, \"missed\": %s, \"wait_to_end_ms\": %.3f, "
                 "\"begin_to_end_ms\": %.3f, \"pose_to_submit_ms\": %s}\n",
                 (unsigned long long)(s->framesEnded), (long long)info->displayTime, info->layerCount, missed ? "true" : "false",
                 ms(s->waitReturned, end), ms(s->beginAt, end), located ? std::to_string(ms(s->locateAt, end)).c_str() : "null");
    std::fflush(log);
}

void checkProjection(Session* s, const XrCompositionLayerProjection* layer, uint64_t frame)
{
    const uint32_t expected = viewCount(s->viewConfiguration);
    if (layer->viewCount != expected) {
        runtime().violation("xrEndFrame: a projection layer with %u views (the view configuration has %u)", layer->viewCount, expected);
        return;
    }
    if (!live(runtime().spaces, reinterpret_cast<Space*>(layer->space))) runtime().violation("xrEndFrame: a projection layer's space is invalid");
    for (uint32_t v = 0; v < layer->viewCount; ++v) {
        const XrCompositionLayerProjectionView& view = layer->views[v];
        Swapchain* sc = swapchainOf(view.subImage.swapchain);
        if (!sc) {
            runtime().violation("xrEndFrame: view %u names an invalid swapchain", v);
            continue;
        }
        if (sc->releasedInFrame != s->framesBegun)
            runtime().violation("xrEndFrame: view %u's swapchain released no image in frame %llu", v, (unsigned long long)frame);
        const XrRect2Di& r = view.subImage.imageRect;
        if (r.offset.x < 0 || r.offset.y < 0 || r.extent.width <= 0 || r.extent.height <= 0 ||
            uint32_t(r.offset.x + r.extent.width) > sc->info.width || uint32_t(r.offset.y + r.extent.height) > sc->info.height ||
            view.subImage.imageArrayIndex >= sc->info.arraySize)
            runtime().violation("xrEndFrame: view %u's image rectangle lies outside its swapchain", v);
        for (const auto* next = static_cast<const XrBaseInStructure*>(view.next); next; next = next->next) {
            if (next->type != XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR) continue;
            if (!s->instance->extensions.count(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME))
                runtime().violation("xrEndFrame: depth submitted without XR_KHR_composition_layer_depth enabled");
            const auto* depth = reinterpret_cast<const XrCompositionLayerDepthInfoKHR*>(next);
            Swapchain* d = swapchainOf(depth->subImage.swapchain);
            if (!d) runtime().violation("xrEndFrame: view %u's depth names an invalid swapchain", v);
            else if (d->releasedInFrame != s->framesBegun) runtime().violation("xrEndFrame: view %u's depth swapchain released no image this frame", v);
            if (!(depth->minDepth >= 0 && depth->minDepth <= depth->maxDepth && depth->maxDepth <= 1) || !(depth->nearZ > 0 || depth->farZ > 0))
                runtime().violation("xrEndFrame: view %u's depth range is invalid", v);
        }
    }
    if (runtime().script.capture.count(frame) && !runtime().captureFolder.empty()) {
        for (uint32_t v = 0; v < layer->viewCount; ++v) {
            Swapchain* sc = swapchainOf(layer->views[v].subImage.swapchain);
            if (!sc || !sc->lastReleased) continue;
            char name[64];
            std::snprintf(name, sizeof name, "/frame-%05llu-view-%u.ppm", (unsigned long long)frame, v);
            try {
                captureImage(s->vulkan, sc->images, *sc->lastReleased, layer->views[v].subImage, runtime().captureFolder + name);
            } catch (const std::exception& e) {
                runtime().violation("capture: %s", e.what());
            }
        }
    }
}

XRAPI_ATTR XrResult XRAPI_CALL endFrame(XrSession handle, const XrFrameEndInfo* info)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_FRAME_END_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    if (!s->begun) {
        runtime().violation("xrEndFrame without xrBeginFrame (frame %llu)", (unsigned long long)s->framesEnded);
        return XR_ERROR_CALL_ORDER_INVALID;
    }
    if (info->displayTime != s->begunPredicted) {
        runtime().violation("xrEndFrame: displayTime %lld is not the predicted display time %lld of the frame begun",
                            (long long)info->displayTime, (long long)s->begunPredicted);
        return XR_ERROR_TIME_INVALID;
    }
    if (info->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE) return XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED;
    if (info->layerCount > 16) return XR_ERROR_LAYER_LIMIT_EXCEEDED;
    for (Swapchain* sc : runtime().swapchains)
        if (sc->session == s && sc->waited) runtime().violation("xrEndFrame: a swapchain image waited for was not released");
    const uint64_t frame = s->framesEnded;
    for (uint32_t i = 0; i < info->layerCount; ++i) {
        const XrCompositionLayerBaseHeader* layer = info->layers[i];
        if (!layer) return XR_ERROR_LAYER_INVALID;
        if (layer->type == XR_TYPE_COMPOSITION_LAYER_PROJECTION)
            checkProjection(s, reinterpret_cast<const XrCompositionLayerProjection*>(layer), frame);
    }
    const bool missed = runtime().now() > info->displayTime;
    logFrame(s, info, missed);
    s->begun = false;
    ++s->framesEnded;
    if (s->state == XR_SESSION_STATE_SYNCHRONIZED && s->framesEnded == 1) {
        setState(s, XR_SESSION_STATE_VISIBLE);
        setState(s, XR_SESSION_STATE_FOCUSED);
    }
    scriptedEvents(s);
    return s->state == XR_SESSION_STATE_LOSS_PENDING ? XR_SESSION_LOSS_PENDING : XR_SUCCESS;
}

// --- paths and actions ------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL stringToPath(XrInstance handle, const char* text, XrPath* path)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (!text || !path) return XR_ERROR_VALIDATION_FAILURE;
    const std::string s = text;
    if (s.empty() || s[0] != '/' || s.back() == '/' || s.find("//") != std::string::npos) return XR_ERROR_PATH_FORMAT_INVALID;
    *path = runtime().path(s);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL pathToString(XrInstance handle, XrPath path, uint32_t capacity, uint32_t* count, char* buffer)
{
    LOCK;
    if (!instanceOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (path == XR_NULL_PATH || path >= runtime().paths.size()) return XR_ERROR_PATH_INVALID;
    return copyString(runtime().paths[path], capacity, count, buffer);
}

XRAPI_ATTR XrResult XRAPI_CALL createActionSet(XrInstance handle, const XrActionSetCreateInfo* info, XrActionSet* out)
{
    LOCK;
    Instance* instance = instanceOf(handle);
    if (!instance) return XR_ERROR_HANDLE_INVALID;
    if (!info || !out || info->type != XR_TYPE_ACTION_SET_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (!info->actionSetName[0]) return XR_ERROR_NAME_INVALID;
    for (ActionSet* set : runtime().actionSets)
        if (set->instance == instance && set->name == info->actionSetName) return XR_ERROR_NAME_DUPLICATED;
    auto* set = new ActionSet{instance, info->actionSetName};
    runtime().actionSets.insert(set);
    *out = reinterpret_cast<XrActionSet>(set);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL destroyActionSet(XrActionSet handle)
{
    LOCK;
    auto* set = reinterpret_cast<ActionSet*>(handle);
    if (!live(runtime().actionSets, set)) return XR_ERROR_HANDLE_INVALID;
    for (auto a = runtime().actions.begin(); a != runtime().actions.end();) {
        if ((*a)->set == set) {
            delete *a;
            a = runtime().actions.erase(a);
        } else {
            ++a;
        }
    }
    runtime().actionSets.erase(set);
    delete set;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL createAction(XrActionSet handle, const XrActionCreateInfo* info, XrAction* out)
{
    LOCK;
    auto* set = reinterpret_cast<ActionSet*>(handle);
    if (!live(runtime().actionSets, set)) return XR_ERROR_HANDLE_INVALID;
    if (!info || !out || info->type != XR_TYPE_ACTION_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    if (!info->actionName[0]) return XR_ERROR_NAME_INVALID;
    for (Action* a : runtime().actions)
        if (a->set == set && a->name == info->actionName) return XR_ERROR_NAME_DUPLICATED;
    auto* action = new Action{set, info->actionName, info->actionType,
                              std::vector<XrPath>(info->subactionPaths, info->subactionPaths + info->countSubactionPaths)};
    runtime().actions.insert(action);
    *out = reinterpret_cast<XrAction>(action);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL destroyAction(XrAction handle)
{
    LOCK;
    Action* a = actionOf(handle);
    if (!a) return XR_ERROR_HANDLE_INVALID;
    runtime().actions.erase(a);
    delete a;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL suggestInteractionProfileBindings(XrInstance handle, const XrInteractionProfileSuggestedBinding* info)
{
    LOCK;
    Instance* instance = instanceOf(handle);
    if (!instance) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING || info->countSuggestedBindings == 0)
        return XR_ERROR_VALIDATION_FAILURE;
    const std::string profile = runtime().name(info->interactionProfile);
    if (profile.rfind("/interaction_profiles/", 0) != 0) return XR_ERROR_PATH_UNSUPPORTED;
    std::vector<std::pair<Action*, XrPath>> bindings;
    for (uint32_t i = 0; i < info->countSuggestedBindings; ++i) {
        Action* a = actionOf(info->suggestedBindings[i].action);
        if (!a) return XR_ERROR_HANDLE_INVALID;
        if (a->set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
        const std::string in = runtime().name(info->suggestedBindings[i].binding);
        if (in.rfind("/user/", 0) != 0) return XR_ERROR_PATH_UNSUPPORTED;
        bindings.emplace_back(a, info->suggestedBindings[i].binding);
    }
    instance->bindings[info->interactionProfile] = std::move(bindings); // a later suggestion replaces the profile's
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL attachSessionActionSets(XrSession handle, const XrSessionActionSetsAttachInfo* info)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (!s->attachedSets.empty()) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    for (uint32_t i = 0; i < info->countActionSets; ++i) {
        auto* set = reinterpret_cast<ActionSet*>(info->actionSets[i]);
        if (!live(runtime().actionSets, set)) return XR_ERROR_HANDLE_INVALID;
        set->attached = true;
        s->attachedSets.push_back(set);
    }
    XrEventDataBuffer buffer{XR_TYPE_EVENT_DATA_BUFFER};
    auto* e = reinterpret_cast<XrEventDataInteractionProfileChanged*>(&buffer);
    e->type = XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED;
    e->next = nullptr;
    e->session = handle;
    pushEvent(s->instance, buffer);
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getCurrentInteractionProfile(XrSession handle, XrPath topLevel, XrInteractionProfileState* state)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!state || state->type != XR_TYPE_INTERACTION_PROFILE_STATE) return XR_ERROR_VALIDATION_FAILURE;
    if (s->attachedSets.empty()) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    if (handOf(topLevel) < 0 && runtime().name(topLevel) != "/user/head") return XR_ERROR_PATH_UNSUPPORTED;
    const XrPath profile = runtime().path(runtime().script.profile);
    state->interactionProfile = s->instance->bindings.count(profile) && handOf(topLevel) >= 0 ? profile : XR_NULL_PATH;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL syncActions(XrSession handle, const XrActionsSyncInfo* info)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_ACTIONS_SYNC_INFO) return XR_ERROR_VALIDATION_FAILURE;
    for (uint32_t i = 0; i < info->countActiveActionSets; ++i) {
        auto* set = reinterpret_cast<ActionSet*>(info->activeActionSets[i].actionSet);
        if (!live(runtime().actionSets, set)) return XR_ERROR_HANDLE_INVALID;
        if (!set->attached) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    }
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    if (!s->focused()) return XR_SESSION_NOT_FOCUSED;
    s->syncedFrame = s->framesWaited ? s->framesWaited - 1 : 0;
    const XrTime now = runtime().now();
    for (Action* a : runtime().actions) {
        if (!a->set->attached) continue;
        std::vector<XrPath> subs = a->subactionPaths;
        subs.push_back(XR_NULL_PATH);
        for (XrPath sub : subs) {
            float x = 0, y = 0;
            actionValue(s, a, sub, &x, &y);
            const auto key = std::make_pair(a, sub);
            auto it = s->lastSynced.find(key);
            const bool changed = it == s->lastSynced.end() ? (x != 0 || y != 0) : (it->second[0] != x || it->second[1] != y);
            s->changed[key] = changed;
            if (changed) s->changeTime[key] = now;
            s->lastSynced[key] = {x, y};
        }
    }
    return XR_SUCCESS;
}

/// Checks the getter's arguments; the action's synced value, whether it is bound, changed, when.
XrResult actionState(const XrActionStateGetInfo* info, XrSession handle, XrActionType type, Session** session, Action** action)
{
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_ACTION_STATE_GET_INFO) return XR_ERROR_VALIDATION_FAILURE;
    Action* a = actionOf(info->action);
    if (!a) return XR_ERROR_HANDLE_INVALID;
    if (!a->set->attached || std::find(s->attachedSets.begin(), s->attachedSets.end(), a->set) == s->attachedSets.end())
        return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    if (a->type != type) return XR_ERROR_ACTION_TYPE_MISMATCH;
    if (!knownSubaction(a, info->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
    *session = s;
    *action = a;
    return XR_SUCCESS;
}

bool synced(Session* s, Action* a, XrPath sub, float* x, float* y, bool* changed, XrTime* when)
{
    float bx, by;
    const bool bound = actionValue(s, a, sub, &bx, &by);
    const auto key = std::make_pair(a, sub);
    auto it = s->lastSynced.find(key);
    if (!bound || !s->focused() || it == s->lastSynced.end()) return false;
    *x = it->second[0];
    *y = it->second[1];
    *changed = s->changed[key];
    *when = s->changeTime.count(key) ? s->changeTime[key] : 0;
    return true;
}

XRAPI_ATTR XrResult XRAPI_CALL getActionStateBoolean(XrSession handle, const XrActionStateGetInfo* info, XrActionStateBoolean* state)
{
    LOCK;
    Session* s;
    Action* a;
    if (XrResult r = actionState(info, handle, XR_ACTION_TYPE_BOOLEAN_INPUT, &s, &a); r != XR_SUCCESS) return r;
    if (!state || state->type != XR_TYPE_ACTION_STATE_BOOLEAN) return XR_ERROR_VALIDATION_FAILURE;
    float x, y;
    bool changed;
    XrTime when;
    state->isActive = synced(s, a, info->subactionPath, &x, &y, &changed, &when) ? XR_TRUE : XR_FALSE;
    state->currentState = state->isActive && x > 0.5f ? XR_TRUE : XR_FALSE;
    state->changedSinceLastSync = state->isActive && changed ? XR_TRUE : XR_FALSE;
    state->lastChangeTime = state->isActive ? when : 0;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getActionStateFloat(XrSession handle, const XrActionStateGetInfo* info, XrActionStateFloat* state)
{
    LOCK;
    Session* s;
    Action* a;
    if (XrResult r = actionState(info, handle, XR_ACTION_TYPE_FLOAT_INPUT, &s, &a); r != XR_SUCCESS) return r;
    if (!state || state->type != XR_TYPE_ACTION_STATE_FLOAT) return XR_ERROR_VALIDATION_FAILURE;
    float x = 0, y;
    bool changed;
    XrTime when;
    state->isActive = synced(s, a, info->subactionPath, &x, &y, &changed, &when) ? XR_TRUE : XR_FALSE;
    state->currentState = state->isActive ? x : 0.0f;
    state->changedSinceLastSync = state->isActive && changed ? XR_TRUE : XR_FALSE;
    state->lastChangeTime = state->isActive ? when : 0;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getActionStateVector2f(XrSession handle, const XrActionStateGetInfo* info, XrActionStateVector2f* state)
{
    LOCK;
    Session* s;
    Action* a;
    if (XrResult r = actionState(info, handle, XR_ACTION_TYPE_VECTOR2F_INPUT, &s, &a); r != XR_SUCCESS) return r;
    if (!state || state->type != XR_TYPE_ACTION_STATE_VECTOR2F) return XR_ERROR_VALIDATION_FAILURE;
    float x = 0, y = 0;
    bool changed;
    XrTime when;
    state->isActive = synced(s, a, info->subactionPath, &x, &y, &changed, &when) ? XR_TRUE : XR_FALSE;
    state->currentState = state->isActive ? XrVector2f{x, y} : XrVector2f{0, 0};
    state->changedSinceLastSync = state->isActive && changed ? XR_TRUE : XR_FALSE;
    state->lastChangeTime = state->isActive ? when : 0;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL getActionStatePose(XrSession handle, const XrActionStateGetInfo* info, XrActionStatePose* state)
{
    LOCK;
    Session* s;
    Action* a;
    if (XrResult r = actionState(info, handle, XR_ACTION_TYPE_POSE_INPUT, &s, &a); r != XR_SUCCESS) return r;
    if (!state || state->type != XR_TYPE_ACTION_STATE_POSE) return XR_ERROR_VALIDATION_FAILURE;
    bool bound = false;
    auto it = s->instance->bindings.find(runtime().path(runtime().script.profile));
    if (it != s->instance->bindings.end()) {
        const std::string prefix = info->subactionPath ? runtime().name(info->subactionPath) + "/" : std::string("/user/");
        for (const auto& [action, input] : it->second)
            if (action == a && runtime().name(input).rfind(prefix, 0) == 0) bound = true;
    }
    state->isActive = bound && s->focused() ? XR_TRUE : XR_FALSE;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL enumerateBoundSourcesForAction(XrSession handle, const XrBoundSourcesForActionEnumerateInfo* info,
                                                              uint32_t capacity, uint32_t* count, XrPath* sources)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_BOUND_SOURCES_FOR_ACTION_ENUMERATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
    Action* a = actionOf(info->action);
    if (!a) return XR_ERROR_HANDLE_INVALID;
    std::vector<XrPath> bound;
    auto it = s->instance->bindings.find(runtime().path(runtime().script.profile));
    if (it != s->instance->bindings.end())
        for (const auto& [action, input] : it->second)
            if (action == a) bound.push_back(input);
    return copyArray(bound, capacity, count, sources);
}

XRAPI_ATTR XrResult XRAPI_CALL getInputSourceLocalizedName(XrSession handle, const XrInputSourceLocalizedNameGetInfo* info, uint32_t capacity,
                                                           uint32_t* count, char* buffer)
{
    LOCK;
    if (!sessionOf(handle)) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_INPUT_SOURCE_LOCALIZED_NAME_GET_INFO) return XR_ERROR_VALIDATION_FAILURE;
    if (info->sourcePath == XR_NULL_PATH || info->sourcePath >= runtime().paths.size()) return XR_ERROR_PATH_INVALID;
    return copyString(runtime().name(info->sourcePath), capacity, count, buffer);
}

XRAPI_ATTR XrResult XRAPI_CALL applyHapticFeedback(XrSession handle, const XrHapticActionInfo* info, const XrHapticBaseHeader* haptic)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || !haptic || info->type != XR_TYPE_HAPTIC_ACTION_INFO || haptic->type != XR_TYPE_HAPTIC_VIBRATION) return XR_ERROR_VALIDATION_FAILURE;
    Action* a = actionOf(info->action);
    if (!a) return XR_ERROR_HANDLE_INVALID;
    if (a->type != XR_ACTION_TYPE_VIBRATION_OUTPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    if (!s->focused()) return XR_SESSION_NOT_FOCUSED;
    ++runtime().hapticPulses;
    return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL stopHapticFeedback(XrSession handle, const XrHapticActionInfo* info)
{
    LOCK;
    Session* s = sessionOf(handle);
    if (!s) return XR_ERROR_HANDLE_INVALID;
    if (!info || info->type != XR_TYPE_HAPTIC_ACTION_INFO || !actionOf(info->action)) return XR_ERROR_VALIDATION_FAILURE;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    return XR_SUCCESS;
}

// --- function lookup --------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL getInstanceProcAddr(XrInstance instance, const char* name, PFN_xrVoidFunction* function)
{
    if (!name || !function) return XR_ERROR_VALIDATION_FAILURE;
    struct Entry {
        const char* name;
        PFN_xrVoidFunction function;
    };
#define FAKEXR_ENTRY(api, impl) {api, reinterpret_cast<PFN_xrVoidFunction>(&impl)}
    static const Entry global[] = {
        FAKEXR_ENTRY("xrGetInstanceProcAddr", getInstanceProcAddr),
        FAKEXR_ENTRY("xrEnumerateApiLayerProperties", enumerateApiLayerProperties),
        FAKEXR_ENTRY("xrEnumerateInstanceExtensionProperties", enumerateInstanceExtensionProperties),
        FAKEXR_ENTRY("xrCreateInstance", createInstance),
    };
    static const Entry perInstance[] = {
        FAKEXR_ENTRY("xrDestroyInstance", destroyInstance),
        FAKEXR_ENTRY("xrGetInstanceProperties", getInstanceProperties),
        FAKEXR_ENTRY("xrPollEvent", pollEvent),
        FAKEXR_ENTRY("xrResultToString", resultToString),
        FAKEXR_ENTRY("xrStructureTypeToString", structureTypeToString),
        FAKEXR_ENTRY("xrGetSystem", getSystem),
        FAKEXR_ENTRY("xrGetSystemProperties", getSystemProperties),
        FAKEXR_ENTRY("xrEnumerateEnvironmentBlendModes", enumerateEnvironmentBlendModes),
        FAKEXR_ENTRY("xrCreateSession", createSession),
        FAKEXR_ENTRY("xrDestroySession", destroySession),
        FAKEXR_ENTRY("xrEnumerateReferenceSpaces", enumerateReferenceSpaces),
        FAKEXR_ENTRY("xrCreateReferenceSpace", createReferenceSpace),
        FAKEXR_ENTRY("xrGetReferenceSpaceBoundsRect", getReferenceSpaceBoundsRect),
        FAKEXR_ENTRY("xrCreateActionSpace", createActionSpace),
        FAKEXR_ENTRY("xrLocateSpace", locateSpace),
        FAKEXR_ENTRY("xrDestroySpace", destroySpace),
        FAKEXR_ENTRY("xrEnumerateViewConfigurations", enumerateViewConfigurations),
        FAKEXR_ENTRY("xrGetViewConfigurationProperties", getViewConfigurationProperties),
        FAKEXR_ENTRY("xrEnumerateViewConfigurationViews", enumerateViewConfigurationViews),
        FAKEXR_ENTRY("xrEnumerateSwapchainFormats", enumerateSwapchainFormats),
        FAKEXR_ENTRY("xrCreateSwapchain", createSwapchain),
        FAKEXR_ENTRY("xrDestroySwapchain", destroySwapchain),
        FAKEXR_ENTRY("xrEnumerateSwapchainImages", enumerateSwapchainImages),
        FAKEXR_ENTRY("xrAcquireSwapchainImage", acquireSwapchainImage),
        FAKEXR_ENTRY("xrWaitSwapchainImage", waitSwapchainImage),
        FAKEXR_ENTRY("xrReleaseSwapchainImage", releaseSwapchainImage),
        FAKEXR_ENTRY("xrBeginSession", beginSession),
        FAKEXR_ENTRY("xrEndSession", endSession),
        FAKEXR_ENTRY("xrRequestExitSession", requestExitSession),
        FAKEXR_ENTRY("xrWaitFrame", waitFrame),
        FAKEXR_ENTRY("xrBeginFrame", beginFrame),
        FAKEXR_ENTRY("xrEndFrame", endFrame),
        FAKEXR_ENTRY("xrLocateViews", locateViews),
        FAKEXR_ENTRY("xrStringToPath", stringToPath),
        FAKEXR_ENTRY("xrPathToString", pathToString),
        FAKEXR_ENTRY("xrCreateActionSet", createActionSet),
        FAKEXR_ENTRY("xrDestroyActionSet", destroyActionSet),
        FAKEXR_ENTRY("xrCreateAction", createAction),
        FAKEXR_ENTRY("xrDestroyAction", destroyAction),
        FAKEXR_ENTRY("xrSuggestInteractionProfileBindings", suggestInteractionProfileBindings),
        FAKEXR_ENTRY("xrAttachSessionActionSets", attachSessionActionSets),
        FAKEXR_ENTRY("xrGetCurrentInteractionProfile", getCurrentInteractionProfile),
        FAKEXR_ENTRY("xrGetActionStateBoolean", getActionStateBoolean),
        FAKEXR_ENTRY("xrGetActionStateFloat", getActionStateFloat),
        FAKEXR_ENTRY("xrGetActionStateVector2f", getActionStateVector2f),
        FAKEXR_ENTRY("xrGetActionStatePose", getActionStatePose),
        FAKEXR_ENTRY("xrSyncActions", syncActions),
        FAKEXR_ENTRY("xrEnumerateBoundSourcesForAction", enumerateBoundSourcesForAction),
        FAKEXR_ENTRY("xrGetInputSourceLocalizedName", getInputSourceLocalizedName),
        FAKEXR_ENTRY("xrApplyHapticFeedback", applyHapticFeedback),
        FAKEXR_ENTRY("xrStopHapticFeedback", stopHapticFeedback),
        FAKEXR_ENTRY("xrGetVulkanGraphicsRequirements2KHR", getVulkanGraphicsRequirements2),
        FAKEXR_ENTRY("xrCreateVulkanInstanceKHR", createVulkanInstance),
        FAKEXR_ENTRY("xrGetVulkanGraphicsDevice2KHR", getVulkanGraphicsDevice2),
        FAKEXR_ENTRY("xrCreateVulkanDeviceKHR", createVulkanDevice),
    };
#undef FAKEXR_ENTRY
    *function = nullptr;
    for (const Entry& e : global)
        if (std::strcmp(e.name, name) == 0) {
            *function = e.function;
            return XR_SUCCESS;
        }
    if (instance == XR_NULL_HANDLE) return XR_ERROR_HANDLE_INVALID;
    {
        LOCK;
        if (!instanceOf(instance)) return XR_ERROR_HANDLE_INVALID;
    }
    for (const Entry& e : perInstance)
        if (std::strcmp(e.name, name) == 0) {
            *function = e.function;
            return XR_SUCCESS;
        }
    return XR_ERROR_FUNCTION_UNSUPPORTED;
}

} // namespace
} // namespace fakexr

extern "C" __attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(const XrNegotiateLoaderInfo* loaderInfo,
                                                                                            XrNegotiateRuntimeRequest* request)
{
    if (!loaderInfo || !request || loaderInfo->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
        request->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST || loaderInfo->minInterfaceVersion > 1 ||
        loaderInfo->maxInterfaceVersion < 1)
        return XR_ERROR_INITIALIZATION_FAILED;
    request->runtimeInterfaceVersion = 1;
    request->runtimeApiVersion = XR_CURRENT_API_VERSION;
    request->getInstanceProcAddr = &fakexr::getInstanceProcAddr;
    return XR_SUCCESS;
}
