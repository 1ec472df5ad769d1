// simplifyMesh: edge collapses within an error bound that keep a mesh's open boundary, its material
// boundaries and its topology.
#include "mesher/MeshMetrics.h"
#include "mesher/MeshQuality.h"
#include "mesher/MeshSimplify.h"
#include "support/MeshShapes.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <map>
#include <set>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// An n x n grid of unit quads on the plane z = 0 (heights from `height`), two triangles each, facing +z;
/// the quads with x below `split` of material 1, the rest of material 2.
template <typename Height>
Mesh gridMesh(int n, Height&& height, int split = 1 << 30)
{
    Mesh m;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            m.positions.push_back({float(i), float(j), float(height(i, j))});
            m.normals.push_back({0.f, 0.f, 1.f});
            m.materials.push_back(MaterialId(i <= split ? 1 : 2));
        }
    const auto at = [n](int i, int j) { return uint32_t(i * (n + 1) + j); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const MaterialId material = MaterialId(i < split ? 1 : 2);
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
            m.triangleMaterials.push_back(material);
            m.triangleMaterials.push_back(material);
        }
    // Vertex materials: the solid side's of a triangle around each (a vertex on the split gets 1 and 2
    // around it, so it is where materials meet).
    for (std::size_t v = 0; v < m.positions.size(); ++v) m.materials[v] = MaterialId(m.positions[v][0] < float(split) + 0.5f ? 1 : 2);
    return m;
}

using Segment = std::pair<std::array<float, 3>, std::array<float, 3>>;

Segment segment(std::array<float, 3> a, std::array<float, 3> b) { return a < b ? Segment{a, b} : Segment{b, a}; }

/// The edges of one triangle (the open boundary), as position pairs.
std::set<Segment> openEdges(const Mesh& m)
{
    std::map<Segment, int> count;
    for (const auto& t : m.triangles)
        for (int c = 0; c < 3; ++c) ++count[segment(m.positions[t[std::size_t(c)]], m.positions[t[std::size_t((c + 1) % 3)]])];
    std::set<Segment> out;
    for (const auto& [s, n] : count)
        if (n == 1) out.insert(s);
    return out;
}

/// The edges whose two triangles differ in material, as position pairs.
std::set<Segment> materialEdges(const Mesh& m)
{
    std::map<Segment, std::vector<MaterialId>> sides;
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (int c = 0; c < 3; ++c)
            sides[segment(m.positions[m.triangles[t][std::size_t(c)]], m.positions[m.triangles[t][std::size_t((c + 1) % 3)]])].push_back(
                m.triangleMaterials[t]);
    std::set<Segment> out;
    for (const auto& [s, materials] : sides)
        if (materials.size() == 2 && materials[0] != materials[1]) out.insert(s);
    return out;
}

void checkTopologyKept(const Mesh& before, const Mesh& after)
{
    const MeshTopology a = analyzeTopology(before, 1e-6), b = analyzeTopology(after, 1e-6);
    CHECK(b.nonManifoldEdges == 0);
    CHECK(b.misorientedEdges == 0);
    CHECK(b.degenerateTriangles == 0);
    if (a.pinchedVertices == 0) CHECK(b.pinchedVertices == 0); // (an open fan counts as pinched)
    CHECK(b.components == a.components);
}

} // namespace

