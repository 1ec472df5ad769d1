// The editor's current brush: what the brush panel, the shortcuts and recorded sessions set, and how a
// stretch of a stroke becomes a stroke-script op (so strokes, scripts, tests and replays share one code
// path: every op the editor applies is one a script could hold).
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace vdbclay {

enum class PressureTarget { None, Size, Strength };

struct BrushSettings {
    std::string mode = "add"; // a script mode: add, remove, paint, erode, smooth, flatten, inflate, deflate, move, mask, unmask
    nlohmann::json shape = {{"shape", "sphere"}, {"radius", 1.0}}; // a script brush at unit size
    double radius = 8.0;      // world units: the op's scale on `shape`
    double strength = 0.5;    // reshaping brushes and erode, 0..1
    std::string falloff = "smooth"; // smooth, linear, constant, or curve (falloffCurve)
    std::vector<double> falloffCurve; // "curve": weights from the rim to the deepest point (2 to 16, in [0, 1])
    std::string material;     // empty: the scene's first (add) or the most common under the brush (reshaping)
    double distance = 2.0;    // inflate, deflate: world units at full strength
    double spacing = 0.25;    // stamps every spacing * radius along a stroke
    PressureTarget pressure = PressureTarget::Size;
    nlohmann::json symmetry;  // null, or a script op's "symmetry" object
    /// A stroke builds on itself: each stamp lands on the surface the stroke has made so far. Off, the
    /// stroke follows the surface as it began (Blender's default), and add and remove change it by at
    /// most strength x radius.
    bool accumulate = false;
    /// Add: the width of its smooth union with the surface, as a fraction of the radius (0: exact, as
    /// sessions recorded before it, which do not name it, are read).
    double smoothness = 0.35;
};

/// Throws std::invalid_argument naming the field for settings no script would accept (checked again
/// when the op is parsed).
void checkBrushSettings(const BrushSettings& brush);
nlohmann::json brushSettingsJson(const BrushSettings& brush);
/// Throws std::invalid_argument naming the key for malformed settings.
BrushSettings parseBrushSettings(const nlohmann::json& json);

bool isReshapingMode(const std::string& mode);
/// Mask brushes paint the mask (VoxelMask.h), never the surface.
bool isMaskMode(const std::string& mode);

/// How far along the surface's outward normal a stamp's centre goes from the surface point under the
/// pointer: add sinks by (1 - strength) x radius so that it raises the surface by strength x radius,
/// remove rises as far so that it cuts as deep; 0 for the other modes.
double stampNormalOffset(const BrushSettings& brush, double pressure);

/// The script op for stamps at `points` (one: a stamp; more: the swept brush along them) at `pressure`
/// (0..1]; `offset` is the drag of a move.
nlohmann::json strokeOpJson(const BrushSettings& brush, const std::vector<std::array<double, 3>>& points, double pressure,
                            const std::array<double, 3>& offset = {0, 0, 0});

} // namespace vdbclay
