#include "editor/EditingSession.h"

#include "editor/CameraControl.h"
#include "render/Framing.h"
#include "scene/OutputCheck.h"
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/RegionCodec.h"

#include <chrono>
#include <filesystem>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vdbclay {

namespace {

double distanceBetween(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

} // namespace

std::pair<std::array<double, 3>, std::array<double, 3>> EditingSession::shownBox() const
{
    const std::vector<BrickKey> shown = scene_->shownBricks();
    if (shown.empty()) return sceneBox();
    const double h = scene_->voxelSize();
    std::array<double, 3> lo{}, hi{};
    lo.fill(std::numeric_limits<double>::infinity());
    hi.fill(-std::numeric_limits<double>::infinity());
    for (const BrickKey& key : shown) {
        const double voxel = std::ldexp(h, key.level), edge = kBrickEdge * voxel;
        for (std::size_t a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], key.brick[a] * edge - voxel);
            hi[a] = std::max(hi[a], (key.brick[a] + 1) * edge + voxel);
        }
    }
    return {lo, hi};
}

std::pair<std::array<double, 3>, std::array<double, 3>> EditingSession::sceneBox() const
{
    const double h = scene_->voxelSize();
    std::array<double, 3> lo{-32 * h, -32 * h, -32 * h}, hi{32 * h, 32 * h, 32 * h};
    if (const auto bounds = scene_->storeBounds())
        for (std::size_t a = 0; a < 3; ++a) {
            lo[a] = double(bounds->first[a]) * h;
            hi[a] = double(bounds->second[a] + 1) * h; // the far side of the last voxel: a one-voxel scene is framed whole
        }
    return {lo, hi};
}

