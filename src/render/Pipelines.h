// The graphics pipelines, built once per render pass shape from the SPIR-V embedded at build time
// (glslc): the surface, its wireframe, and the brush preview.
#pragma once

#include "render/VulkanContext.h"

#include <array>
#include <cstddef>
#include <cstdint>

namespace vdbclay::render {

/// A vertex as the GPU reads it: position, octahedral normal, material (16 bits) | level (7) | masked (1)
/// | occlusion (8), and the colour blend.
struct GpuVertex {
    float position[3];
    int16_t normal[2]; // octahedral, as snorm16 (octahedralNormal)
    uint32_t packed;
    uint32_t blend; // MaterialBlend | 1 << 31, or 0: no blend
};
static_assert(sizeof(GpuVertex) == 24, "the vertex input's strides and offsets");

/// A unit normal folded onto the octahedron and unfolded into the square [-1, 1]^2, as the snorm16 pair
/// the vertex shader folds back (mesh.vert): within 1e-4 radian of the direction. A zero normal (a mesh
/// without normals) becomes +z.
std::array<int16_t, 2> octahedralNormal(const std::array<float, 3>& n);

/// What a graphics pipeline draws with: triangles (or their edges), one colour attachment and reversed
/// depth, viewport and scissor set at draw time.
struct PipelineShape {
    VkShaderModule vert = VK_NULL_HANDLE, frag = VK_NULL_HANDLE; // no fragment shader: depth alone, no colour
    bool meshInput = true; // GpuVertex per vertex (culled back faces); false: the vertex shader makes its positions
    bool cullBackFaces = true; // mesh input: false draws both sides (model files whose triangles face either way)
    VkPolygonMode polygonMode = VK_POLYGON_MODE_FILL;
    bool depthTest = true;
    bool depthWrite = true;
    enum class Blend { None, Alpha, Premultiplied };
    Blend blend = Blend::None;
};
/// Throws VulkanError.
VkPipeline createPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, const PipelineShape& shape);

/// A shader module of SPIR-V words (embedded at build time). Throws VulkanError.
VkShaderModule shaderModule(VkDevice device, const uint32_t* code, std::size_t bytes);

class Pipelines {
public:
    /// `cullBackFaces`, `depthOnly`: the surface pipeline's (RendererOptions).
    Pipelines(const VulkanContext& context, VkRenderPass renderPass, bool cullBackFaces = true, bool depthOnly = false);
    ~Pipelines();
    Pipelines(const Pipelines&) = delete;
    Pipelines& operator=(const Pipelines&) = delete;

    VkDescriptorSetLayout setLayout() const { return setLayout_; }
    VkPipelineLayout layout() const { return layout_; }
    VkPipeline surface() const { return surface_; }
    VkPipeline wireframe() const { return wireframe_; } // VK_NULL_HANDLE where lines are unsupported
    VkPipeline brushPreview() const { return brush_; }
    /// Wall time spent creating the shader modules and pipelines (the first frame's compilation).
    double buildMs() const { return buildMs_; }

private:
    void release();

    const VulkanContext& context_;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline surface_ = VK_NULL_HANDLE, wireframe_ = VK_NULL_HANDLE, brush_ = VK_NULL_HANDLE;
    double buildMs_ = 0.0;
};

} // namespace vdbclay::render
