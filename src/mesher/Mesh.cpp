#include "mesher/Mesh.h"

#include <vector>

namespace vdbclay {

uint64_t edgeKey(int32_t i, int32_t j, int32_t k, int axis)
{
    // 20 bits per coordinate (offset by 2^19) and 2 bits of axis: unique for |coordinates| < 524288.
    constexpr int64_t kBias = int64_t(1) << 19;
    constexpr uint64_t kMask = (uint64_t(1) << 20) - 1;
    const uint64_t x = uint64_t(int64_t(i) + kBias) & kMask;
    const uint64_t y = uint64_t(int64_t(j) + kBias) & kMask;
    const uint64_t z = uint64_t(int64_t(k) + kBias) & kMask;
    return (x << 42) | (y << 22) | (z << 2) | uint64_t(axis);
}

bool identical(const MeshChunk& a, const MeshChunk& b)
{
    const Mesh &m = a.mesh, &n = b.mesh;
    return a.leafOrigin == b.leafOrigin && a.vertexKeys == b.vertexKeys && m.positions == n.positions &&
           m.normals == n.normals && m.materials == n.materials && m.triangles == n.triangles &&
           m.triangleMaterials == n.triangleMaterials;
}

uint64_t faceKey(int32_t i, int32_t j, int32_t k, int axis, int segment, int slot)
{
    // Bit 63 marks a face key (edge keys use bits 0-61): axis in bits 61-62, segment in 60, slot in
    // 57-59, and 19 bits per coordinate.
    constexpr int64_t kBias = int64_t(1) << 18;
    constexpr uint64_t kMask = (uint64_t(1) << 19) - 1;
    const uint64_t x = uint64_t(int64_t(i) + kBias) & kMask;
    const uint64_t y = uint64_t(int64_t(j) + kBias) & kMask;
    const uint64_t z = uint64_t(int64_t(k) + kBias) & kMask;
    return (uint64_t(1) << 63) | (uint64_t(axis & 3) << 61) | (uint64_t(segment & 1) << 60) |
           (uint64_t(slot & 7) << 57) | (x << 38) | (y << 19) | z;
}

namespace {

/// Vertex keys to welded indices: open addressing with linear probing, which avoids a node
/// allocation per vertex. kUnsharedVertex (never inserted) marks empty slots.
class KeyIndex {
public:
    explicit KeyIndex(std::size_t count)
    {
        std::size_t capacity = 16;
        while (capacity < 2 * count) capacity *= 2;
        keys_.assign(capacity, kUnsharedVertex);
        values_.resize(capacity);
        mask_ = capacity - 1;
    }

    /// The index stored for `key`, storing `fresh` first if there is none; `inserted` tells which.
    uint32_t findOrInsert(uint64_t key, uint32_t fresh, bool& inserted)
    {
        std::size_t slot = std::size_t((key * 0x9E3779B97F4A7C15ull) >> 17) & mask_;
        while (true) {
            if (keys_[slot] == key) {
                inserted = false;
                return values_[slot];
            }
            if (keys_[slot] == kUnsharedVertex) {
                keys_[slot] = key;
                values_[slot] = fresh;
                inserted = true;
                return fresh;
            }
            slot = (slot + 1) & mask_;
        }
    }

private:
    std::vector<uint64_t> keys_;
    std::vector<uint32_t> values_;
    std::size_t mask_ = 0;
};

} // namespace

Mesh weldChunks(const std::vector<MeshChunk>& chunks)
{
    std::vector<const MeshChunk*> pointers;
    pointers.reserve(chunks.size());
    for (const MeshChunk& c : chunks) pointers.push_back(&c);
    return weldChunks(pointers);
}

Mesh weldChunks(const std::vector<const MeshChunk*>& chunks)
{
    Mesh out;
    std::size_t vertices = 0, triangles = 0;
    for (const MeshChunk* c : chunks) {
        vertices += c->mesh.vertexCount();
        triangles += c->mesh.triangleCount();
    }
    out.triangles.reserve(triangles);
    out.triangleMaterials.reserve(triangles);
    out.positions.reserve(vertices);
    out.normals.reserve(vertices);
    out.materials.reserve(vertices);
    KeyIndex index(vertices);
    std::vector<uint32_t> remap;
    for (const MeshChunk* chunk : chunks) {
        const MeshChunk& c = *chunk;
        remap.resize(c.mesh.vertexCount());
        for (std::size_t v = 0; v < c.mesh.vertexCount(); ++v) {
            const uint32_t next = uint32_t(out.positions.size());
            bool fresh = true;
            if (c.vertexKeys[v] != kUnsharedVertex) {
                remap[v] = index.findOrInsert(c.vertexKeys[v], next, fresh);
            } else {
                remap[v] = next;
            }
            if (fresh) {
                out.positions.push_back(c.mesh.positions[v]);
                out.normals.push_back(c.mesh.normals[v]);
                out.materials.push_back(c.mesh.materials[v]);
            }
        }
        for (const auto& t : c.mesh.triangles) out.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
        out.triangleMaterials.insert(out.triangleMaterials.end(), c.mesh.triangleMaterials.begin(),
                                     c.mesh.triangleMaterials.end());
    }
    return out;
}

} // namespace vdbclay
