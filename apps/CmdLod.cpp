// vdbclay lod build / lod info: the levels of detail of a store.
#include "Cli.h"

#include "render/Framing.h"
#include "render/ImageFile.h"
#include "render/Renderer.h"
#include "render/ScenePicture.h"
#include "render/SceneChunks.h"
#include "render/VulkanContext.h"
#include "scene/CameraPath.h"
#include "scene/FlightInspection.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/StreamingScene.h"
#include "vdb_hermite/AtomicFile.h"
#include "wavelet/LodPyramid.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <tuple>

namespace vdbclay::cli {

namespace {

void requireStore(const std::string& path)
{
    if (!isStorePath(path))
        throw UsageError("'" + path + "' is not a store: levels of detail live in stores (vdbclay import " + path +
                         " -o SCENE.vdbclay); 'vdbclay mesh --lod K' meshes a level of a .vdb directly");
}

nlohmann::json levelsJson(const SceneStore& scene)
{
    nlohmann::json levels = nlohmann::json::array();
    for (int k = 0; k <= scene.lodLevels(); ++k) {
        const LevelSummary s = scene.summary(k);
        levels.push_back({{"level", k},
                          {"voxel_size", scene.voxelSize() * double(1 << k)},
                          {"bricks", s.bricks},
                          {"leaves", s.leaves},
                          {"bytes", s.bytes}});
    }
    return levels;
}

void printLevels(const SceneStore& scene)
{
    std::vector<std::pair<std::string, std::string>> rows;
    for (int k = 0; k <= scene.lodLevels(); ++k) {
        const LevelSummary s = scene.summary(k);
        rows.push_back({"level " + std::to_string(k), std::to_string(s.bricks) + " bricks, " + std::to_string(s.leaves) +
                                                          " leaves, " + formatBytes(double(s.bytes)) + " (voxel " +
                                                          formatNumber(scene.voxelSize() * double(1 << k)) + ")"});
    }
    printFields(rows, 0);
}

} // namespace

LodCommands addLodCommand(CLI::App& parent, LodOptions& o)
{
    CLI::App* lod = parent.add_subcommand("lod", "Levels of detail of a store: build them, list them");
    lod->require_subcommand(1);
    LodCommands cmds;
    cmds.build = lod->add_subcommand("build", "Build or rebuild the Haar-wavelet LOD pyramid of a store, brick by brick (sculpting the store keeps it current)");
    cmds.build->add_option("scene", o.scene, "Store (.vdbclay)")->required()->type_name("SCENE.vdbclay");
    cmds.build->add_option("--levels", o.levels, "Coarse levels to build (0: enough to bring the scene to about one brick)")
        ->capture_default_str()
        ->check(CLI::Range(0, wavelet::kMaxLodLevels));
    cmds.build->add_flag("--json", o.json, "Print one JSON object on stdout instead of text");
    cmds.info = lod->add_subcommand("info", "List the levels of a store: bricks, leaves and bytes per level");
    cmds.info->add_option("scene", o.scene, "Store (.vdbclay)")->required()->type_name("SCENE.vdbclay");
    cmds.info->add_flag("--json", o.json, "Print {\"levels\": [{\"level\", \"bricks\", \"leaves\", \"bytes\"}, ...]}");

    cmds.inspect = lod->add_subcommand("inspect", "Replay a camera flight against a store and report how its levels stream");
    cmds.inspect->add_option("scene", o.scene, "Store (.vdbclay)")->required()->type_name("SCENE.vdbclay");
    cmds.inspect->add_option("--camera-path", o.cameraPath, "Camera flight (JSON; see 'vdbclay lod inspect --help')")
        ->required()
        ->type_name("PATH.json");
    cmds.inspect->add_option("--memory-budget", o.memoryBudgetMB, "Resident bricks may take at most this many MB")
        ->required()
        ->type_name("MB")
        ->check(memoryBudget());
    cmds.inspect->add_option("--pixel-error", o.pixelError, "Screen-space error a brick may show, in pixels")
        ->capture_default_str()
        ->type_name("PX")
        ->check(positiveNumber());
    cmds.inspect->add_option("--csv", o.csv, "Write one row per frame")->type_name("OUT.csv");
    cmds.inspect->add_option("--plot", o.plot, "Draw the figures over the flight (PNG, PLplot)")->type_name("OUT.png");
    cmds.inspect->add_option("--frames", o.framesDir, "Draw pictures of the flight into this folder (frame-NNNNN.png, and settled.png once the view refined)")
        ->type_name("DIR");
    cmds.inspect->add_option("--every", o.every, "With --frames: a picture every N camera frames")
        ->capture_default_str()
        ->type_name("N")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 40));
    cmds.inspect->add_option("--view", o.frameView, "With --frames: what the colours show (lod: each region's level)")
        ->capture_default_str()
        ->check(CLI::IsMember({"shaded", "clay", "lod", "toughness", "normals"}));
    cmds.inspect->add_option("--frame-size", o.frameSize, "With --frames: picture size (default: the flight's viewport, at most 640 wide)")
        ->type_name("WxH");
    cmds.inspect->add_flag("--json", o.json, "Print {\"frames\": [one object per camera frame], \"summary\": {...}}");
    cmds.inspect->footer(
        "The camera path: {\"fov_degrees\": 60, \"viewport\": [1920, 1080], \"frames\": [{\"position\": [x, y, z],\n"
        "\"target\": [x, y, z]}, ...]} in world units; frames at 90 Hz unless a frame gives \"t\" in seconds. The\n"
        "flight is replayed in real time; after its last frame the view is asked for until refined as far as the\n"
        "budget allows (2 s at most).");
    return cmds;
}

