// The editor's Dear ImGui panels, which the desktop window and the headset's menu quad both draw: brush (mode, shape, size, strength, falloff, pressure, material,
// symmetry), custom brush editor, materials, tools, file actions (through a file browser), finding
// models like the sculpture (QueryPanel), the view's look, stats and help. They read the session and return commands; they never change the scene
// themselves.
#pragma once

#include "panels/FileBrowser.h"
#include "panels/QueryPanel.h"
#include "editor/SessionWorker.h"
#include "render/RenderTypes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

/// What the stats overlay shows of the last whole frame. The parts are measured one after the other
/// inside the frame, so they never add up to more than its interval; the interval is the wall clock from
/// one frame's start to the next (waiting for the display included).
struct FrameFigures {
    FrameReport stream;
    render::FrameStats draw;
    double intervalMs = 0.0;        // the last frame's, wall clock
    double averageIntervalMs = 0.0; // over the frames of about the last second
    double inputMs = 0.0;   // events, menus and commands, sculpting left out
    double sculptMs = 0.0;  // the commands' edits on the frame thread (none: the edit worker applies them)
    double streamMs = 0.0;  // the session's frame: streaming, autosave
    double meshMs = 0.0;    // meshing changed bricks and handing them to the renderer
    double drawMs = 0.0;    // culling, uploads, recording and the device's work until it finished
    double presentMs = 0.0; // acquiring and presenting the swapchain image
    uint64_t bricksShown = 0;
    uint64_t pendingEdits = 0; // commands queued for the edit worker or under way
    uint64_t meshesWaiting = 0; // shown bricks whose new mesh the mesh worker has not finished
    uint64_t uploadsWaiting = 0; // meshes finished and left by the frame's upload budget for later frames
    /// A headset's: display refreshes its frames missed, and the share of full detail the frame keeps to
    /// hold the rate (1: all of it). A window's: none.
    std::optional<uint64_t> missedFrames;
    double detail = 1.0;
};

struct CustomBrushPart {
    int shape = 0; // index into the primitive names
    float at[3] = {0, 0, 0};
    float size = 1.0f;
    float scale[3] = {1, 1, 1};
    bool remove = false;
};

class SessionPanels {
public:
    /// Builds this frame's panels (between ImGui::NewFrame and ImGui::Render) and returns the commands
    /// they issued, in order. File actions that write other files run here and report in `status`.
    std::vector<Command> draw(SessionWorker& session, const FrameFigures& figures);

    /// Where some widgets were drawn in the last frame (min x, min y, max x, max y; window pixels), by label:
    /// "mirror x", "mirror y", "mirror z", "Use as brush", "Save (Ctrl+S)", "Keep them", "Discard them".
    /// Tests click them through ImGui.
    std::map<std::string, std::array<float, 4>> widgetRects;

    /// Where the panels' windows go in the display (x, y from the top left); absent, all of it (a headset
    /// draws other pictures beside them).
    std::optional<std::array<float, 2>> canvas;
    float panelWidth = 340.0f; // the main panel's width at first
    bool showHelp = false;
    bool showStats = true;
    render::ViewMode look = render::ViewMode::Shaded; // the view panel's choice (the window applies it)
    bool wireframe = false;
    float stabilizer = 0.0f;  // lazy mouse: the stroke trails the pointer by this many pixels (0: off)
    std::string helpText;     // the shortcuts in effect (the window's keymap)
    std::string status;       // the last action's outcome, shown at the bottom
    std::string openRequested; // a scene the user asked to open instead (the front end reopens)
    /// Where the brush is, set by the front end each frame (the last surface point under the pointer
    /// outside the panels, a hand's brush): where a found model is placed.
    std::optional<std::array<double, 3>> brushPoint;
    QueryPanel query; // "Find models"
    /// The user chose to drop the edits recovered after a crash (the front end reopens the scene
    /// discarding them).
    bool discardRecoveryRequested = false;

private:
    std::array<float, 2> canvasArea() const;
    void track(const std::string& label);
    void brushPanel(SessionWorker& session, std::vector<Command>& out);
    void customBrushPanel(SessionWorker& session, std::vector<Command>& out);
    void materialsPanel(SessionWorker& session, std::vector<Command>& out);
    void toolsPanel(SessionWorker& session, std::vector<Command>& out);
    void filePanel(SessionWorker& session, std::vector<Command>& out);
    void viewPanel();
    void fileChosen(SessionWorker& session, const std::string& path, std::vector<Command>& out);
    void statsPanel(const SessionWorker& session, const FrameFigures& figures);
    void recoveryOffer(const SessionWorker& session);

    bool recoveryAnswered_ = false;
    std::vector<CustomBrushPart> parts_{CustomBrushPart{}};
    float customSmoothness_ = 0.2f;
    std::string presetName_ = "my-brush";
    std::string materialName_ = "clay";
    float materialColour_[3] = {0.75f, 0.55f, 0.4f};
    float materialToughness_ = 0.5f;
    std::string materialTexture_;
    float toolMin_[3] = {-8, -8, -8}, toolMax_[3] = {8, 8, 8};
    std::string toolPath_ = "tool.vdb";
    FileBrowser browser_;
};

} // namespace vdbclay
