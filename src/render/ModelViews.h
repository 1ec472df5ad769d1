// Pictures of one model after another for retrieval (src/query): silhouettes seen from many directions
// (the light-field descriptor) and shaded thumbnails. Its renderers serve every model, so a library
// of thousands pays for their pipelines once.
#pragma once

#include "mesher/Mesh.h"
#include "render/OffscreenTarget.h"
#include "render/Thumbnail.h"

#include <array>
#include <memory>
#include <vector>

namespace vdbclay::render {

class Renderer;
class VulkanContext;

/// A silhouette: size x size bytes, rows top to bottom, 1 where the model covers the pixel.
using Mask = std::vector<uint8_t>;

class ModelViews {
public:
    explicit ModelViews(VulkanContext& context);
    ~ModelViews();
    ModelViews(const ModelViews&) = delete;
    ModelViews& operator=(const ModelViews&) = delete;

    /// The silhouettes of `mesh` seen along each of `directions` (unit vectors from the eye towards
    /// `centre`) in parallel projection, framed so that the sphere (centre, radius) just fills the
    /// square; both sides of every triangle count, or only the triangles facing the eye where
    /// `closedSurface` says those cover it (a closed surface, oriented either way). Throws
    /// std::invalid_argument for an empty mesh, a radius that is not positive or a size outside 8 .. 1024.
    std::vector<Mask> silhouettes(const Mesh& mesh, const std::array<double, 3>& centre, double radius,
                                  const std::vector<std::array<double, 3>>& directions, int size, bool closedSurface = false);
    /// renderThumbnail with this object's renderer.
    Image thumbnail(const Mesh& mesh, const MaterialTable& materials, const ThumbnailOptions& options = {});

private:
    VulkanContext& context_;
    std::unique_ptr<Renderer> renderer_; // thumbnails: shaded, both sides of each triangle
    // Silhouettes: depth alone, of both sides [0] or the front faces of a closed surface [1]; made on
    // first use.
    std::array<std::unique_ptr<Renderer>, 2> silhouetteRenderers_;
    std::unique_ptr<OffscreenTarget> tiles_; // the silhouettes' last picture
};

} // namespace vdbclay::render
