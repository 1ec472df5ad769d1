// The compact mesh a streaming scene keeps: error bounds of positions and normals, exact corners and
// materials, a lattice shared by every mesh, 16- and 32-bit storage, bytes, and bad input.
#include "mesher/QuantizedMesh.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <stdexcept>

using namespace vdbclay;

namespace {

std::array<float, 3> randomUnit(std::mt19937_64& rng)
{
    std::normal_distribution<double> g(0.0, 1.0);
    for (;;) {
        const double x = g(rng), y = g(rng), z = g(rng), l = std::sqrt(x * x + y * y + z * z);
        if (l > 1e-6) return {float(x / l), float(y / l), float(z / l)};
    }
}

/// `vertices` random vertices in a box of `extent` at `corner`, unit normals, and as many random
/// triangles with a material each.
Mesh randomMesh(std::mt19937_64& rng, std::size_t vertices, double corner, double extent)
{
    std::uniform_real_distribution<double> at(corner, corner + extent);
    std::uniform_int_distribution<uint32_t> pick(0, uint32_t(vertices - 1));
    std::uniform_int_distribution<int> material(1, 300);
    Mesh m;
    for (std::size_t v = 0; v < vertices; ++v) {
        m.positions.push_back({float(at(rng)), float(at(rng)), float(at(rng))});
        m.normals.push_back(randomUnit(rng));
        m.materials.push_back(MaterialId(material(rng)));
    }
    for (std::size_t t = 0; t < vertices; ++t) {
        m.triangles.push_back({pick(rng), pick(rng), pick(rng)});
        m.triangleMaterials.push_back(MaterialId(material(rng)));
    }
    return m;
}

/// Checks every decoded value of `q` against `m`'s: positions within half a step (and a float's
/// rounding of the coordinate), normals within quantizeNormal's bound, the rest exactly.
void checkDecodes(const QuantizedMesh& q, const Mesh& m, double step)
{
    REQUIRE(q.vertexCount() == m.positions.size());
    REQUIRE(q.triangleCount() == m.triangles.size());
    const Mesh d = q.decoded();
    double worstPosition = 0.0, worstNormal = 0.0, worstAllowed = 0.0;
    for (std::size_t v = 0; v < m.positions.size(); ++v)
        for (std::size_t a = 0; a < 3; ++a) {
            const double error = std::fabs(double(d.positions[v][a]) - double(m.positions[v][a]));
            const double allowed = 0.5 * step + 2.0 * std::fabs(double(m.positions[v][a])) * 6e-8;
            worstPosition = std::max(worstPosition, error / allowed);
            worstAllowed = std::max(worstAllowed, allowed);
            worstNormal = std::max(worstNormal, std::fabs(double(d.normals[v][a]) - double(m.normals[v][a])));
            CHECK(d.positions[v][a] == q.position(v)[a]);
            CHECK(d.normals[v][a] == q.normal(v)[a]);
        }
    INFO("worst position error " << worstPosition << " of the bound, worst normal component error " << worstNormal);
    CHECK(worstPosition <= 1.0);
    CHECK(worstNormal <= 1.0 / 1782.0);
    for (const auto& n : d.normals) CHECK(std::fabs(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) < 1e-6);
    CHECK(d.materials == m.materials);
    CHECK(d.triangles == m.triangles);
    CHECK(d.triangleMaterials == m.triangleMaterials);
}

} // namespace

TEST_CASE("quantized mesh: positions within half a lattice step, normals within the octahedral bound, the rest exact", "[mesh][quantized]")
{
    std::mt19937_64 rng(41);
    for (const double corner : {-3000.0, -40.0, 0.0, 17.25, 2900.0})
        for (const double step : {1.0 / 64.0, 0.1 / 64.0, 0.37}) {
            INFO("corner " << corner << ", step " << step);
            const Mesh m = randomMesh(rng, 500, corner, 500.0 * step); // 500 steps across: 16-bit offsets
            const QuantizedMesh q(m, step);
            CHECK(q.step() == step);
            checkDecodes(q, m, step);
            // What was decoded comes back exactly when stored again (the octahedron's folded edges
            // have two codes for one direction, so the codes themselves may differ).
            const Mesh once = q.decoded();
            const Mesh twice = QuantizedMesh(once, step).decoded();
            CHECK(twice.positions == once.positions);
            CHECK(twice.normals == once.normals);
        }
}

TEST_CASE("quantized mesh: a position two meshes share decodes to the same floats in both", "[mesh][quantized]")
{
    // Bricks meet on shared vertices: each brick's mesh is stored relative to its own lowest corner, and
    // the shared vertices must still land on the very same floats, or cracks would open between them.
    std::mt19937_64 rng(7);
    const double step = 0.05 / 64.0;
    for (int trial = 0; trial < 20; ++trial) {
        Mesh a = randomMesh(rng, 200, 10.0 + trial, 3.0), b = randomMesh(rng, 300, 9.0 + trial, 2.5);
        for (std::size_t i = 0; i < 50; ++i) b.positions[i * 3] = a.positions[i * 4];
        const QuantizedMesh qa(a, step), qb(b, step);
        for (std::size_t i = 0; i < 50; ++i) {
            const auto pa = qa.position(i * 4), pb = qb.position(i * 3);
            CHECK(pa == pb);
        }
    }
}

