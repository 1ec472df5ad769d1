// vdbclay render: a picture of a .vdb or a store, drawn offscreen with Vulkan and written as PNG.
#include "Cli.h"

#include "render/ImageFile.h"
#include "render/ScenePicture.h"
#include "render/VulkanContext.h"
#include "scene/CameraPath.h"
#include "scene/SceneStore.h"
#include "vdb_hermite/VolumeIO.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>

namespace vdbclay::cli {

namespace {

} // namespace

std::pair<int, int> parsePictureSize(const std::string& text, const std::string& option)
{
    const auto x = text.find('x');
    const auto bad = [&] { return UsageError(option + " '" + text + "' is not WIDTHxHEIGHT in pixels, each 1 .. " + std::to_string(render::kMaxViewportSide) + " (e.g. 1280x720)"); };
    if (x == std::string::npos || x == 0 || x + 1 >= text.size()) throw bad();
    const std::string w = text.substr(0, x), h = text.substr(x + 1);
    if (w.size() > 5 || h.size() > 5 || w.find_first_not_of("0123456789") != std::string::npos ||
        h.find_first_not_of("0123456789") != std::string::npos)
        throw bad();
    const int width = std::stoi(w), height = std::stoi(h);
    if (width < 1 || height < 1 || width > render::kMaxViewportSide || height > render::kMaxViewportSide) throw bad();
    return {width, height};
}

namespace {

render::Camera parseCamera(const std::string& text)
{
    std::vector<double> v;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t comma = text.find(',', start);
        const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        std::optional<double> value = parseDecimal(part);
        if (!value) throw UsageError("--camera '" + text + "': '" + part + "' is not a finite number");
        v.push_back(*value);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (v.size() != 6 && v.size() != 7)
        throw UsageError("--camera takes X,Y,Z,TX,TY,TZ[,FOV] (eye, target and the vertical field of view in degrees)");
    render::Camera c;
    c.eye = {v[0], v[1], v[2]};
    c.target = {v[3], v[4], v[5]};
    if (v.size() == 7) c.fovYDegrees = v[6];
    if (!(c.fovYDegrees > 0.0 && c.fovYDegrees < 180.0)) throw UsageError("--camera: the field of view must lie between 0 and 180 degrees");
    if (c.eye == c.target) throw UsageError("--camera: the eye and the target are the same point");
    return c;
}

} // namespace

CLI::App* addRenderCommand(CLI::App& parent, RenderOptions& o)
{
    CLI::App* cmd = parent.add_subcommand("render", "Draw a picture of a scene (.vdb or store) with Vulkan and write it as PNG");
    cmd->add_option("scene", o.scene, "Scene: a .vdb or a store (.vdbclay)")->required()->type_name("SCENE")->check(sceneInput());
    cmd->add_option("-o,--output", o.output, "Picture to write")->required()->type_name("OUT.png");
    cmd->add_option("--size", o.size, "Picture size in pixels")->capture_default_str()->type_name("WxH");
    cmd->add_option("--camera", o.camera, "Eye and target in world units, optionally the vertical field of view (default: the whole scene from a three-quarter view)")
        ->type_name("X,Y,Z,TX,TY,TZ[,FOV]");
    cmd->add_option("--camera-path", o.cameraPath, "Take the camera from a flight (as 'vdbclay lod inspect' reads)")->type_name("P.json");
    cmd->add_option("--frame", o.frame, "The flight's frame to draw (0-based; with --camera-path)")->type_name("N")->check(unsignedInteger());
    cmd->add_option("--view", o.view, "What the colours show: shaded, lod (level of each region), toughness, normals")
        ->capture_default_str()
        ->check(CLI::IsMember({"shaded", "clay", "lod", "toughness", "normals"}));
    cmd->add_flag("--wireframe", o.wireframe, "Draw the triangles' edges over the surface");
    cmd->add_option("--memory-budget", o.memoryBudgetMB, "Stores: resident bricks may take at most this many MB")
        ->capture_default_str()
        ->type_name("MB")
        ->check(memoryBudget());
    cmd->add_option("--pixel-error", o.pixelError, "Stores: screen-space error a brick may show, in pixels")
        ->capture_default_str()
        ->type_name("PX")
        ->check(positiveNumber());
    cmd->add_flag("--json", o.json, "Print {\"triangles\", \"chunks\", \"levels_shown\", \"gpu_memory_bytes\", \"cpu_ms\", \"gpu_ms\", \"device\", ...}");
    cmd->footer("Runs on any Vulkan device; without a GPU, Mesa's lavapipe (Debian: mesa-vulkan-drivers) draws on the CPU.\n"
                "A store is streamed for the view first: refined as far as the memory budget allows.");
    return cmd;
}

int runRender(const RenderOptions& o)
{
    const auto [width, height] = parsePictureSize(o.size, "--size");
    if (o.frame && o.cameraPath.empty()) throw UsageError("--frame needs --camera-path");
    if (!o.camera.empty() && !o.cameraPath.empty()) throw UsageError("give --camera or --camera-path, not both");
    std::vector<std::string> inputs{o.scene};
    if (!o.cameraPath.empty()) inputs.push_back(o.cameraPath);
    checkOutput(o.output, OutputForm::Png, inputs);

    render::PictureRequest request;
    request.width = width;
    request.height = height;
    request.shading.mode = render::parseViewMode(o.view);
    request.shading.wireframe = o.wireframe;
    request.memoryBudgetBytes = uint64_t(o.memoryBudgetMB * 1048576.0);
    request.pixelTolerance = o.pixelError;
    request.textureFolder = std::filesystem::path(o.scene).parent_path().string();
    if (!o.camera.empty()) request.camera = parseCamera(o.camera);
    if (!o.cameraPath.empty()) {
        const std::vector<CameraFrame> flight = loadCameraPath(o.cameraPath);
        const uint64_t n = o.frame.value_or(0);
        if (n >= flight.size())
            throw UsageError("--frame " + std::to_string(n) + " is past the flight's last frame (" + std::to_string(flight.size() - 1) + ")");
        render::Camera c;
        c.eye = flight[n].viewer.position;
        c.target = flight[n].viewer.target;
        c.fovYDegrees = flight[n].viewer.fovDegrees;
        request.camera = c;
    }

    const auto start = std::chrono::steady_clock::now();
    std::unique_ptr<render::VulkanContext> context;
    try {
        context = std::make_unique<render::VulkanContext>();
    } catch (const render::NoVulkanDevice& e) {
        printError(std::string("cannot render: ") + e.what());
        return kExitFailure;
    }
    render::Picture picture;
    const bool store = isStorePath(o.scene);
    if (store) {
        try {
            picture = render::renderStore(*context, o.scene, request);
        } catch (const std::invalid_argument& e) {
            throw UsageError(e.what()); // a budget too small for one brick
        }
    } else {
        picture = render::renderVolume(*context, loadVolume(o.scene), request);
    }
    render::writePng(picture.image, o.output);
    for (const std::string& w : picture.warnings) std::cerr << "vdbclay: warning: " << w << "\n";
    const double seconds = secondsSince(start);
    const render::FrameStats& s = picture.stats;
    if (o.json) {
        nlohmann::json j{{"output", o.output},
                         {"width", width},
                         {"height", height},
                         {"view", o.view},
                         {"triangles", s.triangles},
                         {"chunks", s.chunksDrawn},
                         {"chunks_culled", s.chunksCulled},
                         {"levels_shown", s.levelsShown},
                         {"gpu_memory_bytes", s.gpuMemoryBytes},
                         {"upload_bytes", s.uploadBytes},
                         {"cpu_ms", s.cpuMs},
                         {"gpu_ms", s.gpuMs},
                         {"mesh_ms", picture.meshMs},
                         {"pipeline_ms", picture.pipelineMs},
                         {"device", context->deviceName()},
                         {"camera", {{"eye", picture.camera.eye}, {"target", picture.camera.target}, {"fov_degrees", picture.camera.fovYDegrees}}},
                         {"seconds", seconds}};
        if (store) {
            j["stream_ms"] = picture.streamMs;
            j["bricks_shown"] = picture.bricksShown;
            j["refined"] = picture.refined;
        }
        printJson(j);
        return kExitOk;
    }
    std::vector<std::pair<std::string, std::string>> rows{
        {"picture", o.output + " (" + std::to_string(width) + "x" + std::to_string(height) + ", " + o.view + ")"},
        {"drawn", std::to_string(s.triangles) + " triangles in " + std::to_string(s.chunksDrawn) + " chunks (" +
                      std::to_string(s.chunksCulled) + " culled)"},
        {"device", context->deviceName() + ", " + formatBytes(double(s.gpuMemoryBytes)) + " of mesh buffers"},
        {"frame", "cpu " + formatSeconds(s.cpuMs / 1000.0) + ", gpu " + formatSeconds(s.gpuMs / 1000.0) + " (shaders built in " +
                      formatSeconds(picture.pipelineMs / 1000.0) + ")"},
        {"meshing", formatSeconds(picture.meshMs / 1000.0)}};
    if (store) {
        std::string levels;
        for (int l : s.levelsShown) levels += (levels.empty() ? "" : ", ") + std::to_string(l);
        rows.push_back({"streaming", std::to_string(picture.bricksShown) + " bricks at levels " + (levels.empty() ? "-" : levels) +
                                         ", refined in " + formatSeconds(picture.streamMs / 1000.0) +
                                         (picture.refined ? "" : " (as far as the budget allows)")});
    }
    rows.push_back({"time", formatSeconds(seconds)});
    printFields(rows, 0);
    return kExitOk;
}

} // namespace vdbclay::cli
