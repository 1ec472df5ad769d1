// The desktop editor: a GLFW window drawing the editing session with the renderer, Dear ImGui panels
// (brush, custom brush, materials, tools, file, view, stats, help) and the keys and modifiers a sculptor
// expects (Keymap). It only maps mouse, keys and menus to the session's commands; everything it does to the
// scene is in the session's record. The brush, the window and the look persist across sessions
// (DesktopSettings).
#pragma once

#include "panels/SessionPanels.h"
#include "desktop/Keymap.h"
#include "editor/EditingSession.h"
#include "render/RenderTypes.h"

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

struct GLFWwindow;

namespace vdbclay {

/// No display to open a window on (no DISPLAY / WAYLAND_DISPLAY, or GLFW cannot reach it).
struct NoDisplay : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Whether the environment names a display (a window may still fail to open).
bool desktopAvailable();
/// The mouse, the modifiers and the keys of `keymap`, as `vdbclay edit --help` and the help panel list them.
std::string desktopShortcutsHelp(const Keymap& keymap);
/// The keymap in effect: the user's file in `configFolder` over the defaults. A missing file gives the
/// defaults (and, when `writeMissing`, writes them there for the user to edit); a broken one gives the
/// defaults and `warning` saying why.
Keymap loadKeymap(const std::string& configFolder, bool writeMissing, std::string* warning);

struct DesktopOptions {
    std::optional<std::array<int, 2>> windowSize; // absent: the size kept in the settings (1280 x 800 at first)
    bool validation = false; // the Khronos validation layer (tests: zero messages)
    /// Where settings, layout and keymap are kept: absent, the user's (defaultConfigFolder()); empty,
    /// nowhere (nothing read or written).
    std::optional<std::string> configFolder;
    /// Runs after the window's input is polled and before the menus are built, each frame (tests drive
    /// the menus through ImGui's input here).
    std::function<void(uint64_t frame)> beforeUi;
};

class DesktopEditor {
public:
    /// Opens the window. Throws NoDisplay, render::NoVulkanDevice, render::VulkanError.
    DesktopEditor(EditingSession& session, const DesktopOptions& options = {});
    ~DesktopEditor();
    DesktopEditor(const DesktopEditor&) = delete;
    DesktopEditor& operator=(const DesktopEditor&) = delete;

    /// One frame: input, menus, the session's frame, uploads, drawing, presentation. False once the
    /// user closed the window.
    bool frame();
    /// Frames until the window closes.
    void run();

    // Input as GLFW delivers it; the window's callbacks call these (tests may too).
    void mouseButton(int button, int action, int mods);
    void cursorMoved(double x, double y);
    void scrolled(double dx, double dy);
    void key(int key, int action, int mods);

    /// Applies a recorded session's commands, each before the frame it was recorded in.
    void replay(const SessionRecord* record);
    /// A scene the user asked to open from the file menu (the editor stopped for it), or empty.
    std::string openRequested() const;
    /// Whether the user chose to drop the edits recovered after a crash (the editor stopped for it:
    /// reopen the scene with SessionOptions::discardRecovery).
    bool discardRecoveryRequested() const;

    /// Where a tracked widget was drawn last frame (SessionPanels::widgetRects), if it was.
    std::optional<std::array<float, 4>> widgetRect(const std::string& label) const;

    GLFWwindow* window() const;
    const render::FrameStats& lastFrame() const;
    /// What the stats overlay shows: the last whole frame's wall-clock interval and its measured parts.
    const FrameFigures& figures() const;
    const Keymap& keymap() const;
    /// The window's title: the scene's file name, and " *" while it has unsaved changes.
    const std::string& title() const;
    uint64_t validationMessages() const;
    EditingSession& session();
    /// Waits until the edit worker has applied every command the window gave it, and the mesh workers
    /// have made the meshes the last frame asked for (the window's frames never wait; tests and a scene
    /// being closed do).
    void finishEdits();
    /// A command as the window's input gives one: to the edit worker (tests).
    void submit(const Command& command);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// `vdbclay edit` with a window: runs the editor on `session` until it closes (replaying `replay` as it
/// goes, when given), opening other scenes the user asks for with the same options. Returns the exit code;
/// a missing display or Vulkan device is one line on stderr and 1.
int runDesktopEditor(const SessionOptions& options, std::unique_ptr<EditingSession> session, const SessionRecord* replay);

} // namespace vdbclay
