#include "render/Renderer.h"

#include "render/DrawnDepth.h"
#include "render/GpuMemory.h"
#include "render/MaterialTextures.h"
#include "render/OffscreenTarget.h"
#include "render/Pipelines.h"
#include "render/VulkanContext.h"

#define GLM_FORCE_DEPTH_ZERO_TO_ONE
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <future>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace vdbclay::render {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

/// The per-view uniform block, laid out as common.glsl's ViewData (std140).
struct ViewUniforms {
    float viewProj[16];
    float invViewProj[16];
    float eye[4];
    float lightDir[4];
    uint32_t mode[4];
    float brushWorldToLocal[16];
    float brushParams[4];
    float brushExtra[4];
    float brushMin[4];
    float brushMax[4];
    float previewColour[4];
    float highlightColour[4];
};
static_assert(sizeof(ViewUniforms) == 336, "ViewUniforms must match common.glsl");

// Views one frame draws at most: stereo eyes and the desktop's panels need few; the light field's 100
// silhouettes are drawn as one frame of tiles.
constexpr int kMaxViews = 128;
/// Frames recorded while the device still runs earlier ones: the CPU prepares frame N + 1 while frame N
/// draws, and waits only for frame N - 1.
constexpr int kFramesInFlight = 2;
/// Frames removals wait at most for the uploads queued before them.
constexpr int kRemovalWaitFrames = 8;

glm::dmat4 viewProjectionMatrix(const Camera& c, double aspect)
{
    const std::array<double, 3> u = usableUp(c); // a given up along the view would make lookAt's matrix NaN
    const glm::dvec3 eye(c.eye[0], c.eye[1], c.eye[2]), target(c.target[0], c.target[1], c.target[2]), up(u[0], u[1], u[2]);
    // Reversed depth with the far plane at infinity: depth = near / distance along the view, 1 at the near
    // plane and 0 far away, so float depth keeps its relative precision at every distance.
    const double near = usableNearPlane(c);
    glm::dmat4 proj(0.0);
    if (c.asymmetric()) {
        // An eye's off-centre view: x / -z from tan(left) to tan(right) maps to -1 .. 1, y likewise (down).
        const auto& t = c.fovTangents;
        proj[0][0] = 2.0 / (t[1] - t[0]);
        proj[2][0] = (t[1] + t[0]) / (t[1] - t[0]);
        proj[1][1] = -2.0 / (t[2] - t[3]); // Vulkan's framebuffer Y points down
        proj[2][1] = -(t[2] + t[3]) / (t[2] - t[3]);
    } else {
        const double f = 1.0 / std::tan(0.5 * glm::radians(c.fovYDegrees));
        proj[0][0] = f / aspect;
        proj[1][1] = -f; // Vulkan's framebuffer Y points down
    }
    proj[2][3] = -1.0;
    proj[3][2] = near;
    return proj * glm::lookAt(eye, target, up);
}

struct Frustum {
    glm::dvec4 planes[6];
    bool outside(const float lo[3], const float hi[3]) const
    {
        for (const auto& p : planes) {
            const double x = p.x >= 0.0 ? hi[0] : lo[0];
            const double y = p.y >= 0.0 ? hi[1] : lo[1];
            const double z = p.z >= 0.0 ? hi[2] : lo[2];
            if (p.x * x + p.y * y + p.z * z + p.w < 0.0) return true;
        }
        return false;
    }
};

Frustum frustumOf(const glm::dmat4& m)
{
    auto row = [&](int r) { return glm::dvec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
    Frustum f;
    f.planes[0] = row(3) + row(0);
    f.planes[1] = row(3) - row(0);
    f.planes[2] = row(3) + row(1);
    f.planes[3] = row(3) - row(1);
    f.planes[4] = row(2);          // depth >= 0: always true with the far plane at infinity
    f.planes[5] = row(3) - row(2); // depth <= 1: the near plane
    return f;
}

void copyMatrix(float out[16], const glm::dmat4& m)
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) out[c * 4 + r] = float(m[c][r]);
}

} // namespace

std::array<float, 16> viewProjection(const Camera& camera, double aspect)
{
    std::array<float, 16> out{};
    copyMatrix(out.data(), viewProjectionMatrix(camera, aspect));
    return out;
}

std::array<double, 16> viewProjectionExact(const Camera& camera, double aspect)
{
    const glm::dmat4 m = viewProjectionMatrix(camera, aspect);
    std::array<double, 16> out{};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) out[std::size_t(c * 4 + r)] = m[c][r];
    return out;
}

constexpr VkBufferUsageFlags kChunkUsage = VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;

