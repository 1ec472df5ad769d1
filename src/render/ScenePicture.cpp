#include "render/ScenePicture.h"

#include "render/Framing.h"
#include "render/Renderer.h"
#include "render/SceneChunks.h"
#include "render/VulkanContext.h"
#include "scene/StreamingScene.h"

#include <chrono>
#include <filesystem>

namespace vdbclay::render {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

MeshOptions pictureMeshOptions()
{
    MeshOptions o;
    o.kind = MesherKind::CubicalMarchingSquares;
    return o;
}

Viewer viewerOf(const Camera& camera, int width, int height)
{
    Viewer v;
    v.position = camera.eye;
    v.target = camera.target;
    v.fovDegrees = camera.fovYDegrees;
    v.viewport = {width, height};
    return v;
}

Picture draw(VulkanContext& context, Renderer& renderer, const Camera& camera, const PictureRequest& request)
{
    OffscreenTarget target(context, request.width, request.height);
    RenderView view;
    view.camera = camera;
    view.target = &target;
    renderer.setShading(request.shading);
    Picture p;
    p.stats = renderer.render({view});
    p.image = target.colour();
    p.camera = camera;
    p.pipelineMs = renderer.pipelineBuildMs();
    return p;
}

std::array<double, 3> worldOf(const IndexCoord& c, double voxel)
{
    return {c[0] * voxel, c[1] * voxel, c[2] * voxel};
}

} // namespace

MaterialLook materialLook(double voxelSize, const std::string& textureFolder)
{
    MaterialLook look;
    look.textureFolder = textureFolder;
    look.textureTile = 32.0 * voxelSize;
    return look;
}

Camera defaultCamera(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int width, int height)
{
    return framingCamera(lo, hi, double(width) / double(height));
}

Picture renderVolume(VulkanContext& context, const Volume& volume, const PictureRequest& request)
{
    Renderer renderer(context);
    const VolumeUpload upload =
        uploadVolume(renderer, volume, pictureMeshOptions(), materialLook(volume.voxelSize(), request.textureFolder));
    Camera camera = request.camera.value_or(
        framingCamera(upload.outline, upload.lo, upload.hi, double(request.width) / double(request.height)));
    fitNearPlane(camera, upload.lo, upload.hi);
    Picture p = draw(context, renderer, camera, request);
    p.meshMs = upload.meshSeconds * 1000.0;
    p.warnings = upload.warnings;
    return p;
}

Picture renderStreamed(VulkanContext& context, const StreamingScene& scene, const Camera& camera, const PictureRequest& request)
{
    Renderer renderer(context);
    const std::string folder = std::filesystem::path(scene.storePath()).parent_path().string();
    const std::vector<std::string> warnings =
        renderer.setMaterials(scene.materials(), materialLook(scene.voxelSize(), folder)); // edits define materials before an autosave stores them
    StreamedSceneChunks chunks;
    const StreamedSceneChunks::SyncReport sync = chunks.sync(scene, renderer);
    Picture p = draw(context, renderer, camera, request);
    p.meshMs = sync.meshSeconds * 1000.0;
    p.bricksShown = sync.shown;
    p.warnings = warnings;
    return p;
}

Picture renderStore(VulkanContext& context, const std::string& path, const PictureRequest& request)
{
    StreamingOptions options;
    options.memoryBudgetBytes = request.memoryBudgetBytes;
    options.pixelTolerance = request.pixelTolerance;
    StreamingScene scene(path, options);
    Camera camera;
    const double voxel = scene.voxelSize();
    const auto box = scene.storeBounds();
    std::array<double, 3> lo{0, 0, 0}, hi{1, 1, 1};
    if (box) {
        lo = worldOf(box->first, voxel);
        hi = worldOf({box->second[0] + 1, box->second[1] + 1, box->second[2] + 1}, voxel);
    }
    camera = request.camera.value_or(defaultCamera(lo, hi, request.width, request.height));
    fitNearPlane(camera, lo, hi);
    const auto start = Clock::now();
    const auto settle = [&] {
        const Viewer viewer = viewerOf(camera, request.width, request.height);
        FrameReport report;
        do {
            report = scene.frame(viewer);
            if (report.settled && report.pending == 0) break;
            scene.waitForLoads();
        } while (msSince(start) < request.settleSeconds * 1000.0);
        return report;
    };
    FrameReport report = settle();
    if (!request.camera && box) {
        // The bounds' corners frame a box; the surface shown frames the content itself (a sphere fills the
        // view as `render` of a .vdb frames it), then the view is streamed again from there.
        std::vector<std::array<float, 3>> outline;
        for (const BrickKey& key : scene.shownBricks())
            if (const auto mesh = scene.meshBrick(key)) appendOutline(mesh->mesh.decoded().positions, outline);
        if (!outline.empty()) {
            camera = framingCamera(outline, lo, hi, double(request.width) / double(request.height));
            fitNearPlane(camera, lo, hi);
            report = settle();
        }
    }
    const double streamMs = msSince(start);
    Picture p = renderStreamed(context, scene, camera, request);
    p.streamMs = streamMs;
    p.refined = report.complete;
    return p;
}

} // namespace vdbclay::render
