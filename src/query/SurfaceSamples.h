// Points spread uniformly by area over a mesh's surface (seeded, so a descriptor is the same every run),
// with the colour of the triangle each lies on: what the shape descriptors are built from.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay::query {

struct SurfaceSamples {
    std::vector<std::array<double, 3>> points;
    std::vector<std::array<float, 3>> colours; // RGB 0..1, per point
    std::vector<uint32_t> triangles;                  // the triangle each point lies on
    std::vector<std::array<double, 3>> barycentric; // its weights of that triangle's corners
    double area = 0.0;                           // of the mesh
};

/// `count` points uniform by area (a triangle by its area, then a point uniform in it). Throws
/// std::invalid_argument for a mesh without area.
SurfaceSamples sampleSurface(const TriangleSoup& mesh, std::size_t count, uint64_t seed);

/// The surface's colour averaged by area (what a library lists for a model); grey without materials.
std::array<float, 3> meanColour(const TriangleSoup& mesh);

} // namespace vdbclay::query
