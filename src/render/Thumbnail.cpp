#include "render/Thumbnail.h"

#include "render/Framing.h"
#include "render/Renderer.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace vdbclay::render {

Image renderThumbnail(VulkanContext& context, const Mesh& mesh, const MaterialTable& materials, const ThumbnailOptions& options)
{
    RendererOptions rendererOptions;
    rendererOptions.stagingBytes = std::max<uint64_t>(rendererOptions.stagingBytes, mesh.positions.size() * 28 + mesh.triangles.size() * 12 + 64);
    Renderer renderer(context, rendererOptions);
    return renderThumbnail(renderer, mesh, materials, options);
}

Image renderThumbnail(Renderer& renderer, const Mesh& mesh, const MaterialTable& materials, const ThumbnailOptions& options)
{
    if (mesh.triangles.empty()) throw std::invalid_argument("cannot make a thumbnail of an empty mesh");
    if (options.size < 1 || options.size > 4096)
        throw std::invalid_argument("thumbnail size " + std::to_string(options.size) + " is outside 1 .. 4096");
    std::array<double, 3> lo, hi;
    lo.fill(std::numeric_limits<double>::max());
    hi.fill(std::numeric_limits<double>::lowest());
    for (const auto& p : mesh.positions)
        for (std::size_t a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double(p[a]));
            hi[a] = std::max(hi[a], double(p[a]));
        }
    renderer.setMaterials(materials);
    ShadingOptions shading;
    shading.mode = options.mode;
    renderer.setShading(shading);
    renderer.setChunk(0, mesh);
    OffscreenTarget target(renderer.context(), options.size, options.size);
    RenderView view;
    view.camera = framingCamera(mesh.positions, lo, hi, 1.0);
    view.target = &target;
    renderer.render({view});
    Image image = target.colour();
    if (options.transparentBackground) {
        const std::vector<float> depth = target.depth();
        for (std::size_t i = 0; i < depth.size(); ++i)
            if (depth[i] == kNothingDrawn) image.rgba[i * 4 + 3] = 0;
    }
    return image;
}

} // namespace vdbclay::render
