// One picture of a scene, as `vdbclay render`, the demo and `lod inspect --frames` make it: a .vdb is
// meshed whole; a store is streamed for the view (refined as far as the memory budget allows) and its
// shown bricks meshed at their levels.
#pragma once

#include "render/OffscreenTarget.h"
#include "render/RenderTypes.h"
#include "vdb_hermite/Volume.h"

#include <optional>
#include <string>

namespace vdbclay {
class StreamingScene;
}

namespace vdbclay::render {

class VulkanContext;

struct PictureRequest {
    int width = 1280, height = 720;
    std::optional<Camera> camera; // absent: framing the whole scene from a three-quarter view
    ShadingOptions shading;
    uint64_t memoryBudgetBytes = 512ull << 20; // stores: resident bricks
    double pixelTolerance = 1.0;               // stores: screen-space error a brick may show
    double settleSeconds = 60.0;               // stores: the longest wait for the view to refine
    std::string textureFolder;                 // where relative texture paths start (a .vdb's folder; stores: their own)
};

struct Picture {
    Image image;
    Camera camera;
    FrameStats stats;
    double meshMs = 0.0;          // meshing what is drawn (occlusion included)
    double streamMs = 0.0;        // stores: until the view was refined
    double pipelineMs = 0.0;      // shader and pipeline creation (the first frame's compilation)
    uint64_t bricksShown = 0;     // stores
    bool refined = true;          // stores: every brick of the view at its level (false: the budget ran out)
    std::vector<std::string> warnings; // material textures that could not be read (drawn without them)
};

/// How the materials of a scene with this voxel size and texture folder are drawn: a texture repeats
/// every 32 voxels.
MaterialLook materialLook(double voxelSize, const std::string& textureFolder);

/// The camera that frames the box (world units) for an image of that size.
Camera defaultCamera(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int width, int height);

Picture renderVolume(VulkanContext& context, const Volume& volume, const PictureRequest& request);
/// Streams the store at `path` for the view, then draws it.
Picture renderStore(VulkanContext& context, const std::string& path, const PictureRequest& request);
/// Draws the scene's shown bricks as its last frame selected them (for flights already streaming).
Picture renderStreamed(VulkanContext& context, const StreamingScene& scene, const Camera& camera, const PictureRequest& request);

} // namespace vdbclay::render