EditingSession::EditingSession(const std::string& scenePath, const SessionOptions& options)
    : scenePath_(scenePath), options_(options), history_(options.history)
{
    prepared_ = prepareScene(scenePath, options.discardRecovery, {}, options.refuseUnsaved);
    StreamingOptions streaming;
    streaming.memoryBudgetBytes = options.memoryBudgetBytes;
    streaming.loaderThreads = options.loaderThreads;
    streaming.access = StoreAccess::ReadWrite;
    scene_ = std::make_unique<StreamingScene>(prepared_.storePath, streaming);
    const auto [lo, hi] = sceneBox();
    camera_ = render::framingCamera(lo, hi, 16.0 / 9.0);
    unsaved_ = prepared_.recoveredEdits > 0;
    brush_.radius = 8.0 * scene_->voxelSize();
    brush_.distance = 2.0 * scene_->voxelSize();
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

void EditingSession::apply(const Command& given)
{
    Command command = given;
    const bool stroke = command.kind == Command::Kind::StrokeBegin || command.kind == Command::Kind::StrokeMove;
    // A move with no stroke begins one: the record says so, so that it reads as what happened.
    if (command.kind == Command::Kind::StrokeMove && !stroke_.active) {
        command.kind = Command::Kind::StrokeBegin;
        command.mergedWithNext = false; // a stroke's first stamp goes in at once
    }
    // Merged points wait only for the stroke's next point: anything else applies them first.
    if (command.kind != Command::Kind::StrokeMove) flushMerged();
    const bool placed = stroke && placeStroke(command);
    record_.commands.push_back({frameNumber_, time_, command});
    lastCommand_ = time_;
    const auto at = [&] { return Placement{*command.point, command.normal}; };
    switch (command.kind) {
    case Command::Kind::StrokeBegin:
        if (placed) beginStroke(at(), command.pressure);
        else if (stroke_.active) endStroke(); // pressed off the surface: nothing to sculpt until the pointer reaches it
        break;
    case Command::Kind::StrokeMove:
        if (!placed) break; // off the surface for now
        if (brush_.mode == "move") dragStroke(*command.point, command.pressure, command.mergedWithNext);
        else moveStroke(at(), command.pressure, command.mergedWithNext);
        break;
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
        if (command.path.empty() || samePlace(command.path, scenePath_)) unsaved_ = false; // a copy saved elsewhere leaves the scene's file behind
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
        if (!stroke_.maskBefore) stroke_.maskBefore = scene_->mask().encode();
        // Inflate and deflate keep the stroke's start where they reach, to be measured against it.
        StrokeStart* start = nullptr;
        if (capsPerStroke() && stroke_.active) {
            if (!stroke_.start) stroke_.start = std::make_unique<StrokeStart>(scene_->voxelSize());
            start = stroke_.start.get();
        }
        const StreamingScene::EditReport report = scene_->sculpt(script, &changes, start);
        bricksChanged_ += report.bricksChanged;
        for (LeafChange& c : changes) {
            const auto [it, fresh] = stroke_.changeIndex.emplace(c.origin, stroke_.changes.size());
            if (fresh) stroke_.changes.push_back(std::move(c));
            else stroke_.changes[it->second].after = std::move(c.after);
        }
        stroke_.ops.push_back(op);
        ++stats_.stampsApplied;
        editedSinceAutosave_ = true;
        if (report.bricksChanged > 0 || script.ops.front().maskEdit) unsaved_ = true;
    } catch (const std::exception& e) { // ScriptError, limits: the stroke goes on without this stretch
        ++stats_.opsRefused;
        notify(std::string("the brush could not be applied here: ") + e.what());
    }
    editMs_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

bool EditingSession::placeStroke(Command& command)
{
    if (!command.ray) return command.point.has_value();
    const Ray& ray = *command.ray;
    std::optional<std::array<double, 3>> point, normal;
    bool finest = true; // placed from the finest level's data (a coarser level stands in where it is not resident)
    const bool continuing = command.kind == Command::Kind::StrokeMove && stroke_.active;
    if (continuing && brush_.mode == "move") {
        point = dragPoint(camera_, ray, stroke_.grab); // the grabbed point follows the pointer across the view
    } else {
        const std::optional<SurfaceHit> hit =
            continuing && !brush_.accumulate ? castAtStrokeStart(ray) : pick(ray.origin, ray.direction);
        if (hit) point = hit->point, normal = hit->normal, finest = hit->level == 0;
    }
    if (command.point) {
        // A replay: the recorded placement is what happened; the ray checks that it still places the same
        // where the finest data are resident now (a replay streams on its own clock).
        if (point && finest && distanceBetween(*point, *command.point) > 1e-6 * scene_->voxelSize()) {
            if (stats_.placementsDiffering++ == 0)
                notify("a replayed stroke point differs from where its recorded ray now meets the surface; the recorded point is used");
        }
        return true;
    }
    command.point = point;
    command.normal = normal;
    return point.has_value();
}

std::optional<SurfaceHit> EditingSession::castAtStrokeStart(const Ray& ray)
{
    const double h = scene_->voxelSize();
    if (!stroke_.before) stroke_.before = std::make_unique<Volume>(h);
    const std::size_t materials = scene_->materials().size();
    for (; stroke_.decoded < stroke_.changes.size(); ++stroke_.decoded) {
        const LeafChange& c = stroke_.changes[stroke_.decoded];
        pasteRegion(*stroke_.before, decodeRegion(c.before, {c.origin, kLeafDim}, h, materials, "the stroke's starting state"));
        stroke_.replaced.insert(c.origin);
    }
    std::optional<SurfaceHit> hit;
    scene_->visitResidentLevels([&](const std::vector<const Volume*>& levels, const StreamingScene::FinestResidentAt& finestResidentAt) {
        if (levels.empty()) return;
        hit = castRay(OverlaidVolume{*levels[0], *stroke_.before, stroke_.replaced}, ray.origin, ray.direction, 1e30);
        // Where the finest level is not resident, the coarser ones (which may show the stroke) stand in.
        if (!hit && levels.size() > 1) {
            std::vector<const Volume*> coarser(levels.begin(), levels.end());
            coarser[0] = nullptr;
            hit = castRayAcrossLevels(coarser, ray.origin, ray.direction, 1e30, finestResidentAt);
        }
    });
    return hit;
}

std::array<double, 3> EditingSession::stampCentre(const Placement& at, double pressure) const
{
    if (!at.normal) return at.point;
    const std::array<double, 3>& n = *at.normal;
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 1e-12)) return at.point;
    const double offset = stampNormalOffset(brush_, pressure) / length;
    return {at.point[0] + n[0] * offset, at.point[1] + n[1] * offset, at.point[2] + n[2] * offset};
}

