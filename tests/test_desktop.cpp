// The desktop editor under a display (Xvfb and lavapipe in the test command): the window opens and draws
// with the validation layer silent, a mouse stroke made of X events (XTEST) through GLFW equals its
// replay, a menu clicked through Dear ImGui changes what the next stroke does, and recovered edits are
// offered. Skipped, saying so, where
// there is no display or no Vulkan device.
#include "desktop/DesktopEditor.h"
#include "editor/EditingSession.h"
#include "render/VulkanContext.h"
#include "sculpt/StrokeScript.h"
#include "support/TestUtil.h"
#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeIO.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <catch2/catch.hpp>
#include <imgui.h>

#include <filesystem>

// Last: X11's headers define macros (None, Bool, Status...) that other headers use as names.
#include <X11/extensions/XTest.h>
// GLFW's X11 accessor, declared here: glfw3native.h pulls in Xrandr's headers, a package the tests need
// for nothing else.
extern "C" Display* glfwGetX11Display(void);

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

std::string makeBall(const TempDir& dir, const std::string& name)
{
    Volume v(1.0);
    runStrokeScript(v, parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 20}}]})"));
    saveVolume(v, dir.file(name));
    return dir.file(name);
}

SessionOptions quiet()
{
    SessionOptions o;
    o.memoryBudgetBytes = 256ull << 20;
    o.autosaveSeconds = 1e9;
    o.idleAutosaveSeconds = 1e9;
    return o;
}

Volume committed(EditingSession& session)
{
    session.autosave();
    return session.scene().store().loadLevel(0);
}

/// Drives the menus through ImGui's input: this frame's pointer and left button, when set.
struct UiDriver {
    std::optional<std::array<float, 2>> pointer;
    bool button = false;
    std::string configFolder;

    DesktopOptions options()
    {
        DesktopOptions o;
        o.validation = true;
        o.windowSize = std::array<int, 2>{800, 600};
        o.configFolder = configFolder; // nothing kept between tests unless a test asks

        o.beforeUi = [this](uint64_t) {
            if (!pointer) return;
            ImGuiIO& io = ImGui::GetIO();
            io.MousePos = ImVec2((*pointer)[0], (*pointer)[1]);
            io.MouseDown[0] = button;
        };
        return o;
    }
    /// Clicks a tracked widget: pressed one frame, released the next (ImGui acts on the release). False
    /// when a frame reported the window closed.
    bool click(DesktopEditor& editor, const std::string& label)
    {
        const auto rect = editor.widgetRect(label);
        REQUIRE(rect);
        pointer = std::array<float, 2>{((*rect)[0] + (*rect)[2]) * 0.5f, ((*rect)[1] + (*rect)[3]) * 0.5f};
        button = true;
        const bool open = editor.frame();
        button = false;
        const bool stillOpen = open && editor.frame();
        pointer.reset();
        return stillOpen;
    }
};

/// The editor's window, or null (with a warning saying why the test is skipped) where none can open.
std::unique_ptr<DesktopEditor> openEditor(EditingSession& session, const DesktopOptions& options)
{
    try {
        return std::make_unique<DesktopEditor>(session, options);
    } catch (const NoDisplay& e) {
        WARN("skipped: " << e.what());
    } catch (const render::NoVulkanDevice& e) {
        WARN("skipped: no Vulkan device: " << e.what());
    }
    return nullptr;
}

} // namespace

