#include "render/Pipelines.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace vdbclay::render {

namespace {

const uint32_t kMeshVert[] =
#include "shaders/mesh.vert.inc"
    ;
const uint32_t kMeshFrag[] =
#include "shaders/mesh.frag.inc"
    ;
const uint32_t kBrushVert[] =
#include "shaders/brush.vert.inc"
    ;
const uint32_t kBrushFrag[] =
#include "shaders/brush.frag.inc"
    ;

} // namespace

std::array<int16_t, 2> octahedralNormal(const std::array<float, 3>& n)
{
    const float sum = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
    if (!(sum > 0.0f)) return {0, 0};
    float u = n[0] / sum, v = n[1] / sum;
    if (n[2] < 0.0f) {
        // The lower half folds over the square's diagonals.
        const float fu = (1.0f - std::fabs(v)) * (u >= 0.0f ? 1.0f : -1.0f);
        const float fv = (1.0f - std::fabs(u)) * (v >= 0.0f ? 1.0f : -1.0f);
        u = fu, v = fv;
    }
    const auto snorm = [](float x) { return int16_t(std::lround(std::clamp(x, -1.0f, 1.0f) * 32767.0f)); };
    return {snorm(u), snorm(v)};
}

VkPipeline createPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, const PipelineShape& shape)
{
    VkPipelineShaderStageCreateInfo stages[2]{};
    stages[0] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, shape.vert,
                 "main", nullptr};
    stages[1] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_FRAGMENT_BIT,
                 shape.frag, "main", nullptr};
    VkVertexInputBindingDescription binding{0, sizeof(GpuVertex), VK_VERTEX_INPUT_RATE_VERTEX};
    VkVertexInputAttributeDescription attributes[4] = {
        {0, 0, VK_FORMAT_R32G32B32_SFLOAT, uint32_t(offsetof(GpuVertex, position))},
        {1, 0, VK_FORMAT_R16G16_SNORM, uint32_t(offsetof(GpuVertex, normal))},
        {2, 0, VK_FORMAT_R32_UINT, uint32_t(offsetof(GpuVertex, packed))},
        {3, 0, VK_FORMAT_R32_UINT, uint32_t(offsetof(GpuVertex, blend))},
    };
    VkPipelineVertexInputStateCreateInfo input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    if (shape.meshInput) {
        input.vertexBindingDescriptionCount = 1;
        input.pVertexBindingDescriptions = &binding;
        input.vertexAttributeDescriptionCount = 4;
        input.pVertexAttributeDescriptions = attributes;
    }
    VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewport.viewportCount = 1;
    viewport.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = shape.polygonMode;
    // Meshes are closed, counter-clockwise seen from outside; the projection flips Y for Vulkan, which
    // keeps counter-clockwise as the front face.
    raster.cullMode = shape.meshInput && shape.cullBackFaces && shape.polygonMode == VK_POLYGON_MODE_FILL ? VK_CULL_MODE_BACK_BIT
                                                                                    : VK_CULL_MODE_NONE;
    raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    raster.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    depth.depthTestEnable = shape.depthTest ? VK_TRUE : VK_FALSE;
    depth.depthWriteEnable = shape.depthWrite ? VK_TRUE : VK_FALSE;
    depth.depthCompareOp = VK_COMPARE_OP_GREATER_OR_EQUAL; // reversed depth (Renderer: nearer is larger)
    VkPipelineColorBlendAttachmentState attachment{};
    attachment.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                                VK_COLOR_COMPONENT_A_BIT;
    if (shape.blend != PipelineShape::Blend::None) {
        const bool premultiplied = shape.blend == PipelineShape::Blend::Premultiplied;
        attachment.blendEnable = VK_TRUE;
        attachment.srcColorBlendFactor = premultiplied ? VK_BLEND_FACTOR_ONE : VK_BLEND_FACTOR_SRC_ALPHA;
        attachment.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
        attachment.colorBlendOp = VK_BLEND_OP_ADD;
        attachment.srcAlphaBlendFactor = premultiplied ? VK_BLEND_FACTOR_ONE : VK_BLEND_FACTOR_ZERO;
        attachment.dstAlphaBlendFactor = premultiplied ? VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA : VK_BLEND_FACTOR_ONE;
        attachment.alphaBlendOp = VK_BLEND_OP_ADD;
    }
    VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blend.attachmentCount = 1;
    blend.pAttachments = &attachment;
    VkDynamicState dynamicStates[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamicStates;

    if (shape.frag == VK_NULL_HANDLE) attachment.colorWriteMask = 0; // depth alone

    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.stageCount = shape.frag == VK_NULL_HANDLE ? 1 : 2;
    info.pStages = stages;
    info.pVertexInputState = &input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewport;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pDepthStencilState = &depth;
    info.pColorBlendState = &blend;
    info.pDynamicState = &dynamic;
    info.layout = layout;
    info.renderPass = pass;
    VkPipeline pipeline = VK_NULL_HANDLE;
    check(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline), "vkCreateGraphicsPipelines");
    return pipeline;
}

