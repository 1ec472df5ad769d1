#include "render/SceneChunks.h"

#include "mesher/VertexMask.h"
#include "mesher/VertexMaterialBlend.h"
#include "mesher/VertexOcclusion.h"
#include "render/BrickMeshWorkers.h"
#include "render/Framing.h"
#include "scene/SceneStore.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <stdexcept>
#include <limits>
#include <iterator>
#include <set>

namespace vdbclay::render {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

uint64_t packCoordinates(const std::array<int32_t, 3>& c)
{
    // 20 bits per coordinate (offset), enough for +-2^19 leaves.
    uint64_t out = 0;
    for (int a = 0; a < 3; ++a) out = (out << 20) | (uint64_t(int64_t(c[std::size_t(a)]) + (1 << 19)) & 0xFFFFF);
    return out;
}
} // namespace

ChunkId leafChunkId(const std::array<int32_t, 3>& o)
{
    return packCoordinates({o[0] >> 3, o[1] >> 3, o[2] >> 3});
}

std::optional<ChunkId> StreamedSceneChunks::chunkOf(const BrickKey& key) const
{
    const auto it = uploaded_.find(key);
    if (it == uploaded_.end()) return std::nullopt;
    return it->second.id;
}

std::optional<uint64_t> StreamedSceneChunks::versionOf(const BrickKey& key) const
{
    const auto it = uploaded_.find(key);
    if (it == uploaded_.end()) return std::nullopt;
    return it->second.version;
}

std::optional<uint64_t> StreamedSceneChunks::contentOf(const BrickKey& key) const
{
    const auto it = uploaded_.find(key);
    if (it == uploaded_.end()) return std::nullopt;
    return it->second.content;
}

std::vector<BrickKey> StreamedSceneChunks::drawnBricks() const
{
    std::vector<BrickKey> out;
    for (const auto& [key, uploaded] : uploaded_) out.push_back(key);
    return out;
}

VolumeUpload uploadVolume(Renderer& renderer, const Volume& volume, const MeshOptions& options, const MaterialLook& look)
{
    const auto start = Clock::now();
    VolumeUpload out;
    out.lo.fill(std::numeric_limits<double>::max());
    out.hi.fill(std::numeric_limits<double>::lowest());
    out.warnings = renderer.setMaterials(volume.materials(), look);
    for (const MeshChunk& chunk : meshVolumeChunks(volume, options)) {
        if (chunk.mesh.triangles.empty()) continue;
        appendOutline(chunk.mesh.positions, out.outline);
        for (const auto& p : chunk.mesh.positions)
            for (std::size_t a = 0; a < 3; ++a) {
                out.lo[a] = std::min(out.lo[a], double(p[a]));
                out.hi[a] = std::max(out.hi[a], double(p[a]));
            }
        const std::vector<uint8_t> occlusion = vertexOcclusion(volume, chunk.mesh);
        const std::vector<uint8_t> masked = maskedVertices(volume.mask(), chunk.mesh, volume.voxelSize());
        const std::vector<uint32_t> blend = vertexMaterialBlend(volume, chunk.mesh);
        renderer.setChunk(leafChunkId(chunk.leafOrigin), chunk.mesh, 0, {&occlusion, &masked, &blend});
        ++out.chunks;
        out.triangles += chunk.mesh.triangles.size();
    }
    if (out.chunks == 0) out.lo = out.hi = {0.0, 0.0, 0.0};
    out.meshSeconds = secondsSince(start);
    return out;
}

StreamedSceneChunks::StreamedSceneChunks(Meshes meshes) : meshes_(meshes)
{
    if (meshes == Meshes::OnWorkers) throw std::invalid_argument("chunks meshed on workers are made for a scene");
}

StreamedSceneChunks::StreamedSceneChunks(const StreamingScene& scene, int meshThreads)
    : meshes_(Meshes::OnWorkers), scene_(&scene), workers_(std::make_unique<BrickMeshWorkers>(scene, meshThreads))
{
    // An edit's bricks are meshed as it lands, not when the next frame finds their versions changed: a
    // stamp that lands after a frame's sync is drawn a frame sooner.
    BrickMeshWorkers* workers = workers_.get();
    editListener_ = scene.addEditListener([workers](const std::vector<BrickKey>& changed) { workers->requestFirst(changed); });
}

