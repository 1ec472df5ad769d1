// The desktop editor's keymap: every key action by name, bound to key chords ("Ctrl+Z", "Shift+]",
// "KP_1", "Home"). The defaults are built in; a JSON file in the user's config folder rebinds any of them
// ({"undo": "Ctrl+Z", "redo": ["Ctrl+Shift+Z", "Ctrl+Y"]}), and `vdbclay edit --help` and the help panel
// list what is in effect. Keys are GLFW's key codes.
#pragma once

#include <nlohmann/json.hpp>

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay {

enum class KeyAction {
    Undo, Redo, Save, Screenshot,
    ModeAdd, ModeRemove, ModePaint, ModeErode, ModeSmooth, ModeFlatten, ModeInflate, ModeDeflate, ModeMove, ModeMask,
    MaskInvert, MaskClear,
    BrushSmaller, BrushLarger, BrushWeaker, BrushStronger, RadiusDrag, StrengthDrag, MirrorX,
    FrameAll, FrameCursor, ViewFront, ViewBack, ViewRight, ViewLeft, ViewTop, ViewBottom, Parallel, Turntable,
    ShadingNext, Wireframe, Help, Stats, EndStroke,
};
constexpr int kKeyActionCount = int(KeyAction::EndStroke) + 1;

const char* keyActionName(KeyAction action);        // "undo", "view_front": the file's keys
const char* keyActionDescription(KeyAction action); // "undo the last stroke"

/// A key with the modifiers held (GLFW_MOD_CONTROL, GLFW_MOD_SHIFT, GLFW_MOD_ALT; others ignored).
struct KeyChord {
    int key = 0;
    int mods = 0;
    friend bool operator==(const KeyChord& a, const KeyChord& b) { return a.key == b.key && a.mods == b.mods; }
};

/// "Ctrl+Shift+Z", "KP_1", "F12", "["; throws std::invalid_argument naming what is not understood.
KeyChord parseKeyChord(const std::string& text);
std::string keyChordName(const KeyChord& chord);

class KeymapError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class Keymap {
public:
    /// Blender's and ZBrush's habits: Ctrl+Z, [ and ], F for the radius, numpad views, Home frames all.
    static Keymap defaults();
    /// The defaults with a keymap file's bindings over them (each action it names takes the chords it
    /// lists); throws KeymapError naming the file and the entry for unreadable JSON, an unknown action
    /// or key, or a chord bound to two actions.
    static Keymap load(const std::string& path);
    /// The same from JSON text; `name` labels the errors.
    static Keymap parse(const std::string& text, const std::string& name);

    std::optional<KeyAction> actionFor(int key, int mods) const;
    const std::vector<KeyChord>& chords(KeyAction action) const { return chords_[std::size_t(action)]; }
    /// Every action and its chords, as a keymap file holds them.
    nlohmann::json json() const;
    /// One line per action: its chords and what it does.
    std::string help() const;

private:
    std::vector<std::vector<KeyChord>> chords_ = std::vector<std::vector<KeyChord>>(kKeyActionCount);
};

} // namespace vdbclay
