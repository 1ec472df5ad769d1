// Small pictures of a mesh for the retrieval menus and index: one offscreen frame from a framing camera.
#pragma once

#include "mesher/Mesh.h"
#include "render/OffscreenTarget.h"
#include "render/RenderTypes.h"
#include "vdb_hermite/Materials.h"

namespace vdbclay::render {

class Renderer;
class VulkanContext;

struct ThumbnailOptions {
    int size = 128;                // square, pixels
    ViewMode mode = ViewMode::Shaded;
    bool transparentBackground = false; // alpha 0 where nothing was drawn
};

/// Renders `mesh` framed from a three-quarter view. Throws std::invalid_argument for an empty mesh or a
/// size outside 1 .. 4096.
Image renderThumbnail(VulkanContext& context, const Mesh& mesh, const MaterialTable& materials,
                      const ThumbnailOptions& options = {});
/// The same with a renderer kept for many thumbnails (its chunks and shading are replaced).
Image renderThumbnail(Renderer& renderer, const Mesh& mesh, const MaterialTable& materials, const ThumbnailOptions& options = {});

} // namespace vdbclay::render