StreamedSceneChunks::~StreamedSceneChunks()
{
    if (scene_ && editListener_) scene_->removeEditListener(editListener_);
}

void StreamedSceneChunks::waitForMeshes() const
{
    if (workers_) workers_->waitIdle();
}

std::size_t StreamedSceneChunks::meshesInProgress() const { return workers_ ? workers_->pending() : 0; }

std::vector<std::string> StreamedSceneChunks::takeMeshFailures() { return workers_ ? workers_->takeFailures() : std::vector<std::string>{}; }

StreamedSceneChunks::SyncReport StreamedSceneChunks::sync(const StreamingScene& scene, Renderer& renderer, double budgetSeconds)
{
    if (meshes_ == Meshes::OnWorkers && &scene != scene_) throw std::logic_error("chunks meshed on workers synced with another scene");
    const auto start = Clock::now();
    SyncReport report;
    const std::vector<ChunkId> evicted = renderer.takeEvicted();
    const std::set<ChunkId> evictedSet(evicted.begin(), evicted.end());
    for (auto it = uploaded_.begin(); it != uploaded_.end();)
        it = evictedSet.count(it->second.id) ? uploaded_.erase(it) : std::next(it);
    const std::vector<BrickKey> shown = scene.shownBricks();
    const std::set<BrickKey> shownSet(shown.begin(), shown.end());
    report.shown = shown.size();
    // A mesh equal to the one drawn is not uploaded again, only marked as of its version.
    const auto uploadChanged = [&](const BrickKey& key, uint64_t version, uint64_t content, uint64_t hash, const std::function<PackedChunk()>& pack) {
        ++report.meshed;
        const auto it = uploaded_.find(key);
        if (it != uploaded_.end() && it->second.meshHash == hash) {
            it->second.version = version;
            it->second.content = content;
            return;
        }
        const ChunkId id = it != uploaded_.end() ? it->second.id : nextId_++;
        renderer.setPackedChunk(id, pack());
        uploaded_[key] = {id, version, content, hash};
        ++report.uploaded;
    };
    if (workers_)
        for (BrickMeshWorkers::Finished& f : workers_->takeFinished())
            if (shownSet.count(f.key)) uploadChanged(f.key, f.version, f.content, f.hash, [&] { return std::move(f.packed); });
    // What needs a mesh: edited bricks (drawn with their old mesh meanwhile) first, then new ones.
    const std::vector<uint64_t> versions = scene.brickVersions(shown);
    std::vector<BrickKey> edited, fresh;
    for (std::size_t i = 0; i < shown.size(); ++i) {
        const auto it = uploaded_.find(shown[i]);
        if (it == uploaded_.end()) fresh.push_back(shown[i]);
        else if (it->second.version != versions[i]) edited.push_back(shown[i]);
    }
    std::vector<BrickKey> waiting;
    if (workers_) {
        waiting = edited;
        waiting.insert(waiting.end(), fresh.begin(), fresh.end());
        workers_->request(waiting);
    } else {
        for (const auto* list : {&edited, &fresh})
            for (const BrickKey& key : *list) {
                if (report.meshed > 0 && secondsSince(start) >= budgetSeconds) {
                    waiting.push_back(key);
                    continue;
                }
                const std::shared_ptr<const StreamingScene::BrickMesh> m =
                    meshes_ == Meshes::KeptByScene ? scene.meshBrick(key) : scene.meshBrickAfresh(key);
                if (m)
                    uploadChanged(key, m->version, m->content, m->hash,
                                  [&] { return packChunk(m->mesh, key.level, {&m->occlusion, &m->masked, &m->blend}); });
            }
    }
    report.waiting = waiting.size();
    // Bricks no longer shown go, unless a shown brick they overlap has no mesh yet.
    std::vector<BrickKey> unmeshed;
    for (const BrickKey& key : waiting)
        if (!uploaded_.count(key)) unmeshed.push_back(key);
    for (auto it = uploaded_.begin(); it != uploaded_.end();) {
        const bool standsIn = std::any_of(unmeshed.begin(), unmeshed.end(), [&](const BrickKey& k) { return bricksOverlap(k, it->first); });
        if (shownSet.count(it->first) || standsIn) {
            ++it;
            continue;
        }
        renderer.removeChunk(it->second.id);
        it = uploaded_.erase(it);
        ++report.removed;
    }
    report.meshSeconds = secondsSince(start);
    return report;
}

} // namespace vdbclay::render
