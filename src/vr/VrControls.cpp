#include "vr/VrControls.h"

#include <algorithm>
#include <cmath>

namespace vdbclay::vr {

namespace {

constexpr double kStrokeStart = 0.2;  // trigger value that begins a stroke
constexpr double kStrokeEnd = 0.1;    // and that ends it (hysteresis: a light finger does not stutter)
constexpr double kGrabHold = 0.5;     // squeeze value that holds the world
constexpr double kStickDeadZone = 0.3;
constexpr double kStickFlick = 0.7;
constexpr double kFlyMetresPerSecond = 1.5;

Command strokeCommand(Command::Kind kind, const glm::dvec3& point, double pressure)
{
    Command c;
    c.kind = kind;
    c.point = std::array<double, 3>{point.x, point.y, point.z};
    c.pressure = std::clamp(pressure, 0.05, 1.0);
    return c;
}

} // namespace

const std::vector<std::string>& vrBrushModes()
{
    static const std::vector<std::string> modes{"add", "remove", "smooth", "inflate", "deflate", "flatten", "move", "paint"};
    return modes;
}

VrControls::Output VrControls::update(const ControllerFrame& frame, const BrushSettings& brush, const WorldTransform& world)
{
    Output out;
    out.world = world;
    if (!frame.focused) {
        // No input reaches an unfocused session: a stroke under way ends where it was, grabs let go.
        if (stroking_) {
            Command end;
            end.kind = Command::Kind::StrokeEnd;
            out.commands.push_back(end);
            stroking_ = false;
        }
        grab_.update(std::nullopt, std::nullopt, world);
        resizing_.reset();
        previous_ = {};
        out.brushRadius = brush.radius;
        return out;
    }
    moveWorld(frame, out); // first, so that the brush is placed in the scene as it stands this frame
    adjustBrush(frame, brush, out);
    stroke(frame, out);
    pressButtons(frame, out);
    previous_ = frame.hands;
    return out;
}

void VrControls::moveWorld(const ControllerFrame& frame, Output& out)
{
    const HandInput& hand = frame.hands[std::size_t(dominant_)];
    const HandInput& off = frame.hands[std::size_t(1 - dominant_)];
    auto holding = [&](const HandInput& h) { return h.tracked && h.squeeze >= kGrabHold ? std::optional<glm::dvec3>(h.grip.position) : std::nullopt; };
    const std::optional<glm::dvec3> offHold = holding(off);
    // The dominant hand joins a grab the off hand holds (two hands turn and scale), never grabs alone:
    // its squeeze is free while it sculpts.
    const std::optional<glm::dvec3> dominantHold = offHold ? holding(hand) : std::nullopt;
    out.world = dominant_ == 1 ? grab_.update(offHold, dominantHold, out.world) : grab_.update(dominantHold, offHold, out.world);
    if (!grab_.active() && off.tracked && std::fabs(off.thumbstick.y) > kStickDeadZone)
        out.world = fly(out.world, off.aim.forward(), kFlyMetresPerSecond * off.thumbstick.y, frame.seconds);
}

void VrControls::adjustBrush(const ControllerFrame& frame, const BrushSettings& brush, Output& out)
{
    const HandInput& hand = frame.hands[std::size_t(dominant_)];
    BrushSettings shown = brush;
    const double stickY = hand.thumbstick.y, stickX = hand.thumbstick.x;
    const bool menuHasStick = frame.pointerOnMenu; // it scrolls the menu then
    auto setBrush = [&] {
        Command set;
        set.kind = Command::Kind::SetBrush;
        set.brush = shown;
        out.commands.push_back(set);
    };
    if (!menuHasStick && std::fabs(stickY) > kStickDeadZone && std::fabs(stickY) >= std::fabs(stickX)) {
        const double from = resizing_.value_or(brush.radius);
        resizing_ = std::clamp(from * std::exp2(stickY * frame.seconds), 0.5, 4096.0); // doubles a second at full tilt
    } else if (resizing_) {
        // Released: the new size becomes the brush (one command, not one per frame).
        shown.radius = *resizing_;
        setBrush();
        resizing_.reset();
    }
    if (!menuHasStick && !modeFlick_ && std::fabs(stickX) > kStickFlick && std::fabs(stickX) > std::fabs(stickY)) {
        modeFlick_ = true;
        const auto& modes = vrBrushModes();
        auto at = std::find(modes.begin(), modes.end(), shown.mode);
        std::ptrdiff_t i = at == modes.end() ? 0 : at - modes.begin();
        i = (i + (stickX > 0 ? 1 : std::ptrdiff_t(modes.size()) - 1)) % std::ptrdiff_t(modes.size());
        shown.mode = modes[std::size_t(i)];
        setBrush();
    } else if (std::fabs(stickX) < kStickDeadZone) {
        modeFlick_ = false;
    }
    out.brushRadius = resizing_.value_or(shown.radius);
}

void VrControls::stroke(const ControllerFrame& frame, Output& out)
{
    const HandInput& hand = frame.hands[std::size_t(dominant_)];
    // The brush: at the dominant hand's fingertips, in scene units.
    if (hand.tracked) out.brush = out.world.toScene(hand.grip.position + hand.grip.forward() * kBrushReachMetres);
    if (!stroking_ && out.brush && hand.trigger >= kStrokeStart && !resizing_ && !frame.pointerOnMenu) {
        out.commands.push_back(strokeCommand(Command::Kind::StrokeBegin, *out.brush, hand.trigger));
        stroking_ = true;
        lastPoint_ = out.brush;
    } else if (stroking_ && (hand.trigger < kStrokeEnd || !out.brush)) {
        Command end;
        end.kind = Command::Kind::StrokeEnd;
        out.commands.push_back(end);
        stroking_ = false;
    } else if (stroking_ && out.brush && *out.brush != *lastPoint_) {
        out.commands.push_back(strokeCommand(Command::Kind::StrokeMove, *out.brush, hand.trigger));
        lastPoint_ = out.brush;
    }
    out.strokeActive = stroking_;
}

void VrControls::pressButtons(const ControllerFrame& frame, Output& out)
{
    const HandInput& hand = frame.hands[std::size_t(dominant_)];
    const HandInput& off = frame.hands[std::size_t(1 - dominant_)];
    const HandInput& handBefore = previous_[std::size_t(dominant_)];
    const HandInput& offBefore = previous_[std::size_t(1 - dominant_)];
    auto pressed = [](bool now, bool before) { return now && !before; };
    // Undo and redo on the brush hand (never mid-stroke); framing and the menu on the other; hints on
    // either's menu button.
    auto command = [&](Command::Kind kind) {
        Command c;
        c.kind = kind;
        out.commands.push_back(c);
    };
    if (!stroking_ && pressed(hand.primary, handBefore.primary)) command(Command::Kind::Undo);
    if (!stroking_ && pressed(hand.secondary, handBefore.secondary)) command(Command::Kind::Redo);
    out.frameAgain = pressed(off.primary, offBefore.primary);
    out.toggleMenu = pressed(off.secondary, offBefore.secondary);
    out.toggleHints = pressed(off.menu, offBefore.menu) || pressed(hand.menu, handBefore.menu);
}

} // namespace vdbclay::vr