TEST_CASE("simplify: a flat grid keeps its open boundary exactly and its area, in a few triangles", "[simplify]")
{
    const Mesh flat = gridMesh(20, [](int, int) { return 0.0; });
    Mesh m = flat;
    const SimplifyReport report = simplifyMesh(m, 1e-3);
    CHECK(report.trianglesBefore == 800);
    CHECK(report.trianglesAfter == m.triangleCount());
    // Nearly every inner vertex goes (they lie on the boundary's plane; a few stay where the fans would
    // grow past 12 neighbours); the boundary's 80 vertices need at least 78 triangles.
    CHECK(m.vertexCount() < 90);
    CHECK(m.triangleCount() < 200);
    CHECK(report.largestError < 1e-9);
    CHECK(openEdges(m) == openEdges(flat));
    CHECK(std::fabs(surfaceArea(m) - 400.0) < 1e-6);
    for (const auto& t : m.triangles) {
        const auto& a = m.positions[t[0]];
        const auto& b = m.positions[t[1]];
        const auto& c = m.positions[t[2]];
        CHECK((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0f); // still facing +z
    }
    checkTopologyKept(flat, m);
}

TEST_CASE("simplify: vertices where materials meet stay, and so does the line between them", "[simplify]")
{
    const Mesh two = gridMesh(16, [](int, int) { return 0.0; }, 7);
    Mesh m = two;
    simplifyMesh(m, 1e-3);
    CHECK(m.triangleCount() < two.triangleCount() / 2);
    CHECK(materialEdges(m) == materialEdges(two));
    CHECK(openEdges(m) == openEdges(two));
    // Each triangle keeps its material's side of the line.
    for (std::size_t t = 0; t < m.triangleCount(); ++t)
        for (uint32_t v : m.triangles[t]) CHECK((m.triangleMaterials[t] == 1 ? m.positions[v][0] <= 7.0f : m.positions[v][0] >= 7.0f));
}

TEST_CASE("simplify: a sphere stays closed, within the bound of the original, in fewer triangles", "[simplify]")
{
    const Mesh sphere = icosphereMesh(10.0, 4);
    for (const double bound : {0.1, 0.3, 0.6}) {
        Mesh m = sphere;
        const SimplifyReport report = simplifyMesh(m, bound);
        INFO("bound " << bound << ": " << report.trianglesBefore << " -> " << report.trianglesAfter << " triangles, largest error "
                      << report.largestError);
        CHECK(report.largestError <= bound);
        CHECK(m.triangleCount() < sphere.triangleCount());
        CHECK(analyzeTopology(m, 1e-6).watertight());
        checkTopologyKept(sphere, m);
        // Every kept vertex lies on the sphere (the collapses move none), so the simplified surface lies
        // inside it, by at most the sagitta the bound allows; the original lies within the bound of it.
        const double farthest = maxDistanceToMesh(sphere, m, 0.2);
        CHECK(farthest <= bound * 1.05);
        CHECK(maxDistanceToMesh(m, sphere, 0.2) <= bound * 1.05);
        CHECK(std::fabs(enclosedVolume(m) - enclosedVolume(sphere)) < 0.02 * enclosedVolume(sphere));
    }
}

TEST_CASE("simplify: a rough height field never folds, and keeps within the bound where it is flatter", "[simplify]")
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> noise(-0.3, 0.3);
    std::vector<double> heights(31 * 31);
    for (double& h : heights) h = noise(rng);
    const Mesh rough = gridMesh(30, [&](int i, int j) { return heights[std::size_t(i * 31 + j)] + 0.2 * std::sin(0.3 * i); });
    for (const double bound : {0.05, 0.25}) {
        Mesh m = rough;
        const SimplifyReport report = simplifyMesh(m, bound);
        INFO("bound " << bound << ": " << report.trianglesAfter << " triangles");
        CHECK(report.largestError <= bound);
        CHECK(m.triangleCount() <= rough.triangleCount());
        CHECK(openEdges(m) == openEdges(rough));
        checkTopologyKept(rough, m);
        for (const auto& t : m.triangles) { // a height field still: every triangle faces up
            const auto& a = m.positions[t[0]];
            const auto& b = m.positions[t[1]];
            const auto& c = m.positions[t[2]];
            CHECK((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0f);
        }
        CHECK(maxDistanceToMesh(m, rough, 0.1) <= bound * 1.05);
    }
}

TEST_CASE("simplify: no bound leaves the mesh as it was", "[simplify]")
{
    const Mesh sphere = icosphereMesh(3.0, 2);
    for (const double bound : {0.0, -1.0}) {
        Mesh m = sphere;
        const SimplifyReport report = simplifyMesh(m, bound);
        CHECK(report.trianglesAfter == sphere.triangleCount());
        CHECK(contentHash(m) == contentHash(sphere));
    }
}
