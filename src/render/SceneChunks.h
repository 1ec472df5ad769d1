// What the renderer draws of a scene: a whole volume as one chunk per leaf, or a streaming scene's
// shown bricks, each meshed at its level and uploaded when it is new or its content changed.
#pragma once

#include "mesher/Mesher.h"
#include "render/Renderer.h"
#include "scene/StreamingScene.h"

#include <cstdint>
#include <limits>
#include <map>
#include <memory>

namespace vdbclay::render {

class BrickMeshWorkers;

/// The chunk id of a leaf of a whole volume (leaves within +-2^22 voxels of the origin).
ChunkId leafChunkId(const std::array<int32_t, 3>& leafOrigin);

struct VolumeUpload {
    std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0}; // the meshes' bounds, world units
    std::vector<std::array<float, 3>> outline;       // appendOutline of each mesh: enough to frame them
    uint64_t chunks = 0;
    uint64_t triangles = 0;
    double meshSeconds = 0.0;
    std::vector<std::string> warnings; // material textures that could not be read
};
/// Gives the renderer the volume's materials, meshes `volume` (per leaf, with per-vertex occlusion) and
/// queues every chunk.
VolumeUpload uploadVolume(Renderer& renderer, const Volume& volume, const MeshOptions& options, const MaterialLook& look = {});

/// Keeps the renderer's chunks equal to a streaming scene's shown bricks.
class StreamedSceneChunks {
public:
    /// Where the meshes live: kept by the scene under its budget (a view that draws every frame), or made
    /// apart and dropped once uploaded, so that drawing changes nothing the scene reports (its resident
    /// bytes, what its budget lets it refine: pictures of a flight that is being measured). Both are
    /// made within sync(); OnWorkers (the constructor taking the scene) has them made, kept by the scene,
    /// on worker threads, and sync() only takes those finished.
    enum class Meshes { KeptByScene, Apart, OnWorkers };
    /// KeptByScene or Apart (OnWorkers needs the scene: the constructor below).
    explicit StreamedSceneChunks(Meshes meshes = Meshes::KeptByScene);
    /// Meshes made on `meshThreads` workers (BrickMeshWorkers) for `scene`, the only scene synced; the
    /// scene outlives this.
    StreamedSceneChunks(const StreamingScene& scene, int meshThreads);
    ~StreamedSceneChunks();
    StreamedSceneChunks(const StreamedSceneChunks&) = delete;
    StreamedSceneChunks& operator=(const StreamedSceneChunks&) = delete;

    struct SyncReport {
        uint64_t meshed = 0;   // bricks whose mesh was taken again (their content or their neighbourhood changed)
        uint64_t uploaded = 0; // of those, the ones whose mesh changed: queued for upload
        uint64_t removed = 0;  // chunks of bricks no longer shown
        uint64_t shown = 0;
        uint64_t waiting = 0;  // shown bricks left for a later call: new or changed, not meshed within the budget
        double meshSeconds = 0.0;
    };
    /// After scene.frame(): takes the meshes of the shown bricks that are new or whose version changed
    /// (StreamingScene::meshBrick makes them), uploads the meshes that changed, drops the bricks not shown.
    /// Within `budgetSeconds` of meshing (at least one brick a call): edited bricks first, then new ones,
    /// in the order the scene shows them; the rest wait for later calls. OnWorkers: uploads what the
    /// workers finished and asks them for the rest, in the same order, meshing nothing itself (the
    /// budget does not apply). Meanwhile a brick keeps its old mesh, and the meshes of bricks no longer
    /// shown stay while a shown brick they overlap has none yet (a parent stands in for its children,
    /// children for their parent), so the view never opens a hole.
    SyncReport sync(const StreamingScene& scene, Renderer& renderer, double budgetSeconds = std::numeric_limits<double>::infinity());
    /// OnWorkers: waits until the workers have finished what the last sync asked for (0 otherwise).
    void waitForMeshes() const;
    /// OnWorkers: bricks asked of the workers and not finished yet; what meshing threw since the last call.
    std::size_t meshesInProgress() const;
    std::vector<std::string> takeMeshFailures();

    /// The chunk a shown brick is drawn as, if it has one.
    std::optional<ChunkId> chunkOf(const BrickKey& key) const;
    /// The brick version (StreamingScene::brickVersion) its drawn mesh was made at, if it has one.
    std::optional<uint64_t> versionOf(const BrickKey& key) const;
    /// The brick's content (StreamingScene::brickContent) its drawn mesh was made from, if it has one.
    std::optional<uint64_t> contentOf(const BrickKey& key) const;
    /// The bricks drawn: those shown that have a mesh, and those standing in for shown ones still without.
    std::vector<BrickKey> drawnBricks() const;

private:
    struct Uploaded {
        ChunkId id;
        uint64_t version;  // StreamingScene::brickVersion the chunk was made at
        uint64_t content;  // StreamingScene::brickContent it was made from
        uint64_t meshHash; // of its mesh: a brick meshed again to the same mesh is not uploaded again
    };
    Meshes meshes_;
    const StreamingScene* scene_ = nullptr; // OnWorkers: the scene the workers mesh
    std::unique_ptr<BrickMeshWorkers> workers_;
    uint64_t editListener_ = 0; // OnWorkers: StreamingScene::addEditListener's id
    std::map<BrickKey, Uploaded> uploaded_;
    ChunkId nextId_ = ChunkId(1) << 62; // apart from leaf ids
};

} // namespace vdbclay::render
