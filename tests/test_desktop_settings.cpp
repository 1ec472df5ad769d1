// What the desktop keeps and reads without a window: the keymap (defaults, a user's file, clear errors),
// the settings file and the file browser's listing.
#include "desktop/DesktopEditor.h"
#include "desktop/DesktopSettings.h"
#include "panels/FileBrowser.h"
#include "desktop/Keymap.h"
#include "support/TestUtil.h"
#include "vdb_hermite/PrintableText.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

using namespace vdbclay;
using namespace vdbclay::test;

TEST_CASE("editor: the keymap binds every action by default, a user's file rebinds some, and bad files are refused clearly", "[editor][keymap]")
{
    const Keymap k = Keymap::defaults();
    for (int a = 0; a < kKeyActionCount; ++a) CHECK_FALSE(k.chords(KeyAction(a)).empty());
    CHECK(k.actionFor(GLFW_KEY_Z, GLFW_MOD_CONTROL) == KeyAction::Undo);
    CHECK(k.actionFor(GLFW_KEY_Z, GLFW_MOD_CONTROL | GLFW_MOD_SHIFT) == KeyAction::Redo);
    CHECK(k.actionFor(GLFW_KEY_Y, GLFW_MOD_CONTROL) == KeyAction::Redo);
    CHECK(k.actionFor(GLFW_KEY_F, 0) == KeyAction::RadiusDrag);
    CHECK(k.actionFor(GLFW_KEY_F, GLFW_MOD_SHIFT) == KeyAction::StrengthDrag);
    CHECK(k.actionFor(GLFW_KEY_HOME, 0) == KeyAction::FrameAll);
    CHECK(k.actionFor(GLFW_KEY_KP_1, 0) == KeyAction::ViewFront);
    CHECK(k.actionFor(GLFW_KEY_KP_1, GLFW_MOD_CONTROL) == KeyAction::ViewBack);
    CHECK(k.actionFor(GLFW_KEY_KP_7, 0) == KeyAction::ViewTop);
    CHECK(k.actionFor(GLFW_KEY_S, GLFW_MOD_CONTROL) == KeyAction::Save);
    CHECK(k.actionFor(GLFW_KEY_S, 0) == KeyAction::ModeSmooth);
    CHECK(k.actionFor(GLFW_KEY_S, GLFW_MOD_CONTROL | 0x10 /* Caps Lock */) == KeyAction::Save);
    CHECK_FALSE(k.actionFor(GLFW_KEY_J, 0));
    // Every chord prints as it parses.
    for (int a = 0; a < kKeyActionCount; ++a)
        for (const KeyChord& c : k.chords(KeyAction(a))) CHECK(parseKeyChord(keyChordName(c)) == c);

    // The defaults, written as a file, read back the same.
    CHECK(Keymap::parse(k.json().dump(), "k.json").json() == k.json());
    // A user's file rebinds what it names and keeps the rest.
    const Keymap mine = Keymap::parse(R"({"undo": ["Ctrl+U", "F1"], "mode_add": "Shift+A", "help": []})", "mine.json");
    CHECK(mine.actionFor(GLFW_KEY_U, GLFW_MOD_CONTROL) == KeyAction::Undo);
    CHECK(mine.actionFor(GLFW_KEY_F1, 0) == KeyAction::Undo);
    CHECK_FALSE(mine.actionFor(GLFW_KEY_Z, GLFW_MOD_CONTROL));
    CHECK(mine.actionFor(GLFW_KEY_A, GLFW_MOD_SHIFT) == KeyAction::ModeAdd);
    CHECK_FALSE(mine.actionFor(GLFW_KEY_H, 0));
    CHECK(mine.actionFor(GLFW_KEY_R, 0) == KeyAction::ModeRemove);
    CHECK(mine.help().find("(unbound)") != std::string::npos);

    const auto refused = [](const std::string& text, const std::string& expected) {
        try {
            Keymap::parse(text, "bad.json");
            FAIL("accepted: " << text);
        } catch (const KeymapError& e) {
            INFO(e.what());
            CHECK(std::string(e.what()).find(expected) != std::string::npos);
            CHECK(std::string(e.what()).find("bad.json") != std::string::npos);
            CHECK(isPrintableName(e.what(), std::string::npos));
        }
    };
    refused("{", "JSON");
    refused("[]", "must be an object");
    refused(R"({"fly": "F"})", "unknown action 'fly'");
    refused(R"({"undo": "Hyper+Z"})", "unknown modifier 'Hyper'");
    refused(R"({"undo": "Ctrl+Zed"})", "unknown key 'Zed'");
    refused(R"({"undo": 3})", "undo: must be a chord");
    refused(R"({"undo": "R"})", "R is bound to both undo and mode_remove");
    refused(R"({"undo": "Ctrl+Z", "undo": "Ctrl+U"})", "appears twice");
    refused("{\"undo\": \"Ctrl+\x7f\"}", "unknown key");
}

