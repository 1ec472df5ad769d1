// What the desktop editor keeps between sessions, in the user's config folder ($XDG_CONFIG_HOME/vdbclay,
// else ~/.config/vdbclay): the brush, the window's size, the panels shown, the look (settings.json), the
// panels' layout (imgui.ini) and the keymap (keymap.json, written with the defaults when missing so
// that users find it to edit).
#pragma once

#include "editor/BrushSettings.h"
#include "render/RenderTypes.h"

#include <array>
#include <optional>
#include <string>

namespace vdbclay {

/// The config folder (not created): $XDG_CONFIG_HOME/vdbclay, else $HOME/.config/vdbclay; empty when
/// neither is set.
std::string defaultConfigFolder();

struct DesktopSettings {
    std::optional<BrushSettings> brush;
    std::array<int, 2> windowSize{1280, 800};
    bool showStats = true;
    bool showHelp = false;
    render::ViewMode look = render::ViewMode::Shaded;
    bool wireframe = false;
    double stabilizerPixels = 0.0; // lazy mouse (0: off)
};

/// The settings in `folder`/settings.json; defaults when the file is missing. A damaged file (or one
/// with settings this version refuses) gives the defaults and `warning` saying why, never an error:
/// the editor must open.
DesktopSettings loadDesktopSettings(const std::string& folder, std::string* warning = nullptr);
/// Writes `folder`/settings.json atomically, making the folder; throws FileWriteError.
void saveDesktopSettings(const DesktopSettings& settings, const std::string& folder);

} // namespace vdbclay