struct Renderer::Impl {
    // A chunk lives in its heap block's buffer (one buffer per block, bound to the whole block), so draws
    // bind a block once and address chunks by first index and vertex offset.
    struct GpuChunk {
        GpuAllocation allocation;
        uint32_t firstIndex = 0;   // in the block's buffer, as uint32 indices
        int32_t vertexOffset = 0;  // in the block's buffer, as vertices
        uint32_t indexCount = 0;
        float lo[3], hi[3];
        int level = 0;
        uint64_t lastDrawn = 0;
    };
    VulkanContext& context;
    RendererOptions options;
    VkRenderPass compatiblePass = VK_NULL_HANDLE;
    std::unique_ptr<Pipelines> pipelines;
    GpuHeap heap;
    VkMemoryRequirements chunkRequirements{}; // of a buffer with the chunks' usage: memory types, alignment
    std::vector<VkBuffer> blockBuffers;       // per heap block
    /// What one frame in flight owns until its fence signals: its commands, its part of the uniforms,
    /// its staging ring and indirect draws, and the chunk memory freed while it may still draw from it.
    struct FrameSlot {
        VkCommandBuffer cmd = VK_NULL_HANDLE;
        VkFence fence = VK_NULL_HANDLE;
        std::unique_ptr<HostBuffer> staging;
        std::unique_ptr<HostBuffer> drawCommands; // one indirect draw per visible chunk and view
        std::vector<GpuAllocation> freed;        // returned to the heap once the fence signals
        bool submitted = false;                  // commands submitted and not yet waited for
        bool timed = false;                      // those commands hold the frame's timestamps
    };
    std::array<FrameSlot, kFramesInFlight> slots;
    std::size_t current = 0;        // the slot recorded now
    VkDeviceSize awaitingFree = 0;  // bytes of the slots' freed lists
    std::unique_ptr<HostBuffer> uniforms, materialBuffer;
    std::unique_ptr<TextureArray> textures;
    std::string textureKey;               // what the textures were loaded for
    bool texturesFinal = false;           // false: a stand-in while the pictures load
    std::vector<uint32_t> textureLayers;  // per material id: layer + 1, 0 = none
    std::vector<std::string> textureErrors;
    VkDeviceSize uniformStride = 0;
    VkDescriptorPool descriptorPool = VK_NULL_HANDLE;
    VkDescriptorSet descriptorSet = VK_NULL_HANDLE;
    VkQueryPool queries = VK_NULL_HANDLE;  // two timestamps per slot

    std::unordered_map<ChunkId, GpuChunk> chunks;
    /// Chunks to upload, in the order they were first queued (a new version keeps its place).
    struct Queued {
        PackedChunk chunk;
        uint64_t order = 0;
    };
    std::unordered_map<ChunkId, Queued> pending;
    std::map<uint64_t, ChunkId> pendingOrder;
    uint64_t nextOrder = 0;
    std::set<ChunkId> removals;
    int removalsWaited = 0; // frames the removals have waited for uploads
    std::vector<ChunkId> evicted;
    ShadingOptions shading;
    std::optional<BrushOverlay> brush;
    uint64_t frameNumber = 0;
    double lastGpuMs = 0.0; // of the last frame finished
    std::unique_ptr<DepthTileReducer> depthTiles; // made when a view first keeps its depth
    std::shared_ptr<const OccluderDepth> drawnDepth;

