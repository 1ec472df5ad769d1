// The graphics pipelines, built once per render pass shape from the SPIR-V embedded at build time
// (glslc): the surface, its wireframe, and the brush preview.
#pragma once

#include "render/VulkanContext.h"

#include <cstddef>

namespace vdbclay::render {

/// A vertex as the GPU reads it: position, normal, material (16 bits) | level (8) | occlusion (8).
struct GpuVertex {
    float position[3];
    float normal[3];
    uint32_t packed;
    uint32_t blend; // MaterialBlend | 1 << 31, or 0: no blend
};

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
