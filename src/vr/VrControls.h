// What the controllers mean, as editing-session commands (the headset's only way to change the scene)
// and as moves of the world: the dominant hand is the brush (its trigger strokes with pressure, its
// thumbstick sizes the brush and cycles modes, its buttons undo and redo), the other hand grabs and
// flies the world, frames the scene again and shows the menu, both hands grab to turn and scale it. Device-free: XrControllers fills a
// ControllerFrame from OpenXR; tests fill it by hand.
#pragma once

#include "editor/BrushSettings.h"
#include "editor/SessionCommand.h"
#include "vr/WorldPlacement.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay::vr {

struct HandInput {
    bool tracked = false;
    Pose grip;               // stage metres
    Pose aim;
    double trigger = 0.0;    // 0..1
    double squeeze = 0.0;    // 0..1
    glm::dvec2 thumbstick{0.0};
    bool primary = false;    // A / X
    bool secondary = false;  // B / Y
    bool menu = false;
};

struct ControllerFrame {
    std::array<HandInput, 2> hands; // left, right
    double seconds = 0.0;           // since the previous frame
    bool focused = true;            // the session has input focus (else no input reaches it)
    bool pointerOnMenu = false;     // the dominant hand points at the menu: its trigger and thumbstick are the menu's
};

/// How far in front of the grip the brush's centre sits (metres): between the fingertips, as seed 004's
/// brush sits at the controller's tip.
constexpr double kBrushReachMetres = 0.06;
/// The brush modes the thumbstick cycles through.
const std::vector<std::string>& vrBrushModes();

class VrControls {
public:
    explicit VrControls(int dominantHand = 1) : dominant_(dominantHand) {}

    struct Output {
        std::vector<Command> commands; // for the session, in order
        WorldTransform world;          // where the scene stands after this frame's grabs and flight
        std::optional<glm::dvec3> brush; // the brush's centre in scene units (none: the hand is not tracked)
        double brushRadius = 0.0;        // scene units, as it would be applied now (a resize under way included)
        bool touchedSurface = false;     // set by the caller's surface test; see brushTouch
        bool frameAgain = false;         // the off hand's primary button: frame the scene again
        bool toggleMenu = false;         // the off hand's secondary button
        bool toggleHints = false;        // a menu button
        bool strokeActive = false;
    };
    /// One frame of input: `brush` is the session's brush as the frame sees it, `world` the transform now.
    Output update(const ControllerFrame& frame, const BrushSettings& brush, const WorldTransform& world);
    /// Scale limits for two-hand grabs (metres per scene unit).
    void setScaleLimits(double minScale, double maxScale) { grab_.setScaleLimits(minScale, maxScale); }
    int dominantHand() const { return dominant_; }

private:
    void moveWorld(const ControllerFrame& frame, Output& out);
    void adjustBrush(const ControllerFrame& frame, const BrushSettings& brush, Output& out);
    void stroke(const ControllerFrame& frame, Output& out);
    void pressButtons(const ControllerFrame& frame, Output& out);

    int dominant_;
    bool stroking_ = false;
    std::optional<glm::dvec3> lastPoint_;
    std::optional<double> resizing_;   // the radius the thumbstick is taking the brush to
    bool modeFlick_ = false;           // the thumbstick is pushed sideways (a mode change made, waiting for it to centre)
    std::array<HandInput, 2> previous_;
    WorldGrab grab_;
};

} // namespace vdbclay::vr
