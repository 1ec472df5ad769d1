// A library of 3D models to search by shape: an SQLite database of model records (name, source path,
// class, triangle count, mean colour) with their descriptor vectors, so reopening never recomputes, and
// beside it FLANN's index per descriptor (LIBRARY.d2.flann), rebuilt from the stored vectors when it is
// missing or no longer matches the records. Each model is added in a transaction of its own: a killed
// `index add` leaves the library as it was or with whole models added.
#pragma once

#include "query/ShapeDistribution.h"

#include <array>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay::query {

/// A file that is not a library, a damaged one, or one written by a newer VDBClay; what() is one line.
class LibraryError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The descriptors a library holds (more come with the light field and ClusterD2+Color).
enum class Descriptor { D2 };
const char* descriptorName(Descriptor d);
enum class Metric { ChiSquare, JensenShannon };
const char* metricName(Metric m);

/// A model's descriptor as the library stores and compares it (smoothed, summing to 1).
Histogram describeModel(const TriangleSoup& mesh, Descriptor descriptor);

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

    /// Adds a model with its descriptor (describeModel). Throws LibraryError when the name is taken.
    ModelRecord add(const std::string& name, const std::string& sourcePath, const std::string& label, const TriangleSoup& mesh,
                    const Histogram& d2);
    /// Removes the model of that name; false when there is none.
    bool remove(const std::string& name);
    bool contains(const std::string& name) const;
    std::vector<ModelRecord> models() const;

    /// The `k` models nearest `query` (a descriptor as describeModel makes it): FLANN's shortlist ranked
    /// exactly with `metric`, nearest first.
    std::vector<QueryHit> query(const Histogram& query, std::size_t k, Metric metric = Metric::ChiSquare) const;
    const std::string& path() const { return path_; }
    /// The FLANN index file of a descriptor.
    std::string indexPath(Descriptor descriptor) const;

private:
    struct Impl;
    std::string path_;
    std::unique_ptr<Impl> impl_;
};

} // namespace vdbclay::query
