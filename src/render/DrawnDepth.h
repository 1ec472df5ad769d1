// The last frame's depth as the next selection's occluders (scene/ViewSelection.h's OccluderDepth): per
// tile of pixels, the farthest distance along the view at which the frame drew a surface. On the device
// (DepthTileReducer: one compute dispatch after the view's pass, a few hundred kilobytes read back once
// its frame is done), or from a depth image already read back (occluderDepthOf).
#pragma once

#include "render/RenderTypes.h"
#include "scene/ViewSelection.h"

#include <vulkan/vulkan.h>

#include <array>
#include <memory>
#include <vector>

namespace vdbclay::render {

class HostBuffer;
class RenderTarget;
class VulkanContext;

/// Pixels per side of a tile of the drawn depth.
constexpr int kDepthTile = 8;
/// Views of one frame whose depth is kept at most (a headset's eyes, and room to spare).
constexpr int kMaxKeptViews = 4;

/// Tiles of `tile` x `tile` pixels (the last row and column may be narrower) of a reversed depth image
/// (OffscreenTarget::depth(): rows top to bottom, 0 where nothing was drawn) that `camera` drew at
/// `width` x `height`. Throws std::invalid_argument when the image's size is not width x height or the
/// tile is not positive.
OccluderDepth occluderDepthOf(const std::vector<float>& depth, int width, int height, const Camera& camera, int tile = kDepthTile);

/// Whether the device samples the depth format: targets then make their depth images sampled.
bool depthSampleable(const VulkanContext& context);

/// The depth of one view per frame reduced to kDepthTile tiles on the device, for frames in flight: the
/// renderer records it after the view's pass into the frame's slot and takes the tiles once that slot's
/// fence has signalled.
class DepthTileReducer {
public:
    /// Throws VulkanError.
    DepthTileReducer(const VulkanContext& context, int slots);
    ~DepthTileReducer();
    DepthTileReducer(const DepthTileReducer&) = delete;
    DepthTileReducer& operator=(const DepthTileReducer&) = delete;

    /// Records the reduction of `target`'s depth within `viewport` (x, y, width, height) into `slot`,
    /// which the device must be done with; `camera` drew the view. Up to kMaxKeptViews views a frame.
    /// Records nothing and returns false when the target's depth cannot be sampled or the frame keeps
    /// as many views already.
    bool record(VkCommandBuffer cmd, std::size_t slot, const RenderTarget& target, const std::array<int, 4>& viewport, const Camera& camera);
    /// Once the commands `slot` was recorded into are done: its tiles (those of its first view, seen also
    /// from the others: OccluderDepth::alsoSeenFrom), or nullptr when it recorded none since the last take.
    std::shared_ptr<const OccluderDepth> take(std::size_t slot);

private:
    struct Slot;
    const VulkanContext& context_;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    std::vector<std::unique_ptr<Slot>> slots_;
    void release();
};

} // namespace vdbclay::render
