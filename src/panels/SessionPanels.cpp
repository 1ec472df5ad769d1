#include "panels/SessionPanels.h"

#include "editor/SceneFileActions.h"
#include "sculpt/FieldBrushes.h"
#include "vdb_hermite/AtomicFile.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace vdbclay {

namespace {

constexpr const char* kModes[] = {"add", "remove", "paint", "erode", "smooth", "flatten", "inflate", "deflate", "move", "intersect", "mask", "unmask"};
constexpr const char* kShapes[] = {"sphere", "box", "cylinder", "capsule", "torus", "cone"};
constexpr const char* kFalloffs[] = {"smooth", "linear", "constant", "curve"};
constexpr int kCurvePoints = 6; // a new curve's points (a curve read from a file keeps its own)
constexpr const char* kAxes[] = {"x", "y", "z"};
constexpr const char* kPressures[] = {"size", "strength", "none"};
constexpr PressureTarget kPressureTargets[] = {PressureTarget::Size, PressureTarget::Strength, PressureTarget::None};
constexpr const char* kLooks[] = {"material", "clay", "normals", "levels of detail", "toughness"};
constexpr render::ViewMode kLookModes[] = {render::ViewMode::Shaded, render::ViewMode::Clay, render::ViewMode::Normals, render::ViewMode::Lod,
                                           render::ViewMode::Toughness};
constexpr const char* kOpenTitle = "Open a scene";
constexpr const char* kSaveAsTitle = "Save the scene as";
constexpr const char* kImportTitle = "Import a mesh";
constexpr const char* kExportTitle = "Export the scene";

/// A figure the frame may not know yet (a view with nothing shown reports no error): "-" then.
std::string figure(double value, const char* format)
{
    if (!std::isfinite(value) || std::fabs(value) >= 1e29) return "-";
    char text[64];
    std::snprintf(text, sizeof text, format, value);
    return text;
}

int indexOf(const char* const* names, int count, const std::string& name)
{
    for (int i = 0; i < count; ++i)
        if (name == names[i]) return i;
    return -1;
}

/// A primitive of unit size as a script brush: what the brush's radius scales.
nlohmann::json unitShape(int shape)
{
    switch (shape) {
    case 1: return {{"shape", "box"}, {"size", {1.0, 1.0, 1.0}}, {"rounding", 0.1}};
    case 2: return {{"shape", "cylinder"}, {"radius", 1.0}, {"height", 2.0}};
    case 3: return {{"shape", "capsule"}, {"radius", 0.6}, {"length", 0.8}};
    case 4: return {{"shape", "torus"}, {"radius", 0.75}, {"minor_radius", 0.25}};
    case 5: return {{"shape", "cone"}, {"radius", 1.0}, {"height", 2.0}};
    default: return {{"shape", "sphere"}, {"radius", 1.0}};
    }
}

/// The falloff curve: its weights from the brush's rim (left) to its deepest point (right), one vertical
/// slider each, drawn as a curve above them.
bool falloffCurveEditor(std::vector<double>& curve)
{
    std::vector<float> values(curve.begin(), curve.end());
    ImGui::PlotLines("##falloff curve", values.data(), int(values.size()), 0, "rim -> centre", 0.0f, 1.0f, ImVec2(0, 60));
    bool changed = false;
    for (std::size_t i = 0; i < curve.size(); ++i) {
        if (i > 0) ImGui::SameLine();
        ImGui::PushID(int(i));
        float w = float(curve[i]);
        if (ImGui::VSliderFloat("##w", ImVec2(18, 80), &w, 0.0f, 1.0f, "")) {
            curve[i] = std::clamp(double(w), 0.0, 1.0);
            changed = true;
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("weight %.2f at %.0f%% of the way in", w, 100.0 * double(i) / double(curve.size() - 1));
        ImGui::PopID();
    }
    return changed;
}

Command brushCommand(const BrushSettings& brush)
{
    Command c;
    c.kind = Command::Kind::SetBrush;
    c.brush = brush;
    return c;
}

struct SymmetryUi {
    bool mirror[3] = {false, false, false};
    int radialAxis = 1, radialCount = 1;
    float center[3] = {0, 0, 0};
};

SymmetryUi symmetryOf(const nlohmann::json& s)
{
    SymmetryUi ui;
    if (!s.is_object()) return ui;
    if (s.contains("mirror"))
        for (const auto& m : s.at("mirror"))
            if (m.is_string()) {
                const int a = indexOf(kAxes, 3, m.get<std::string>());
                if (a >= 0) ui.mirror[a] = true;
            }
    if (s.contains("radial")) {
        const nlohmann::json& r = s.at("radial");
        if (r.contains("count")) ui.radialCount = r.at("count").get<int>();
        if (r.contains("axis")) ui.radialAxis = std::max(0, indexOf(kAxes, 3, r.at("axis").get<std::string>()));
    }
    if (s.contains("center"))
        for (int a = 0; a < 3; ++a) ui.center[a] = s.at("center")[std::size_t(a)].get<float>();
    return ui;
}

nlohmann::json symmetryJson(const SymmetryUi& ui)
{
    nlohmann::json mirror = nlohmann::json::array();
    for (int a = 0; a < 3; ++a)
        if (ui.mirror[a]) mirror.push_back(kAxes[a]);
    if (mirror.empty() && ui.radialCount <= 1) return nullptr;
    nlohmann::json s = {{"center", {ui.center[0], ui.center[1], ui.center[2]}}};
    if (!mirror.empty()) s["mirror"] = mirror;
    if (ui.radialCount > 1) s["radial"] = {{"axis", kAxes[ui.radialAxis]}, {"count", ui.radialCount}};
    return s;
}

} // namespace

std::array<float, 2> SessionPanels::canvasArea() const
{
    return canvas.value_or(std::array<float, 2>{ImGui::GetIO().DisplaySize.x, ImGui::GetIO().DisplaySize.y});
}

std::vector<Command> SessionPanels::draw(SessionWorker& session, const FrameFigures& figures)
{
    std::vector<Command> out;
    widgetRects.clear();
    const auto [areaX, areaY] = canvasArea();
    const ImVec2 area(areaX, areaY);
    // The panel takes the window's height at first and may be resized; what does not fit scrolls, and the
    // last action's outcome stays in sight below the scrolling part.
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(panelWidth, std::max(200.0f, area.y - 20.0f)), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSizeConstraints(ImVec2(240, 120), ImVec2(std::max(240.0f, area.x - 20.0f), std::max(120.0f, area.y - 20.0f)));
    if (ImGui::Begin("VDBClay")) {
        const float footer = status.empty() ? 0.0f : ImGui::GetTextLineHeightWithSpacing() * 3.0f;
        if (ImGui::BeginChild("panels", ImVec2(0, -footer))) {
            if (ImGui::CollapsingHeader("Brush", ImGuiTreeNodeFlags_DefaultOpen)) brushPanel(session, out);
            if (ImGui::CollapsingHeader("Custom brush")) customBrushPanel(session, out);
            if (ImGui::CollapsingHeader("Materials")) materialsPanel(session, out);
            if (ImGui::CollapsingHeader("Tools")) toolsPanel(session, out);
            if (ImGui::CollapsingHeader("File", ImGuiTreeNodeFlags_DefaultOpen)) filePanel(session, out);
            if (ImGui::CollapsingHeader("Find models")) query.draw(session, brushPoint, out, status, widgetRects);
            if (ImGui::CollapsingHeader("View")) viewPanel();
            ImGui::Checkbox("Stats", &showStats);
            ImGui::SameLine();
            ImGui::Checkbox("Help (H)", &showHelp);
        }
        ImGui::EndChild();
        if (!status.empty()) {
            ImGui::Separator();
            ImGui::TextWrapped("%s", status.c_str());
        }
    }
    ImGui::End();
    if (showStats) statsPanel(session, figures);
    recoveryOffer(session);
    if (showHelp) {
        ImGui::SetNextWindowPos(ImVec2(360, 10), ImGuiCond_FirstUseEver);
        ImGui::SetNextWindowSizeConstraints(ImVec2(200, 100), ImVec2(std::max(200.0f, area.x - 20.0f), std::max(100.0f, area.y - 20.0f)));
        if (ImGui::Begin("Help", &showHelp)) ImGui::TextUnformatted(helpText.c_str());
        ImGui::End();
    }
    if (const auto chosen = browser_.draw()) fileChosen(session, *chosen, out);
    query.drawBrowser();
    return out;
}

void SessionPanels::recoveryOffer(const SessionWorker& session)
{
    if (recoveryAnswered_ || session.recoveredEdits() == 0) return;
    const char* title = "Recovered edits";
    if (!ImGui::IsPopupOpen(title)) ImGui::OpenPopup(title);
    ImGui::SetNextWindowPos(ImGui::GetMainViewport()->GetCenter(), ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
    if (!ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) return;
    // A store keeps its edits as they are made: only a .vdb's working store can drop them.
    const bool canDiscard = !isStorePath(session.scenePath());
    const uint64_t edits = session.recoveredEdits();
    ImGui::Text("%llu %s made after the last save of\n%s\n%s recovered (the editor stopped before saving %s).",
                static_cast<unsigned long long>(edits), edits == 1 ? "edit" : "edits", session.scenePath().c_str(),
                edits == 1 ? "was" : "were", edits == 1 ? "it" : "them");
    ImGui::TextUnformatted(canDiscard ? "Keep them (Ctrl+S saves them into the file), or go back to the file as last saved?"
                                      : "A store keeps every edit as it is made.");
    if (ImGui::Button("Keep them")) {
        recoveryAnswered_ = true;
        ImGui::CloseCurrentPopup();
    }
    track("Keep them");
    if (canDiscard) {
        ImGui::SameLine();
        if (ImGui::Button("Discard them")) {
            recoveryAnswered_ = true;
            discardRecoveryRequested = true;
            ImGui::CloseCurrentPopup();
        }
        track("Discard them");
    }
    ImGui::EndPopup();
}

void SessionPanels::track(const std::string& label)
{
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    widgetRects[label] = {lo.x, lo.y, hi.x, hi.y};
}

void SessionPanels::brushPanel(SessionWorker& session, std::vector<Command>& out)
{
    BrushSettings b = session.brush();
    bool changed = false;
    int mode = std::max(0, indexOf(kModes, IM_ARRAYSIZE(kModes), b.mode));
    if (ImGui::Combo("Mode", &mode, kModes, IM_ARRAYSIZE(kModes))) {
        b.mode = kModes[mode];
        changed = true;
    }
    // The mask: no brush changes masked voxels; shown darkened.
    for (const char* edit : {"mask_invert", "mask_clear"}) {
        if (std::string(edit) == "mask_clear") ImGui::SameLine();
        if (ImGui::SmallButton(std::string(edit) == "mask_invert" ? "Invert mask (Ctrl+I)" : "Clear mask (Alt+M)")) {
            Command c;
            c.kind = Command::Kind::ApplyOp;
            c.op = {{"mode", edit}};
            out.push_back(c);
        }
    }
    const std::string shapeName = b.shape.value("shape", std::string("sphere"));
    int shape = indexOf(kShapes, IM_ARRAYSIZE(kShapes), shapeName);
    const char* preview = shape >= 0 ? kShapes[shape] : shapeName.c_str();
    if (ImGui::BeginCombo("Shape", preview)) {
        for (int i = 0; i < IM_ARRAYSIZE(kShapes); ++i)
            if (ImGui::Selectable(kShapes[i], i == shape)) {
                b.shape = unitShape(i);
                changed = true;
            }
        ImGui::EndCombo();
    }
    float radius = float(b.radius);
    const float voxel = float(session.scene().voxelSize());
    if (ImGui::SliderFloat("Radius", &radius, voxel, 200.0f * voxel, "%.2f", ImGuiSliderFlags_Logarithmic)) {
        b.radius = std::max(radius, 0.01f * voxel);
        changed = true;
    }
    float strength = float(b.strength);
    if (ImGui::SliderFloat("Strength", &strength, 0.0f, 1.0f)) {
        b.strength = strength;
        changed = true;
    }
    int falloff = std::max(0, indexOf(kFalloffs, IM_ARRAYSIZE(kFalloffs), b.falloff));
    if (ImGui::Combo("Falloff", &falloff, kFalloffs, IM_ARRAYSIZE(kFalloffs))) {
        if (std::string(kFalloffs[falloff]) == "curve" && b.falloff != "curve") {
            // A new curve starts as the falloff it replaces.
            const Falloff from = parseFalloff(b.falloff);
            b.falloffCurve.clear();
            for (int i = 0; i < kCurvePoints; ++i) b.falloffCurve.push_back(falloffWeight(from, double(i) / (kCurvePoints - 1), 1.0));
        }
        b.falloff = kFalloffs[falloff];
        changed = true;
    }
    if (b.falloff == "curve") changed |= falloffCurveEditor(b.falloffCurve);
    if (b.mode == "inflate" || b.mode == "deflate") {
        float distance = float(b.distance);
        if (ImGui::SliderFloat("Distance", &distance, 0.1f * voxel, 16.0f * voxel)) {
            b.distance = std::max(distance, 0.01f * voxel);
            changed = true;
        }
    }
    ImGui::SliderFloat("Stabilizer", &stabilizer, 0.0f, 120.0f, stabilizer > 0.0f ? "%.0f px" : "off");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Lazy mouse: the stroke follows the pointer on a string this long, for steady lines");
    if (b.mode == "add") {
        float blend = float(b.smoothness);
        if (ImGui::SliderFloat("Blend", &blend, 0.0f, 1.0f)) {
            b.smoothness = blend;
            changed = true;
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("How wide add blends into the surface, as a fraction of the radius (0: a hard edge)");
    }
    if (b.shape.value("shape", std::string()) == "blend") {
        float smoothness = b.shape.value("smoothness", 0.0f);
        if (ImGui::SliderFloat("Smoothness", &smoothness, 0.0f, 1.0f)) {
            b.shape["smoothness"] = smoothness;
            changed = true;
        }
    }
    float spacing = float(b.spacing);
    if (ImGui::SliderFloat("Spacing", &spacing, 0.05f, 2.0f)) {
        b.spacing = spacing;
        changed = true;
    }
    int pressure = 0;
    while (pressure < 2 && kPressureTargets[pressure] != b.pressure) ++pressure;
    if (ImGui::Combo("Pressure", &pressure, kPressures, IM_ARRAYSIZE(kPressures))) {
        b.pressure = kPressureTargets[pressure];
        changed = true;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("What a tablet's pen pressure scales: the brush's size, its strength, or nothing");
    if (ImGui::Checkbox("Accumulate", &b.accumulate)) changed = true;
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("A stroke builds on itself (off: it follows the surface as the stroke began)");
    // The scene's materials, one entry each: no brush material means the scene's first one (its default).
    const MaterialTable materials = session.scene().materials();
    const std::vector<std::string> names = materials.names();
    const std::string current = b.material.empty() && !names.empty() ? names.front() : b.material;
    if (ImGui::BeginCombo("Material", current.c_str())) {
        for (const std::string& n : names)
            if (ImGui::Selectable(n.c_str(), n == current)) {
                b.material = n;
                changed = true;
            }
        ImGui::EndCombo();
    }
    SymmetryUi sym = symmetryOf(b.symmetry);
    bool symChanged = false;
    ImGui::Text("Symmetry");
    for (int a = 0; a < 3; ++a) {
        ImGui::SameLine();
        symChanged |= ImGui::Checkbox((std::string("mirror ") + kAxes[a]).c_str(), &sym.mirror[a]);
        track(std::string("mirror ") + kAxes[a]);
    }
    symChanged |= ImGui::SliderInt("Radial copies", &sym.radialCount, 1, 16);
    symChanged |= ImGui::Combo("Radial axis", &sym.radialAxis, kAxes, 3);
    symChanged |= ImGui::InputFloat3("Symmetry centre", sym.center);
    if (symChanged) {
        b.symmetry = symmetryJson(sym);
        changed = true;
    }
    if (changed) out.push_back(brushCommand(b));
}

void SessionPanels::customBrushPanel(SessionWorker& session, std::vector<Command>& out)
{
    ImGui::SliderFloat("Blend", &customSmoothness_, 0.0f, 1.0f);
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        CustomBrushPart& p = parts_[i];
        ImGui::PushID(int(i));
        ImGui::Separator();
        ImGui::Combo("Part", &p.shape, kShapes, IM_ARRAYSIZE(kShapes));
        ImGui::InputFloat3("Offset", p.at);
        ImGui::SliderFloat("Size", &p.size, 0.05f, 2.0f);
        ImGui::InputFloat3("Axis scale", p.scale);
        if (i > 0) ImGui::Checkbox("Subtract", &p.remove);
        if (i > 0 && ImGui::SmallButton("Remove part")) {
            parts_.erase(parts_.begin() + std::ptrdiff_t(i));
            ImGui::PopID();
            break;
        }
        ImGui::PopID();
    }
    if (ImGui::Button("Add part")) parts_.push_back(CustomBrushPart{});
    nlohmann::json partsJson = nlohmann::json::array();
    for (const CustomBrushPart& p : parts_) {
        nlohmann::json part = unitShape(p.shape);
        part["at"] = {p.at[0], p.at[1], p.at[2]};
        part["scale"] = {std::max(p.size * p.scale[0], 0.01f), std::max(p.size * p.scale[1], 0.01f), std::max(p.size * p.scale[2], 0.01f)};
        if (p.remove) part["op"] = "remove";
        partsJson.push_back(part);
    }
    const nlohmann::json shape = {{"shape", "blend"}, {"smoothness", customSmoothness_}, {"parts", partsJson}};
    const bool use = ImGui::Button("Use as brush");
    track("Use as brush");
    if (use) {
        BrushSettings b = session.brush();
        b.shape = shape;
        out.push_back(brushCommand(b));
    }
    ImGui::InputText("Preset name", &presetName_);
    if (ImGui::Button("Save preset and script brush")) {
        try {
            BrushSettings b = session.brush();
            b.shape = shape;
            const std::string base = (std::filesystem::path(session.scenePath()).parent_path() / presetName_).string();
            const std::string preset = brushSettingsJson(b).dump(1) + "\n";
            const std::string script = nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", shape}, {"at", {0, 0, 0}}, {"scale", b.radius}}}}}.dump(1) + "\n";
            writeFileAtomically(base + ".brush.json", [&](std::ostream& o) { o << preset; });
            writeFileAtomically(base + ".script.json", [&](std::ostream& o) { o << script; });
            status = "saved " + base + ".brush.json (preset) and " + base + ".script.json (a stroke script using it)";
        } catch (const std::exception& e) {
            status = std::string("could not save the preset: ") + e.what();
        }
    }
    if (ImGui::Button("Load preset")) {
        try {
            const std::string path = (std::filesystem::path(session.scenePath()).parent_path() / (presetName_ + ".brush.json")).string();
            std::ifstream in(path);
            if (!in) throw std::runtime_error("cannot read " + path);
            out.push_back(brushCommand(parseBrushSettings(nlohmann::json::parse(in))));
        } catch (const std::exception& e) {
            status = std::string("could not load the preset: ") + e.what();
        }
    }
}

void SessionPanels::materialsPanel(SessionWorker& session, std::vector<Command>& out)
{
    const MaterialTable materials = session.scene().materials();
    for (const std::string& n : materials.names()) {
        const Material& m = materials.at(*materials.find(n));
        ImGui::ColorButton(("##" + n).c_str(), ImVec4(m.color[0], m.color[1], m.color[2], 1.0f));
        ImGui::SameLine();
        if (ImGui::Selectable((n + "  (toughness " + std::to_string(m.toughness).substr(0, 4) + ")").c_str(), false)) {
            materialName_ = n;
            std::copy(m.color.begin(), m.color.begin() + 3, materialColour_);
            materialToughness_ = m.toughness;
            materialTexture_ = m.texture;
        }
    }
    ImGui::Separator();
    ImGui::InputText("Name", &materialName_);
    ImGui::ColorPicker3("Colour", materialColour_, ImGuiColorEditFlags_PickerHueWheel | ImGuiColorEditFlags_DisplayHSV);
    ImGui::SliderFloat("Toughness", &materialToughness_, 0.0f, 1.0f);
    ImGui::InputText("Texture", &materialTexture_);
    if (ImGui::Button("Define / update") && !materialName_.empty()) {
        Command c;
        c.kind = Command::Kind::DefineMaterial;
        c.material = {{"name", materialName_}, {"color", {materialColour_[0], materialColour_[1], materialColour_[2]}}, {"toughness", materialToughness_}};
        if (!materialTexture_.empty()) c.material["texture"] = materialTexture_;
        out.push_back(c);
        BrushSettings b = session.brush();
        b.material = materialName_;
        out.push_back(brushCommand(b));
    }
}

void SessionPanels::toolsPanel(SessionWorker& session, std::vector<Command>& out)
{
    ImGui::InputFloat3("Box min", toolMin_);
    ImGui::InputFloat3("Box max", toolMax_);
    ImGui::InputText("Tool file", &toolPath_);
    if (ImGui::Button("Make tool and stamp with it")) {
        try {
            WorldBounds box{Vec3d(toolMin_[0], toolMin_[1], toolMin_[2]), Vec3d(toolMax_[0], toolMax_[1], toolMax_[2])};
            const std::string path = (std::filesystem::path(session.scenePath()).parent_path() / toolPath_).string();
            BrushSettings b = session.brush();
            session.waitIdle(); // the tool is cut from the scene as the edits so far left it
            b.shape = makeToolFromBox(session.session(), box, path);
            b.radius = 1.0; // a tool keeps its size
            out.push_back(brushCommand(b));
            status = "made the tool " + path + ": the brush now stamps it";
        } catch (const std::exception& e) {
            status = std::string("could not make the tool: ") + e.what();
        }
    }
}

void SessionPanels::filePanel(SessionWorker& session, std::vector<Command>& out)
{
    const bool save = ImGui::Button("Save (Ctrl+S)");
    track("Save (Ctrl+S)");
    if (save) {
        Command c;
        c.kind = Command::Kind::Save;
        out.push_back(c);
    }
    const std::string folder = std::filesystem::absolute(session.scenePath()).parent_path().string();
    const std::string stem = std::filesystem::path(session.scenePath()).stem().string();
    ImGui::SameLine();
    if (ImGui::Button("Save as...")) browser_.open(kSaveAsTitle, folder, {".vdb", ".vdbclay"}, true, stem + "-copy.vdb");
    ImGui::SameLine();
    if (ImGui::Button("Open...")) browser_.open(kOpenTitle, folder, {".vdb", ".vdbclay"}, false);
    if (ImGui::Button("Import mesh...")) browser_.open(kImportTitle, folder, {".obj", ".ply", ".stl", ".off"}, false);
    ImGui::SameLine();
    if (ImGui::Button("Export...")) browser_.open(kExportTitle, folder, {".obj", ".ply", ".stl", ".vdb"}, true, stem + ".obj");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("A mesh (.obj, .ply, .stl) or an OpenVDB level set (.vdb)");
}

void SessionPanels::fileChosen(SessionWorker& session, const std::string& path, std::vector<Command>& out)
{
    const std::string title = browser_.title();
    try {
        if (title == kOpenTitle) {
            openRequested = path;
        } else if (title == kSaveAsTitle) {
            Command c;
            c.kind = Command::Kind::Save;
            c.path = path;
            out.push_back(c);
        } else if (title == kImportTitle) {
            Command c;
            c.kind = Command::Kind::ApplyOp;
            c.op = importIntoScene(session.session(), path, session.brush().material);
            out.push_back(c);
            status = "imported " + path;
        } else if (title == kExportTitle) {
            session.waitIdle(); // the scene as the edits so far left it
            if (std::filesystem::path(path).extension() == ".vdb") exportSceneLevelSet(session.session(), path);
            else exportSceneMesh(session.session(), path);
            status = "exported " + path;
        }
    } catch (const std::exception& e) {
        status = title + ": " + e.what();
    }
}

void SessionPanels::viewPanel()
{
    int look = 0;
    while (look < IM_ARRAYSIZE(kLookModes) - 1 && kLookModes[look] != this->look) ++look;
    if (ImGui::Combo("Look", &look, kLooks, IM_ARRAYSIZE(kLooks))) this->look = kLookModes[look];
    ImGui::Checkbox("Wireframe", &wireframe);
}

void SessionPanels::statsPanel(const SessionWorker& session, const FrameFigures& f)
{
    const auto [areaX, areaY] = canvasArea();
    const ImVec2 area(areaX, areaY);
    ImGui::SetNextWindowPos(ImVec2(area.x - 10, 10), ImGuiCond_FirstUseEver, ImVec2(1.0f, 0.0f)); // top right, whatever its width
    // Never wider than half the window: long lines wrap instead of running off its edge.
    ImGui::SetNextWindowSizeConstraints(ImVec2(220, 0), ImVec2(std::max(220.0f, area.x * 0.5f), std::max(100.0f, area.y - 20.0f)));
    ImGui::SetNextWindowBgAlpha(0.6f);
    if (ImGui::Begin("Stats", &showStats, ImGuiWindowFlags_AlwaysAutoResize)) {
        ImGui::PushTextWrapPos(std::max(220.0f, area.x * 0.5f) - 16.0f);
        const double fps = f.averageIntervalMs > 0.0 ? 1000.0 / f.averageIntervalMs : 0.0;
        ImGui::TextWrapped("frame %s ms (%s fps over the last second)", figure(f.intervalMs, "%.1f").c_str(), figure(fps, "%.1f").c_str());
        if (f.missedFrames)
            ImGui::TextWrapped("missed frames %llu (display refreshes skipped), detail %.0f%%", (unsigned long long)*f.missedFrames, 100.0 * f.detail);
        ImGui::TextWrapped("input %s, sculpt %s, stream %s, mesh %s, draw %s, present %s ms", figure(f.inputMs, "%.1f").c_str(),
                           figure(f.sculptMs, "%.1f").c_str(), figure(f.streamMs, "%.1f").c_str(), figure(f.meshMs, "%.1f").c_str(),
                           figure(f.drawMs, "%.1f").c_str(), figure(f.presentMs, "%.1f").c_str());
        ImGui::TextWrapped("triangles %llu, chunks %llu, uploaded %.1f KiB", (unsigned long long)f.draw.triangles, (unsigned long long)f.draw.chunksDrawn,
                           double(f.draw.uploadBytes) / 1024.0);
        ImGui::TextWrapped("resident %.1f MiB (meshes %.1f MiB)", double(f.stream.residentBytes) / 1048576.0, double(f.stream.meshBytes) / 1048576.0);
        std::string perLevel;
        for (uint64_t n : f.stream.residentPerLevel) perLevel += std::to_string(n) + " ";
        ImGui::TextWrapped("bricks per level: %s", perLevel.empty() ? "-" : perLevel.c_str());
        ImGui::TextWrapped("shown %llu (%llu left coarse behind what was drawn), pending %llu, hit rate %.0f%%", (unsigned long long)f.bricksShown,
                           (unsigned long long)f.stream.hidden, (unsigned long long)f.stream.pending, 100.0 * f.stream.hitRate());
        const bool nothingShown = f.bricksShown == 0;
        // A brick's error is its level's voxel projected at the brick's nearest point: at level 0 that is
        // the data itself, not a loss (and a brick around the eye would show it as hundreds of pixels).
        const bool finestOnly = !f.draw.levelsShown.empty() && f.draw.levelsShown.back() == 0;
        if (!nothingShown && finestOnly)
            ImGui::TextWrapped("screen error 0 px: every brick at level 0%s", f.stream.budgetLimited ? ", budget-limited" : "");
        else
            ImGui::TextWrapped("screen error %s px (target %s)%s", nothingShown ? "-" : figure(f.stream.screenError, "%.2f").c_str(),
                               nothingShown ? "-" : figure(f.stream.targetError, "%.2f").c_str(), f.stream.budgetLimited ? ", budget-limited" : "");
        const SessionSnapshot done = session.snapshot();
        ImGui::TextWrapped("pending edits %llu (the edit worker's last frame: %s ms), meshes waiting %llu, uploads waiting %llu",
                           (unsigned long long)f.pendingEdits, figure(done.stats.editMsLastFrame, "%.1f").c_str(),
                           (unsigned long long)f.meshesWaiting, (unsigned long long)f.uploadsWaiting);
        ImGui::TextWrapped("undo %zu, redo %zu, history %.1f MiB (+%.1f spilled)", done.undoDepth, done.redoDepth,
                           double(done.historyBytes) / 1048576.0, double(done.historySpilledBytes) / 1048576.0);
        ImGui::TextWrapped("edits %llu, autosaves %llu%s", (unsigned long long)session.scene().edits(), (unsigned long long)done.stats.autosaves,
                           done.unsaved ? ", unsaved" : "");
        ImGui::PopTextWrapPos();
    }
    ImGui::End();
}

} // namespace vdbclay