VkShaderModule shaderModule(VkDevice device, const uint32_t* code, std::size_t bytes)
{
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = bytes;
    info.pCode = code;
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(device, &info, nullptr, &module), "vkCreateShaderModule");
    return module;
}

Pipelines::Pipelines(const VulkanContext& context, VkRenderPass renderPass, bool cullBackFaces, bool depthOnly) : context_(context)
{
    const auto start = std::chrono::steady_clock::now();
    VkDevice device = context.device();
    VkDescriptorSetLayoutBinding bindings[3]{};
    bindings[0].binding = 0;
    bindings[0].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC;
    bindings[0].descriptorCount = 1;
    bindings[0].stageFlags = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    bindings[1].binding = 1;
    bindings[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[1].descriptorCount = 1;
    bindings[1].stageFlags = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT; // vertices blend materials' colours
    bindings[2].binding = 2;
    bindings[2].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    bindings[2].descriptorCount = 1;
    bindings[2].stageFlags = VK_SHADER_STAGE_FRAGMENT_BIT;
    VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    setInfo.bindingCount = 3;
    setInfo.pBindings = bindings;
    check(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");
    VkPushConstantRange push{VK_SHADER_STAGE_FRAGMENT_BIT, 0, 16};
    VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layoutInfo.setLayoutCount = 1;
    layoutInfo.pSetLayouts = &setLayout_;
    layoutInfo.pushConstantRangeCount = 1;
    layoutInfo.pPushConstantRanges = &push;
    check(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &layout_), "vkCreatePipelineLayout");

    VkShaderModule meshVert = shaderModule(device, kMeshVert, sizeof(kMeshVert));
    VkShaderModule meshFrag = shaderModule(device, kMeshFrag, sizeof(kMeshFrag));
    VkShaderModule brushVert = shaderModule(device, kBrushVert, sizeof(kBrushVert));
    VkShaderModule brushFrag = shaderModule(device, kBrushFrag, sizeof(kBrushFrag));
    try {
        PipelineShape surface;
        surface.vert = meshVert;
        surface.frag = depthOnly ? VK_NULL_HANDLE : meshFrag;
        surface.cullBackFaces = cullBackFaces;
        surface_ = createPipeline(device, renderPass, layout_, surface);
        if (context.supportsWireframe()) {
            PipelineShape wireframe = surface;
            wireframe.polygonMode = VK_POLYGON_MODE_LINE;
            wireframe.depthWrite = false;
            wireframe_ = createPipeline(device, renderPass, layout_, wireframe);
        }
        PipelineShape brush;
        brush.vert = brushVert;
        brush.frag = brushFrag;
        brush.meshInput = false;
        brush.depthWrite = false;
        brush.blend = PipelineShape::Blend::Alpha;
        brush_ = createPipeline(device, renderPass, layout_, brush);
    } catch (...) {
        for (VkShaderModule m : {meshVert, meshFrag, brushVert, brushFrag}) vkDestroyShaderModule(device, m, nullptr);
        release();
        throw;
    }
    for (VkShaderModule m : {meshVert, meshFrag, brushVert, brushFrag}) vkDestroyShaderModule(device, m, nullptr);
    buildMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

Pipelines::~Pipelines() { release(); }

void Pipelines::release()
{
    VkDevice device = context_.device();
    for (VkPipeline p : {surface_, wireframe_, brush_})
        if (p) vkDestroyPipeline(device, p, nullptr);
    if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
    if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
    surface_ = wireframe_ = brush_ = VK_NULL_HANDLE;
    layout_ = VK_NULL_HANDLE;
    setLayout_ = VK_NULL_HANDLE;
}

} // namespace vdbclay::render
