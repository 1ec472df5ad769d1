#include "desktop/Keymap.h"

#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/StrictJson.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

namespace vdbclay {

namespace {

struct ActionInfo {
    KeyAction action;
    const char* name;
    const char* description;
    const char* chords; // default bindings, comma separated
};

constexpr ActionInfo kActions[] = {
    {KeyAction::Undo, "undo", "undo the last stroke", "Ctrl+Z"},
    {KeyAction::Redo, "redo", "redo", "Ctrl+Shift+Z, Ctrl+Y"},
    {KeyAction::Save, "save", "save the scene", "Ctrl+S"},
    {KeyAction::Screenshot, "screenshot", "write the view as a PNG beside the scene", "F12"},
    {KeyAction::ModeAdd, "mode_add", "add (clay)", "A"},
    {KeyAction::ModeRemove, "mode_remove", "remove", "R"},
    {KeyAction::ModePaint, "mode_paint", "paint", "P"},
    {KeyAction::ModeErode, "mode_erode", "erode", "E"},
    {KeyAction::ModeSmooth, "mode_smooth", "smooth", "S"},
    {KeyAction::ModeFlatten, "mode_flatten", "flatten", "L"},
    {KeyAction::ModeInflate, "mode_inflate", "inflate", "I"},
    {KeyAction::ModeDeflate, "mode_deflate", "deflate", "D"},
    {KeyAction::ModeMove, "mode_move", "grab (move)", "G"},
    {KeyAction::ModeMask, "mode_mask", "mask: masked surface shows dark and no brush changes it (Ctrl unmasks)", "M"},
    {KeyAction::MaskInvert, "mask_invert", "invert the mask", "Ctrl+I"},
    {KeyAction::MaskClear, "mask_clear", "clear the mask", "Alt+M"},
    {KeyAction::BrushSmaller, "brush_smaller", "brush smaller", "["},
    {KeyAction::BrushLarger, "brush_larger", "brush larger", "]"},
    {KeyAction::BrushWeaker, "brush_weaker", "brush weaker", "Shift+["},
    {KeyAction::BrushStronger, "brush_stronger", "brush stronger", "Shift+]"},
    {KeyAction::RadiusDrag, "radius_drag", "drag the radius on screen (click to keep, Esc or right click to cancel)", "F"},
    {KeyAction::StrengthDrag, "strength_drag", "drag the strength on screen", "Shift+F"},
    {KeyAction::MirrorX, "mirror_x", "mirror across x on/off", "X"},
    {KeyAction::FrameAll, "frame_all", "frame the whole scene", "Home"},
    {KeyAction::FrameCursor, "frame_cursor", "centre the view on the surface under the cursor", "KP_Decimal, C"},
    {KeyAction::ViewFront, "view_front", "look from the front (+z)", "KP_1"},
    {KeyAction::ViewBack, "view_back", "look from the back (-z)", "Ctrl+KP_1"},
    {KeyAction::ViewRight, "view_right", "look from the right (+x)", "KP_3"},
    {KeyAction::ViewLeft, "view_left", "look from the left (-x)", "Ctrl+KP_3"},
    {KeyAction::ViewTop, "view_top", "look from the top (+y)", "KP_7"},
    {KeyAction::ViewBottom, "view_bottom", "look from below (-y)", "Ctrl+KP_7"},
    {KeyAction::Parallel, "parallel_view", "parallel (orthographic) view on/off", "KP_5"},
    {KeyAction::Turntable, "turntable", "turn the view about the scene on/off", "T"},
    {KeyAction::ShadingNext, "shading_next", "next look: material, clay, normals", "Z"},
    {KeyAction::Wireframe, "wireframe", "wireframe on/off", "Shift+Z"},
    {KeyAction::Help, "help", "help panel", "H"},
    {KeyAction::Stats, "stats", "stats overlay on/off", "Tab"},
    {KeyAction::EndStroke, "end_stroke", "end the stroke, cancel an on-screen drag", "Escape"},
};
static_assert(sizeof(kActions) / sizeof(kActions[0]) == std::size_t(kKeyActionCount), "every action has a name");

const ActionInfo& infoOf(KeyAction a)
{
    for (const ActionInfo& i : kActions)
        if (i.action == a) return i;
    return kActions[0];
}

struct KeyName {
    int key;
    const char* name;
};

constexpr KeyName kNamedKeys[] = {
    {GLFW_KEY_LEFT_BRACKET, "["}, {GLFW_KEY_RIGHT_BRACKET, "]"}, {GLFW_KEY_MINUS, "-"}, {GLFW_KEY_EQUAL, "="},
    {GLFW_KEY_COMMA, ","}, {GLFW_KEY_PERIOD, "."}, {GLFW_KEY_SLASH, "/"}, {GLFW_KEY_SEMICOLON, ";"},
    {GLFW_KEY_APOSTROPHE, "'"}, {GLFW_KEY_BACKSLASH, "\\"}, {GLFW_KEY_GRAVE_ACCENT, "`"},
    {GLFW_KEY_SPACE, "Space"}, {GLFW_KEY_ESCAPE, "Escape"}, {GLFW_KEY_ENTER, "Enter"}, {GLFW_KEY_TAB, "Tab"},
    {GLFW_KEY_BACKSPACE, "Backspace"}, {GLFW_KEY_INSERT, "Insert"}, {GLFW_KEY_DELETE, "Delete"},
    {GLFW_KEY_HOME, "Home"}, {GLFW_KEY_END, "End"}, {GLFW_KEY_PAGE_UP, "PageUp"}, {GLFW_KEY_PAGE_DOWN, "PageDown"},
    {GLFW_KEY_LEFT, "Left"}, {GLFW_KEY_RIGHT, "Right"}, {GLFW_KEY_UP, "Up"}, {GLFW_KEY_DOWN, "Down"},
    {GLFW_KEY_KP_DECIMAL, "KP_Decimal"}, {GLFW_KEY_KP_DIVIDE, "KP_Divide"}, {GLFW_KEY_KP_MULTIPLY, "KP_Multiply"},
    {GLFW_KEY_KP_SUBTRACT, "KP_Subtract"}, {GLFW_KEY_KP_ADD, "KP_Add"}, {GLFW_KEY_KP_ENTER, "KP_Enter"},
};

constexpr int kModMask = GLFW_MOD_CONTROL | GLFW_MOD_SHIFT | GLFW_MOD_ALT;

std::string trimmed(const std::string& s)
{
    const auto first = s.find_first_not_of(' '), last = s.find_last_not_of(' ');
    return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
}

int keyOfName(const std::string& name)
{
    if (name.size() == 1) {
        const char c = char(std::toupper(static_cast<unsigned char>(name[0])));
        if (c >= 'A' && c <= 'Z') return GLFW_KEY_A + (c - 'A');
        if (c >= '0' && c <= '9') return GLFW_KEY_0 + (c - '0');
    }
    for (const KeyName& k : kNamedKeys)
        if (name == k.name) return k.key;
    if (name.size() == 4 && name.compare(0, 3, "KP_") == 0 && name[3] >= '0' && name[3] <= '9') return GLFW_KEY_KP_0 + (name[3] - '0');
    if (name.size() >= 2 && name.size() <= 3 && name[0] == 'F' && std::all_of(name.begin() + 1, name.end(), ::isdigit)) {
        const int n = std::stoi(name.substr(1));
        if (n >= 1 && n <= 25) return GLFW_KEY_F1 + (n - 1);
    }
    return -1;
}

std::string nameOfKey(int key)
{
    if (key >= GLFW_KEY_A && key <= GLFW_KEY_Z) return std::string(1, char('A' + (key - GLFW_KEY_A)));
    if (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) return std::string(1, char('0' + (key - GLFW_KEY_0)));
    if (key >= GLFW_KEY_KP_0 && key <= GLFW_KEY_KP_9) return "KP_" + std::to_string(key - GLFW_KEY_KP_0);
    if (key >= GLFW_KEY_F1 && key <= GLFW_KEY_F25) return "F" + std::to_string(key - GLFW_KEY_F1 + 1);
    for (const KeyName& k : kNamedKeys)
        if (key == k.key) return k.name;
    return "key " + std::to_string(key);
}

std::vector<KeyChord> parseChordList(const std::string& list)
{
    std::vector<KeyChord> out;
    std::stringstream in(list);
    std::string one;
    while (std::getline(in, one, ',')) out.push_back(parseKeyChord(trimmed(one)));
    return out;
}

} // namespace

const char* keyActionName(KeyAction action) { return infoOf(action).name; }
const char* keyActionDescription(KeyAction action) { return infoOf(action).description; }

KeyChord parseKeyChord(const std::string& text)
{
    KeyChord chord;
    std::string rest = text;
    // Modifiers first; the key is what is left ("Shift++" is not needed: no default uses "+").
    while (true) {
        const auto plus = rest.find('+');
        if (plus == std::string::npos || plus + 1 == rest.size()) break;
        const std::string mod = rest.substr(0, plus);
        if (mod == "Ctrl") chord.mods |= GLFW_MOD_CONTROL;
        else if (mod == "Shift") chord.mods |= GLFW_MOD_SHIFT;
        else if (mod == "Alt") chord.mods |= GLFW_MOD_ALT;
        else throw std::invalid_argument("'" + printableText(text, 80) + "': unknown modifier '" + printableText(mod, 40) + "' (Ctrl, Shift, Alt)");
        rest = rest.substr(plus + 1);
    }
    chord.key = keyOfName(rest);
    if (chord.key < 0)
        throw std::invalid_argument("'" + printableText(text, 80) + "': unknown key '" + printableText(rest, 40) +
                                    "' (A-Z, 0-9, F1-F25, KP_0-KP_9, KP_Decimal, Home, End, Tab, Escape, Space, [, ], ...)");
    return chord;
}

std::string keyChordName(const KeyChord& chord)
{
    std::string out;
    if (chord.mods & GLFW_MOD_CONTROL) out += "Ctrl+";
    if (chord.mods & GLFW_MOD_SHIFT) out += "Shift+";
    if (chord.mods & GLFW_MOD_ALT) out += "Alt+";
    return out + nameOfKey(chord.key);
}

Keymap Keymap::defaults()
{
    Keymap k;
    for (const ActionInfo& i : kActions) k.chords_[std::size_t(i.action)] = parseChordList(i.chords);
    return k;
}

Keymap Keymap::load(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw KeymapError("cannot read the keymap '" + printableText(path, 200) + "'");
    std::stringstream text;
    text << in.rdbuf();
    return parse(text.str(), path);
}

Keymap Keymap::parse(const std::string& text, const std::string& name)
{
    const std::string where = "keymap '" + printableText(name, 200) + "'";
    nlohmann::json root;
    try {
        root = parseStrictJson(text, where);
    } catch (const std::invalid_argument& e) {
        throw KeymapError(e.what());
    }
    if (!root.is_object()) throw KeymapError(where + ": must be an object of action names, e.g. {\"undo\": \"Ctrl+Z\"}");
    Keymap k = defaults();
    for (const auto& item : root.items()) {
        const ActionInfo* info = nullptr;
        for (const ActionInfo& i : kActions)
            if (item.key() == i.name) info = &i;
        if (!info) throw KeymapError(where + ": unknown action '" + printableText(item.key(), 80) + "'");
        std::vector<KeyChord> chords;
        try {
            if (item.value().is_string()) chords = parseChordList(item.value().get<std::string>());
            else if (item.value().is_array()) {
                for (const nlohmann::json& c : item.value()) {
                    if (!c.is_string()) throw std::invalid_argument("must list chords as strings");
                    chords.push_back(parseKeyChord(c.get<std::string>()));
                }
            } else {
                throw std::invalid_argument("must be a chord (\"Ctrl+Z\"), a list of them, or [] to unbind it");
            }
        } catch (const std::invalid_argument& e) {
            throw KeymapError(where + "." + info->name + ": " + e.what());
        }
        k.chords_[std::size_t(info->action)] = chords;
    }
    // One chord, one action: a file that binds a chord the defaults use elsewhere must rebind that too.
    for (int a = 0; a < kKeyActionCount; ++a)
        for (const KeyChord& c : k.chords_[std::size_t(a)])
            for (int b = a + 1; b < kKeyActionCount; ++b)
                for (const KeyChord& d : k.chords_[std::size_t(b)])
                    if (c == d)
                        throw KeymapError(where + ": " + keyChordName(c) + " is bound to both " + kActions[a].name + " and " + kActions[b].name);
    return k;
}

std::optional<KeyAction> Keymap::actionFor(int key, int mods) const
{
    const KeyChord chord{key, mods & kModMask};
    for (int a = 0; a < kKeyActionCount; ++a)
        for (const KeyChord& c : chords_[std::size_t(a)])
            if (c == chord) return KeyAction(a);
    return std::nullopt;
}

nlohmann::json Keymap::json() const
{
    nlohmann::json out = nlohmann::json::object();
    for (const ActionInfo& i : kActions) {
        nlohmann::json list = nlohmann::json::array();
        for (const KeyChord& c : chords_[std::size_t(i.action)]) list.push_back(keyChordName(c));
        out[i.name] = list;
    }
    return out;
}

std::string Keymap::help() const
{
    std::string out;
    for (const ActionInfo& i : kActions) {
        std::string keys;
        for (const KeyChord& c : chords_[std::size_t(i.action)]) keys += (keys.empty() ? "" : ", ") + keyChordName(c);
        if (keys.empty()) keys = "(unbound)";
        keys.resize(std::max<std::size_t>(keys.size(), 22), ' ');
        out += "  " + keys + " " + i.description + "\n";
    }
    return out;
}

} // namespace vdbclay
