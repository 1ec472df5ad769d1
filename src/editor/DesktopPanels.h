// The desktop editor's Dear ImGui panels: brush (mode, shape, size, strength, falloff, material, colour,
// symmetry), custom brush editor, materials, tools, file actions, stats and help. They read the session
// and return commands; they never change the scene themselves.
#pragma once

#include "editor/EditingSession.h"
#include "render/RenderTypes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace vdbclay {

/// What the stats overlay shows of the last frame.
struct FrameFigures {
    FrameReport stream;
    render::FrameStats draw;
    double frameMs = 0.0;   // CPU time of the last frame (input, edits, streaming, uploads, recording)
    double editMs = 0.0;    // of which sculpting
    uint64_t bricksShown = 0;
};

struct CustomBrushPart {
    int shape = 0; // index into the primitive names
    float at[3] = {0, 0, 0};
    float size = 1.0f;
    float scale[3] = {1, 1, 1};
    bool remove = false;
};

class DesktopPanels {
public:
    /// Builds this frame's panels (between ImGui::NewFrame and ImGui::Render) and returns the commands
    /// they issued, in order. File actions that write other files run here and report in `status`.
    std::vector<Command> draw(EditingSession& session, const FrameFigures& figures);

    /// Where some widgets were drawn in the last frame (min x, min y, max x, max y; window pixels), by label:
    /// "mirror x", "mirror y", "mirror z", "Use as brush", "Save (Ctrl+S)", "Keep them", "Discard them".
    /// Tests click them through ImGui.
    std::map<std::string, std::array<float, 4>> widgetRects;

    bool showHelp = false;
    bool showStats = true;
    std::string status;       // the last action's outcome, shown at the bottom
    std::string openRequested; // a scene the user asked to open instead (the front end reopens)
    /// The user chose to drop the edits recovered after a crash (the front end reopens the scene
    /// discarding them).
    bool discardRecoveryRequested = false;

private:
    void track(const std::string& label);
    void brushPanel(EditingSession& session, std::vector<Command>& out);
    void customBrushPanel(EditingSession& session, std::vector<Command>& out);
    void materialsPanel(EditingSession& session, std::vector<Command>& out);
    void toolsPanel(EditingSession& session, std::vector<Command>& out);
    void filePanel(EditingSession& session, std::vector<Command>& out);
    void statsPanel(const EditingSession& session, const FrameFigures& figures);
    void recoveryOffer(const EditingSession& session);

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
    std::string savePath_, importPath_, exportPath_ = "scene.obj", openPath_;
};

} // namespace vdbclay
