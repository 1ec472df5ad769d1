#include "render/ModelViews.h"

#include "render/Renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vdbclay::render {

namespace {

/// Tiles of one frame at most: the renderer's view limit, and a target no larger than 4096 square.
std::size_t tilesPerFrame(int size) { return std::min<std::size_t>(100, std::size_t(4096 / size) * std::size_t(4096 / size)); }

} // namespace

namespace {

RendererOptions drawing(bool backFaces, bool depthOnly)
{
    RendererOptions o;
    o.cullBackFaces = !backFaces;
    o.depthOnly = depthOnly;
    return o;
}

} // namespace

ModelViews::ModelViews(VulkanContext& context) : context_(context), renderer_(std::make_unique<Renderer>(context, drawing(true, false))) {}

ModelViews::~ModelViews() = default;

std::vector<Mask> ModelViews::silhouettes(const Mesh& mesh, const std::array<double, 3>& centre, double radius,
                                          const std::vector<std::array<double, 3>>& directions, int size, bool closedSurface)
{
    if (mesh.triangles.empty()) throw std::invalid_argument("cannot draw the silhouettes of an empty mesh");
    if (!(radius > 0.0) || !std::isfinite(radius)) throw std::invalid_argument("silhouettes need a positive radius");
    if (size < 8 || size > 1024) throw std::invalid_argument("silhouette size " + std::to_string(size) + " is outside 8 .. 1024");
    // Depth alone. A model file's triangles may face either way: both sides are drawn, unless the
    // surface closes (then every line of sight through it crosses a triangle facing the eye).
    std::unique_ptr<Renderer>& chosen = silhouetteRenderers_[closedSurface ? 1 : 0];
    if (!chosen) chosen = std::make_unique<Renderer>(context_, drawing(!closedSurface, true));
    Renderer& renderer = *chosen;
    renderer.setChunk(0, mesh);
    ShadingOptions shading;
    renderer.setShading(shading);

    // A parallel projection, nearly: an eye a hundred radii away whose view just holds the sphere.
    const double distance = 100.0 * radius;
    std::vector<Mask> masks;
    masks.reserve(directions.size());
    const std::size_t perFrame = tilesPerFrame(size);
    for (std::size_t first = 0; first < directions.size(); first += perFrame) {
        const std::size_t count = std::min(perFrame, directions.size() - first);
        const int columns = int(std::ceil(std::sqrt(double(count))));
        const int rows = int((count + std::size_t(columns) - 1) / std::size_t(columns));
        // One picture of tiles, kept for the next model (a library's models all take the same size).
        if (!tiles_ || tiles_->width() != columns * size || tiles_->height() != rows * size)
            tiles_ = std::make_unique<OffscreenTarget>(context_, columns * size, rows * size);
        OffscreenTarget& target = *tiles_;
        std::vector<RenderView> views(count);
        for (std::size_t i = 0; i < count; ++i) {
            const auto& d = directions[first + i];
            const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(n > 0.0)) throw std::invalid_argument("a silhouette's direction is zero");
            Camera& camera = views[i].camera;
            camera.target = centre;
            for (int a = 0; a < 3; ++a) camera.eye[std::size_t(a)] = centre[std::size_t(a)] - d[std::size_t(a)] / n * distance;
            camera.fovYDegrees = 2.0 * std::atan(radius / std::sqrt(distance * distance - radius * radius)) * 180.0 / M_PI;
            camera.nearPlane = distance - 1.01 * radius;
            views[i].target = &target;
            views[i].viewport = {int(i % std::size_t(columns)) * size, int(i / std::size_t(columns)) * size, size, size};
        }
        renderer.render(views);
        const std::vector<float> depth = target.depth();
        const std::size_t width = std::size_t(columns) * std::size_t(size);
        for (std::size_t i = 0; i < count; ++i) {
            Mask mask(std::size_t(size) * std::size_t(size));
            const std::size_t x0 = i % std::size_t(columns) * std::size_t(size), y0 = i / std::size_t(columns) * std::size_t(size);
            for (std::size_t y = 0; y < std::size_t(size); ++y)
                for (std::size_t x = 0; x < std::size_t(size); ++x)
                    mask[y * std::size_t(size) + x] = depth[(y0 + y) * width + x0 + x] != kNothingDrawn ? 1 : 0;
            masks.push_back(std::move(mask));
        }
    }
    renderer.removeChunk(0);
    return masks;
}

Image ModelViews::thumbnail(const Mesh& mesh, const MaterialTable& materials, const ThumbnailOptions& options)
{
    Image image = renderThumbnail(*renderer_, mesh, materials, options);
    renderer_->removeChunk(0);
    return image;
}

} // namespace vdbclay::render
