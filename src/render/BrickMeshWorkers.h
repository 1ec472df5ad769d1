// A streaming scene's bricks meshed on worker threads, most needed first, and packed for the GPU there:
// the frame thread only asks for bricks and takes what is finished, so it never waits for a mesh.
#pragma once

#include "render/Renderer.h"
#include "scene/StreamingScene.h"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vdbclay::render {

class BrickMeshWorkers {
public:
    struct Finished {
        BrickKey key;
        uint64_t version = 0; // StreamingScene::brickVersion the mesh was made at
        uint64_t content = 0; // StreamingScene::brickContent the mesh was made at
        uint64_t hash = 0;    // StreamingScene::BrickMesh::hash
        PackedChunk packed;
    };

    /// `threads` workers meshing `scene`'s bricks with StreamingScene::meshBrick (which keeps the meshes
    /// under the scene's budget). The scene outlives the workers.
    BrickMeshWorkers(const StreamingScene& scene, int threads);
    /// Finishes the bricks in hand; the rest asked for is dropped.
    ~BrickMeshWorkers();
    BrickMeshWorkers(const BrickMeshWorkers&) = delete;
    BrickMeshWorkers& operator=(const BrickMeshWorkers&) = delete;

    /// Replaces what is asked for, most needed first. A brick a worker has in hand is not asked for
    /// again: if its mesh comes out older than the scene by then, the next request asks anew.
    void request(const std::vector<BrickKey>& bricks);
    /// Puts bricks ahead of what is asked for (those queued or in hand stay where they are): from any
    /// thread, as an edit lands, so that its bricks are meshed before the next frame asks.
    void requestFirst(const std::vector<BrickKey>& bricks);
    /// The meshes finished since the last call, in the order they were finished (bricks no longer
    /// resident give none).
    std::vector<Finished> takeFinished();
    /// Bricks asked for and not finished yet (queued or in hand).
    std::size_t pending() const;
    /// Waits until nothing asked for is left.
    void waitIdle() const;
    /// What meshing threw since the last call, one message per brick.
    std::vector<std::string> takeFailures();

private:
    void work();

    const StreamingScene& scene_;
    mutable std::mutex mutex_;
    mutable std::condition_variable wake_, idle_;
    std::deque<BrickKey> queue_;
    std::vector<BrickKey> inHand_;
    std::vector<Finished> finished_;
    std::vector<std::string> failures_;
    bool stopping_ = false;
    std::vector<std::thread> threads_;
};

} // namespace vdbclay::render
