// The pictures materials name (Material::texture): read with stb, scaled to square layers with their
// mipmaps, and kept on the GPU as one image array the mesh shader samples tri-planarly.
#pragma once

#include "render/OffscreenTarget.h"
#include "render/VulkanContext.h"
#include "vdb_hermite/Materials.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vdbclay::render {

struct MaterialTextureSet {
    int layerSize = 1;                      // pixels per side of every layer's finest level
    std::vector<std::vector<Image>> layers; // per layer: its mip chain, finest first (sRGB-encoded RGBA8)
    std::vector<uint32_t> layerOfMaterial;  // per material id (0 .. table size): layer + 1, 0 = none
    std::vector<std::string> errors;        // textures that could not be read: one message each
};

/// Reads the pictures the table's materials name (relative paths from `folder`), one layer per distinct
/// path, each scaled to `layerSize` (a power of two) with its mipmaps. A picture that cannot be read is
/// reported in `errors` and its materials go untextured.
MaterialTextureSet loadMaterialTextures(const MaterialTable& table, const std::string& folder, int layerSize = 256);

/// A MaterialTextureSet on the GPU: an sRGB 2D array image with mipmaps, its view and a repeating
/// trilinear sampler. A set without layers becomes one white texel.
class TextureArray {
public:
    TextureArray(const VulkanContext& context, const MaterialTextureSet& set);
    ~TextureArray();
    TextureArray(const TextureArray&) = delete;
    TextureArray& operator=(const TextureArray&) = delete;

    VkImageView view() const { return view_; }
    VkSampler sampler() const { return sampler_; }

private:
    void release();
    const VulkanContext& context_;
    VkImage image_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkImageView view_ = VK_NULL_HANDLE;
    VkSampler sampler_ = VK_NULL_HANDLE;
};

} // namespace vdbclay::render
