// Pictures of one model after another for retrieval (src/query): silhouettes seen from many directions
// (the light-field descriptor) and shaded thumbnails. One renderer serves every model, so a library
// of thousands pays for its pipelines once.
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
    /// square; both sides of every triangle count. Throws std::invalid_argument for an empty mesh, a
    /// radius that is not positive or a size outside 8 .. 1024.
    std::vector<Mask> silhouettes(const Mesh& mesh, const std::array<double, 3>& centre, double radius,
                                  const std::vector<std::array<double, 3>>& directions, int size);
    /// renderThumbnail with this object's renderer.
    Image thumbnail(const Mesh& mesh, const MaterialTable& materials, const ThumbnailOptions& options = {});

private:
    VulkanContext& context_;
    std::unique_ptr<Renderer> renderer_;
    std::unique_ptr<OffscreenTarget> tiles_; // the silhouettes' last picture
};

} // namespace vdbclay::render
