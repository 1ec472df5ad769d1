// The desktop editor under a display (Xvfb and lavapipe in the test command): the window opens and draws
// with the validation layer silent, a mouse stroke made of X events (XTEST) through GLFW equals its
// replay, a menu clicked through Dear ImGui changes what the next stroke does, and recovered edits are
// offered. Skipped, saying so, where
// there is no display or no Vulkan device.
#include "desktop/DesktopEditor.h"
#include "editor/CameraControl.h"
#include "editor/EditingSession.h"
#include "render/ImageFile.h"
#include "render/VulkanContext.h"
#include "sculpt/StrokeScript.h"
#include "support/TestUtil.h"
#include "vdb_hermite/Volume.h"
#include "vdb_hermite/VolumeIO.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <catch2/catch.hpp>
#include <imgui.h>

#include <chrono>
#include <cmath>
#include <filesystem>

// Last: X11's headers define macros (None, Bool, Status...) that other headers use as names.
#include <X11/extensions/XTest.h>
#include <X11/keysym.h>
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
    return session.scene().storedLevel0();
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
        editor.finishEdits();
        return stillOpen;
    }
};

/// Input as the X server delivers it (XTEST), made on a connection of the test's own; the server sends
/// the events to the window under the pointer. When XSync returns, the server has made the events and put
/// them in the window's output; a round trip on GLFW's own connection then reads them into its queue (its
/// reply comes after them), so the next frame's poll sees them however the two processes are scheduled.
/// Without it, a release still in flight on a loaded machine left the stroke open when the test looked.
struct XInput {
    std::unique_ptr<Display, int (*)(Display*)> connection{XOpenDisplay(nullptr), XCloseDisplay};
    DesktopEditor& editor;
    int windowX = 0, windowY = 0;

    explicit XInput(DesktopEditor& e) : editor(e)
    {
        REQUIRE(connection);
        glfwGetWindowPos(editor.window(), &windowX, &windowY);
    }
    void deliver()
    {
        XSync(connection.get(), False);
        XSync(glfwGetX11Display(), False);
    }
    void moveTo(double x, double y)
    {
        XTestFakeMotionEvent(connection.get(), -1, windowX + int(x), windowY + int(y), CurrentTime);
        deliver();
    }
    void button(unsigned int which, bool down)
    {
        XTestFakeButtonEvent(connection.get(), which, down ? True : False, CurrentTime);
        deliver();
    }
    void key(KeySym symbol, bool down)
    {
        XTestFakeKeyEvent(connection.get(), XKeysymToKeycode(connection.get(), symbol), down ? True : False, CurrentTime);
        deliver();
    }
    void tap(KeySym symbol)
    {
        key(symbol, true);
        key(symbol, false);
        REQUIRE(editor.frame());
        editor.finishEdits();
    }
    /// A left-button drag from (x0, y0) in `steps` moves of (dx, dy), a frame after each event.
    void drag(double x0, double y0, double dx, double dy, int steps)
    {
        moveTo(x0, y0);
        REQUIRE(editor.frame());
        button(1, true);
        REQUIRE(editor.frame());
        for (int k = 1; k <= steps; ++k) {
            moveTo(x0 + dx * k, y0 + dy * k);
            REQUIRE(editor.frame());
        }
        button(1, false);
        REQUIRE(editor.frame());
        editor.finishEdits();
    }
};

/// One frame, then what its input gave the edit worker applied: the session may be read.
bool settledFrame(DesktopEditor& editor)
{
    const bool open = editor.frame();
    editor.finishEdits();
    return open;
}