void EditingSession::beginStroke(const Placement& at, double pressure)
{
    if (stroke_.active) endStroke();
    stroke_ = Stroke{};
    stroke_.active = true;
    stroke_.lastStamp = stroke_.lastPoint = at;
    stroke_.grab = at.point;
    if (brush_.mode != "move") applyOp(strokeOpJson(brush_, {stampCentre(at, pressure)}, pressure));
}

void EditingSession::dragStroke(const std::array<double, 3>& point, double pressure, bool merged)
{
    stroke_.lastPoint = stroke_.lastStamp = Placement{point, std::nullopt};
    // Each step drags by the whole way from the grabbed point: a step merged with the next is left out.
    stroke_.pendingDrag.reset();
    if (merged) {
        stroke_.pendingDrag = point;
        stroke_.pendingPressure = pressure;
        return;
    }
    const std::array<double, 3> offset{point[0] - stroke_.grab[0], point[1] - stroke_.grab[1], point[2] - stroke_.grab[2]};
    // Grab drags the surface as the stroke found it by the whole way from where it was grabbed (Blender's
    // grab): the last step is put back first, so that the grabbed point stays under the pointer however
    // far it goes, and the stroke is one move op.
    if (!stroke_.changes.empty()) {
        std::vector<LeafImage> start;
        start.reserve(stroke_.changes.size());
        for (LeafChange& c : stroke_.changes) {
            start.push_back({c.origin, c.before});
            c.after = c.before;
        }
        bricksChanged_ += scene_->restoreLeaves(start).bricksChanged;
        stroke_.ops = nlohmann::json::array();
    }
    if (distanceBetween(point, stroke_.grab) > 0.0) applyOp(strokeOpJson(brush_, {stroke_.grab}, pressure, offset));
}

void EditingSession::moveStroke(const Placement& at, double pressure, bool merged)
{
    if (!stroke_.active) return beginStroke(at, pressure);
    // Stamps every `spacing` along the pointer's path; CSG brushes sweep from the last stamp through the
    // new ones (no gaps at any speed), reshaping brushes reshape the new stamps once each.
    const double scale = brush_.pressure == PressureTarget::Size ? std::clamp(pressure, 0.05, 1.0) : 1.0;
    const double spacing = std::max(brush_.spacing * brush_.radius * scale, 1e-3 * scene_->voxelSize());
    const Placement from = stroke_.lastPoint;
    std::vector<Placement> stamps;
    const double length = distanceBetween(at.point, from.point);
    double along = spacing - stroke_.travelled;
    while (along <= length) {
        const double f = along / length;
        Placement p;
        for (std::size_t a = 0; a < 3; ++a) p.point[a] = from.point[a] + (at.point[a] - from.point[a]) * f;
        if (from.normal && at.normal) { // the normals in between: blended (stampCentre normalizes)
            p.normal = std::array<double, 3>{};
            for (std::size_t a = 0; a < 3; ++a) (*p.normal)[a] = (*from.normal)[a] * (1.0 - f) + (*at.normal)[a] * f;
        }
        stamps.push_back(p);
        along += spacing;
    }
    stroke_.travelled = stamps.empty() ? stroke_.travelled + length : length - (along - spacing);
    stroke_.lastPoint = at;
    if (!stamps.empty()) {
        std::vector<std::array<double, 3>>& path = stroke_.pendingPath;
        if (path.empty() && !isReshapingMode(brush_.mode)) path.push_back(stampCentre(stroke_.lastStamp, pressure));
        for (const Placement& p : stamps) path.push_back(stampCentre(p, pressure));
        stroke_.lastStamp = stamps.back();
        stroke_.pendingPressure = pressure;
    }
    if (!merged) flushMerged();
}

