// The corner-case table both meshers read (CellTopology.h), and Cubical Marching Squares' shortcut for
// smooth cells, voxel-wide and adaptive, checked against the full face walk. White-box: includes the
// mesher's internal, OpenVDB-heavy headers.
#include "mesher/AdaptiveCellCache.h"
#include "mesher/CellGrid.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"

#include <catch2/catch.hpp>

#include <array>
#include <functional>
#include <string>
#include <vector>

using namespace vdbclay;
using namespace vdbclay::mesher_detail;
using namespace vdbclay::test;

namespace {

bool solidCorner(unsigned mask, int corner) { return (mask >> corner) & 1u; }

bool crossed(unsigned mask, int edge)
{
    const int low = edgeLowCorner(edge);
    return solidCorner(mask, low) != solidCorner(mask, low | (1 << (edge / 4)));
}

std::array<double, 3> cornerPosition(int corner)
{
    return {double(cornerBit(corner, 0)), double(cornerBit(corner, 1)), double(cornerBit(corner, 2))};
}

std::array<double, 3> edgeMidpoint(int edge)
{
    std::array<double, 3> p = cornerPosition(edgeLowCorner(edge));
    p[edge / 4] = 0.5;
    return p;
}

/// The loops of a case, each as its list of edges.
std::vector<std::vector<int>> loopsOf(const CellCase& cell)
{
    std::vector<std::vector<int>> loops;
    for (int l = 0, begin = 0; l < cell.loopCount; begin = cell.loopEnd[l++])
        loops.emplace_back(cell.edges + begin, cell.edges + cell.loopEnd[l]);
    return loops;
}

} // namespace

TEST_CASE("each corner case's loops cross every cut cell edge once, face by face, facing out of the solid", "[cms][cases]")
{
    for (unsigned mask = 0; mask < 256; ++mask) {
        INFO("solid corners " << mask);
        const CellCase& cell = kCellCases[mask];
        const std::vector<std::vector<int>> loops = loopsOf(cell);

        int visits[12] = {};
        for (const auto& loop : loops)
            for (int e : loop) ++visits[e];
        for (int e = 0; e < 12; ++e) CHECK(visits[e] == (crossed(mask, e) ? 1 : 0));

        bool ambiguous = false;
        for (const CellFace& f : kFaces) {
            const bool s0 = solidCorner(mask, f.corners[0]), s1 = solidCorner(mask, f.corners[1]);
            ambiguous |= s0 == solidCorner(mask, f.corners[2]) && s1 == solidCorner(mask, f.corners[3]) && s0 != s1;
        }
        CHECK(cell.ambiguousFace == ambiguous);

        for (int l = 0, begin = 0; l < cell.loopCount; begin = cell.loopEnd[l++]) {
            const int end = cell.loopEnd[l];
            CHECK(end - begin >= 3);
            std::array<double, 3> newell{}, outward{};
            for (int i = begin; i < end; ++i) {
                const int e = cell.edges[i], next = cell.edges[i + 1 < end ? i + 1 : begin];
                // Consecutive edges lie on one face with the recorded normal axis.
                const int axis = cell.segmentAxis[i];
                CHECK(e / 4 != axis);
                CHECK(next / 4 != axis);
                CHECK(cornerBit(edgeLowCorner(e), axis) == cornerBit(edgeLowCorner(next), axis));
                // Newell's normal of the loop through the edge midpoints, and the edges' solid-to-empty directions.
                const std::array<double, 3> p = edgeMidpoint(e), q = edgeMidpoint(next);
                for (int k = 0; k < 3; ++k) {
                    const int a = (k + 1) % 3, b = (k + 2) % 3;
                    newell[k] += (p[a] - q[a]) * (p[b] + q[b]);
                }
                const int low = edgeLowCorner(e);
                outward[e / 4] += solidCorner(mask, low) ? 1.0 : -1.0;
            }
            CHECK(newell[0] * outward[0] + newell[1] * outward[1] + newell[2] * outward[2] > 0.0);
        }

        // Swapping solid and empty reverses each loop, where no face's pairing depends on which is which.
        if (!ambiguous) {
            std::vector<std::vector<int>> reversed = loopsOf(kCellCases[~mask & 0xFFu]);
            for (auto& loop : reversed) std::reverse(loop.begin(), loop.end());
            REQUIRE(reversed.size() == loops.size());
            for (const auto& loop : loops) {
                bool found = false;
                for (const auto& other : reversed) {
                    const auto at = std::find(other.begin(), other.end(), loop[0]);
                    if (at == other.end() || other.size() != loop.size()) continue;
                    std::vector<int> rotated(at, other.end());
                    rotated.insert(rotated.end(), other.begin(), at);
                    found = rotated == loop;
                }
                CHECK(found);
            }
        }
    }
}

