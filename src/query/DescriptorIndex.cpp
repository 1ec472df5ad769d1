#include "query/DescriptorIndex.h"

#include <flann/flann.hpp>

#include <stdexcept>

namespace vdbclay::query {

namespace {

/// Beyond this many vectors the k-means tree pays (a linear scan of 100k 64-bin vectors takes milliseconds).
constexpr std::size_t kTreeFrom = 2000;

} // namespace

struct DescriptorIndex::Impl {
    std::vector<float> data; // row-major: FLANN's matrix points into it
    std::size_t rows = 0, columns = 0;
    std::unique_ptr<flann::Index<flann::L1<float>>> index;

    void take(std::vector<std::vector<float>> vectors)
    {
        rows = vectors.size();
        columns = rows ? vectors.front().size() : 0;
        data.reserve(rows * columns);
        for (const auto& v : vectors) {
            if (v.size() != columns) throw std::invalid_argument("descriptor vectors of different lengths");
            data.insert(data.end(), v.begin(), v.end());
        }
    }
    flann::Matrix<float> matrix() { return flann::Matrix<float>(data.data(), rows, columns); }
};

DescriptorIndex::DescriptorIndex(std::vector<std::vector<float>> vectors) : impl_(std::make_unique<Impl>())
{
    impl_->take(std::move(vectors));
    if (impl_->rows == 0) return;
    if (impl_->rows >= kTreeFrom)
        impl_->index = std::make_unique<flann::Index<flann::L1<float>>>(impl_->matrix(), flann::KMeansIndexParams(32, 11, flann::FLANN_CENTERS_KMEANSPP));
    else
        impl_->index = std::make_unique<flann::Index<flann::L1<float>>>(impl_->matrix(), flann::LinearIndexParams());
    impl_->index->buildIndex();
}

DescriptorIndex::DescriptorIndex(std::vector<std::vector<float>> vectors, const std::string& path) : impl_(std::make_unique<Impl>())
{
    impl_->take(std::move(vectors));
    if (impl_->rows == 0) return;
    try {
        impl_->index = std::make_unique<flann::Index<flann::L1<float>>>(impl_->matrix(), flann::SavedIndexParams(path));
    } catch (const std::exception& e) {
        throw std::runtime_error("cannot read the index " + path + ": " + e.what());
    }
    if (impl_->index->size() != impl_->rows) throw std::runtime_error("the index " + path + " does not match the library's models");
}

DescriptorIndex::~DescriptorIndex() = default;

void DescriptorIndex::save(const std::string& path) const
{
    if (impl_->index) impl_->index->save(path);
}

std::size_t DescriptorIndex::size() const { return impl_->rows; }

std::vector<std::size_t> DescriptorIndex::nearest(const std::vector<float>& query, std::size_t k) const
{
    if (!impl_->index || k == 0) return {};
    if (query.size() != impl_->columns) throw std::invalid_argument("a query descriptor of another length than the library's");
    k = std::min(k, impl_->rows);
    std::vector<float> q = query;
    flann::Matrix<float> queryMatrix(q.data(), 1, q.size());
    std::vector<std::vector<size_t>> indices;
    std::vector<std::vector<float>> distances;
    flann::SearchParams params(128);
    impl_->index->knnSearch(queryMatrix, indices, distances, k, params);
    std::vector<std::size_t> out;
    if (!indices.empty())
        for (size_t i : indices.front()) out.push_back(std::size_t(i));
    return out;
}

} // namespace vdbclay::query