TEST_CASE("quantized mesh: 16-bit offsets and corners where they reach, 32-bit beyond, half the bytes of a mesh or less", "[mesh][quantized]")
{
    std::mt19937_64 rng(3);
    const double step = 1.0 / 64.0;
    const Mesh narrow = randomMesh(rng, 4000, 100.0, 65535 * step); // spans at most 65535 steps
    const Mesh wide = randomMesh(rng, 4000, 100.0, 70000 * step);   // more than 2^16 steps across
    const QuantizedMesh qn(narrow, step), qw(wide, step);
    checkDecodes(qn, narrow, step);
    checkDecodes(qw, wide, step);
    // Positions take 6 bytes a vertex instead of 12 while the mesh spans fewer than 2^16 steps.
    CHECK(qw.memoryBytes() - qn.memoryBytes() == 4000 * 3 * 2);
    // Half a Mesh's bytes, give or take the arrays' headers.
    CHECK(100 * qn.memoryBytes() <= 51 * narrow.memoryBytes());

    // More than 2^16 vertices: 32-bit corners, still exact, on both sides of 65536.
    Mesh many = randomMesh(rng, 70000, 0.0, 100.0);
    many.triangles.push_back({65535, 65536, 69999});
    many.triangleMaterials.push_back(5);
    const QuantizedMesh qm(many, step);
    checkDecodes(qm, many, step);
    CHECK(qm.triangle(qm.triangleCount() - 1) == std::array<uint32_t, 3>{65535, 65536, 69999});
    Mesh exactly = randomMesh(rng, 65536, 0.0, 100.0); // the largest that 16-bit corners name
    exactly.triangles.push_back({0, 65534, 65535});
    exactly.triangleMaterials.push_back(9);
    checkDecodes(QuantizedMesh(exactly, step), exactly, step);
}

TEST_CASE("quantized mesh: equal meshes compare and hash alike, a step's move or a material does not", "[mesh][quantized]")
{
    std::mt19937_64 rng(11);
    const double step = 1.0 / 64.0;
    const Mesh m = randomMesh(rng, 100, 0.0, 50.0);
    const QuantizedMesh q(m, step), same(m, step);
    CHECK(q == same);
    CHECK(q.contentHash() == same.contentHash());
    Mesh moved = m;
    moved.positions[37][1] += float(step * 1.01);
    const QuantizedMesh qMoved(moved, step);
    CHECK(qMoved != q);
    CHECK(qMoved.contentHash() != q.contentHash());
    Mesh repainted = m;
    repainted.triangleMaterials[5] = MaterialId(repainted.triangleMaterials[5] + 1);
    CHECK(QuantizedMesh(repainted, step) != q);
    CHECK(QuantizedMesh(repainted, step).contentHash() != q.contentHash());
    // A mesh with neither normals nor materials stays so.
    Mesh bare;
    bare.positions = m.positions;
    bare.triangles = m.triangles;
    const QuantizedMesh qBare(bare, step);
    CHECK_FALSE(qBare.hasNormals());
    CHECK_FALSE(qBare.hasMaterials());
    CHECK_FALSE(qBare.hasTriangleMaterials());
    CHECK(qBare.decoded().normals.empty());
    CHECK(qBare.decoded().triangles == m.triangles);
    CHECK(QuantizedMesh().decoded().positions.empty());
}

TEST_CASE("quantized mesh: a broken mesh or step is refused with a clear error", "[mesh][quantized]")
{
    std::mt19937_64 rng(5);
    const Mesh m = randomMesh(rng, 10, 0.0, 1.0);
    Mesh badCorner = m;
    badCorner.triangles[3][2] = 10;
    CHECK_THROWS_AS(QuantizedMesh(badCorner, 0.01), std::invalid_argument);
    Mesh fewNormals = m;
    fewNormals.normals.pop_back();
    CHECK_THROWS_AS(QuantizedMesh(fewNormals, 0.01), std::invalid_argument);
    Mesh fewMaterials = m;
    fewMaterials.triangleMaterials.pop_back();
    CHECK_THROWS_AS(QuantizedMesh(fewMaterials, 0.01), std::invalid_argument);
    Mesh notFinite = m;
    notFinite.positions[2][0] = std::nanf("");
    CHECK_THROWS_AS(QuantizedMesh(notFinite, 0.01), std::invalid_argument);
    Mesh tooWide = m;
    tooWide.positions[0][0] = 1e30f;
    CHECK_THROWS_AS(QuantizedMesh(tooWide, 0.01), std::invalid_argument);
    for (const double step : {0.0, -1.0, double(NAN)}) CHECK_THROWS_AS(QuantizedMesh(m, step), std::invalid_argument);
}
