#include "render/MaterialTextures.h"

#include "render/GpuMemory.h"
#include "render/ImageFile.h"
#include "vdb_hermite/PrintableText.h"

#include <stb_image_resize.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>

namespace vdbclay::render {

namespace {

/// sRGB bytes to linear light and back (tables: a texture's halvings touch every pixel).
struct SrgbTables {
    float toLinear[256];
    uint8_t toSrgb[4096]; // by linear value x 4095
    SrgbTables()
    {
        for (int i = 0; i < 256; ++i) {
            const double c = i / 255.0;
            toLinear[i] = float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
        }
        for (int i = 0; i < 4096; ++i) {
            const double l = i / 4095.0;
            const double c = l <= 0.0031308 ? l * 12.92 : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
            toSrgb[i] = uint8_t(std::lround(std::clamp(c, 0.0, 1.0) * 255.0));
        }
    }
};

const SrgbTables& srgbTables()
{
    static const SrgbTables tables;
    return tables;
}

/// Half the size (rounded down, at least 1): each pixel the mean of a 2x2 box, colour in linear light,
/// alpha as it is. An odd last row or column is left out (the next halving loses less than a pixel).
Image halved(const uint8_t* rgba, int width, int height)
{
    const SrgbTables& t = srgbTables();
    Image out;
    out.width = std::max(1, width / 2);
    out.height = std::max(1, height / 2);
    out.rgba.resize(std::size_t(out.width) * std::size_t(out.height) * 4);
    const auto texel = [&](int x, int y) { return &rgba[(std::size_t(std::min(y, height - 1)) * std::size_t(width) + std::size_t(std::min(x, width - 1))) * 4]; };
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            const uint8_t* p[4] = {texel(2 * x, 2 * y), texel(2 * x + 1, 2 * y), texel(2 * x, 2 * y + 1), texel(2 * x + 1, 2 * y + 1)};
            uint8_t* o = &out.rgba[(std::size_t(y) * std::size_t(out.width) + std::size_t(x)) * 4];
            for (int c = 0; c < 3; ++c) {
                const float linear = 0.25f * (t.toLinear[p[0][c]] + t.toLinear[p[1][c]] + t.toLinear[p[2][c]] + t.toLinear[p[3][c]]);
                o[c] = t.toSrgb[std::size_t(std::lround(linear * 4095.0f))];
            }
            o[3] = uint8_t((p[0][3] + p[1][3] + p[2][3] + p[3][3] + 2) / 4);
        }
    return out;
}

/// A picture scaled to size x size, then halved down to one pixel, all in linear light (sRGB pictures
/// average correctly). A large picture is first halved in 2x2 boxes while it is at least twice the size,
/// so the filter only ever reads a picture at most twice the layer's size: a 16384^2 picture costs about
/// a third more than its own pixels, not a full-size filter per level.
std::vector<Image> mipChain(const DecodedPicture& picture, int size)
{
    Image image; // the picture halved while it is at least twice the size (the first halving reads stb's pixels)
    const uint8_t* pixels = picture.rgba.get();
    int width = picture.width, height = picture.height;
    while (width >= 2 * size && height >= 2 * size) {
        image = halved(pixels, width, height);
        pixels = image.rgba.data();
        width = image.width;
        height = image.height;
    }
    std::vector<Image> chain;
    Image level;
    level.width = level.height = size;
    level.rgba.resize(std::size_t(size) * std::size_t(size) * 4);
    if (!stbir_resize_uint8_srgb(pixels, width, height, 0, level.rgba.data(), size, size, 0, 4, 3, 0))
        throw std::runtime_error("cannot scale the picture");
    chain.push_back(std::move(level));
    while (chain.back().width > 1) chain.push_back(halved(chain.back().rgba.data(), chain.back().width, chain.back().height));
    return chain;
}

} // namespace

