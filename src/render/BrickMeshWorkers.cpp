#include "render/BrickMeshWorkers.h"

#include <algorithm>
#include <optional>
#include <utility>

namespace vdbclay::render {

BrickMeshWorkers::BrickMeshWorkers(const StreamingScene& scene, int threads) : scene_(scene)
{
    for (int i = 0; i < std::max(1, threads); ++i) threads_.emplace_back([this] { work(); });
}

BrickMeshWorkers::~BrickMeshWorkers()
{
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
        queue_.clear();
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
}

void BrickMeshWorkers::request(const std::vector<BrickKey>& bricks)
{
    {
        std::lock_guard<std::mutex> lock(mutex_);
        queue_.clear();
        for (const BrickKey& key : bricks)
            if (std::find(inHand_.begin(), inHand_.end(), key) == inHand_.end()) queue_.push_back(key);
    }
    wake_.notify_all();
    if (bricks.empty()) idle_.notify_all();
}

void BrickMeshWorkers::requestFirst(const std::vector<BrickKey>& bricks)
{
    {
        std::lock_guard<std::mutex> lock(mutex_);
        for (auto key = bricks.rbegin(); key != bricks.rend(); ++key)
            if (std::find(inHand_.begin(), inHand_.end(), *key) == inHand_.end() && std::find(queue_.begin(), queue_.end(), *key) == queue_.end())
                queue_.push_front(*key);
    }
    wake_.notify_all();
}

std::vector<BrickMeshWorkers::Finished> BrickMeshWorkers::takeFinished()
{
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(finished_, {});
}

std::size_t BrickMeshWorkers::pending() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.size() + inHand_.size();
}

void BrickMeshWorkers::waitIdle() const
{
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [&] { return queue_.empty() && inHand_.empty(); });
}

std::vector<std::string> BrickMeshWorkers::takeFailures()
{
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(failures_, {});
}

void BrickMeshWorkers::work()
{
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
        if (stopping_) return;
        const BrickKey key = queue_.front();
        queue_.pop_front();
        inHand_.push_back(key);
        lock.unlock();
        std::optional<Finished> done;
        std::string failure;
        try {
            if (const std::shared_ptr<const StreamingScene::BrickMesh> mesh = scene_.meshBrick(key))
                done = Finished{key, mesh->version, mesh->content, mesh->hash, packChunk(mesh->mesh, key.level, {&mesh->occlusion, &mesh->masked, &mesh->blend})};
        } catch (const std::exception& e) {
            failure = "meshing brick " + std::to_string(key.level) + ":" + std::to_string(key.brick[0]) + "," +
                      std::to_string(key.brick[1]) + "," + std::to_string(key.brick[2]) + " failed: " + e.what();
        } catch (...) {
            failure = "meshing a brick failed";
        }
        lock.lock();
        inHand_.erase(std::find(inHand_.begin(), inHand_.end(), key));
        if (done) finished_.push_back(std::move(*done));
        if (!failure.empty()) failures_.push_back(std::move(failure));
        if (queue_.empty() && inHand_.empty()) idle_.notify_all();
    }
}

} // namespace vdbclay::render
