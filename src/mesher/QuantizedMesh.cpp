#include "mesher/QuantizedMesh.h"

#include "vdb_hermite/Quantize.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace vdbclay {
namespace {

void mixBytes(uint64_t& h, const void* data, std::size_t bytes)
{
    const auto* p = static_cast<const uint8_t*>(data);
    for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
    h = (h ^ bytes) * 1099511628211ull; // array boundaries count: [a][bc] differs from [ab][c]
}

template <typename T> void mixArray(uint64_t& h, const std::vector<T>& v) { mixBytes(h, v.data(), v.size() * sizeof(T)); }

template <typename T> uint64_t capacityBytes(const std::vector<T>& v) { return v.capacity() * sizeof(T); }

} // namespace

QuantizedMesh::QuantizedMesh(const Mesh& mesh, double step) : step_(step)
{
    if (!(step > 0.0) || !std::isfinite(step)) throw std::invalid_argument("QuantizedMesh: the lattice step must be positive");
    const std::size_t n = mesh.positions.size(), triangles = mesh.triangles.size();
    if (!mesh.normals.empty() && mesh.normals.size() != n) throw std::invalid_argument("QuantizedMesh: one normal per vertex");
    if (!mesh.materials.empty() && mesh.materials.size() != n) throw std::invalid_argument("QuantizedMesh: one material per vertex");
    if (!mesh.triangleMaterials.empty() && mesh.triangleMaterials.size() != triangles)
        throw std::invalid_argument("QuantizedMesh: one material per triangle");

    // Lattice coordinates of every position; the lattice is the world's, so a shared position rounds alike.
    std::vector<int64_t> lattice(n * 3);
    std::array<int64_t, 3> lo{0, 0, 0}, hi{0, 0, 0};
    constexpr double kLimit = 4.0e18;
    for (std::size_t v = 0; v < n; ++v)
        for (std::size_t a = 0; a < 3; ++a) {
            const double steps = std::nearbyint(double(mesh.positions[v][a]) / step);
            if (!(std::fabs(steps) < kLimit)) throw std::invalid_argument("QuantizedMesh: a position is not finite or lies too far out");
            const int64_t c = int64_t(steps);
            lattice[v * 3 + a] = c;
            lo[a] = v == 0 ? c : std::min(lo[a], c);
            hi[a] = v == 0 ? c : std::max(hi[a], c);
        }
    base_ = lo;
    int64_t span = 0;
    for (std::size_t a = 0; a < 3; ++a) span = std::max(span, hi[a] - lo[a]);
    if (span > int64_t(std::numeric_limits<uint32_t>::max())) throw std::invalid_argument("QuantizedMesh: the mesh spans too many lattice steps");
    if (span <= int64_t(std::numeric_limits<uint16_t>::max())) {
        narrowPositions_.resize(n * 3);
        for (std::size_t i = 0; i < n * 3; ++i) narrowPositions_[i] = uint16_t(lattice[i] - base_[i % 3]);
    } else {
        widePositions_.resize(n * 3);
        for (std::size_t i = 0; i < n * 3; ++i) widePositions_[i] = uint32_t(lattice[i] - base_[i % 3]);
    }

    normals_.reserve(mesh.normals.size());
    for (const auto& n : mesh.normals) normals_.push_back(quantizeNormal({double(n[0]), double(n[1]), double(n[2])}));
    materials_ = mesh.materials;

    const bool narrow = n <= std::size_t(std::numeric_limits<uint16_t>::max()) + 1;
    if (narrow) narrowCorners_.reserve(triangles * 3);
    else wideCorners_.reserve(triangles * 3);
    for (const auto& t : mesh.triangles)
        for (const uint32_t corner : t) {
            if (corner >= n)
                throw std::invalid_argument("QuantizedMesh: a triangle names vertex " + std::to_string(corner) + " of " + std::to_string(n));
            if (narrow) narrowCorners_.push_back(uint16_t(corner));
            else wideCorners_.push_back(corner);
        }
    triangleMaterials_ = mesh.triangleMaterials;
}

std::array<float, 3> QuantizedMesh::position(std::size_t v) const
{
    std::array<float, 3> p{};
    for (std::size_t a = 0; a < 3; ++a) {
        const int64_t offset = narrowPositions_.empty() ? int64_t(widePositions_[v * 3 + a]) : int64_t(narrowPositions_[v * 3 + a]);
        p[a] = float(double(base_[a] + offset) * step_);
    }
    return p;
}

std::array<float, 3> QuantizedMesh::normal(std::size_t v) const { return dequantizeNormal(normals_[v][0], normals_[v][1]); }

std::array<uint32_t, 3> QuantizedMesh::triangle(std::size_t t) const
{
    if (wideCorners_.empty())
        return {narrowCorners_[t * 3], narrowCorners_[t * 3 + 1], narrowCorners_[t * 3 + 2]};
    return {wideCorners_[t * 3], wideCorners_[t * 3 + 1], wideCorners_[t * 3 + 2]};
}

Mesh QuantizedMesh::decoded() const
{
    Mesh m;
    m.positions.resize(vertexCount());
    for (std::size_t v = 0; v < m.positions.size(); ++v) m.positions[v] = position(v);
    m.normals.resize(normals_.size());
    for (std::size_t v = 0; v < normals_.size(); ++v) m.normals[v] = normal(v);
    m.materials = materials_;
    m.triangles.resize(triangleCount());
    for (std::size_t t = 0; t < m.triangles.size(); ++t) m.triangles[t] = triangle(t);
    m.triangleMaterials = triangleMaterials_;
    return m;
}

uint64_t QuantizedMesh::memoryBytes() const
{
    return sizeof(QuantizedMesh) + capacityBytes(narrowPositions_) + capacityBytes(widePositions_) + capacityBytes(normals_) +
           capacityBytes(materials_) + capacityBytes(narrowCorners_) + capacityBytes(wideCorners_) + capacityBytes(triangleMaterials_);
}

uint64_t QuantizedMesh::contentHash() const
{
    uint64_t h = 1469598103934665603ull;
    mixBytes(h, &step_, sizeof(step_));
    mixBytes(h, base_.data(), sizeof(base_));
    mixArray(h, narrowPositions_);
    mixArray(h, widePositions_);
    mixArray(h, normals_);
    mixArray(h, materials_);
    mixArray(h, narrowCorners_);
    mixArray(h, wideCorners_);
    mixArray(h, triangleMaterials_);
    return h;
}

bool QuantizedMesh::operator==(const QuantizedMesh& o) const
{
    return step_ == o.step_ && base_ == o.base_ && narrowPositions_ == o.narrowPositions_ && widePositions_ == o.widePositions_ && normals_ == o.normals_ &&
           materials_ == o.materials_ && narrowCorners_ == o.narrowCorners_ && wideCorners_ == o.wideCorners_ &&
           triangleMaterials_ == o.triangleMaterials_;
}

} // namespace vdbclay