int runLodBuild(const LodOptions& o)
{
    requireStore(o.scene);
    const auto start = std::chrono::steady_clock::now();
    SceneStore scene = SceneStore::open(o.scene, StoreAccess::ReadWrite);
    buildStoreLod(scene, o.levels, terminalProgress("building levels", !o.json));
    const double seconds = secondsSince(start);
    if (o.json) {
        printJson({{"scene", o.scene}, {"levels", levelsJson(scene)}, {"seconds", seconds}});
    } else {
        printLevels(scene);
        printFields({{"time", formatSeconds(seconds)}}, 0);
    }
    return kExitOk;
}

int runLodInfo(const LodOptions& o)
{
    requireStore(o.scene);
    const SceneStore scene = SceneStore::open(o.scene, StoreAccess::ReadOnly);
    if (o.json) {
        printJson({{"levels", levelsJson(scene)}, {"stale", scene.lodStale()}});
    } else {
        printLevels(scene);
        if (scene.lodStale()) printFields({{"note", "edited since the last 'vdbclay lod build'"}}, 0);
    }
    return kExitOk;
}

} // namespace vdbclay::cli

namespace vdbclay::cli {

namespace {

nlohmann::json frameJson(const InspectedFrame& f)
{
    const FrameReport& r = f.report;
    return {{"t", f.time},
            {"resident_bricks_per_level", r.residentPerLevel},
            {"resident_bytes", r.residentBytes},
            {"bytes_read", r.bytesRead},
            {"loads", r.loads},
            {"evictions", r.evictions},
            {"requested", r.requested},
            {"hit_rate", r.hitRate()},
            {"screen_error_px", r.screenError},
            {"target_error_px", r.targetError},
            {"coarse_complete", r.coarseComplete},
            {"complete", r.complete},
            {"budget_limited", r.budgetLimited},
            {"settled", r.settled},
            {"pending", r.pending}};
}

nlohmann::json optionalSeconds(const std::optional<double>& t) { return t ? nlohmann::json(*t) : nlohmann::json(); }

/// `lod inspect --frames`: pictures of what the scene shows along the flight, drawn with one renderer
/// that uploads only the bricks that changed since the last picture.
class FlightPictures {
public:
    FlightPictures(const LodOptions& o, const std::vector<CameraFrame>& flight, const StreamingScene& scene)
        : dir_(o.framesDir), every_(o.every), scene_(scene)
    {
        namespace fs = std::filesystem;
        std::error_code ec;
        if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
            throw UsageError("--frames '" + dir_ + "' is a file, not a folder");
        checkOutputFolder(dir_);
        fs::create_directory(dir_, ec);
        if (!fs::is_directory(dir_, ec)) throw std::runtime_error("cannot create the folder '" + dir_ + "'" + (ec ? ": " + ec.message() : ""));
        if (!o.frameSize.empty()) {
            std::tie(width_, height_) = parsePictureSize(o.frameSize, "--frame-size");
        } else {
            const auto [w, h] = flight.front().viewer.viewport;
            const double scale = std::min(1.0, 640.0 / double(w));
            width_ = std::max(1, int(std::lround(w * scale)));
            height_ = std::max(1, int(std::lround(h * scale)));
        }
        // Every picture is checked before the flight: a folder of other files is never overwritten, nor
        // the flight's other outputs (a --plot or --csv inside the folder under a picture's name).
        std::vector<std::pair<std::string, std::string>> others;
        for (const auto& [option, path] : {std::pair{"--plot", o.plot}, std::pair{"--csv", o.csv}})
            if (!path.empty() && samePlace(fs::path(path).parent_path().empty() ? "." : fs::path(path).parent_path().string(), dir_))
                others.emplace_back(option, fs::path(path).filename().string());
        const auto check = [&](std::size_t index) {
            const std::string picture = pathOf(index, flight.size());
            for (const auto& [option, name] : others)
                if (fs::path(picture).filename() == name)
                    throw UsageError(std::string(option) + " names '" + picture + "', a picture of --frames: one would write over the other");
            checkOutput(picture, OutputForm::Png);
        };
        for (std::size_t i = 0; i < flight.size(); i += every_) check(i);
        check(flight.size());
        total_ = flight.size();
        try {
            context_ = std::make_unique<render::VulkanContext>();
        } catch (const render::NoVulkanDevice& e) {
            throw std::runtime_error(std::string("cannot draw the frames: ") + e.what());
        }
        renderer_ = std::make_unique<render::Renderer>(*context_);
        const std::string folder = std::filesystem::path(scene.storePath()).parent_path().string();
        for (const std::string& w : renderer_->setMaterials(scene.materials(), render::materialLook(scene.voxelSize(), folder)))
            std::cerr << "vdbclay: warning: " << w << "\n";
        render::ShadingOptions shading;
        shading.mode = render::parseViewMode(o.frameView);
        renderer_->setShading(shading);
        target_ = std::make_unique<render::OffscreenTarget>(*context_, width_, height_);
        const auto box = scene.storeBounds();
        const double voxel = scene.voxelSize();
        if (box)
            for (int a = 0; a < 3; ++a) {
                lo_[std::size_t(a)] = box->first[std::size_t(a)] * voxel;
                hi_[std::size_t(a)] = (box->second[std::size_t(a)] + 1) * voxel;
            }
    }