    Impl(VulkanContext& c, const RendererOptions& o)
        : context(c), options(o), heap(c, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)
    {
        VkDevice device = c.device();
        compatiblePass = createRenderPass(device, o.colourFormat, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
        pipelines = std::make_unique<Pipelines>(c, compatiblePass, options.cullBackFaces, options.depthOnly);
        {
            VkBufferCreateInfo probe{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
            probe.size = 1 << 16;
            probe.usage = kChunkUsage;
            VkBuffer buffer = VK_NULL_HANDLE;
            check(vkCreateBuffer(device, &probe, nullptr, &buffer), "vkCreateBuffer");
            vkGetBufferMemoryRequirements(device, buffer, &chunkRequirements);
            vkDestroyBuffer(device, buffer, nullptr);
            // Chunks start on a vertex (their indices are offset by whole vertices).
            chunkRequirements.alignment = std::lcm<VkDeviceSize>(chunkRequirements.alignment, sizeof(GpuVertex));
        }
        const VkDeviceSize align = std::max<VkDeviceSize>(c.properties().limits.minUniformBufferOffsetAlignment, 16);
        uniformStride = (sizeof(ViewUniforms) + align - 1) / align * align;
        uniforms = std::make_unique<HostBuffer>(c, uniformStride * kMaxViews * kFramesInFlight, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);

        VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, 1},
                                         {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1},
                                         {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1}};
        VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        poolInfo.maxSets = 1;
        poolInfo.poolSizeCount = 3;
        poolInfo.pPoolSizes = sizes;
        check(vkCreateDescriptorPool(device, &poolInfo, nullptr, &descriptorPool), "vkCreateDescriptorPool");
        VkDescriptorSetLayout layout = pipelines->setLayout();
        VkDescriptorSetAllocateInfo setAlloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        setAlloc.descriptorPool = descriptorPool;
        setAlloc.descriptorSetCount = 1;
        setAlloc.pSetLayouts = &layout;
        check(vkAllocateDescriptorSets(device, &setAlloc, &descriptorSet), "vkAllocateDescriptorSets");
        setMaterials(MaterialTable(), {}, PictureLoading::Wait);

        for (FrameSlot& slot : slots) {
            VkCommandBufferAllocateInfo cmdAlloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
            cmdAlloc.commandPool = c.commandPool();
            cmdAlloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
            cmdAlloc.commandBufferCount = 1;
            check(vkAllocateCommandBuffers(device, &cmdAlloc, &slot.cmd), "vkAllocateCommandBuffers");
            VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
            check(vkCreateFence(device, &fenceInfo, nullptr, &slot.fence), "vkCreateFence");
            slot.staging = std::make_unique<HostBuffer>(c, std::max<uint64_t>(o.stagingBytes, 1 << 20), VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
        }
        if (c.timestampPeriodNs() > 0.0) {
            VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
            q.queryType = VK_QUERY_TYPE_TIMESTAMP;
            q.queryCount = 2 * kFramesInFlight;
            check(vkCreateQueryPool(device, &q, nullptr, &queries), "vkCreateQueryPool");
        }
    }

    ~Impl()
    {
        VkDevice device = context.device();
        vkDeviceWaitIdle(device);
        for (VkBuffer b : blockBuffers) vkDestroyBuffer(device, b, nullptr);
        if (queries) vkDestroyQueryPool(device, queries, nullptr);
        for (FrameSlot& slot : slots) {
            if (slot.fence) vkDestroyFence(device, slot.fence, nullptr);
            if (slot.cmd) vkFreeCommandBuffers(device, context.commandPool(), 1, &slot.cmd);
        }
        if (descriptorPool) vkDestroyDescriptorPool(device, descriptorPool, nullptr);
        depthTiles.reset();
        pipelines.reset();
        if (compatiblePass) vkDestroyRenderPass(device, compatiblePass, nullptr);
    }

    /// The pictures of the key asked for last, read and scaled on a worker (MaterialTextureSet only: the
    /// GPU upload stays on the thread that draws).
    std::future<MaterialTextureSet> pendingTextures;
    std::string pendingKey;

    bool picturesReady() const
    {
        return pendingTextures.valid() && pendingTextures.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
    }

    std::vector<std::string> setMaterials(const MaterialTable& table, const MaterialLook& look, PictureLoading loading)
    {
        // Entry 0 (empty) is never drawn; it gets the default colour so a stray id still shows.
        const std::size_t count = table.size() + 1;
        const VkDeviceSize bytes = count * 2 * 4 * sizeof(float);
        finishAll(); // the frames in flight may still read the table and the textures
        std::vector<VkWriteDescriptorSet> writes;
        const auto write = [&](uint32_t binding, VkDescriptorType type) -> VkWriteDescriptorSet& {
            VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
            w.dstSet = descriptorSet;
            w.dstBinding = binding;
            w.descriptorCount = 1;
            w.descriptorType = type;
            writes.push_back(w);
            return writes.back();
        };
        writes.reserve(3); // the references write() returns stay valid
        VkDescriptorBufferInfo uniformInfo{}, materialInfo{};
        if (!materialBuffer || materialBuffer->size() < bytes) {
            materialBuffer = std::make_unique<HostBuffer>(context, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
            uniformInfo = {uniforms->buffer(), 0, sizeof(ViewUniforms)};
            materialInfo = {materialBuffer->buffer(), 0, VK_WHOLE_SIZE};
            write(0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC).pBufferInfo = &uniformInfo;
            write(1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER).pBufferInfo = &materialInfo;
        }
        // Pictures are read again only when the textures named (or their folder) change.
        std::string key = look.textureFolder;
        for (std::size_t id = 1; id <= table.size(); ++id) key += '\n' + table.at(MaterialId(id)).texture;
        VkDescriptorImageInfo imageInfo{};
        if (!textures || key != textureKey || !texturesFinal) {
            if (!pendingTextures.valid() || pendingKey != key) {
                pendingKey = key;
                pendingTextures = std::async(std::launch::async, [table, folder = look.textureFolder] { return loadMaterialTextures(table, folder); });
            }
            std::optional<MaterialTextureSet> set;
            if (loading == PictureLoading::Wait || picturesReady()) {
                set = pendingTextures.get();
                textureKey = key;
                texturesFinal = true;
            } else if (!textures) {
                set = MaterialTextureSet{}; // the procedural patterns until the pictures come
                texturesFinal = false;
            }
            if (set) {
                textures = std::make_unique<TextureArray>(context, *set);
                textureLayers = std::move(set->layerOfMaterial);
                textureErrors = std::move(set->errors);
                imageInfo = {textures->sampler(), textures->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
                write(2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER).pImageInfo = &imageInfo;
            }
        }
        if (!writes.empty()) vkUpdateDescriptorSets(context.device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
        float* out = reinterpret_cast<float*>(materialBuffer->data());
        for (std::size_t id = 0; id < count; ++id) {
            const Material m = id == 0 ? Material{} : table.at(MaterialId(id));
            std::memcpy(out + id * 8, m.color.data(), 4 * sizeof(float));
            out[id * 8 + 4] = m.toughness;
            out[id * 8 + 5] = float((id * 37) % 101); // procedural pattern seed
            const bool pictured = id < textureLayers.size() && textureLayers[id] > 0;
            // Repetitions per world unit: the procedural grain is fine, a picture covers a tile.
            out[id * 8 + 6] = pictured ? float(1.0 / std::max(look.textureTile, 1e-9)) : 0.35f;
            out[id * 8 + 7] = pictured ? float(textureLayers[id]) : 0.0f; // picture layer + 1, 0 = none
        }
        return textureErrors;
    }

    /// The chunk is gone from the next draws at once; its memory returns to the heap when the frames
    /// that may still draw it are done (those in flight end before the current slot's fence signals).
    void destroyChunk(ChunkId id, FrameStats& stats)
    {
        auto it = chunks.find(id);
        if (it == chunks.end()) return;
        slots[current].freed.push_back(it->second.allocation);
        awaitingFree += it->second.allocation.size;
        chunks.erase(it);
        ++stats.chunksFreed;
    }

    /// The buffer bound to the whole of a heap block, made when the block is first used.
    VkBuffer blockBuffer(uint32_t block)
    {
        while (blockBuffers.size() <= block) {
            const uint32_t b = uint32_t(blockBuffers.size());
            VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
            info.size = heap.blockSize(b);
            info.usage = kChunkUsage;
            VkBuffer buffer = VK_NULL_HANDLE;
            check(vkCreateBuffer(context.device(), &info, nullptr, &buffer), "vkCreateBuffer");
            VkMemoryRequirements req;
            vkGetBufferMemoryRequirements(context.device(), buffer, &req);
            if (req.size > heap.blockSize(b)) {
                vkDestroyBuffer(context.device(), buffer, nullptr);
                throw VulkanError("a mesh block's buffer needs more memory than its block holds");
            }
            check(vkBindBufferMemory(context.device(), buffer, heap.blockMemory(b), 0), "vkBindBufferMemory");
            blockBuffers.push_back(buffer);
        }
        return blockBuffers[block];
    }

    void beginCommands()
    {
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(slots[current].cmd, &begin), "vkBeginCommandBuffer");
    }

    /// Ends and submits the current slot's commands, signalling `signal` when they are done; they draw
    /// (colour output onwards) once `wait` is signalled.
    void submit(const std::vector<VkSemaphore>& signal = {}, const std::vector<VkSemaphore>& wait = {})
    {
        FrameSlot& slot = slots[current];
        check(vkEndCommandBuffer(slot.cmd), "vkEndCommandBuffer");
        VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        const std::vector<VkPipelineStageFlags> stages(wait.size(), VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT);
        submit.waitSemaphoreCount = uint32_t(wait.size());
        submit.pWaitSemaphores = wait.data();
        submit.pWaitDstStageMask = stages.data();
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &slot.cmd;
        submit.signalSemaphoreCount = uint32_t(signal.size());
        submit.pSignalSemaphores = signal.data();
        check(vkResetFences(context.device(), 1, &slot.fence), "vkResetFences");
        check(vkQueueSubmit(context.queue(), 1, &submit, slot.fence), "vkQueueSubmit");
        slot.submitted = true;
    }

    /// Waits for a slot's commands, so that its command buffer, staging ring, uniforms and draw commands
    /// may be used again and the chunk memory freed meanwhile returns to the heap (a fence also covers
    /// every submission before it); takes that frame's GPU time.
    void finishSlot(std::size_t index)
    {
        FrameSlot& slot = slots[index];
        if (!slot.submitted) return;
        check(vkWaitForFences(context.device(), 1, &slot.fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
        check(vkResetCommandBuffer(slot.cmd, 0), "vkResetCommandBuffer");
        slot.submitted = false;
        for (const GpuAllocation& a : slot.freed) {
            awaitingFree -= a.size;
            heap.free(a);
        }
        slot.freed.clear();
        if (depthTiles)
            if (auto tiles = depthTiles->take(index)) drawnDepth = std::move(tiles);
        if (queries && slot.timed) {
            uint64_t ticks[2] = {0, 0};
            if (vkGetQueryPoolResults(context.device(), queries, uint32_t(2 * index), 2, sizeof(ticks), ticks, sizeof(uint64_t),
                                      VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS)
                lastGpuMs = double(ticks[1] - ticks[0]) * context.timestampPeriodNs() * 1e-6;
        }
        slot.timed = false;
    }

    /// The chunks' device memory, less what waits to be freed.
    VkDeviceSize chunkBytes() const { return heap.usedBytes() - awaitingFree; }

    /// Waits for every frame in flight.
    void finishAll()
    {
        for (std::size_t k = 1; k <= slots.size(); ++k) finishSlot((current + k) % slots.size());
    }

    /// Mid-frame, when the staging ring is full: the copies so far are submitted and waited for.
    void submitAndWait()
    {
        submit();
        finishSlot(current);
    }

    void queueChunk(ChunkId id, PackedChunk chunk)
    {
        auto it = pending.find(id);
        if (it != pending.end()) {
            it->second.chunk = std::move(chunk);
            return;
        }
        pending.emplace(id, Queued{std::move(chunk), nextOrder});
        pendingOrder.emplace(nextOrder++, id);
    }

    void unqueueChunk(ChunkId id)
    {
        auto it = pending.find(id);
        if (it == pending.end()) return;
        pendingOrder.erase(it->second.order);
        pending.erase(it);
    }

    /// Records the copies of the queued chunks through the staging ring, oldest first, within the
    /// frame's upload budget (always one chunk at least); when the ring is full the copies so far are
    /// submitted and waited for, and the ring starts over.
    void recordUploads(FrameStats& stats)
    {
        VkDeviceSize ringOffset = 0;
        const VkCommandBuffer cmd = slots[current].cmd; // the same buffer again after a mid-frame submit
        HostBuffer& staging = *slots[current].staging;
        const uint64_t budget = options.uploadBytesPerFrame;
        while (!pendingOrder.empty()) {
            const ChunkId id = pendingOrder.begin()->second;
            const PackedChunk& p = pending.at(id).chunk;
            const VkDeviceSize size = p.bytes.size();
            if (budget > 0 && stats.uploadBytes > 0 && stats.uploadBytes + size > budget) break;
            if (size > staging.size())
                throw std::runtime_error("a mesh chunk of " + std::to_string(size) + " bytes exceeds the staging ring of " +
                                         std::to_string(staging.size()) + " bytes");
            if (ringOffset + size > staging.size()) {
                submitAndWait();
                beginCommands();
                ringOffset = 0;
            }
            if (chunks.count(id)) destroyChunk(id, stats), --stats.chunksFreed; // replaced, not freed
            GpuChunk chunk;
            VkMemoryRequirements req = chunkRequirements;
            req.size = size;
            chunk.allocation = heap.allocate(req);
            std::memcpy(staging.data() + ringOffset, p.bytes.data(), size);
            VkBufferCopy copy{ringOffset, chunk.allocation.offset, size};
            vkCmdCopyBuffer(cmd, staging.buffer(), blockBuffer(chunk.allocation.block), 1, &copy);
            ringOffset = (ringOffset + size + 15) / 16 * 16;
            chunk.firstIndex = uint32_t((chunk.allocation.offset + p.indexOffset) / sizeof(uint32_t));
            chunk.vertexOffset = int32_t(chunk.allocation.offset / sizeof(GpuVertex));
            chunk.indexCount = p.indexCount;
            std::copy(p.lo.begin(), p.lo.end(), chunk.lo);
            std::copy(p.hi.begin(), p.hi.end(), chunk.hi);
            chunk.level = p.level;
            chunks.emplace(id, chunk);
            ++stats.chunksUploaded;
            stats.uploadBytes += size;
            unqueueChunk(id);
        }
        stats.chunksWaitingUpload = pending.size();
        VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_VERTEX_INPUT_BIT, 0, 1, &barrier, 0,
                             nullptr, 0, nullptr);
    }

    void fillUniforms(ViewUniforms& u, const Camera& camera, int viewportWidth, int viewportHeight) const
    {
        const glm::dmat4 vp = viewProjectionMatrix(camera, double(viewportWidth) / double(viewportHeight));
        copyMatrix(u.viewProj, vp);
        copyMatrix(u.invViewProj, glm::inverse(vp));
        for (int i = 0; i < 3; ++i) {
            u.eye[i] = float(camera.eye[std::size_t(i)]);
            u.lightDir[i] = shading.lightDirection[std::size_t(i)];
        }
        // A pixel's size per unit of distance: textures pick their mipmap from it (see mesh.frag).
        u.eye[3] = float((camera.asymmetric() ? camera.fovTangents[2] - camera.fovTangents[3] : 2.0 * camera.tanHalfFovY()) /
                         double(viewportHeight));
        u.lightDir[3] = shading.ambientOcclusion ? 1.0f : 0.0f;
        u.mode[0] = uint32_t(shading.mode);
        u.mode[1] = brush ? (brush->preview ? 1u : 0u) | (brush->highlight ? 2u : 0u) : 0u;
        u.mode[2] = brush ? uint32_t(brush->shape) : 0u;
        u.mode[3] = 0;
        const BrushOverlay b = brush.value_or(BrushOverlay{});
        std::copy(b.worldToLocal.begin(), b.worldToLocal.end(), u.brushWorldToLocal);
        std::copy(b.params.begin(), b.params.end(), u.brushParams);
        u.brushExtra[0] = b.height;
        u.brushExtra[1] = b.distanceScale;
        u.brushExtra[2] = u.brushExtra[3] = 0.0f;
        std::copy(b.worldBoundsMin.begin(), b.worldBoundsMin.end(), u.brushMin);
        std::copy(b.worldBoundsMax.begin(), b.worldBoundsMax.end(), u.brushMax);
        std::copy(b.previewColour.begin(), b.previewColour.end(), u.previewColour);
        std::copy(b.highlightColour.begin(), b.highlightColour.end(), u.highlightColour);
    }

    FrameStats render(const std::vector<RenderView>& views)
    {
        const auto start = Clock::now();
        FrameStats stats;
        if (views.size() > std::size_t(kMaxViews))
            throw std::invalid_argument("a frame draws at most " + std::to_string(kMaxViews) + " views");
        ++frameNumber;
        // Frames run on while later ones are prepared (a target presents later, waiting on its
        // semaphore): this slot's last frame, kFramesInFlight ago, must be done before its resources are
        // used again.
        current = (current + 1) % slots.size();
        const VkCommandBuffer cmd = slots[current].cmd;
        const auto waited = Clock::now();
        finishSlot(current);
        stats.submitWaitMs = msSince(waited);
        beginCommands();
        recordUploads(stats);
        // Removals go with the uploads that usually replace them: while some wait for a later frame, so
        // do the removals (a few frames at most, so that memory is not held for long).
        if (!removals.empty() && (pending.empty() || ++removalsWaited > kRemovalWaitFrames)) {
            for (ChunkId id : removals) destroyChunk(id, stats);
            removals.clear();
            removalsWaited = 0;
        }
        const uint32_t firstQuery = uint32_t(2 * current);
        if (queries) {
            vkCmdResetQueryPool(cmd, queries, firstQuery, 2);
            vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries, firstQuery);
        }

        std::set<int> levels;
        // Room for every chunk in every view (this slot's last frame, waited for, no longer reads it).
        const std::size_t commandsNeeded = std::max<std::size_t>(chunks.size() * views.size(), 1);
        std::unique_ptr<HostBuffer>& drawCommands = slots[current].drawCommands;
        if (!drawCommands || drawCommands->size() < commandsNeeded * sizeof(VkDrawIndexedIndirectCommand))
            drawCommands = std::make_unique<HostBuffer>(context, 2 * commandsNeeded * sizeof(VkDrawIndexedIndirectCommand),
                                                        VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT);
        std::size_t commandsUsed = 0;
        const std::size_t maxDrawsPerCall = std::max<uint32_t>(1, context.properties().limits.maxDrawIndirectCount);
        // Views that share a target are drawn in one render pass, which clears the target once.
        std::vector<RenderTarget*> targets;
        for (const auto& v : views) {
            if (!v.target) throw std::invalid_argument("a view has no render target");
            if (std::find(targets.begin(), targets.end(), v.target) == targets.end()) targets.push_back(v.target);
        }
        for (RenderTarget* target : targets) {
            VkClearValue clears[2]{};
            clears[0].color = {{shading.background[0], shading.background[1], shading.background[2], 1.0f}};
            clears[1].depthStencil = {0.0f, 0}; // reversed depth: 0 is infinitely far
            VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
            begin.renderPass = target->renderPass();
            begin.framebuffer = target->framebuffer();
            begin.renderArea = {{0, 0}, {uint32_t(target->width()), uint32_t(target->height())}};
            begin.clearValueCount = 2;
            begin.pClearValues = clears;
            target->recordBeforePass(cmd);
            vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
            for (std::size_t vi = 0; vi < views.size(); ++vi) {
                const RenderView& v = views[vi];
                if (v.target != target) continue;
                std::array<int, 4> vp = v.viewport;
                if (vp[2] <= 0 || vp[3] <= 0) vp = {0, 0, target->width(), target->height()};
                const std::size_t uniformSlot = current * kMaxViews + vi;
                auto* u = reinterpret_cast<ViewUniforms*>(uniforms->data() + uniformStride * uniformSlot);
                fillUniforms(*u, v.camera, vp[2], vp[3]);
                VkViewport viewport{float(vp[0]), float(vp[1]), float(vp[2]), float(vp[3]), 0.0f, 1.0f};
                VkRect2D scissor{{vp[0], vp[1]}, {uint32_t(vp[2]), uint32_t(vp[3])}};
                vkCmdSetViewport(cmd, 0, 1, &viewport);
                vkCmdSetScissor(cmd, 0, 1, &scissor);
                const uint32_t dynamicOffset = uint32_t(uniformStride * uniformSlot);
                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines->layout(), 0, 1, &descriptorSet, 1,
                                        &dynamicOffset);
                const Frustum frustum = frustumOf(viewProjectionMatrix(v.camera, double(vp[2]) / double(vp[3])));
                std::vector<const GpuChunk*> visible;
                for (auto& [id, c] : chunks) {
                    if (frustum.outside(c.lo, c.hi)) {
                        ++stats.chunksCulled;
                        continue;
                    }
                    c.lastDrawn = frameNumber;
                    visible.push_back(&c);
                    levels.insert(c.level);
                }
                const float noTint[4] = {0, 0, 0, 0};
                const float lineTint[4] = {0.05f, 0.05f, 0.05f, 1.0f};
                // The view's draws, a block's together: one indirect draw per block and pipeline.
                std::stable_sort(visible.begin(), visible.end(),
                                 [](const GpuChunk* a, const GpuChunk* b) { return a->allocation.block < b->allocation.block; });
                auto* commands = reinterpret_cast<VkDrawIndexedIndirectCommand*>(drawCommands->data()) + commandsUsed;
                for (std::size_t i = 0; i < visible.size(); ++i)
                    commands[i] = {visible[i]->indexCount, 1, visible[i]->firstIndex, visible[i]->vertexOffset, 0};
                const std::size_t viewCommands = commandsUsed;
                commandsUsed += visible.size();
                auto drawChunks = [&](VkPipeline pipeline, const float* tint) {
                    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
                    vkCmdPushConstants(cmd, pipelines->layout(), VK_SHADER_STAGE_FRAGMENT_BIT, 0, 16, tint);
                    for (std::size_t first = 0; first < visible.size();) {
                        const uint32_t block = visible[first]->allocation.block;
                        std::size_t last = first;
                        while (last < visible.size() && visible[last]->allocation.block == block) ++last;
                        const VkBuffer buffer = blockBuffers[block];
                        const VkDeviceSize zero = 0;
                        vkCmdBindVertexBuffers(cmd, 0, 1, &buffer, &zero);
                        vkCmdBindIndexBuffer(cmd, buffer, 0, VK_INDEX_TYPE_UINT32);
                        if (context.supportsMultiDrawIndirect()) {
                            for (std::size_t from = first; from < last; from += maxDrawsPerCall) {
                                const uint32_t count = uint32_t(std::min<std::size_t>(last - from, maxDrawsPerCall));
                                vkCmdDrawIndexedIndirect(cmd, drawCommands->buffer(), (viewCommands + from) * sizeof(VkDrawIndexedIndirectCommand),
                                                         count, sizeof(VkDrawIndexedIndirectCommand));
                            }
                        } else {
                            for (std::size_t i = first; i < last; ++i)
                                vkCmdDrawIndexed(cmd, visible[i]->indexCount, 1, visible[i]->firstIndex, visible[i]->vertexOffset, 0);
                        }
                        first = last;
                    }
                };
                drawChunks(pipelines->surface(), noTint);
                if (shading.wireframe && pipelines->wireframe()) drawChunks(pipelines->wireframe(), lineTint);
                for (const GpuChunk* c : visible) stats.triangles += c->indexCount / 3;
                stats.chunksDrawn += visible.size();
                if (brush && brush->preview) {
                    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines->brushPreview());
                    vkCmdPushConstants(cmd, pipelines->layout(), VK_SHADER_STAGE_FRAGMENT_BIT, 0, 16, noTint);
                    vkCmdDraw(cmd, 3, 1, 0, 0);
                }
            }
            target->recordOverlay(cmd);
            vkCmdEndRenderPass(cmd);
            target->recordAfterPass(cmd);
            for (const RenderView& v : views)
                if (v.keepDepth && v.target == target) {
                    if (!depthTiles) depthTiles = std::make_unique<DepthTileReducer>(context, kFramesInFlight);
                    std::array<int, 4> vp = v.viewport;
                    if (vp[2] <= 0 || vp[3] <= 0) vp = {0, 0, target->width(), target->height()};
                    depthTiles->record(cmd, current, *target, vp, v.camera);
                }
        }
        if (queries) vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries, firstQuery + 1);
        stats.cpuMs = msSince(start);
        const auto submittedAt = Clock::now();
        std::vector<VkSemaphore> finished, ready;
        bool readBack = false;
        for (RenderTarget* target : targets) {
            if (const VkSemaphore s = target->finishedSemaphore()) finished.push_back(s);
            if (const VkSemaphore s = target->readySemaphore()) ready.push_back(s);
            readBack = readBack || target->readsBack();
        }
        submit(finished, ready);
        slots[current].timed = queries != VK_NULL_HANDLE;
        // Pixels read back are waited for; a frame presented runs on while the next ones are prepared.
        if (readBack) finishSlot(current);
        stats.submitWaitMs += msSince(submittedAt);
        stats.gpuMs = lastGpuMs;
        enforceBudget(stats);
        stats.gpuMemoryBytes = chunkBytes();
        stats.gpuBytesAwaitingFree = awaitingFree;
        stats.residentChunks = chunks.size();
        stats.levelsShown.assign(levels.begin(), levels.end());
        return stats;
    }

    /// Frees the chunks drawn longest ago (never this frame's) while over the budget.
    void enforceBudget(FrameStats& stats)
    {
        if (chunkBytes() <= options.gpuBudgetBytes) return;
        std::vector<std::pair<uint64_t, ChunkId>> byAge;
        for (const auto& [id, c] : chunks)
            if (c.lastDrawn < frameNumber) byAge.emplace_back(c.lastDrawn, id);
        std::sort(byAge.begin(), byAge.end());
        for (const auto& [age, id] : byAge) {
            if (chunkBytes() <= options.gpuBudgetBytes) break;
            destroyChunk(id, stats);
            evicted.push_back(id);
        }
    }
};

PackedChunk packChunk(const Mesh& mesh, int level, const VertexShading& shading)
{
    PackedChunk p;
    if (mesh.triangles.empty()) return p;
    p.level = level;
    const std::size_t nv = mesh.positions.size();
    std::vector<GpuVertex> vertices(nv);
    for (int a = 0; a < 3; ++a) {
        p.lo[std::size_t(a)] = std::numeric_limits<float>::max();
        p.hi[std::size_t(a)] = std::numeric_limits<float>::lowest();
    }
    const uint32_t levelBits = uint32_t(std::clamp(level, 0, 127)) << 16;
    for (std::size_t i = 0; i < nv; ++i) {
        GpuVertex& v = vertices[i];
        for (int a = 0; a < 3; ++a) {
            v.position[a] = mesh.positions[i][std::size_t(a)];
            p.lo[std::size_t(a)] = std::min(p.lo[std::size_t(a)], v.position[a]);
            p.hi[std::size_t(a)] = std::max(p.hi[std::size_t(a)], v.position[a]);
        }
        const std::array<int16_t, 2> normal = octahedralNormal(i < mesh.normals.size() ? mesh.normals[i] : std::array<float, 3>{});
        v.normal[0] = normal[0];
        v.normal[1] = normal[1];
        const uint32_t material = i < mesh.materials.size() ? mesh.materials[i] : 1u;
        const uint32_t open = shading.occlusion && i < shading.occlusion->size() ? (*shading.occlusion)[i] : 255u;
        const uint32_t maskBit = shading.masked && i < shading.masked->size() && (*shading.masked)[i] ? 1u << 23 : 0u;
        v.packed = material | levelBits | maskBit | (open << 24);
        // Bit 31: the vertex carries a blend (its colour mixes in the other material's by the share).
        v.blend = shading.blend && i < shading.blend->size() ? ((*shading.blend)[i] & 0xffffffu) | (1u << 31) : 0u;
    }
    // The shaders take a triangle's material from its first (provoking) vertex: each triangle starts at
    // a corner of its own material (the meshers' triangleMaterials follow material transitions inside a
    // cell, the vertices' do not), else at a copy of its first corner carrying it.
    std::vector<uint32_t> indices;
    indices.reserve(mesh.triangles.size() * 3);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        std::array<uint32_t, 3> tri = mesh.triangles[t];
        for (const uint32_t k : tri)
            if (k >= nv) throw std::invalid_argument("a mesh triangle names vertex " + std::to_string(k) + " of " + std::to_string(nv));
        if (t < mesh.triangleMaterials.size()) {
            const uint32_t want = mesh.triangleMaterials[t];
            int first = 0;
            while (first < 3 && (vertices[tri[std::size_t(first)]].packed & 0xffffu) != want) ++first;
            if (first < 3) {
                std::rotate(tri.begin(), tri.begin() + first, tri.end()); // keeps the winding
            } else {
                GpuVertex copy = vertices[tri[0]];
                copy.packed = (copy.packed & ~0xffffu) | want;
                tri[0] = uint32_t(vertices.size());
                vertices.push_back(copy);
            }
        }
        indices.insert(indices.end(), tri.begin(), tri.end());
    }
    const VkDeviceSize vertexBytes = vertices.size() * sizeof(GpuVertex);
    p.indexOffset = vertexBytes;
    p.indexCount = uint32_t(indices.size());
    p.bytes.resize(vertexBytes + indices.size() * sizeof(uint32_t));
    std::memcpy(p.bytes.data(), vertices.data(), vertexBytes);
    std::memcpy(p.bytes.data() + vertexBytes, indices.data(), indices.size() * sizeof(uint32_t));
    return p;
}

