#include "mesher/Mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <vector>

namespace vdbclay {

uint64_t Mesh::memoryBytes() const
{
    return sizeof(Mesh) + positions.capacity() * sizeof(positions[0]) + normals.capacity() * sizeof(normals[0]) +
           materials.capacity() * sizeof(materials[0]) + triangles.capacity() * sizeof(triangles[0]) +
           triangleMaterials.capacity() * sizeof(triangleMaterials[0]);
}

void appendMesh(Mesh& mesh, const Mesh& part)
{
    const uint32_t base = uint32_t(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
    mesh.normals.insert(mesh.normals.end(), part.normals.begin(), part.normals.end());
    mesh.materials.insert(mesh.materials.end(), part.materials.begin(), part.materials.end());
    for (const auto& t : part.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    mesh.triangleMaterials.insert(mesh.triangleMaterials.end(), part.triangleMaterials.begin(), part.triangleMaterials.end());
}

uint64_t contentHash(const Mesh& m)
{
    uint64_t h = 1469598103934665603ull;
    const auto mix = [&](const void* data, std::size_t bytes) {
        const auto* p = static_cast<const uint8_t*>(data);
        for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
        h = (h ^ bytes) * 1099511628211ull; // array boundaries count: [a][bc] differs from [ab][c]
    };
    mix(m.positions.data(), m.positions.size() * sizeof(m.positions[0]));
    mix(m.normals.data(), m.normals.size() * sizeof(m.normals[0]));
    mix(m.materials.data(), m.materials.size() * sizeof(m.materials[0]));
    mix(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
    mix(m.triangleMaterials.data(), m.triangleMaterials.size() * sizeof(m.triangleMaterials[0]));
    return h;
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
    const KeyCoordinateLayout& l = kFaceKeyLayout;
    return (uint64_t(1) << 63) | (uint64_t(axis & 3) << 61) | (uint64_t(segment & 1) << 60) |
           (uint64_t(slot & 7) << 57) | l.encode(i, 0) | l.encode(j, 1) | l.encode(k, 2);
}

namespace {

/// Whether a vertex key can occur only in the chunk of the leaf at `origin`: a crossing on a voxel edge
/// or a point on a cell face that lies inside the leaf is met only by cells the leaf owns (every cell
/// touching it has its minimum corner in the leaf; wide cells never leave their leaf).
bool onlyInLeaf(uint64_t key, const std::array<int32_t, 3>& origin)
{
    if (key == kUnsharedVertex) return true;
    const bool face = key >> 63;
    const int axis = face ? int((key >> 61) & 3) : int(key & 3);
    const KeyCoordinateLayout& layout = face ? kFaceKeyLayout : kEdgeKeyLayout;
    for (int a = 0; a < 3; ++a) {
        const int64_t local = layout.decode(key, a) - origin[a];
        // An edge's cells reach one voxel below it across the edge; a face's cells one voxel below it
        // along its normal.
        const int64_t lowest = (a == axis) == face ? 1 : 0;
        if (local < lowest || local > 7) return false;
    }
    return true;
}

/// Keys of the vertices that several chunks may hold, to the first vertex holding each: open
/// addressing with linear probing, no allocation per key. kUnsharedVertex marks empty slots.
class KeyIndex {
public:
    explicit KeyIndex(std::size_t count)
    {
        std::size_t capacity = 16;
        while (capacity < 2 * count) capacity *= 2;
        keys_.assign(capacity, kUnsharedVertex);
        holders_.resize(capacity);
        mask_ = capacity - 1;
    }

    /// The first holder of `key`, which becomes `holder` if there is none.
    uint32_t findOrInsert(uint64_t key, uint32_t holder)
    {
        std::size_t slot = std::size_t((key * 0x9E3779B97F4A7C15ull) >> 17) & mask_;
        while (true) {
            if (keys_[slot] == key) return holders_[slot];
            if (keys_[slot] == kUnsharedVertex) {
                keys_[slot] = key;
                holders_[slot] = holder;
                return holder;
            }
            slot = (slot + 1) & mask_;
        }
    }

private:
    std::vector<uint64_t> keys_;
    std::vector<uint32_t> holders_;
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

Mesh weldChunks(const std::vector<const MeshChunk*>& chunks) { return weldChunks(chunks, {}, nullptr); }

Mesh weldChunks(const std::vector<const MeshChunk*>& chunks, const std::vector<const std::vector<uint32_t>*>& values,
                std::vector<uint32_t>* welded)
{
    if (welded) {
        if (values.size() != chunks.size()) throw std::invalid_argument("weldChunks: one value array per chunk");
        for (std::size_t c = 0; c < chunks.size(); ++c)
            if (values[c]->size() != chunks[c]->mesh.vertexCount()) throw std::invalid_argument("weldChunks: one value per vertex");
    }
    // The welded mesh is the chunks' vertices in order, each shared key at its first holder, then their
    // triangles in order. Built in parallel: only keys on a leaf's border can be shared, and those are
    // matched in shards by key, each shard walking the chunks in order. Vertices are numbered as in the
    // chunks' concatenation ("global" below).
    constexpr std::size_t kShards = 16;
    auto shardOf = [](uint64_t key) { return std::size_t((key * 0x9E3779B97F4A7C15ull) >> 60); };
    const std::size_t n = chunks.size();
    std::vector<std::size_t> vertexBase(n + 1, 0), triangleBase(n + 1, 0);
    for (std::size_t c = 0; c < n; ++c) {
        vertexBase[c + 1] = vertexBase[c] + chunks[c]->mesh.vertexCount();
        triangleBase[c + 1] = triangleBase[c] + chunks[c]->mesh.triangleCount();
    }
    if (vertexBase[n] >= std::numeric_limits<uint32_t>::max()) throw std::length_error("too many vertices to weld");
    // first[g]: the global index of the first vertex holding g's key (g itself for an own vertex).
    std::vector<uint32_t> first(vertexBase[n]);
    // Each chunk's border vertices (global indices) in its own range, grouped by shard.
    std::vector<uint32_t> border(vertexBase[n]);
    std::vector<std::array<uint32_t, kShards + 1>> shardStart(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8), [&](const auto& range) {
        std::vector<uint8_t> shardOfVertex;
        for (std::size_t c = range.begin(); c != range.end(); ++c) {
            const MeshChunk& chunk = *chunks[c];
            const uint32_t base = uint32_t(vertexBase[c]), count = uint32_t(chunk.mesh.vertexCount());
            shardOfVertex.resize(count);
            std::array<uint32_t, kShards + 1>& start = shardStart[c];
            start.fill(0);
            for (uint32_t v = 0; v < count; ++v) {
                first[base + v] = base + v;
                const uint64_t key = chunk.vertexKeys[v];
                const bool shared = !onlyInLeaf(key, chunk.leafOrigin);
                shardOfVertex[v] = shared ? uint8_t(shardOf(key)) : uint8_t(kShards);
                if (shared) ++start[shardOfVertex[v] + 1];
            }
            for (std::size_t s = 0; s < kShards; ++s) start[s + 1] += start[s];
            std::array<uint32_t, kShards> fill;
            std::copy_n(start.begin(), kShards, fill.begin());
            for (uint32_t v = 0; v < count; ++v)
                if (shardOfVertex[v] < kShards) border[base + fill[shardOfVertex[v]]++] = base + v;
        }
    });
    tbb::parallel_for(std::size_t(0), kShards, [&](std::size_t shard) {
        std::size_t count = 0;
        for (std::size_t c = 0; c < n; ++c) count += shardStart[c][shard + 1] - shardStart[c][shard];
        KeyIndex index(count);
        for (std::size_t c = 0; c < n; ++c) {
            const uint32_t* const held = border.data() + vertexBase[c];
            const std::vector<uint64_t>& keys = chunks[c]->vertexKeys;
            for (uint32_t i = shardStart[c][shard]; i < shardStart[c][shard + 1]; ++i) {
                const uint32_t g = held[i];
                first[g] = index.findOrInsert(keys[g - vertexBase[c]], g);
            }
        }
    });
    // Own vertices are numbered in order; `output` maps a global own vertex to the welded mesh.
    std::vector<std::size_t> outputBase(n + 1, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8), [&](const auto& range) {
        for (std::size_t c = range.begin(); c != range.end(); ++c) {
            std::size_t own = 0;
            for (std::size_t g = vertexBase[c]; g < vertexBase[c + 1]; ++g) own += first[g] == g;
            outputBase[c + 1] = own;
        }
    });
    for (std::size_t c = 0; c < n; ++c) outputBase[c + 1] += outputBase[c];
    Mesh out;
    out.positions.resize(outputBase[n]);
    out.normals.resize(outputBase[n]);
    out.materials.resize(outputBase[n]);
    out.triangles.resize(triangleBase[n]);
    out.triangleMaterials.resize(triangleBase[n]);
    if (welded) welded->resize(outputBase[n]);
    std::vector<uint32_t>& output = border; // its border lists are no longer needed
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8), [&](const auto& range) {
        for (std::size_t c = range.begin(); c != range.end(); ++c) {
            const Mesh& m = chunks[c]->mesh;
            std::size_t next = outputBase[c];
            for (std::size_t v = 0, g = vertexBase[c]; v < m.vertexCount(); ++v, ++g) {
                if (first[g] != g) continue;
                output[g] = uint32_t(next);
                out.positions[next] = m.positions[v];
                out.normals[next] = m.normals[v];
                out.materials[next] = m.materials[v];
                if (welded) (*welded)[next] = (*values[c])[v];
                ++next;
            }
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8), [&](const auto& range) {
        for (std::size_t c = range.begin(); c != range.end(); ++c) {
            const Mesh& m = chunks[c]->mesh;
            const std::size_t base = vertexBase[c];
            std::array<uint32_t, 3>* to = out.triangles.data() + triangleBase[c];
            for (const auto& t : m.triangles)
                *to++ = {output[first[base + t[0]]], output[first[base + t[1]]], output[first[base + t[2]]]};
            std::copy(m.triangleMaterials.begin(), m.triangleMaterials.end(),
                      out.triangleMaterials.begin() + std::ptrdiff_t(triangleBase[c]));
        }
    });
    return out;
}

} // namespace vdbclay
