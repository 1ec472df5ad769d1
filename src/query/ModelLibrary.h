// A library of 3D models to search by shape: an SQLite database of model records (name, source path,
// class, triangle count, mean colour, thumbnail) with their descriptor vectors, so reopening never
// recomputes, and beside it FLANN's index per descriptor (LIBRARY.d2.flann, ...) and the light fields'
// records (LIBRARY.lightfield.records), made again from the stored vectors when missing or no longer
// matching the records. Each model is added in a transaction of
// its own: a killed `index add` leaves the library as it was or with whole models added.
#pragma once

#include "query/LightField.h"
#include "query/ShapeDistribution.h"

#include <array>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay::render {
class ModelViews;
}

namespace vdbclay::query {

/// A file that is not a library, a damaged one, or one written by a newer VDBClay; what() is one line.
class LibraryError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// How models are compared: one descriptor's distance, or all of them combined (not stored: ranked
/// from the others).
enum class Descriptor { ClusterD2, D2, LightField, Combined };
const char* descriptorName(Descriptor d);
/// "clusterd2", "d2", "lightfield" or "combined"; nullopt for anything else.
std::optional<Descriptor> parseDescriptor(const std::string& name);
/// The descriptors a library stores.
constexpr std::array<Descriptor, 3> kStoredDescriptors{Descriptor::ClusterD2, Descriptor::D2, Descriptor::LightField};
/// How histograms (D2, ClusterD2) are compared; the light field is always L1.
enum class Metric { ChiSquare, JensenShannon };
const char* metricName(Metric m);

/// A model as the library stores and compares it.
struct ModelDescription {
    Histogram d2, clusterD2;     // smoothed, summing to 1
    std::vector<float> lightField; // empty when it was not drawn (no renderer)
    std::string thumbnailPng;    // empty when none was drawn
};

/// The descriptors computed on the CPU (D2, ClusterD2+Color): safe on any thread.
void describeShape(const TriangleSoup& mesh, ModelDescription& description);
/// What the renderer draws (the light field, a thumbnail of `thumbnailSize` pixels): on the thread that
/// owns `views`.
void describeViews(render::ModelViews& views, const TriangleSoup& mesh, ModelDescription& description, int thumbnailSize = 128);

struct ModelRecord {
    int64_t id = 0;
    std::string name;  // unique in the library
    std::string path;  // where it was read from
    std::string label; // its class, if known (the folder it was found in)
    uint64_t triangles = 0;
    std::array<float, 3> colour{0, 0, 0}; // area-weighted mean
};

struct QueryHit {
    ModelRecord model;
    double distance = 0.0;
};

class ModelLibrary {
public:
    /// Opens the library at `path`; `create` makes it when the file does not exist. Throws LibraryError.
    ModelLibrary(const std::string& path, bool create);
    ~ModelLibrary();
    ModelLibrary(const ModelLibrary&) = delete;
    ModelLibrary& operator=(const ModelLibrary&) = delete;

    /// Adds a model with its descriptors (describeShape, describeViews). Throws LibraryError when the name is taken or
    /// the description lacks D2 or ClusterD2.
    ModelRecord add(const std::string& name, const std::string& sourcePath, const std::string& label, const TriangleSoup& mesh,
                    const ModelDescription& description);
    /// A model for addAll: what add() takes (pointers, not copies: a batch may be large).
    struct NewModel {
        std::string name, sourcePath, label;
        const TriangleSoup* mesh = nullptr;
        const ModelDescription* description = nullptr;
    };
    /// Adds models as add() does, in one transaction: all of them, or none when one is refused (a name
    /// taken, in the library or earlier in the batch). Far faster than one add() each for many models.
    std::vector<ModelRecord> addAll(const std::vector<NewModel>& models);
    /// Removes the model of that name; false when there is none.
    bool remove(const std::string& name);
    bool contains(const std::string& name) const;
    std::vector<ModelRecord> models() const;
    /// How many models hold the descriptor.
    std::size_t count(Descriptor descriptor) const;
    /// The model's thumbnail (PNG bytes); empty when it has none.
    std::string thumbnail(int64_t model) const;

    /// The `k` models nearest `query` (described as the models are): FLANN's shortlist ranked
    /// exactly, nearest first. Combined ranks by the mean of each stored descriptor's distance over its
    /// typical distance in this library. Throws LibraryError when the query lacks the descriptor.
    std::vector<QueryHit> query(const ModelDescription& query, std::size_t k, Descriptor descriptor = Descriptor::ClusterD2,
                                Metric metric = Metric::ChiSquare) const;
    const std::string& path() const { return path_; }
    /// The FLANN index file of a stored descriptor.
    std::string indexPath(Descriptor descriptor) const;
    /// The file of the light fields' records (LightFieldRecords.h), beside the FLANN indexes.
    std::string lightFieldRecordsPath() const { return path_ + ".lightfield.records"; }

private:
    struct Impl;
    std::string path_;
    std::unique_ptr<Impl> impl_;
};

} // namespace vdbclay::query