PackedChunk packChunk(const QuantizedMesh& mesh, int level, const VertexShading& shading)
{
    return packChunk(mesh.decoded(), level, shading);
}

Renderer::Renderer(VulkanContext& context, const RendererOptions& options)
    : impl_(std::make_unique<Impl>(context, options))
{
}

Renderer::~Renderer() = default;

std::vector<std::string> Renderer::setMaterials(const MaterialTable& materials, const MaterialLook& look, PictureLoading loading)
{
    return impl_->setMaterials(materials, look, loading);
}

bool Renderer::picturesReady() const { return impl_->picturesReady(); }

void Renderer::setChunk(ChunkId id, const Mesh& mesh, int level, const VertexShading& shading)
{
    setPackedChunk(id, packChunk(mesh, level, shading));
}

void Renderer::setPackedChunk(ChunkId id, PackedChunk chunk)
{
    impl_->removals.erase(id);
    if (chunk.bytes.empty()) {
        removeChunk(id);
        return;
    }
    impl_->queueChunk(id, std::move(chunk));
}

void Renderer::removeChunk(ChunkId id)
{
    impl_->unqueueChunk(id);
    if (impl_->chunks.count(id)) impl_->removals.insert(id);
}

void Renderer::setUploadBytesPerFrame(uint64_t bytes) { impl_->options.uploadBytesPerFrame = bytes; }

std::size_t Renderer::uploadsWaiting() const { return impl_->pending.size(); }

bool Renderer::hasChunk(ChunkId id) const { return impl_->chunks.count(id) || impl_->pending.count(id); }
std::size_t Renderer::chunkCount() const { return impl_->chunks.size(); }
void Renderer::setShading(const ShadingOptions& shading) { impl_->shading = shading; }
const ShadingOptions& Renderer::shading() const { return impl_->shading; }
void Renderer::setBrush(const std::optional<BrushOverlay>& brush) { impl_->brush = brush; }
FrameStats Renderer::render(const std::vector<RenderView>& views) { return impl_->render(views); }

std::shared_ptr<const OccluderDepth> Renderer::drawnDepth() const { return impl_->drawnDepth; }

std::vector<ChunkId> Renderer::takeEvicted()
{
    std::vector<ChunkId> out;
    out.swap(impl_->evicted);
    return out;
}

uint64_t Renderer::gpuMemoryBytes() const { return impl_->chunkBytes(); }
double Renderer::pipelineBuildMs() const { return impl_->pipelines->buildMs(); }
const VulkanContext& Renderer::context() const { return impl_->context; }

} // namespace vdbclay::render
