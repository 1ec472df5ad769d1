// A nearest-neighbour index over descriptor vectors (FLANN): built from the vectors, saved to a file and
// loaded again with the same vectors (FLANN saves the index, not the data). It gives a shortlist; the
// library ranks the shortlist exactly. Kept to one translation unit: FLANN's headers are heavy.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace vdbclay::query {

class DescriptorIndex {
public:
    /// An index over `vectors` (all of one length), L1 distances: a k-means tree for many, a linear scan
    /// for few. Throws std::invalid_argument for vectors of different lengths.
    explicit DescriptorIndex(std::vector<std::vector<float>> vectors);
    /// The index saved at `path` for these same vectors; throws std::runtime_error when it cannot be read.
    DescriptorIndex(std::vector<std::vector<float>> vectors, const std::string& path);
    ~DescriptorIndex();
    DescriptorIndex(const DescriptorIndex&) = delete;
    DescriptorIndex& operator=(const DescriptorIndex&) = delete;

    /// Writes the index (not the vectors) to `path`.
    void save(const std::string& path) const;
    /// The positions of the `k` nearest vectors (fewer when there are fewer), nearest first.
    std::vector<std::size_t> nearest(const std::vector<float>& query, std::size_t k) const;
    std::size_t size() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace vdbclay::query