TEST_CASE("desktop: a mouse stroke through the window equals its replay, a menu clicked through ImGui changes the next stroke", "[desktop][editor]")
{
    if (!desktopAvailable()) {
        WARN("skipped: no display (the test command runs the suite under xvfb-run)");
        return;
    }
    TempDir dir;
    const std::string ball = makeBall(dir, "ball.vdb");
    std::filesystem::copy_file(ball, dir.file("copy.vdb"));
    EditingSession session(ball, quiet());
    UiDriver ui;
    std::unique_ptr<DesktopEditor> editor = openEditor(session, ui.options());
    if (!editor) return;
    for (int i = 0; i < 3; ++i) REQUIRE(editor->frame());
    session.scene().waitForLoads();
    for (int i = 0; i < 2; ++i) REQUIRE(editor->frame());
    CHECK(editor->lastFrame().triangles > 1000);

    // A stroke as the X server delivers it (XTEST: the pointer moves, the left button goes down, the
    // pointer drags across the ball, the button comes up), through GLFW's event loop and callbacks. The
    // events are made on a connection of the test's own; the server sends them to the window under the
    // pointer.
    const std::unique_ptr<Display, int (*)(Display*)> connection(XOpenDisplay(nullptr), XCloseDisplay);
    Display* display = connection.get();
    REQUIRE(display);
    int windowX = 0, windowY = 0;
    glfwGetWindowPos(editor->window(), &windowX, &windowY);
    // When the test's XSync returns, the server has made the events and put them in the window's
    // output; a round trip on GLFW's own connection then reads them into its queue (its reply comes
    // after them), so the next frame's poll sees them however the two processes are scheduled. Without
    // it, a release still in flight on a loaded machine left the stroke open when the test looked.
    const auto deliver = [&] {
        XSync(display, False);
        XSync(glfwGetX11Display(), False);
    };
    const auto moveTo = [&](double x, double y) {
        XTestFakeMotionEvent(display, -1, windowX + int(x), windowY + int(y), CurrentTime);
        deliver();
    };
    const auto leftButton = [&](bool down) {
        XTestFakeButtonEvent(display, 1, down ? True : False, CurrentTime);
        deliver();
    };
    const auto stroke = [&](double x0, double y0) {
        moveTo(x0, y0);
        REQUIRE(editor->frame());
        leftButton(true);
        REQUIRE(editor->frame());
        for (int k = 1; k <= 4; ++k) {
            moveTo(x0 + 12.0 * k, y0 - 4.0 * k);
            REQUIRE(editor->frame());
        }
        leftButton(false);
        REQUIRE(editor->frame());
    };
    stroke(420, 300);
    CHECK(session.history().undoDepth() == 1);
    CHECK(session.stats().stampsApplied >= 3);
    CHECK_FALSE(session.brush().symmetry.is_object());

    // Click "mirror x" in the brush panel (two frames per UI step).
    REQUIRE(ui.click(*editor, "mirror x"));
    REQUIRE(session.brush().symmetry.is_object());
    CHECK(session.brush().symmetry.at("mirror") == nlohmann::json::array({"x"}));

    // The next stroke is mirrored: it adds where its mirror image lies too.
    const Volume beforeSecond = committed(session);
    stroke(430, 330);
    CHECK(session.history().undoDepth() == 2);
    const Volume after = committed(session);
    const nlohmann::json ops = session.appliedScript().at("ops");
    REQUIRE(!ops.empty());
    const nlohmann::json& lastOp = ops.back();
    REQUIRE(lastOp.contains("symmetry"));
    const nlohmann::json& at = lastOp.contains("at") ? lastOp.at("at") : lastOp.at("path").back();
    const std::array<int32_t, 3> mirrored{int32_t(std::lround(-at[0].get<double>())), int32_t(std::lround(at[1].get<double>())),
                                          int32_t(std::lround(at[2].get<double>()))};
    INFO("stamp at " << at.dump());
    CHECK(after.materialAt(mirrored) != kEmptyMaterial);
    CHECK_FALSE(identical(beforeSecond, after));

    // The session's record, replayed with no window on the scene as it was, makes the same scene.
    const SessionRecord record = session.record();
    CHECK(editor->validationMessages() == 0);
    editor.reset();
    EditingSession replayed(dir.file("copy.vdb"), quiet());
    replaySession(replayed, record);
    CHECK(identical(committed(replayed), after));
}

TEST_CASE("desktop: edits recovered after a crash are offered: kept, or dropped through the dialog", "[desktop][editor]")
{
    if (!desktopAvailable()) {
        WARN("skipped: no display (the test command runs the suite under xvfb-run)");
        return;
    }
    TempDir dir;
    const std::string ball = makeBall(dir, "ball.vdb");
    const Volume saved = loadVolume(ball);
    {
        // Edits autosaved, never saved into the .vdb: what a crash leaves.
        EditingSession crashed(ball, quiet());
        Command op;
        op.kind = Command::Kind::ApplyOp;
        op.op = {{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 6}}}, {"at", {20, 0, 0}}};
        crashed.apply(op);
        crashed.autosave();
    }
    UiDriver ui;
    for (const std::string answer : {"Keep them", "Discard them"}) {
        EditingSession session(ball, quiet());
        REQUIRE(session.recoveredEdits() > 0);
        std::unique_ptr<DesktopEditor> editor = openEditor(session, ui.options());
        if (!editor) return;
        for (int i = 0; i < 2; ++i) REQUIRE(editor->frame());
        INFO(answer);
        if (answer == "Keep them") {
            CHECK(ui.click(*editor, answer)); // the editor goes on, the edits stay
            CHECK_FALSE(editor->discardRecoveryRequested());
            REQUIRE(editor->frame());
            CHECK_FALSE(editor->widgetRect("Keep them")); // the dialog is gone
            CHECK_FALSE(identical(committed(session), saved));
        } else {
            CHECK_FALSE(ui.click(*editor, answer)); // the editor stops so that the scene is opened again
            CHECK(editor->discardRecoveryRequested());
            CHECK(editor->validationMessages() == 0);
            editor.reset();
        }
    }
    SessionOptions discard = quiet();
    discard.discardRecovery = true;
    EditingSession reopened(ball, discard);
    CHECK(reopened.recoveredEdits() == 0);
    CHECK(identical(committed(reopened), saved));
}