void EditingSession::flushMerged()
{
    if (stroke_.pendingDrag) {
        const std::array<double, 3> point = *stroke_.pendingDrag;
        dragStroke(point, stroke_.pendingPressure, false);
    }
    if (stroke_.pendingPath.empty()) return;
    const std::vector<std::array<double, 3>> path = std::move(stroke_.pendingPath);
    stroke_.pendingPath.clear();
    nlohmann::json op = strokeOpJson(brush_, path, stroke_.pendingPressure);
    if (capsPerStroke()) op["stroke"] = "continue";
    applyOp(op);
}

bool EditingSession::capsPerStroke() const
{
    return (brush_.mode == "inflate" || brush_.mode == "deflate") && !brush_.accumulate;
}

void EditingSession::endStroke()
{
    if (!stroke_.active) return;
    flushMerged();
    // Leaves a grab put back as they were are no change.
    std::vector<LeafChange> changes;
    changes.reserve(stroke_.changes.size());
    for (LeafChange& c : stroke_.changes)
        if (c.before != c.after) changes.push_back(std::move(c));
    std::optional<MaskChange> mask;
    if (stroke_.maskBefore) mask = MaskChange{std::move(*stroke_.maskBefore), scene_->mask().encode()};
    history_.push(std::move(changes), std::move(stroke_.ops), std::move(mask));
    stroke_ = Stroke{};
}

void EditingSession::putBack(const HistoryStep& step)
{
    if (!step.leaves.empty()) bricksChanged_ += scene_->restoreLeaves(step.leaves).bricksChanged;
    if (step.mask) scene_->setMask(VoxelMask::decode(*step.mask));
    editedSinceAutosave_ = true;
    unsaved_ = true;
}

void EditingSession::undo()
{
    if (stroke_.active) endStroke();
    if (const auto step = history_.undo()) putBack(*step);
}

void EditingSession::redo()
{
    if (stroke_.active) endStroke();
    if (const auto step = history_.redo()) putBack(*step);
}

void EditingSession::defineMaterial(const nlohmann::json& material)
{
    const StrokeScript script = parseStrokeScript(nlohmann::json{{"materials", {material}}, {"ops", nlohmann::json::array()}}.dump());
    scene_->sculpt(script);
    materialsDefined_.push_back(material);
    unsaved_ = true;
}

FrameReport EditingSession::frame(double time, const std::array<int, 2>& viewport)
{
    const FrameReport report = streamView(camera_, viewport);
    advanceFrame(time, viewport);
    return report;
}

FrameReport EditingSession::streamView(const render::Camera& camera, const std::array<int, 2>& viewport, const OccluderDepth* drawn)
{
    return scene_->frame(viewerOf(camera, viewport), drawn);
}

void EditingSession::advanceFrame(double time, const std::array<int, 2>& viewport)
{
    time_ = std::max(time_, time);
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
    scene_->visitResidentLevels([&](const std::vector<const Volume*>& levels, const StreamingScene::FinestResidentAt& finestResidentAt) {
        hit = castRayAcrossLevels(levels, origin, direction, maxDistance, finestResidentAt);
    });
    return hit;
}

bool EditingSession::tryPick(const std::array<double, 3>& origin, const std::array<double, 3>& direction, double maxDistance,
                             std::optional<SurfaceHit>* hit) const
{
    return scene_->tryVisitResidentLevels([&](const std::vector<const Volume*>& levels, const StreamingScene::FinestResidentAt& finestResidentAt) {
        *hit = castRayAcrossLevels(levels, origin, direction, maxDistance, finestResidentAt);
    });
}

nlohmann::json EditingSession::appliedScript() const { return {{"materials", materialsDefined_}, {"ops", history_.opsInEffect()}}; }

std::size_t applyRecordedFrame(EditingSession& session, const SessionRecord& record, std::size_t next, uint64_t frame, double* time)
{
    return forRecordedFrame(record, next, frame, time, [&](const Command& c) { session.apply(c); });
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
