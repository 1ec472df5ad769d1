// `vdbclay edit SCENE --vr`: the editing session in a headset through OpenXR. The frame loop follows
// the runtime's predicted display times and never waits for an edit, a mesh or a load: the session's
// commands go to its edit worker (SessionWorker), meshes are made on workers (StreamedSceneChunks), and
// each frame only reads the controllers, turns them into commands and moves of the world (VrControls),
// streams for the head, uploads within a budget and draws both eyes in one frame of the renderer.
#pragma once

#include "editor/EditingSession.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay::vr {

struct VrOptions {
    std::optional<uint64_t> frames; // the session ends after this many frames (tests, CI, bug reports)
    bool validation = false;        // the Vulkan validation layer (tests: zero messages)
    int dominantHand = 1;           // 0 left, 1 right: the hand that sculpts
    bool json = false;              // runVrEditor prints the report as one JSON object on stdout (vrReportJson)
};

/// What a VR session did: its frames and how they kept time.
struct VrReport {
    uint64_t frames = 0;          // frames ended
    uint64_t framesDrawn = 0;     // of those, frames whose eyes were drawn (shouldRender)
    uint64_t missedFrames = 0;    // display refreshes the frames skipped (predicted display times more than one period apart)
    std::vector<uint64_t> missedSoFar; // per drawn frame: missedFrames up to it (a benchmark counts a stretch's)
    std::vector<double> wallMs;   // per drawn frame: from xrBeginFrame's return to xrEndFrame's (waits for the device included)
    std::vector<double> cpuMs;    // per drawn frame: the frame thread's work (input, streaming, taking meshes, recording; the
                                  // device's drawing and the runtime's waits apart, as bench editor counts)
    std::vector<double> poseToSubmitMs; // per drawn frame: from locating the eyes to xrEndFrame's return
    std::vector<double> editToVisibleFrames; // per stroke point: frames until the view showed it at level 0 with its new mesh (1: the frame it was given)
    std::vector<std::string> states; // the session states, in order
    uint64_t commands = 0;        // commands the controllers gave
    uint64_t hapticPulses = 0;
    uint64_t validationMessages = 0;
    bool lost = false;            // the runtime lost the session (LOSS_PENDING)
    std::string headset;          // what the runtime offered
    /// Where the menu's tracked widgets were drawn last (SessionPanels::widgetRects), in the menus'
    /// picture's pixels; empty when the menu was hidden.
    std::map<std::string, std::array<float, 4>> menuWidgets;
};

/// {"frames", "frames_drawn", "missed_frames", "frame_ms": {"p50", "p99"} (the frame thread's work),
/// "frame_wall_ms": {"p50", "p99"}, "pose_to_submit_ms": {"p50", "p99"}, "edit_to_visible_frames": {"p50",
/// "p99", "max"}, "states", "commands", "haptic_pulses", "validation_messages", "lost", "headset",
/// "menu_widgets": {label: [x0, y0, x1, y1]}}.
nlohmann::json vrReportJson(const VrReport& report);

/// Runs the VR editor on `session` until the headset's session ends (or `options.frames` frames).
/// Throws NoXrRuntime (XrCheck.h) when no runtime answers, render::NoVulkanDevice, XrError.
VrReport runVrSession(EditingSession& session, const VrOptions& options);

/// `vdbclay edit --vr`: runVrSession with the one-line messages and exit codes of the command line (no
/// runtime: one line, 1; a lost session: one line, 1, the edits autosaved).
int runVrEditor(std::unique_ptr<EditingSession> session, const VrOptions& options);

} // namespace vdbclay::vr
