// What the fake headset does, frame by frame: the head's and the hands' poses, the controllers' trigger,
// grip, thumbstick and buttons, and the runtime's own events (focus lost, asked to stop, session lost),
// read from a JSON script (FAKEXR_SCRIPT). Keyframes are indexed by frame (one per xrWaitFrame): poses
// and analog values are interpolated between keys, buttons hold their last key's state.
#pragma once

#include <openxr/openxr.h>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace fakexr {

struct HandState {
    XrPosef pose{{0, 0, 0, 1}, {0, 0, 0}}; // the grip (and aim) pose in the stage space
    float trigger = 0.0f, squeeze = 0.0f;
    XrVector2f thumbstick{0, 0};
    std::map<std::string, bool> buttons; // "a", "b", "x", "y", "menu", "thumbstick", "system"
};

struct HeadsetScript {
    uint64_t stopAfterFrames = 0; // the runtime asks the session to stop after this many frames (0: never)
    bool pace = true;             // xrWaitFrame keeps the display's 90 Hz (else frames run as fast as they can)
    double refreshHz = 90.0;
    double ipd = 0.064;
    int width = 256, height = 256; // recommended per eye
    XrFovf fov{-0.8f, 0.8f, 0.8f, -0.8f};
    std::vector<int64_t> formats;  // swapchain formats offered, preferred first (VkFormat values)
    bool depthExtension = true;    // XR_KHR_composition_layer_depth offered
    bool stereo = true;            // PRIMARY_STEREO offered (else PRIMARY_MONO only)
    std::string profile = "/interaction_profiles/oculus/touch_controller";
    std::optional<uint64_t> focusLostAt, focusBackAt, lossPendingAt;
    std::set<uint64_t> capture; // frames whose submitted eye images are written out (FAKEXR_CAPTURE)

    struct HeadKey {
        uint64_t frame = 0;
        XrPosef pose{{0, 0, 0, 1}, {0, 1.6f, 0}};
    };
    struct HandKey {
        uint64_t frame = 0;
        HandState state;
    };
    std::vector<HeadKey> head;
    std::array<std::vector<HandKey>, 2> hands; // left, right

    XrPosef headAt(uint64_t frame) const;
    HandState handAt(int hand, uint64_t frame) const;
};

/// Reads a script; throws std::runtime_error naming the file and the key.
HeadsetScript loadHeadsetScript(const std::string& path);
HeadsetScript parseHeadsetScript(const std::string& text);

// Pose arithmetic (stage space).
XrPosef multiply(const XrPosef& a, const XrPosef& b); // a then b in a's frame: the pose b relative to a, in a's parent
XrPosef inverse(const XrPosef& p);
XrVector3f rotate(const XrQuaternionf& q, const XrVector3f& v);

} // namespace fakexr
