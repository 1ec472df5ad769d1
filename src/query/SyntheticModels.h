// A labeled set of synthetic models for retrieval's tests and benchmark: parametric families built from
// primitives (boxes, ellipsoids, cylinders, cones, tori, and tables of a top and four legs) with random
// proportions, orientations, scales, positions, tessellations and colours. Each model is a plain
// description (SyntheticShape) turned into a mesh, so a test can change one property of a model alone.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace vdbclay::query {

struct SyntheticShape {
    std::string family;                       // one of syntheticFamilies()
    std::array<double, 3> proportions{1, 1, 1}; // the family's shape parameters, around 1
    int tessellation = 16;                    // segments along a primitive's curve or side
    std::array<double, 4> rotation{0, 0, 0, 1}; // unit quaternion x, y, z, w
    double scale = 1.0;
    std::array<double, 3> position{0, 0, 0};
    std::array<float, 3> colour{0.8f, 0.8f, 0.8f};
};

const std::vector<std::string>& syntheticFamilies();
/// A shape of `family` with random proportions, pose, tessellation and colour.
SyntheticShape randomShape(const std::string& family, std::mt19937_64& random);
/// Its triangles (one material, the shape's colour). Throws std::invalid_argument for an unknown family.
TriangleSoup buildShape(const SyntheticShape& shape);

struct LabeledModel {
    std::string label; // the family
    std::string name;  // family-index
    SyntheticShape shape;
};
/// `perFamily` random shapes of every family, seeded.
std::vector<LabeledModel> syntheticSet(int perFamily, uint64_t seed);

/// Writes a mesh as an ASCII PLY with per-vertex colours (what `import` and `index add` read back as
/// colour materials). Throws std::runtime_error when the file cannot be written.
void writeColouredPly(const TriangleSoup& mesh, const std::string& path);

} // namespace vdbclay::query