TEST_CASE("editor: the desktop's settings and keymap live in the config folder, survive a round trip, and damaged ones fall back to defaults", "[editor][keymap]")
{
    TempDir dir;
    const std::string folder = dir.file("config/vdbclay");
    std::string warning;
    // Nothing kept yet: the defaults, quietly; the keymap file is written for the user to find.
    const DesktopSettings none = loadDesktopSettings(folder, &warning);
    CHECK(warning.empty());
    CHECK_FALSE(none.brush);
    CHECK(loadKeymap(folder, true, &warning).json() == Keymap::defaults().json());
    CHECK(warning.empty());
    CHECK(std::filesystem::exists(folder + "/keymap.json"));

    DesktopSettings s;
    s.brush.emplace();
    s.brush->mode = "inflate";
    s.brush->radius = 3.5;
    s.brush->strength = 0.25;
    s.brush->pressure = PressureTarget::Strength;
    s.brush->accumulate = true;
    s.windowSize = {1024, 700};
    s.showStats = false;
    s.showHelp = true;
    s.look = render::ViewMode::Clay;
    s.wireframe = true;
    saveDesktopSettings(s, folder);
    const DesktopSettings back = loadDesktopSettings(folder, &warning);
    CHECK(warning.empty());
    REQUIRE(back.brush);
    CHECK(brushSettingsJson(*back.brush) == brushSettingsJson(*s.brush));
    CHECK(back.windowSize == s.windowSize);
    CHECK(back.showStats == s.showStats);
    CHECK(back.showHelp == s.showHelp);
    CHECK(back.look == s.look);
    CHECK(back.wireframe == s.wireframe);

    // A damaged settings file or keymap: the defaults, and a warning naming the file.
    for (const std::string text : {"{", R"({"window": [10, 10]})", R"({"brush": {"mode": "melt"}})", R"({"look": "sepia"})"}) {
        { std::ofstream(folder + "/settings.json") << text; }
        warning.clear();
        const DesktopSettings fallback = loadDesktopSettings(folder, &warning);
        CHECK(warning.find("settings.json") != std::string::npos);
        CHECK_FALSE(fallback.brush);
        CHECK(fallback.windowSize == DesktopSettings{}.windowSize);
    }
    { std::ofstream(folder + "/keymap.json") << R"({"undo": "Nope"})"; }
    warning.clear();
    CHECK(loadKeymap(folder, true, &warning).json() == Keymap::defaults().json());
    CHECK(warning.find("keymap.json") != std::string::npos);
    // No folder at all (no HOME): nothing read or written.
    CHECK(loadKeymap("", true, &warning).json() == Keymap::defaults().json());
}

TEST_CASE("editor: the file browser lists folders first, then the files of the kinds asked for, hidden ones left out", "[editor]")
{
    TempDir dir;
    std::filesystem::create_directories(dir.file("b-folder"));
    std::filesystem::create_directories(dir.file("a-folder"));
    std::filesystem::create_directories(dir.file(".hidden"));
    for (const char* name : {"z.vdb", "scene.VDB", "notes.txt", "store.vdbclay", ".secret.vdb"}) std::ofstream(dir.file(name)) << "x";
    const std::vector<FolderEntry> scenes = browseFolder(dir.path().string(), {".vdb", ".vdbclay"});
    std::vector<std::string> names;
    for (const FolderEntry& e : scenes) names.push_back(e.name + (e.folder ? "/" : ""));
    CHECK(names == std::vector<std::string>{"a-folder/", "b-folder/", "scene.VDB", "store.vdbclay", "z.vdb"});
    CHECK(browseFolder(dir.path().string(), {}).size() == 6);
    CHECK_THROWS_AS(browseFolder(dir.file("missing"), {}), std::filesystem::filesystem_error);
}
