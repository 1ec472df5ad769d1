#include "editor/EditingSession.h"

#include "editor/CameraControl.h"
#include "render/Framing.h"
#include "sculpt/StrokeScript.h"

#include <chrono>
#include <filesystem>
#include <cmath>
#include <stdexcept>

namespace vdbclay {

namespace {

double distanceBetween(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

render::Camera initialCamera(const StreamingScene& scene)
{
    const double h = scene.store().voxelSize();
    std::array<double, 3> lo{-32 * h, -32 * h, -32 * h}, hi{32 * h, 32 * h, 32 * h};
    if (const auto bounds = scene.store().bounds())
        for (std::size_t a = 0; a < 3; ++a) {
            lo[a] = double(bounds->first[a]) * h;
            hi[a] = double(bounds->second[a] + 1) * h; // the far side of the last voxel: a one-voxel scene is framed whole
        }
    return render::framingCamera(lo, hi, 16.0 / 9.0);
}

} // namespace

EditingSession::EditingSession(const std::string& scenePath, const SessionOptions& options)
    : scenePath_(scenePath), options_(options), history_(options.history)
{
    prepared_ = prepareScene(scenePath, options.discardRecovery, {}, options.refuseUnsaved);
    StreamingOptions streaming;
    streaming.memoryBudgetBytes = options.memoryBudgetBytes;
    streaming.loaderThreads = options.loaderThreads;
    streaming.access = StoreAccess::ReadWrite;
    scene_ = std::make_unique<StreamingScene>(prepared_.storePath, streaming);
    camera_ = initialCamera(*scene_);
    brush_.radius = 8.0 * scene_->store().voxelSize();
    brush_.distance = 2.0 * scene_->store().voxelSize();
}

EditingSession::~EditingSession()
{
    try {
        if (stroke_.active) endStroke();
        scene_->autosave();
        saveRecord();
    } catch (const std::exception& e) {
        notify(std::string("the last autosave failed: ") + e.what());
    }
}

void EditingSession::notify(const std::string& text) const
{
    if (options_.message) options_.message(text);
}

void EditingSession::apply(const Command& command)
{
    record_.commands.push_back({frameNumber_, time_, command});
    // A move with no stroke begins one: the record says so, so that it reads as what happened.
    if (command.kind == Command::Kind::StrokeMove && !stroke_.active) record_.commands.back().command.kind = Command::Kind::StrokeBegin;
    lastCommand_ = time_;
    switch (command.kind) {
    case Command::Kind::StrokeBegin: beginStroke(command.point, command.pressure); break;
    case Command::Kind::StrokeMove: moveStroke(command.point, command.pressure); break;
    case Command::Kind::StrokeEnd: endStroke(); break;
    case Command::Kind::SetBrush:
        if (!command.brush) throw std::invalid_argument("a brush command carries no brush settings");
        checkBrushSettings(*command.brush);
        brush_ = *command.brush;
        break;
    case Command::Kind::Undo: undo(); break;
    case Command::Kind::Redo: redo(); break;
    case Command::Kind::Save:
        if (stroke_.active) endStroke();
        saveScene(*scene_, prepared_, scenePath_, command.path.empty() ? scenePath_ : command.path);
        editedSinceAutosave_ = false;
        break;
    case Command::Kind::SetCamera: camera_ = command.camera; break;
    case Command::Kind::DefineMaterial: defineMaterial(command.material); break;
    case Command::Kind::ApplyOp:
        if (stroke_.active) endStroke();
        stroke_.active = true;
        applyOp(command.op);
        endStroke();
        break;
    }
}

void EditingSession::applyOp(const nlohmann::json& op)
{
    const auto start = std::chrono::steady_clock::now();
    try {
        StrokeScript script = parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump());
        loadScriptTools(script, std::filesystem::path(scenePath_).parent_path().string(), tools_);
        std::vector<LeafChange> changes;
        const StreamingScene::EditReport report = scene_->sculpt(script, &changes);
        bricksChanged_ += report.bricksChanged;
        for (LeafChange& c : changes) {
            const auto [it, fresh] = stroke_.changeIndex.emplace(c.origin, stroke_.changes.size());
            if (fresh) stroke_.changes.push_back(std::move(c));
            else stroke_.changes[it->second].after = std::move(c.after);
        }
        stroke_.ops.push_back(op);
        ++stats_.stampsApplied;
        editedSinceAutosave_ = true;
    } catch (const std::exception& e) { // ScriptError, limits: the stroke goes on without this stretch
        ++stats_.opsRefused;
        notify(std::string("the brush could not be applied here: ") + e.what());
    }
    editMs_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void EditingSession::beginStroke(const std::array<double, 3>& point, double pressure)
{
    if (stroke_.active) endStroke();
    stroke_ = Stroke{};
    stroke_.active = true;
    stroke_.lastStamp = stroke_.lastPoint = point;
    if (brush_.mode != "move") applyOp(strokeOpJson(brush_, {point}, pressure));
}

void EditingSession::moveStroke(const std::array<double, 3>& point, double pressure)
{
    if (!stroke_.active) return beginStroke(point, pressure);
    if (brush_.mode == "move") {
        // The grabbed surface follows the pointer: each step drags the brush's region by the pointer's move.
        const std::array<double, 3> offset{point[0] - stroke_.lastPoint[0], point[1] - stroke_.lastPoint[1], point[2] - stroke_.lastPoint[2]};
        if (distanceBetween(point, stroke_.lastPoint) > 0.0) applyOp(strokeOpJson(brush_, {stroke_.lastPoint}, pressure, offset));
        stroke_.lastPoint = stroke_.lastStamp = point;
        return;
    }
    // Stamps every `spacing` along the pointer's path; CSG brushes sweep from the last stamp through the
    // new ones (no gaps at any speed), reshaping brushes reshape the new stamps once each.
    const double scale = brush_.pressure == PressureTarget::Size ? std::clamp(pressure, 0.05, 1.0) : 1.0;
    const double spacing = std::max(brush_.spacing * brush_.radius * scale, 1e-3 * scene_->store().voxelSize());
    std::vector<std::array<double, 3>> stamps;
    const double length = distanceBetween(point, stroke_.lastPoint);
    double along = spacing - stroke_.travelled;
    while (along <= length) {
        const double f = along / length;
        stamps.push_back({stroke_.lastPoint[0] + (point[0] - stroke_.lastPoint[0]) * f, stroke_.lastPoint[1] + (point[1] - stroke_.lastPoint[1]) * f,
                          stroke_.lastPoint[2] + (point[2] - stroke_.lastPoint[2]) * f});
        along += spacing;
    }
    stroke_.travelled = stamps.empty() ? stroke_.travelled + length : length - (along - spacing);
    stroke_.lastPoint = point;
    if (stamps.empty()) return;
    std::vector<std::array<double, 3>> path;
    if (!isReshapingMode(brush_.mode)) path.push_back(stroke_.lastStamp);
    path.insert(path.end(), stamps.begin(), stamps.end());
    stroke_.lastStamp = stamps.back();
    applyOp(strokeOpJson(brush_, path, pressure));
}

void EditingSession::endStroke()
{
    if (!stroke_.active) return;
    history_.push(std::move(stroke_.changes), std::move(stroke_.ops));
    stroke_ = Stroke{};
}

void EditingSession::undo()
{
    if (stroke_.active) endStroke();
    if (const auto images = history_.undo()) {
        bricksChanged_ += scene_->restoreLeaves(*images).bricksChanged;
        editedSinceAutosave_ = true;
    }
}

void EditingSession::redo()
{
    if (stroke_.active) endStroke();
    if (const auto images = history_.redo()) {
        bricksChanged_ += scene_->restoreLeaves(*images).bricksChanged;
        editedSinceAutosave_ = true;
    }
}

void EditingSession::defineMaterial(const nlohmann::json& material)
{
    const StrokeScript script = parseStrokeScript(nlohmann::json{{"materials", {material}}, {"ops", nlohmann::json::array()}}.dump());
    scene_->sculpt(script);
    materialsDefined_.push_back(material);
}

FrameReport EditingSession::frame(double time, const std::array<int, 2>& viewport)
{
    time_ = std::max(time_, time);
    const FrameReport report = scene_->frame(viewerOf(camera_, viewport));
    stats_.editMsLastFrame = editMs_;
    stats_.bricksChangedLastFrame = bricksChanged_;
    editMs_ = 0.0;
    bricksChanged_ = 0;
    const bool due = time_ - lastAutosave_ >= options_.autosaveSeconds;
    const bool idle = !stroke_.active && time_ - lastCommand_ >= options_.idleAutosaveSeconds;
    if (editedSinceAutosave_ && (due || idle)) autosave();
    ++frameNumber_;
    record_.frames = frameNumber_;
    record_.viewport = viewport;
    return report;
}

void EditingSession::autosave()
{
    scene_->autosave();
    ++stats_.autosaves;
    lastAutosave_ = time_;
    editedSinceAutosave_ = false;
    saveRecord();
}

void EditingSession::saveRecord() const
{
    if (!options_.recordPath.empty()) saveSessionRecord(record_, options_.recordPath);
}

std::optional<SurfaceHit> EditingSession::pick(const std::array<double, 3>& origin, const std::array<double, 3>& direction,
                                               double maxDistance) const
{
    std::optional<SurfaceHit> hit;
    scene_->visitResidentLevels([&](const std::vector<const Volume*>& levels) { hit = castRayAcrossLevels(levels, origin, direction, maxDistance); });
    return hit;
}

nlohmann::json EditingSession::appliedScript() const { return {{"materials", materialsDefined_}, {"ops", history_.opsInEffect()}}; }

std::size_t applyRecordedFrame(EditingSession& session, const SessionRecord& record, std::size_t next, uint64_t frame, double* time)
{
    while (next < record.commands.size() && record.commands[next].frame <= frame) {
        const RecordedCommand& rc = record.commands[next++];
        if (time) *time = rc.time;
        if (rc.command.kind != Command::Kind::Save) session.apply(rc.command);
    }
    return next;
}

void replaySession(EditingSession& session, const SessionRecord& record, std::optional<uint64_t> frames,
                   const std::function<void(uint64_t frame, const FrameReport&)>& onFrame)
{
    const uint64_t last = frames ? std::min(*frames, record.frames) : record.frames;
    std::size_t next = 0;
    for (uint64_t f = 0; f < last; ++f) {
        double time = 0.0;
        next = applyRecordedFrame(session, record, next, f, &time);
        const FrameReport report = session.frame(time, record.viewport);
        if (onFrame) onFrame(f, report);
    }
}

} // namespace vdbclay