/// Whether there is no display to test on, warning that the test is skipped.
bool skippedWithoutDisplay()
{
    if (desktopAvailable()) return false;
    WARN("skipped: no display (the test command runs the suite under xvfb-run)");
    return true;
}

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
    if (skippedWithoutDisplay()) return;
    TempDir dir;
    const std::string ball = makeBall(dir, "ball.vdb");
    std::filesystem::copy_file(ball, dir.file("copy.vdb"));
    EditingSession session(ball, quiet());
    UiDriver ui;
    std::unique_ptr<DesktopEditor> editor = openEditor(session, ui.options());
    if (!editor) return;
    for (int i = 0; i < 3; ++i) REQUIRE(settledFrame(*editor));
    session.scene().waitForLoads();
    for (int i = 0; i < 2; ++i) REQUIRE(settledFrame(*editor));
    CHECK(editor->lastFrame().triangles > 1000);

    // A stroke as the X server delivers it (XTEST: the pointer moves, the left button goes down, the
    // pointer drags across the ball, the button comes up), through GLFW's event loop and callbacks.
    XInput x(*editor);
    const auto stroke = [&](double x0, double y0) { x.drag(x0, y0, 12.0, -4.0, 4); };
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
    if (skippedWithoutDisplay()) return;
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
        for (int i = 0; i < 2; ++i) REQUIRE(settledFrame(*editor));
        INFO(answer);
        if (answer == "Keep them") {
            CHECK(ui.click(*editor, answer)); // the editor goes on, the edits stay
            CHECK_FALSE(editor->discardRecoveryRequested());
            REQUIRE(settledFrame(*editor));
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

namespace {

/// The ball streamed in, drawn, with the brush resting over it.
std::unique_ptr<DesktopEditor> readyEditor(EditingSession& session, UiDriver& ui)
{
    std::unique_ptr<DesktopEditor> editor = openEditor(session, ui.options());
    if (!editor) return nullptr;
    for (int i = 0; i < 3; ++i) REQUIRE(settledFrame(*editor));
    session.scene().waitForLoads();
    for (int i = 0; i < 2; ++i) REQUIRE(settledFrame(*editor));
    return editor;
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// The stroke points the session placed since command `from`.
std::vector<std::array<double, 3>> strokePoints(const EditingSession& session, std::size_t from)
{
    std::vector<std::array<double, 3>> out;
    const auto& commands = session.record().commands;
    for (std::size_t i = from; i < commands.size(); ++i)
        if (commands[i].command.point &&
            (commands[i].command.kind == Command::Kind::StrokeBegin || commands[i].command.kind == Command::Kind::StrokeMove))
            out.push_back(*commands[i].command.point);
    return out;
}

} // namespace

TEST_CASE("desktop: a sideways drag stays on the ball as the stroke found it, Ctrl inverts the brush and Shift smooths", "[desktop][editor]")
{
    if (skippedWithoutDisplay()) return;
    TempDir dir;
    EditingSession session(makeBall(dir, "ball.vdb"), quiet());
    UiDriver ui;
    std::unique_ptr<DesktopEditor> editor = readyEditor(session, ui);
    if (!editor) return;
    XInput x(*editor);
    CHECK(editor->title() == "VDBClay - ball.vdb");

    // Add, dragged sideways across the ball's middle: every stamp within a brush radius of the ball as it
    // was (the stamps used to climb the blobs they made, towards the camera).
    std::size_t from = session.record().commands.size();
    x.drag(420, 300, 10.0, 0.0, 14);
    const std::vector<std::array<double, 3>> points = strokePoints(session, from);
    CHECK(points.size() >= 10);
    for (const auto& p : points) CHECK(std::fabs(distance(p, {0, 0, 0}) - 20.0) <= session.brush().radius);
    for (const auto& p : points) CHECK(std::fabs(distance(p, {0, 0, 0}) - 20.0) <= 1.0); // on the surface itself
    CHECK(session.history().undoDepth() == 1);
    CHECK(editor->title() == "VDBClay - ball.vdb *");

    // Ctrl held: the stroke removes, and the brush is add again afterwards; Shift held: it smooths.
    for (const auto& [modifier, expected] : {std::pair<KeySym, std::string>{XK_Control_L, "remove"}, {XK_Shift_L, "smooth"}}) {
        x.key(modifier, true);
        x.drag(440, 320, 8.0, 0.0, 6);
        x.key(modifier, false);
        REQUIRE(settledFrame(*editor));
        INFO(expected);
        CHECK(session.brush().mode == "add");
        const nlohmann::json ops = session.appliedScript().at("ops");
        REQUIRE(!ops.empty());
        CHECK(ops.back().at("mode") == expected);
    }
    CHECK(session.history().undoDepth() == 3);

    // Ctrl+S saves: the title loses its mark.
    x.key(XK_Control_L, true);
    x.tap(XK_s);
    x.key(XK_Control_L, false);
    REQUIRE(settledFrame(*editor));
    CHECK_FALSE(session.unsaved());
    CHECK(editor->title() == "VDBClay - ball.vdb");
    CHECK(editor->validationMessages() == 0);
}

TEST_CASE("desktop: the wheel zooms up to two voxels from the surface and it is still drawn, numpad views, Home and F12", "[desktop][editor]")
{
    if (skippedWithoutDisplay()) return;
    TempDir dir;
    EditingSession session(makeBall(dir, "ball.vdb"), quiet());
    UiDriver ui;
    std::unique_ptr<DesktopEditor> editor = readyEditor(session, ui);
    if (!editor) return;
    XInput x(*editor);
    const std::array<int, 2> size{800, 600};
    x.moveTo(400, 300);
    REQUIRE(settledFrame(*editor));
    const auto gap = [&] {
        const Ray r = pointerRay(session.camera(), size, 400, 300);
        const auto hit = session.pick(r.origin, r.direction);
        REQUIRE(hit);
        return hit->distance;
    };
    const double framed = gap();
    int notches = 0;
    while (gap() > 2.0 && notches < 100) {
        x.button(4, true); // the wheel, one notch towards the scene
        x.button(4, false);
        REQUIRE(settledFrame(*editor));
        ++notches;
    }
    INFO("from " << framed << " to " << gap() << " voxels in " << notches << " notches");
    REQUIRE(gap() <= 2.0);
    for (int i = 0; i < 3; ++i) REQUIRE(settledFrame(*editor));
    session.scene().waitForLoads();
    REQUIRE(settledFrame(*editor));
    CHECK(editor->lastFrame().triangles > 0);

    // F12 writes the view as drawn: the surface fills its centre (the near plane used to cut it away).
    x.tap(XK_F12);
    const std::string shot = dir.file("ball-shot-001.png");
    REQUIRE(std::filesystem::exists(shot));
    const render::Image image = render::readImage(shot);
    REQUIRE(image.width == 800);
    const uint8_t* centre = image.pixel(400, 300);
    const int background = std::abs(int(centre[0]) - 41) + std::abs(int(centre[1]) - 43) + std::abs(int(centre[2]) - 48);
    INFO("centre pixel " << int(centre[0]) << " " << int(centre[1]) << " " << int(centre[2]));
    CHECK(background > 30);

    // Home frames the whole ball again; numpad 7 looks down on it, Ctrl + numpad 1 from behind.
    x.tap(XK_Home);
    CHECK(gap() > 20.0);
    x.tap(XK_KP_7);
    CHECK(session.camera().eye[1] - session.camera().target[1] > 0.0);
    CHECK(std::fabs(session.camera().eye[0] - session.camera().target[0]) < 1e-9);
    x.key(XK_Control_L, true);
    x.tap(XK_KP_1);
    x.key(XK_Control_L, false);
    CHECK(session.camera().eye[2] < session.camera().target[2]);
    CHECK(editor->validationMessages() == 0);
}

TEST_CASE("desktop: a grab dragged three radii keeps the grabbed point under the pointer", "[desktop][editor]")
{
    if (skippedWithoutDisplay()) return;
    TempDir dir;
    EditingSession session(makeBall(dir, "ball.vdb"), quiet());
    UiDriver ui;
    std::unique_ptr<DesktopEditor> editor = readyEditor(session, ui);
    if (!editor) return;
    XInput x(*editor);
    x.tap(XK_g);
    REQUIRE(session.brush().mode == "move");
    BrushSettings full = session.brush();
    full.strength = 1.0;
    Command setFull;
    setFull.kind = Command::Kind::SetBrush;
    setFull.brush = full;
    editor->submit(setFull);
    editor->finishEdits();
    // Three radii on the screen at the grabbed point's depth.
    const render::Camera& camera = session.camera();
    const double depth = distance(camera.eye, camera.target) - 20.0;
    const double pixelsPerUnit = 600.0 / (2.0 * depth * std::tan(camera.fovYDegrees * 3.14159265358979 / 360.0));
    const double pixels = 3.0 * full.radius * pixelsPerUnit;
    const int steps = 12;
    const std::size_t from = session.record().commands.size();
    x.drag(400, 300, pixels / steps, 0.0, steps);
    const std::vector<std::array<double, 3>> points = strokePoints(session, from);
    REQUIRE(points.size() == std::size_t(steps) + 1);
    const std::array<double, 3> held = points.back();
    CHECK(distance(points.front(), held) > 2.5 * full.radius);
    const Ray last = pointerRay(session.camera(), {800, 600}, 400 + pixels, 300);
    const auto hit = session.pick(last.origin, last.direction);
    REQUIRE(hit);
    INFO("held at " << held[0] << " " << held[1] << " " << held[2] << ", the surface under the pointer at " << hit->point[0] << " "
                    << hit->point[1] << " " << hit->point[2]);
    CHECK(distance(hit->point, held) <= 0.5);
    CHECK(editor->validationMessages() == 0);
}

TEST_CASE("desktop: the overlay's frame interval agrees with the wall clock, its parts never exceed it, the brush persists", "[desktop][editor]")
{
    if (skippedWithoutDisplay()) return;
    TempDir dir;
    const std::string ball = makeBall(dir, "ball.vdb");
    UiDriver ui;
    ui.configFolder = dir.file("config");
    {
        EditingSession session(ball, quiet());
        std::unique_ptr<DesktopEditor> editor = readyEditor(session, ui);
        if (!editor) return;
        XInput x(*editor);
        REQUIRE(settledFrame(*editor));
        double reported = 0.0;
        const auto start = std::chrono::steady_clock::now();
        for (int i = 0; i < 100; ++i) {
            REQUIRE(settledFrame(*editor));
            const FrameFigures& f = editor->figures();
            reported += f.intervalMs;
            const double parts = f.inputMs + f.sculptMs + f.streamMs + f.meshMs + f.drawMs + f.presentMs;
            CHECK(parts <= f.intervalMs * 1.0001 + 1e-6);
            CHECK(f.sculptMs >= 0.0);
        }
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        INFO("reported " << reported << " ms, wall clock " << wall << " ms");
        // The 100 intervals end at the 100th frame's start, a frame before the clock stops.
        CHECK(std::fabs(reported - wall) <= 0.1 * wall);
        x.tap(XK_r); // the brush becomes remove, and is kept for the next session
        CHECK(session.brush().mode == "remove");
    }
    CHECK(std::filesystem::exists(dir.file("config/settings.json")));
    CHECK(std::filesystem::exists(dir.file("config/keymap.json")));
    EditingSession again(ball, quiet());
    std::unique_ptr<DesktopEditor> editor = readyEditor(again, ui);
    CHECK(again.brush().mode == "remove");
}

TEST_CASE("desktop: the stabilizer keeps the stroke a string's length behind the pointer", "[desktop][editor]")
{
    if (skippedWithoutDisplay()) return;
    TempDir dir;
    std::filesystem::create_directories(dir.file("config"));
    writeText(dir.file("config/settings.json"), R"({"stabilizer": 40})");
    EditingSession session(makeBall(dir, "ball.vdb"), quiet());
    UiDriver ui;
    ui.configFolder = dir.file("config");
    std::unique_ptr<DesktopEditor> editor = readyEditor(session, ui);
    if (!editor) return;
    XInput x(*editor);
    // A drag of 100 pixels to the right: the stroke moves only once the string is taut, and ends 40
    // pixels behind the pointer.
    const std::size_t from = session.record().commands.size();
    x.drag(400, 300, 10.0, 0.0, 10);
    int moves = 0;
    std::optional<Ray> last;
    for (std::size_t i = from; i < session.record().commands.size(); ++i) {
        const Command& c = session.record().commands[i].command;
        if (c.kind == Command::Kind::StrokeMove) {
            ++moves;
            last = c.ray;
        }
    }
    CHECK(moves == 6); // the first four moves (40 pixels) leave the string slack
    REQUIRE(last);
    const Ray expected = pointerRay(session.camera(), {800, 600}, 460, 300);
    for (std::size_t a = 0; a < 3; ++a) CHECK(last->direction[a] == Approx(expected.direction[a]).margin(1e-9));
}