MaterialTextureSet loadMaterialTextures(const MaterialTable& table, const std::string& folder, int layerSize)
{
    if (layerSize < 1 || (layerSize & (layerSize - 1)) != 0) throw std::invalid_argument("texture layers need a power-of-two size");
    MaterialTextureSet set;
    set.layerSize = layerSize;
    set.layerOfMaterial.assign(table.size() + 1, 0);
    std::map<std::string, uint32_t> layerOfPath; // 0: could not be read
    for (std::size_t id = 1; id <= table.size(); ++id) {
        const Material& m = table.at(MaterialId(id));
        if (m.texture.empty()) continue;
        const std::filesystem::path given(m.texture);
        const std::string path = given.is_absolute() || folder.empty() ? given.string() : (std::filesystem::path(folder) / given).string();
        auto found = layerOfPath.find(path);
        if (found == layerOfPath.end()) {
            uint32_t layer = 0;
            try {
                set.layers.push_back(mipChain(decodePicture(path), layerSize));
                layer = uint32_t(set.layers.size());
            } catch (const std::exception& e) {
                set.errors.push_back("material '" + printableText(m.name, 80) + "': texture " + printableText(path, 200) +
                                     " not used: " + printableText(e.what(), 200));
            }
            found = layerOfPath.emplace(path, layer).first;
        }
        set.layerOfMaterial[id] = found->second;
    }
    return set;
}

TextureArray::TextureArray(const VulkanContext& context, const MaterialTextureSet& set) : context_(context)
{
    MaterialTextureSet white;
    if (set.layers.empty()) {
        Image texel;
        texel.width = texel.height = 1;
        texel.rgba = {255, 255, 255, 255};
        white.layers.push_back({texel});
    }
    const MaterialTextureSet& use = set.layers.empty() ? white : set;
    const uint32_t layers = uint32_t(use.layers.size()), levels = uint32_t(use.layers[0].size());
    const uint32_t size = uint32_t(use.layers[0][0].width);
    VkDevice device = context.device();
    try {
        VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        info.imageType = VK_IMAGE_TYPE_2D;
        info.format = VK_FORMAT_R8G8B8A8_SRGB;
        info.extent = {size, size, 1};
        info.mipLevels = levels;
        info.arrayLayers = layers;
        info.samples = VK_SAMPLE_COUNT_1_BIT;
        info.tiling = VK_IMAGE_TILING_OPTIMAL;
        info.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
        info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        createDeviceImage(context, info, image_, memory_);

        VkDeviceSize bytes = 0;
        for (const auto& chain : use.layers)
            for (const Image& level : chain) bytes += level.rgba.size();
        HostBuffer staging(context, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
        std::vector<VkBufferImageCopy> copies;
        VkDeviceSize offset = 0;
        for (uint32_t layer = 0; layer < layers; ++layer)
            for (uint32_t level = 0; level < levels; ++level) {
                const Image& image = use.layers[layer][level];
                std::memcpy(staging.data() + offset, image.rgba.data(), image.rgba.size());
                VkBufferImageCopy copy{};
                copy.bufferOffset = offset;
                copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level, layer, 1};
                copy.imageExtent = {uint32_t(image.width), uint32_t(image.height), 1};
                copies.push_back(copy);
                offset += image.rgba.size();
            }
        context.submitAndWait([&](VkCommandBuffer cmd) {
            VkImageMemoryBarrier barrier{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
            barrier.srcQueueFamilyIndex = barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
            barrier.image = image_;
            barrier.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, levels, 0, layers};
            barrier.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
            barrier.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
            barrier.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &barrier);
            vkCmdCopyBufferToImage(cmd, staging.buffer(), image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, uint32_t(copies.size()), copies.data());
            barrier.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
            barrier.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
            barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
            vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0, 0, nullptr, 0, nullptr, 1, &barrier);
        });

        VkImageViewCreateInfo viewInfo{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        viewInfo.image = image_;
        viewInfo.viewType = VK_IMAGE_VIEW_TYPE_2D_ARRAY;
        viewInfo.format = info.format;
        viewInfo.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, levels, 0, layers};
        check(vkCreateImageView(device, &viewInfo, nullptr, &view_), "vkCreateImageView");
        VkSamplerCreateInfo sampler{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
        sampler.magFilter = sampler.minFilter = VK_FILTER_LINEAR;
        sampler.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
        sampler.addressModeU = sampler.addressModeV = sampler.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
        sampler.maxLod = float(levels);
        check(vkCreateSampler(device, &sampler, nullptr, &sampler_), "vkCreateSampler");
    } catch (...) {
        release();
        throw;
    }
}

TextureArray::~TextureArray() { release(); }

void TextureArray::release()
{
    VkDevice device = context_.device();
    if (sampler_) vkDestroySampler(device, sampler_, nullptr);
    if (view_) vkDestroyImageView(device, view_, nullptr);
    if (image_) vkDestroyImage(device, image_, nullptr);
    if (memory_) vkFreeMemory(device, memory_, nullptr);
    sampler_ = VK_NULL_HANDLE;
    view_ = VK_NULL_HANDLE;
    image_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
}

} // namespace vdbclay::render