TEST_CASE("CMS meshes smooth cells from the corner-case table exactly as the face walk does", "[cms]")
{
    struct Case {
        const char* name;
        std::function<void(Volume&)> build;
        double minShareFromTable;         // of the surface cells, voxel cells
        double minAdaptiveShareFromTable; // of the surface cells, adaptive (below it without wide cells' shortcut)
    };
    const std::vector<Case> cases = {
        {"sphere", [](Volume& v) { apply(v, CsgMode::Add, sphere(14.0), at(Vec3d(0.2, -0.3, 0.1))); }, 0.95, 0.85},
        {"rotated box", [](Volume& v) { apply(v, CsgMode::Add, box(Vec3d(10.3, 7.2, 5.6)), at(Vec3d(0.3, 0.2, 0.1), Vec3d(20, 35, 10))); },
         0.8, 0.43},
        {"box minus sphere",
         [](Volume& v) {
             apply(v, CsgMode::Add, box(Vec3d(12.0)), at(Vec3d(0.5)));
             apply(v, CsgMode::Remove, sphere(8.0), at(Vec3d(12.5)));
         },
         0.85, 0.42},
        {"thin wall",
         [](Volume& v) {
             apply(v, CsgMode::Add, box(Vec3d(14.0)), at(Vec3d(0.2)));
             apply(v, CsgMode::Remove, sphere(7.0), at(Vec3d(-7.6, 0.3, 14.0)));
             apply(v, CsgMode::Remove, sphere(7.0), at(Vec3d(7.1, 0.3, 14.0)));
         },
         0.85, 0.6},
        {"two materials",
         [](Volume& v) {
             const MaterialId stone = defineMaterial(v, "stone", 0.9f);
             const MaterialId moss = defineMaterial(v, "moss", 0.2f);
             apply(v, CsgMode::Add, sphere(12.0), at(Vec3d(0.3)), stone);
             apply(v, CsgMode::Paint, box(Vec3d(50.0)), at(Vec3d(0.0, 0.0, 50.3)), moss);
         },
         0.9, 0.6},
    };
    for (const Case& c : cases) {
        SECTION(c.name)
        {
            Volume v(1.0);
            c.build(v);
            const HermiteTree& tree = v.impl().grid->tree();
            ConstAccessor acc(tree);
            const bool adaptive = GENERATE(false, true);
            // Adaptive: the cells of every leaf, as the mesher subdivides them.
            AdaptiveCellCache cells;
            if (adaptive) {
                std::vector<const HermiteLeaf*> leaves;
                for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) leaves.push_back(leaf.getLeaf());
                cells.prepare(tree, leaves, MeshOptions{});
            }
            CubicalMarchingSquaresMesher walked(v.voxelSize(), 30.0, /*walkEveryCell=*/true);
            CubicalMarchingSquaresMesher shortcut(v.voxelSize(), 30.0);
            std::size_t triangles = 0;
            for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
                const CellWidthField widths = cells.around(*leaf);
                const CellWidthField* field = adaptive ? &widths : nullptr;
                const MeshChunk expected = walked.mesh(*leaf, acc, field);
                REQUIRE(identical(expected, shortcut.mesh(*leaf, acc, field)));
                triangles += expected.mesh.triangleCount();
            }
            CHECK(triangles > (adaptive ? 200 : 1000));
            CHECK(walked.cellsFromCaseTable() == 0);
            REQUIRE(shortcut.cellsMeshed() == walked.cellsMeshed());
            const double share = double(shortcut.cellsFromCaseTable()) / double(shortcut.cellsMeshed());
            INFO((adaptive ? "adaptive: " : "voxel cells: ") << shortcut.cellsFromCaseTable() << " of "
                                                              << shortcut.cellsMeshed() << " cells from the table");
            CHECK(share >= (adaptive ? c.minAdaptiveShareFromTable : c.minShareFromTable));
            // Each shape with creases also has cells the walk must take; a sphere's voxel cells have no
            // normals a sharp angle apart, so the table takes them all (wide cells may span one).
            if (std::string(c.name) == "sphere" && !adaptive) CHECK(share == 1.0);
            else CHECK(share < 1.0);
        }
    }
}
