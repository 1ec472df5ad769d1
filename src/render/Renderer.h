// The renderer: mesh chunks in GPU buffers, uploaded only when new or changed (through a staging ring
// that is never reallocated), freed when their brick goes, culled per chunk against each view's
// frustum; a frame draws one or more views (camera + viewport + target), so stereo is two views of
// one frame. Shading, debug views and the brush overlay follow ShadingOptions and BrushOverlay.
#pragma once

#include "mesher/Mesh.h"
#include "mesher/QuantizedMesh.h"
#include "render/RenderTypes.h"
#include "vdb_hermite/Materials.h"

namespace vdbclay {
class OccluderDepth;
}

#include <vulkan/vulkan.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace vdbclay::render {

class VulkanContext;
class RenderTarget;

using ChunkId = uint64_t;

/// What an interactive frame uploads at most (RendererOptions::uploadBytesPerFrame): about a millisecond
/// of copying, well inside a 90 Hz frame.
constexpr uint64_t kInteractiveUploadBytesPerFrame = 8ull << 20;

struct RendererOptions {
    uint64_t gpuBudgetBytes = 1ull << 30; // mesh buffers; chunks not drawn lately are freed beyond it
    uint64_t stagingBytes = 16ull << 20;  // the staging ring per frame in flight: uploads beyond it in one frame flush early
    /// Chunk bytes a frame uploads at most (0: every chunk queued); the rest wait, in the order they were
    /// queued, for later frames, and a chunk replaced is drawn as it was until its new version is up. A
    /// window's frame sets it (a frame then never copies more than this, nor waits on a full staging
    /// ring); a picture leaves it at 0.
    uint64_t uploadBytesPerFrame = 0;
    VkFormat colourFormat = VK_FORMAT_R8G8B8A8_UNORM; // of every target drawn into (a swapchain's may differ)
    /// Sculptures are closed and face outwards: their back faces are culled. Model files' triangles may
    /// face either way (retrieval's silhouettes and thumbnails draw both sides).
    bool cullBackFaces = true;
    /// Surfaces write depth alone, no colour (silhouettes read from depth; no shading to pay for).
    bool depthOnly = false;
};

struct RenderView {
    Camera camera;
    RenderTarget* target = nullptr; // an OffscreenTarget, a window's swapchain image, a headset's eye
    std::array<int, 4> viewport{0, 0, 0, 0}; // x, y, width, height in pixels; zero size: the whole target
    /// Its depth, reduced to tiles on the device, becomes Renderer::drawnDepth() once the frame is done:
    /// the next selections' occluders. Several such views of a frame (a headset's eyes) hide a brick
    /// only when each of them does (kMaxKeptViews at most); targets without a sampled depth keep none.
    bool keepDepth = false;
};

/// What a chunk's vertices may carry beside the mesh (Renderer::setChunk): each null, or one value per vertex.
struct VertexShading {
    const std::vector<uint8_t>* occlusion = nullptr; // 0 = fully occluded .. 255 = open: creases darken (shaded view)
    const std::vector<uint8_t>* masked = nullptr;    // non-zero where the sculptor's mask keeps the voxel: darkened in every look
    const std::vector<uint32_t>* blend = nullptr;    // MaterialBlend: colours blend with the material beside
};

/// A chunk's vertices and indices as the GPU takes them (packChunk): packed on any thread (a mesh
/// worker), queued on the renderer's (Renderer::setPackedChunk) with nothing left to compute.
struct PackedChunk {
    std::vector<uint8_t> bytes; // vertices, then uint32 indices; empty: the mesh has no triangles
    VkDeviceSize indexOffset = 0;
    uint32_t indexCount = 0;
    std::array<float, 3> lo{0, 0, 0}, hi{0, 0, 0}; // bounds of the vertices
    int level = 0;
};
/// Packs a mesh as Renderer::setChunk draws it. Throws std::invalid_argument for a triangle naming a
/// vertex the mesh lacks.
PackedChunk packChunk(const Mesh& mesh, int level = 0, const VertexShading& shading = VertexShading());
/// The same for a mesh as a scene keeps it (decoded first).
PackedChunk packChunk(const QuantizedMesh& mesh, int level = 0, const VertexShading& shading = VertexShading());

class Renderer {
public:
    Renderer(VulkanContext& context, const RendererOptions& options = {});
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Colours, toughness, texture patterns and pictures of the materials the meshes name. Returns one
    /// message per texture that could not be read (those materials are drawn with the procedural pattern).
    /// Pictures are read and scaled on a worker: with PictureLoading::Wait (pictures of a file) this
    /// waits for them; with Background (a window's frame) the materials are drawn with their procedural
    /// patterns until picturesReady(), when calling setMaterials again installs them and returns their
    /// messages.
    enum class PictureLoading { Wait, Background };
    std::vector<std::string> setMaterials(const MaterialTable& materials, const MaterialLook& look = {},
                                          PictureLoading loading = PictureLoading::Wait);
    /// Whether pictures asked for with PictureLoading::Background are read and wait to be installed.
    bool picturesReady() const;
    /// Queues `mesh` as chunk `id` (a new chunk, or a new version of one); uploaded by the next frame.
    /// `level` (< 128) is what the lod view shows. Without a blend, a triangle shows its own material
    /// alone; with one, each vertex's colour is its own and the other material's, mixed by the share.
    void setChunk(ChunkId id, const Mesh& mesh, int level = 0, const VertexShading& shading = VertexShading());
    /// The same with the packing done (packChunk): what the frame thread calls for meshes made on workers.
    void setPackedChunk(ChunkId id, PackedChunk chunk);
    /// Frees the chunk's buffers at a next frame (its brick was evicted or it became empty). While chunks
    /// wait for their upload (uploadBytesPerFrame), removals wait with them (a few frames at most): what
    /// replaces a removed chunk is usually among them, and the view keeps no hole meanwhile.
    void removeChunk(ChunkId id);
    /// Changes RendererOptions::uploadBytesPerFrame from the next frame on (a headset's frame that runs
    /// late uploads less).
    void setUploadBytesPerFrame(uint64_t bytes);
    /// Chunks queued and not yet uploaded.
    std::size_t uploadsWaiting() const;
    bool hasChunk(ChunkId id) const;
    std::size_t chunkCount() const;

    void setShading(const ShadingOptions& shading);
    const ShadingOptions& shading() const;
    void setBrush(const std::optional<BrushOverlay>& brush);

    /// Uploads what changed, draws the views and, for offscreen targets, reads their pixels back.
    FrameStats render(const std::vector<RenderView>& views);
    /// The depth of the last finished frame's view with RenderView::keepDepth, as occluders for the
    /// next selections (StreamingScene::frame); nullptr before any. A frame presented is finished when a
    /// later one reuses its slot (frames in flight): these tiles lag the view by a frame or two, which
    /// the selection allows for (OccluderDepth).
    std::shared_ptr<const OccluderDepth> drawnDepth() const;
    /// Chunks freed to keep within the GPU budget since the last call (their owner uploads them again
    /// when they are needed).
    std::vector<ChunkId> takeEvicted();

    uint64_t gpuMemoryBytes() const;
    /// Time spent building shaders and pipelines (once, at construction).
    double pipelineBuildMs() const;
    const VulkanContext& context() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// The view-projection matrix (column-major, depth 0..1, Y down as Vulkan's framebuffer) of a camera.
std::array<float, 16> viewProjection(const Camera& camera, double aspect);
/// The same in double precision (occlusion tests compare distances across a whole scene).
std::array<double, 16> viewProjectionExact(const Camera& camera, double aspect);

} // namespace vdbclay::render
