// The editor's search of a model library (src/query) with the sculpture, and the placing of a found
// model at the brush: both run on a thread of their own, so the frame that asks never waits; the frame
// polls for the outcome. The sculpture is what the view shows (each shown brick's mesh at its level),
// whole or within a box; it is described as the command line describes a query (ClusterD2+Color and D2
// on the CPU, and where asked the light field, its silhouettes drawn by a renderer the search makes on
// its own thread and device, on its first such search).
#pragma once

#include "query/ModelLibrary.h"
#include "render/OffscreenTarget.h"
#include "sculpt/Brush.h"

#include <nlohmann/json.hpp>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

class EditingSession;

struct ModelSearchRequest {
    std::string library;
    std::optional<WorldBounds> box; // absent: the whole sculpture as shown
    query::Descriptor descriptor = query::Descriptor::Combined;
    query::Metric metric = query::Metric::ChiSquare;
    std::size_t k = 8;
    /// Describe the sculpture's light field too (combined then ranks with it, as the command line
    /// does). Without a usable Vulkan device the search goes on without it and says so in its note.
    bool lightField = false;
};

struct ModelSearchResult {
    query::ModelRecord model;
    double distance = 0.0;
    render::Image thumbnail; // empty when the library holds none
};

/// What a finished job left: results, an op placing a model, or why it failed (one line).
struct ModelSearchOutcome {
    std::optional<std::vector<ModelSearchResult>> results;
    std::optional<nlohmann::json> placement;
    std::string error;
    std::string note; // what the search did without (the light field, and why)
};

class ModelSearch {
public:
    ModelSearch();
    /// Waits for a job under way (a search takes a fraction of a second).
    ~ModelSearch();
    ModelSearch(const ModelSearch&) = delete;
    ModelSearch& operator=(const ModelSearch&) = delete;

    /// Starts a search; false (nothing started) while a job runs. `session` must outlive the job: its
    /// scene is read from the job's thread (shown bricks' meshes, safe beside the frame and the editor).
    bool search(const EditingSession& session, const ModelSearchRequest& request);
    /// Starts placing the model file at `centre`, scaled to `radius` (placeModelIntoScene); false while
    /// a job runs. Apply the outcome's op as a Command::Kind::ApplyOp: one undoable edit.
    bool place(const EditingSession& session, const std::string& modelPath, const std::array<double, 3>& centre, double radius,
               const std::string& material);
    bool busy() const;
    /// The outcome of the job that finished since the last call, once.
    std::optional<ModelSearchOutcome> take();
    /// Waits for the job under way (tests, replays).
    void wait();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// The sculpture as the view shows it (each shown brick's mesh), triangles with their centroid in `box`
/// when one is given, as a soup with the materials' colours, the lattice's facets smoothed away
/// (query::smoothedSculpture).
TriangleSoup shownSculpture(const EditingSession& session, const std::optional<WorldBounds>& box);

} // namespace vdbclay
