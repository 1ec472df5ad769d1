// A mesh as a streaming scene keeps it resident: positions on a lattice shared by every brick and level,
// stored relative to the mesh's lowest lattice corner, octahedral normals, and 16-bit indices where the
// vertices allow. About half the bytes of a Mesh; a position two meshes share decodes alike in both.
#pragma once

#include "mesher/Mesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay {

class QuantizedMesh {
public:
    QuantizedMesh() = default;
    /// `mesh` with each position rounded to the nearest multiple of `step` (world units, > 0) on each
    /// axis. The lattice is the same whatever the mesh: a position two meshes share decodes to the same
    /// floats in both. Normals and materials, when given, need one per vertex; every triangle's corners
    /// must name vertices of the mesh (std::invalid_argument otherwise).
    QuantizedMesh(const Mesh& mesh, double step);

    std::size_t vertexCount() const { return (narrowPositions_.size() + widePositions_.size()) / 3; }
    std::size_t triangleCount() const { return (narrowCorners_.size() + wideCorners_.size()) / 3; }
    bool hasNormals() const { return !normals_.empty(); }
    bool hasMaterials() const { return !materials_.empty(); }
    double step() const { return step_; }

    /// Within step / 2 of the position given on each axis (plus float rounding).
    std::array<float, 3> position(std::size_t v) const;
    /// Unit length, within 1/1782 on each axis of the direction given (quantizeNormal's bound).
    std::array<float, 3> normal(std::size_t v) const;
    MaterialId material(std::size_t v) const { return materials_[v]; }
    std::array<uint32_t, 3> triangle(std::size_t t) const;
    MaterialId triangleMaterial(std::size_t t) const { return triangleMaterials_[t]; }
    bool hasTriangleMaterials() const { return !triangleMaterials_.empty(); }

    /// The mesh with every value decoded (what position(), normal(), ... give).
    Mesh decoded() const;
    /// Bytes its arrays hold (capacity), for memory budgets.
    uint64_t memoryBytes() const;
    /// A hash of everything it holds: equal quantized meshes hash alike.
    uint64_t contentHash() const;

    bool operator==(const QuantizedMesh& other) const;
    bool operator!=(const QuantizedMesh& other) const { return !(*this == other); }

private:
    double step_ = 1.0;
    std::array<int64_t, 3> base_{0, 0, 0}; // the lowest lattice corner, in steps
    // Positions in steps above base_, x y z per vertex: 16 bits when the mesh spans fewer than 2^16 steps.
    std::vector<uint16_t> narrowPositions_;
    std::vector<uint32_t> widePositions_;
    std::vector<std::array<uint16_t, 2>> normals_; // octahedral codes, as Hermite samples keep theirs (quantizeNormal)
    std::vector<MaterialId> materials_;
    // Corners, three per triangle: 16 bits when the mesh has at most 2^16 vertices.
    std::vector<uint16_t> narrowCorners_;
    std::vector<uint32_t> wideCorners_;
    std::vector<MaterialId> triangleMaterials_;
};

} // namespace vdbclay