    void observe(std::size_t index, const Viewer& viewer, const InspectedFrame&)
    {
        if (index < total_ && index % every_ != 0) return;
        chunks_.sync(scene_, *renderer_);
        render::RenderView view;
        view.camera.eye = viewer.position;
        view.camera.target = viewer.target;
        view.camera.fovYDegrees = viewer.fovDegrees;
        render::fitNearPlane(view.camera, lo_, hi_);
        view.target = target_.get();
        renderer_->render({view});
        render::writePng(target_->colour(), pathOf(index, total_));
        ++written_;
    }

    std::size_t written() const { return written_; }

private:
    std::string pathOf(std::size_t index, std::size_t total) const
    {
        if (index >= total) return (std::filesystem::path(dir_) / "settled.png").string();
        char name[32];
        std::snprintf(name, sizeof name, "frame-%05zu.png", index);
        return (std::filesystem::path(dir_) / name).string();
    }

    std::string dir_;
    uint64_t every_;
    const StreamingScene& scene_;
    int width_ = 0, height_ = 0;
    std::size_t total_ = 0, written_ = 0;
    std::array<double, 3> lo_{0, 0, 0}, hi_{1, 1, 1};
    std::unique_ptr<render::VulkanContext> context_;
    std::unique_ptr<render::Renderer> renderer_;
    std::unique_ptr<render::OffscreenTarget> target_;
    render::StreamedSceneChunks chunks_{render::StreamedSceneChunks::Meshes::Apart}; // the flight's figures stay its own
};

} // namespace

int runLodInspect(const LodOptions& o)
{
    requireStore(o.scene);
    // A path's content is the file's: a failed command (exit 1), like a bad script.
    const std::vector<CameraFrame> flight = loadCameraPath(o.cameraPath);
    StreamingOptions options;
    options.memoryBudgetBytes = uint64_t(o.memoryBudgetMB * 1048576.0);
    options.pixelTolerance = o.pixelError;
    std::unique_ptr<StreamingScene> scene;
    try {
        scene = std::make_unique<StreamingScene>(o.scene, options);
    } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
    }
    // The outputs are checked before the flight, which replays in real time.
    if (!o.csv.empty()) checkOutput(o.csv, OutputForm::Csv, {o.scene, o.cameraPath});
    if (!o.plot.empty()) checkOutput(o.plot, OutputForm::Png, {o.scene, o.cameraPath});
    checkDistinctOutputs({{"--csv", o.csv}, {"--plot", o.plot}});
    std::unique_ptr<FlightPictures> pictures;
    if (!o.framesDir.empty()) pictures = std::make_unique<FlightPictures>(o, flight, *scene);
    else if (o.every != 1 || o.frameView != "lod" || !o.frameSize.empty())
        throw UsageError("--every, --view and --frame-size go with --frames DIR");
    FrameObserver observer;
    if (pictures) observer = [&](std::size_t index, const Viewer& viewer, const InspectedFrame& f) { pictures->observe(index, viewer, f); };
    const FlightInspection inspection =
        inspectFlight(*scene, flight, 2.0, terminalProgress("replaying the flight", !o.json), observer);
    if (!o.csv.empty()) writeFlightCsv(inspection, o.csv);
    if (!o.plot.empty()) writeFlightPlot(inspection, options.memoryBudgetBytes, o.plot);
    const FlightSummary& s = inspection.summary;
    if (o.json) {
        // Frame by frame: a flight of a million frames would make a document of gigabytes in memory.
        std::cout << "{\"frames\":[";
        bool first = true;
        for (const InspectedFrame& f : inspection.frames) {
            if (f.settling) continue;
            std::cout << (first ? "" : ",") << frameJson(f).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
            first = false;
        }
        const nlohmann::json summary{{"frames", flight.size()},
                                     {"settle_frames", inspection.frames.size() - flight.size()},
                                     {"seconds", s.seconds},
                                     {"memory_budget_bytes", options.memoryBudgetBytes},
                                     {"peak_resident_bytes", s.peakResidentBytes},
                                     {"bytes_read", s.bytesRead},
                                     {"loads", s.loads},
                                     {"evictions", s.evictions},
                                     {"mean_hit_rate", s.meanHitRate},
                                     {"max_screen_error_px", s.maxScreenError},
                                     {"first_coarse_complete_s", optionalSeconds(s.firstCoarseComplete)},
                                     {"first_complete_s", optionalSeconds(s.firstComplete)},
                                     {"first_settled_s", optionalSeconds(s.firstSettled)},
                                     {"budget_limited", s.budgetLimited},
                                     {"damaged_bricks", s.damagedBricks}};
        std::cout << "],\"summary\":" << summary.dump() << "}" << std::endl;
        return kExitOk;
    }
    const auto when = [](const std::optional<double>& t) { return t ? formatSeconds(*t) : std::string("never"); };
    printFields({{"flight", std::to_string(flight.size()) + " frames, replayed in " + formatSeconds(s.seconds)},
                 {"resident", "peak " + formatBytes(double(s.peakResidentBytes)) + " of " + formatBytes(double(options.memoryBudgetBytes))},
                 {"read", formatBytes(double(s.bytesRead)) + " in " + std::to_string(s.loads) + " loads, " +
                              std::to_string(s.evictions) + " evictions"},
                 {"hit rate", formatNumber(std::round(1000.0 * s.meanHitRate) / 10.0) + " % (mean over the frames)"},
                 {"coarse view", "first complete at " + when(s.firstCoarseComplete)},
                 {"refined view", "first complete at " + when(s.firstComplete) + "; refined as far as the budget allows at " +
                                      when(s.firstSettled)},
                 {"budget", s.budgetLimited ? "too small for the view at some frames: it refined less there" : "enough"},
                 {"damaged", s.damagedBricks == 0 ? std::string("none")
                                                  : std::to_string(s.damagedBricks) +
                                                        " bricks could not be read (shown by coarser levels); 'vdbclay lod build' rebuilds the coarse levels "
                                                          "or names the first damaged brick of level 0"}},
                0);
    return kExitOk;
}

} // namespace vdbclay::cli
