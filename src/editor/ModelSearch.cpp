#include "editor/ModelSearch.h"

#include "editor/EditingSession.h"
#include "editor/SceneFileActions.h"
#include "query/LightField.h"
#include "query/SceneModels.h"
#include "render/ImageFile.h"
#include "render/ModelViews.h"
#include "render/VulkanContext.h"

#include <functional>
#include <mutex>
#include <thread>

namespace vdbclay {

struct ModelSearch::Impl {
    std::thread job;
    mutable std::mutex mutex;
    bool running = false;
    std::optional<ModelSearchOutcome> outcome;
    // The light field's renderer, made by the first search that asks for it and used by the jobs alone
    // (one at a time); a device of its own, so that the window's queue is never shared.
    std::unique_ptr<render::VulkanContext> context;
    std::unique_ptr<render::ModelViews> views;
    std::string viewsUnavailable; // why there is none, once it failed

    /// The silhouettes' renderer, or null (and `why`) where there is no usable device.
    render::ModelViews* silhouettes(std::string& why)
    {
        if (!views && viewsUnavailable.empty()) {
            try {
                context = std::make_unique<render::VulkanContext>();
                views = std::make_unique<render::ModelViews>(*context);
            } catch (const std::exception& e) {
                views.reset();
                context.reset();
                viewsUnavailable = e.what();
            }
        }
        why = viewsUnavailable;
        return views.get();
    }

    bool start(std::function<ModelSearchOutcome()> work)
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (running) return false;
        if (job.joinable()) job.join(); // finished: its outcome is kept
        running = true;
        job = std::thread([this, work = std::move(work)] {
            ModelSearchOutcome done;
            try {
                done = work();
            } catch (const std::exception& e) {
                done.error = e.what();
            }
            std::lock_guard<std::mutex> lock(mutex);
            outcome = std::move(done);
            running = false;
        });
        return true;
    }
};

TriangleSoup shownSculpture(const EditingSession& session, const std::optional<WorldBounds>& box)
{
    const StreamingScene& scene = session.scene();
    Mesh all;
    for (const BrickKey& key : scene.shownBricks()) {
        const std::shared_ptr<const StreamingScene::BrickMesh> brick = scene.meshBrick(key);
        if (!brick) continue; // evicted since the frame showed it
        const Mesh m = brick->mesh.decoded();
        const uint32_t offset = uint32_t(all.positions.size());
        all.positions.insert(all.positions.end(), m.positions.begin(), m.positions.end());
        for (std::size_t t = 0; t < m.triangles.size(); ++t) {
            const auto& tri = m.triangles[t];
            if (box) {
                std::array<double, 3> c{0, 0, 0};
                for (uint32_t v : tri)
                    for (int a = 0; a < 3; ++a) c[std::size_t(a)] += m.positions[v][std::size_t(a)] / 3.0;
                bool inside = true;
                for (int a = 0; a < 3; ++a) inside = inside && c[std::size_t(a)] >= box->min[a] && c[std::size_t(a)] <= box->max[a];
                if (!inside) continue;
            }
            all.triangles.push_back({tri[0] + offset, tri[1] + offset, tri[2] + offset});
            all.triangleMaterials.push_back(t < m.triangleMaterials.size() ? m.triangleMaterials[t] : MaterialId(1));
        }
    }
    return query::smoothedSculpture(query::soupOfMesh(all, scene.materials()));
}

ModelSearch::ModelSearch() : impl_(std::make_unique<Impl>()) {}

ModelSearch::~ModelSearch() { wait(); }

bool ModelSearch::search(const EditingSession& session, const ModelSearchRequest& request)
{
    return impl_->start([&session, request, impl = impl_.get()] {
        const query::ModelLibrary library(request.library, false);
        const TriangleSoup sculpture = shownSculpture(session, request.box);
        if (sculpture.triangles.empty())
            throw std::runtime_error(request.box ? "the box holds none of the sculpture the view shows" : "the view shows no sculpture to search with");
        query::ModelDescription description;
        query::describeShape(sculpture, description);
        ModelSearchOutcome outcome;
        if (request.lightField) {
            std::string why;
            if (render::ModelViews* views = impl->silhouettes(why)) description.lightField = query::lightFieldDescriptor(*views, sculpture);
            else outcome.note = "ranked without the light field (" + why + ")";
        }
        outcome.results.emplace();
        for (const query::QueryHit& hit : library.query(description, request.k, request.descriptor, request.metric)) {
            ModelSearchResult r{hit.model, hit.distance, {}};
            const std::string png = library.thumbnail(hit.model.id);
            if (!png.empty()) r.thumbnail = render::decodeImage(png);
            outcome.results->push_back(std::move(r));
        }
        return outcome;
    });
}

bool ModelSearch::place(const EditingSession& session, const std::string& modelPath, const std::array<double, 3>& centre, double radius,
                        const std::string& material)
{
    return impl_->start([&session, modelPath, centre, radius, material] {
        ModelSearchOutcome outcome;
        outcome.placement = placeModelIntoScene(session, modelPath, centre, radius, material);
        return outcome;
    });
}

bool ModelSearch::busy() const
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->running;
}

std::optional<ModelSearchOutcome> ModelSearch::take()
{
    std::lock_guard<std::mutex> lock(impl_->mutex);
    std::optional<ModelSearchOutcome> out = std::move(impl_->outcome);
    impl_->outcome.reset();
    return out;
}

void ModelSearch::wait()
{
    std::thread finishing;
    {
        std::lock_guard<std::mutex> lock(impl_->mutex);
        finishing = std::move(impl_->job);
    }
    if (finishing.joinable()) finishing.join();
}

} // namespace vdbclay
