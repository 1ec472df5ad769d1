// CSG on the Hermite volume, checked through the Marching Cubes mesh (closedness, enclosed volume
// against analytic volumes), through the voxels themselves, and through bit-exact comparisons.
#include "mesher/MeshMetrics.h"
#include "mesher/Mesher.h"
#include "sculpt/StrokeScript.h"
#include "support/ExampleScript.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/HermiteGrid.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <tuple>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

using Coord3 = std::array<int, 3>;

struct MeshReport {
    MeshTopology topology;
    double volume = 0.0;
    std::size_t triangles = 0;
};

MeshReport meshReport(const Volume& v)
{
    MeshOptions options;
    options.kind = MesherKind::MarchingCubes;
    const Mesh mesh = meshVolume(v, options);
    return {analyzeTopology(mesh, kMergeDistanceVoxels * v.voxelSize()), enclosedVolume(mesh), mesh.triangleCount()};
}

/// The Marching Cubes mesh is closed and encloses `expected` within the relative tolerance.
void checkClosedMesh(const Volume& v, double expected, double relTolerance)
{
    REQUIRE(checkInvariants(v) == "");
    const MeshReport r = meshReport(v);
    INFO("boundary " << r.topology.boundaryEdges << ", non-manifold " << r.topology.nonManifoldEdges
                     << ", misoriented " << r.topology.misorientedEdges << ", triangles " << r.triangles);
    CHECK(r.triangles > 0);
    CHECK(r.topology.watertight());
    CHECK(r.topology.degenerateTriangles == 0);
    INFO("enclosed volume " << r.volume << ", analytic " << expected << ", relative error "
                            << (r.volume - expected) / expected);
    CHECK(std::fabs(r.volume - expected) <= relTolerance * expected);
}

bool isEmptyVolume(const Volume& v)
{
    const VolumeStats s = v.stats();
    INFO("leaves " << s.leafCount << ", tiles " << s.tileCount << ", active " << s.activeVoxels << ", samples "
                   << s.samples);
    return s.empty && s.leafCount == 0 && s.tileCount == 0 && s.activeVoxels == 0 && s.samples == 0;
}

/// Voxels in [lo, hi] whose solidity differs from "distance at the voxel centre < 0".
int countSolidityMismatches(const Volume& v, const SdfField& field, const Coord3& lo, const Coord3& hi)
{
    int mismatches = 0;
    const double vs = v.voxelSize();
    for (int i = lo[0]; i <= hi[0]; ++i)
        for (int j = lo[1]; j <= hi[1]; ++j)
            for (int k = lo[2]; k <= hi[2]; ++k) {
                const bool inside = field.distance(Vec3d(i, j, k) * vs) < 0.0;
                const bool solid = v.materialAt({i, j, k}) != kEmptyMaterial;
                if (inside != solid) ++mismatches;
            }
    return mismatches;
}

const Vec3d kC(0.21, -0.13, 0.17); // an off-grid centre

} // namespace

TEST_CASE("forEachTile sees exactly the tiles OpenVDB's iterator sees, at every level", "[csg]")
{
    // CSG folds whole 8^3 and 128^3 blocks of a large box into tiles; a 4096^3 root tile is set directly
    // (a brush that large is refused), far from the rest.
    Volume v(1.0);
    const MaterialId red = defineMaterial(v, "red", 0.5f);
    apply(v, CsgMode::Add, box(Vec3d(300.0, 300.0, 300.0)), at(Vec3d(0.0, 0.0, 0.0)));
    apply(v, CsgMode::Paint, sphere(90.0), at(Vec3d(-40.0, 100.0, 300.0)), red);
    v.impl().grid->tree().addTile(3, Coord(-4 * 4096, 0, 0), MaterialValue{red}, false);
    using Tile = std::tuple<Coord, Coord, MaterialId>;
    std::vector<Tile> walked, iterated;
    const HermiteTree& tree = v.impl().grid->constTree();
    forEachTile(tree, [&](const CoordBBox& b, MaterialValue m) { walked.emplace_back(b.min(), b.max(), m.id); });
    auto it = tree.cbeginValueAll();
    it.setMaxDepth(HermiteTree::ValueAllCIter::LEAF_DEPTH - 1);
    for (; it; ++it) {
        CoordBBox b;
        it.getBoundingBox(b);
        iterated.emplace_back(b.min(), b.max(), (*it).id);
    }
    std::sort(walked.begin(), walked.end());
    std::sort(iterated.begin(), iterated.end());
    CHECK(walked == iterated);
    std::set<int> sizes;
    for (const Tile& t : walked)
        if (std::get<2>(t) != kEmptyMaterial) sizes.insert(std::get<1>(t).x() - std::get<0>(t).x() + 1);
    CHECK(sizes == std::set<int>{8, 128, 4096});
}

TEST_CASE("sphere minus a box that cuts off a cap", "[csg]")
{
    const double R = 14.0, cut = 5.37; // the box's -x face is the plane x = c.x + cut
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(R), at(kC));
    apply(v, CsgMode::Remove, box({20.0, 20.0, 20.0}), at(kC + Vec3d(cut + 20.0, 0.0, 0.0)));
    CHECK(v.materialAt({0, 0, 0}) == 1);
    CHECK(v.materialAt({10, 0, 0}) == kEmptyMaterial);
    checkClosedMesh(v, sphereVolume(R) - sphereCapVolume(R, R - cut), 0.01);
}

TEST_CASE("sphere minus a half-space", "[csg]")
{
    const double R = 14.0, cut = -3.4;
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(R), at(kC));
    apply(v, CsgMode::Remove, halfSpace({0.0, -1.0, 0.0}), at(kC + Vec3d(0.0, cut, 0.0)));
    // Solid where -(y - c.y - cut) < 0 is removed, i.e. everything above y = c.y + cut goes.
    CHECK(v.materialAt({0, -10, 0}) == 1);
    CHECK(v.materialAt({0, 0, 0}) == kEmptyMaterial);
    checkClosedMesh(v, sphereCapVolume(R, R + cut), 0.01);
}

TEST_CASE("sphere minus a box inside it leaves a closed cavity", "[csg]")
{
    const double R = 14.0;
    const Vec3d h(5.1, 4.1, 3.1); // faces 0.1 voxel beyond the last removed voxel centres
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(R), at(kC));
    apply(v, CsgMode::Remove, box(h), at(Vec3d(0.0)));
    CHECK(v.materialAt({0, 0, 0}) == kEmptyMaterial);
    CHECK(v.materialAt({5, 4, 3}) == kEmptyMaterial);
    CHECK(v.materialAt({6, 0, 0}) == 1);
    checkClosedMesh(v, sphereVolume(R) - 8.0 * h.x() * h.y() * h.z(), 0.01);
}

TEST_CASE("sphere minus a rotated box inside it", "[csg]")
{
    const double R = 15.0;
    const Vec3d h(6.0, 5.0, 4.0);
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(R), at(kC));
    apply(v, CsgMode::Remove, box(h), at({0.3, 0.2, 0.1}, {25.0, 40.0, 10.0}));
    checkClosedMesh(v, sphereVolume(R) - 8.0 * h.x() * h.y() * h.z(), 0.01);
}

TEST_CASE("sphere union box", "[csg]")
{
    SECTION("a box inside the sphere, same material, changes nothing")
    {
        Volume a(1.0);
        apply(a, CsgMode::Add, sphere(14.0), at(kC));
        Volume b = a.clone();
        apply(b, CsgMode::Add, box({5.0, 4.0, 3.0}), at({0.3, 0.2, 0.1}, {10.0, 20.0, 30.0}));
        CHECK(identical(a, b));
        checkClosedMesh(b, sphereVolume(14.0), 0.01);
    }
    SECTION("a box that covers the sphere's +x half")
    {
        const double R = 12.0, cut = 0.3;
        const Vec3d h(7.0, 14.3, 14.3);
        Volume v(1.0);
        apply(v, CsgMode::Add, sphere(R), at(kC));
        apply(v, CsgMode::Add, box(h), at(kC + Vec3d(cut + h.x(), 0.0, 0.0)));
        const double expected = sphereVolume(R) - sphereCapVolume(R, R - cut) + 8.0 * h.x() * h.y() * h.z();
        checkClosedMesh(v, expected, 0.01);
    }
    SECTION("a separate box in another material")
    {
        Volume v(1.0);
        const MaterialId stone = defineMaterial(v, "stone", 0.9f);
        const Vec3d h(4.1, 4.1, 4.1);
        apply(v, CsgMode::Add, sphere(10.0), at(kC));
        apply(v, CsgMode::Add, box(h), at({20.0, 0.0, 0.0}), stone);
        CHECK(v.materialAt({20, 0, 0}) == stone);
        CHECK(v.materialAt({0, 0, 0}) == 1);
        checkClosedMesh(v, sphereVolume(10.0) + 8.0 * h.x() * h.y() * h.z(), 0.01);
    }
}

TEST_CASE("sphere intersect a box inside it gives the box", "[csg]")
{
    SECTION("axis-aligned")
    {
        const Vec3d h(6.1, 5.1, 4.1);
        Volume v(1.0);
        apply(v, CsgMode::Add, sphere(14.0), at(kC));
        apply(v, CsgMode::Intersect, box(h), at(Vec3d(0.0)));
        CHECK(v.materialAt({6, 5, 4}) == 1);
        CHECK(v.materialAt({7, 0, 0}) == kEmptyMaterial);
        checkClosedMesh(v, 8.0 * h.x() * h.y() * h.z(), 0.01);
    }
    SECTION("rotated")
    {
        const Vec3d h(8.0, 7.0, 6.0);
        Volume v(1.0);
        apply(v, CsgMode::Add, sphere(16.0), at(kC));
        const Brush b(box(h), at({0.3, 0.2, 0.1}, {25.0, 40.0, 10.0}));
        applyCsg(v, b, op(CsgMode::Intersect));
        CHECK(countSolidityMismatches(v, b, {-17, -17, -17}, {17, 17, 17}) == 0);
        // Marching Cubes chamfers the box's sharp, grid-oblique edges: allow 2%.
        checkClosedMesh(v, 8.0 * h.x() * h.y() * h.z(), 0.02);
    }
}

TEST_CASE("adding a brush again changes nothing (A + A == A)", "[csg]")
{
    std::vector<std::pair<std::string, std::shared_ptr<SdfField>>> brushes;
    brushes.emplace_back("sphere", std::make_shared<Brush>(sphere(12.0), at(kC)));
    brushes.emplace_back("rotated rounded box",
                         std::make_shared<Brush>(box({9.0, 6.0, 4.0}, 1.5), at(kC, {30.0, 10.0, 50.0})));
    brushes.emplace_back("torus", std::make_shared<Brush>(torus(10.0, 3.0), at(kC, {60.0, 0.0, 0.0})));
    std::vector<BrushPart> parts(2);
    parts[0].primitive = sphere(8.0);
    parts[1].primitive = cylinder(3.0, 20.0);
    parts[1].placement = at({0.0, 0.0, 0.0}, {0.0, 0.0, 90.0});
    parts[1].op = PartOp::Remove;
    brushes.emplace_back("blend", std::make_shared<Brush>(parts, 2.0, at(kC, Vec3d(0.0), {1.0, 1.5, 1.0})));
    brushes.emplace_back("stroke", std::make_shared<SweptBrush>(Brush(sphere(4.0), at(Vec3d(0.0))),
                                                               std::vector<Vec3d>{{-10, 0, 0}, {5, 7, 2}, {12, -3, 4}}));
    for (const auto& [name, brush] : brushes) {
        INFO(name);
        Volume a(1.0);
        applyCsg(a, *brush, op(CsgMode::Add));
        REQUIRE_FALSE(a.stats().empty);
        REQUIRE(checkInvariants(a) == "");
        Volume b = a.clone();
        CHECK(identical(a, b));
        applyCsg(b, *brush, op(CsgMode::Add));
        CHECK(identical(a, b));
        // A - A is empty: nothing survives, not even a tile or an empty leaf.
        applyCsg(b, *brush, op(CsgMode::Remove));
        CHECK(isEmptyVolume(b));
        CHECK(checkInvariants(b) == "");
    }
}

TEST_CASE("adding a large sphere again changes nothing, also on edges its surface grazes", "[csg]")
{
    // Near where a large sphere's normal turns across an axis, an edge meets the surface at a shallow
    // angle: the crossing search stops within a distance tolerance that allows the crossing to drift
    // along the edge further than the stored offset's precision.
    Volume a(1.0);
    const Brush big(sphere(250.0), at(kC, {10.0, 20.0, 0.0}));
    applyCsg(a, big, op(CsgMode::Add));
    Volume b = a.clone();
    const EditStats again = applyCsg(b, big, op(CsgMode::Add));
    CHECK(again.dirtyBlocks.empty());
    CHECK(identical(a, b));
}

namespace {

/// Two materials, tiles in the sphere's core, leaves on the surfaces.
Volume makeComposite()
{
    Volume v(1.0);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f);
    apply(v, CsgMode::Add, sphere(18.0), at(kC), stone);
    apply(v, CsgMode::Add, box({6.0, 6.0, 20.0}, 1.0), at({20.0, 0.0, 0.0}, {0.0, 20.0, 0.0}));
    apply(v, CsgMode::Remove, cylinder(3.0, 50.0), at(kC + Vec3d(11.0, 0.0, 0.0)));
    apply(v, CsgMode::Paint, sphere(6.0), at({0.0, 18.0, 0.0}), 1);
    REQUIRE(v.stats().tileCount > 0); // the sphere's core is stored as tiles
    REQUIRE(v.stats().leafCount > 0);
    REQUIRE(checkInvariants(v) == "");
    return v;
}

/// Nothing left: no leaves, no tiles, no triangles.
void checkEverythingGone(const Volume& v)
{
    CHECK(isEmptyVolume(v));
    CHECK(meshReport(v).triangles == 0);
    CHECK(checkInvariants(v) == "");
}

} // namespace

TEST_CASE("removing everything leaves no leaves and no tiles", "[csg]")
{
    Volume v = makeComposite();
    SECTION("with a big sphere")
    {
        apply(v, CsgMode::Remove, sphere(60.0), at(Vec3d(0.0)));
    }
    SECTION("with a big box")
    {
        apply(v, CsgMode::Remove, box({40.0, 40.0, 40.0}), at({5.0, 0.0, 0.0}));
    }
    checkEverythingGone(v);
}

TEST_CASE("removing everything gives back the tree's nodes", "[csg][prune]")
{
    Volume v = makeComposite();
    apply(v, CsgMode::Remove, sphere(60.0), at(Vec3d(0.0)));
    REQUIRE(isEmptyVolume(v));
    // Identical to a fresh volume with the same materials: no empty internal nodes are left behind.
    Volume fresh(1.0);
    fresh.materials() = v.materials();
    CHECK(identical(v, fresh));
    INFO("memory of the emptied volume " << v.stats().memoryBytes << " B, of a fresh one "
                                         << fresh.stats().memoryBytes << " B");
    CHECK(v.stats().memoryBytes <= 2 * fresh.stats().memoryBytes);
}

TEST_CASE("a half-space that covers the whole volume removes everything", "[csg][halfspace]")
{
    Volume v = makeComposite();
    // Solid side of the half-space: -(z + 100) < 0, i.e. every z above -100.
    apply(v, CsgMode::Remove, halfSpace({0.0, 0.0, -1.0}), at({0.0, 0.0, -100.0}));
    checkEverythingGone(v);
}

TEST_CASE("intersect with a brush far away empties the volume", "[csg][intersect]")
{
    Volume v = makeComposite();
    apply(v, CsgMode::Intersect, sphere(5.0), at({1000.0, 0.0, 0.0}));
    checkEverythingGone(v);
}

TEST_CASE("a brush that covers whole 128^3 nodes fills them", "[csg][add]")
{
    Volume v(1.0);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f);
    apply(v, CsgMode::Add, sphere(6.0), at({20.3, 20.2, 20.1}), 1); // some content in the node at the origin
    REQUIRE(v.materialAt({20, 20, 20}) == 1);
    // Half-extent 180: the 128^3 nodes around the origin lie wholly inside the box.
    apply(v, CsgMode::Add, box({180.0, 180.0, 180.0}), at({0.3, 0.2, 0.1}), stone);
    for (const Coord3& c : {Coord3{20, 20, 20}, Coord3{0, 0, 0}, Coord3{100, 100, 100}, Coord3{-100, 50, -20},
                            Coord3{-150, -150, -150}, Coord3{170, 0, 0}}) {
        INFO("voxel " << c[0] << " " << c[1] << " " << c[2]);
        CHECK(v.materialAt(c) == stone);
    }
    CHECK(v.materialAt({181, 0, 0}) == kEmptyMaterial);
    CHECK(solidVoxelsPerMaterial(v)[1] == 0);
    CHECK(checkInvariants(v) == "");
}

namespace {

std::vector<Coord3> sortedUnique(std::vector<Coord3> blocks)
{
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    return blocks;
}

/// EditStats::blockChanges lists the dirty blocks in order, each with the bounds of exactly the voxels
/// whose material or samples changed where a leaf stays a leaf, and the whole block elsewhere. Returns
/// how many changes cover only part of their block.
std::size_t checkBlockChanges(const Volume& before, const Volume& after, const EditStats& stats)
{
    REQUIRE(stats.blockChanges.size() == stats.dirtyBlocks.size());
    using EdgeId = std::tuple<int, int, int, int>;
    auto samplesOf = [](const Volume& v) {
        std::map<EdgeId, std::array<uint16_t, 3>> out;
        for (const EdgeRecord& e : collectEdges(v))
            out[{e.voxel[0], e.voxel[1], e.voxel[2], e.axis}] = {e.sample.offset, e.sample.normalU, e.sample.normalV};
        return out;
    };
    const auto samplesBefore = samplesOf(before), samplesAfter = samplesOf(after);
    auto sampleAt = [](const auto& samples, const EdgeId& id) {
        const auto it = samples.find(id);
        return it == samples.end() ? std::optional<std::array<uint16_t, 3>>() : it->second;
    };
    const std::vector<Coord3> leavesBefore = leafOrigins(before), leavesAfter = leafOrigins(after);
    auto isLeaf = [](const std::vector<Coord3>& sorted, const Coord3& b) { return std::binary_search(sorted.begin(), sorted.end(), b); };
    std::size_t partial = 0;
    for (std::size_t i = 0; i < stats.blockChanges.size(); ++i) {
        const BlockChange& change = stats.blockChanges[i];
        const Coord3 b = change.origin;
        REQUIRE(b == stats.dirtyBlocks[i]);
        Coord3 lo{kLeafDim - 1, kLeafDim - 1, kLeafDim - 1}, hi{0, 0, 0};
        if (isLeaf(leavesBefore, b) && isLeaf(leavesAfter, b)) {
            for (int x = 0; x < kLeafDim; ++x)
                for (int y = 0; y < kLeafDim; ++y)
                    for (int z = 0; z < kLeafDim; ++z) {
                        const Coord3 voxel{b[0] + x, b[1] + y, b[2] + z};
                        bool differs = before.materialAt(voxel) != after.materialAt(voxel);
                        for (int axis = 0; axis < 3 && !differs; ++axis) {
                            const EdgeId id{voxel[0], voxel[1], voxel[2], axis};
                            differs = sampleAt(samplesBefore, id) != sampleAt(samplesAfter, id);
                        }
                        if (!differs) continue;
                        const Coord3 local{x, y, z};
                        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], local[a]), hi[a] = std::max(hi[a], local[a]);
                    }
        } else {
            lo = {0, 0, 0};
            hi = {kLeafDim - 1, kLeafDim - 1, kLeafDim - 1};
        }
        INFO("block " << b[0] << " " << b[1] << " " << b[2]);
        for (int a = 0; a < 3; ++a) {
            CHECK(int(change.min[a]) == lo[a]);
            CHECK(int(change.max[a]) == hi[a]);
        }
        if (hi[0] - lo[0] < kLeafDim - 1 || hi[1] - lo[1] < kLeafDim - 1 || hi[2] - lo[2] < kLeafDim - 1) ++partial;
    }
    return partial;
}

/// The dirty-block contract of EditStats: every listed block changed, and every changed block that was
/// a leaf before, or has a leaf in its 3x3x3 neighbourhood after, is listed. Returns how many changed
/// blocks the contract required to be listed.
std::size_t checkDirtyBlocks(const Volume& before, const Volume& after, const EditStats& stats)
{
    const std::vector<Coord3> dirty = sortedUnique(stats.dirtyBlocks);
    const std::vector<Coord3> changed = changedBlocks(before, after);
    const std::vector<Coord3> leavesBefore = leafOrigins(before), leavesAfter = leafOrigins(after);
    auto contains = [](const std::vector<Coord3>& sorted, const Coord3& b) {
        return std::binary_search(sorted.begin(), sorted.end(), b);
    };
    auto leafAround = [&](const Coord3& b) {
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    if (contains(leavesAfter, {b[0] + 8 * dx, b[1] + 8 * dy, b[2] + 8 * dz})) return true;
        return false;
    };
    std::size_t missing = 0, required = 0;
    for (const Coord3& b : changed) {
        if (!contains(leavesBefore, b) && !leafAround(b)) continue;
        ++required;
        if (!contains(dirty, b)) ++missing;
    }
    CHECK(missing == 0);
    CHECK(std::includes(changed.begin(), changed.end(), dirty.begin(), dirty.end()));
    return required;
}

} // namespace

TEST_CASE("an edit reports the blocks whose content changed and that a mesh reads", "[csg][dirty]")
{
    Volume v(1.0);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f);
    apply(v, CsgMode::Add, sphere(30.0), at(kC));
    struct Step {
        const char* name;
        CsgMode mode;
        Brush brush;
    };
    const std::vector<Step> steps = {
        {"remove at the surface", CsgMode::Remove, Brush(sphere(9.0), at({29.0, 3.0, -2.0}))},
        {"the same remove again", CsgMode::Remove, Brush(sphere(9.0), at({29.0, 3.0, -2.0}))},
        {"add a rotated box", CsgMode::Add, Brush(box({10.0, 4.0, 6.0}), at({-20.0, 20.0, 5.0}, {20.0, 35.0, 10.0}))},
        {"paint across the surface", CsgMode::Paint, Brush(sphere(12.0), at({0.0, -30.0, 0.0}))},
        {"erode", CsgMode::Erode, Brush(sphere(8.0), at({0.0, 0.0, 30.0}))},
        {"intersect with a large sphere", CsgMode::Intersect, Brush(sphere(34.0), at({3.0, 0.0, 0.0}))},
    };
    for (const Step& step : steps) {
        INFO(step.name);
        const Volume before = v.clone();
        const EditStats stats = applyCsg(v, step.brush, op(step.mode, step.mode == CsgMode::Paint ? stone : 1));
        const std::size_t required = checkDirtyBlocks(before, v, stats);
        const std::size_t partial = checkBlockChanges(before, v, stats);
        if (std::string(step.name) == "the same remove again") {
            CHECK(stats.dirtyBlocks.empty());
        } else {
            CHECK(required > 0);
            // A brush at the surface changes only part of some of the blocks it reaches.
            CHECK(partial > 0);
            // Fewer blocks than the CSG kernel looked at: the brush's bounding box is not the change.
            CHECK(stats.dirtyBlocks.size() < stats.blocksComputed + stats.tilesWritten);
        }
    }
}

TEST_CASE("a 128^3 node that becomes a tile reports the blocks on its faces that leaves border", "[csg][dirty]")
{
    // A sphere that covers the node [0, 128)^3 turns it into one tile; the sphere's surface passes just
    // beyond the node's corners, so leaves there border blocks on the node's faces.
    Volume v(1.0);
    apply(v, CsgMode::Add, box({10.0, 10.0, 10.0}), at({-20.0, 64.0, 64.0}));
    const Volume before = v.clone();
    const EditStats stats = applyCsg(v, Brush(sphere(120.0), at({64.0, 64.0, 64.0})), op(CsgMode::Add));
    std::size_t faceBlocks = 0;
    for (const Coord3& b : sortedUnique(stats.dirtyBlocks)) {
        const bool inNode = std::all_of(b.begin(), b.end(), [](int c) { return c >= 0 && c < 128; });
        if (inNode) ++faceBlocks;
    }
    CHECK(faceBlocks > 0);
    checkDirtyBlocks(before, v, stats);
    checkBlockChanges(before, v, stats);
    // The listed blocks follow the surface: the changed tiles deep inside the sphere are left out.
    const std::size_t changed = changedBlocks(before, v).size();
    INFO(stats.dirtyBlocks.size() << " dirty of " << changed << " changed blocks");
    CHECK(2 * sortedUnique(stats.dirtyBlocks).size() < changed);
}

TEST_CASE("brushes that do not reach the solid change nothing", "[csg]")
{
    Volume a(1.0);
    const MaterialId stone = defineMaterial(a, "stone", 0.9f);
    apply(a, CsgMode::Add, sphere(12.0), at(kC), stone);
    apply(a, CsgMode::Add, box({4.0, 4.0, 4.0}), at({14.0, 0.0, 0.0}));
    Volume b = a.clone();
    apply(b, CsgMode::Remove, sphere(5.0), at({40.0, 0.0, 0.0}));
    CHECK(identical(a, b));
    apply(b, CsgMode::Paint, sphere(5.0), at({0.0, 30.0, 0.0}), 1);
    CHECK(identical(a, b));
    apply(b, CsgMode::Intersect, sphere(40.0), at(Vec3d(0.0))); // encloses everything
    CHECK(identical(a, b));
    applyCsg(b, Brush(sphere(5.0), at({0.0, -30.0, 0.0})), op(CsgMode::Erode));
    CHECK(identical(a, b));
}

TEST_CASE("adding or painting a solid's own material inside it computes no block, another material does", "[csg][add]")
{
    Volume a(1.0);
    const MaterialId red = defineMaterial(a, "red", 0.5f);
    apply(a, CsgMode::Add, box({40.0, 40.0, 40.0}), at({0.3, -0.2, 0.1}));
    const Vec3d inside(5.5, -3.25, 2.0);
    for (const CsgMode mode : {CsgMode::Add, CsgMode::Paint}) {
        INFO(csgModeName(mode));
        Volume b = a.clone();
        // The sphere lies inside the box, across tiles only: nothing there can change.
        const EditStats same = apply(b, mode, sphere(20.0), at(inside), 1);
        CHECK(same.blocksComputed == 0);
        CHECK(same.tilesWritten == 0);
        CHECK(identical(a, b));
        const EditStats other = apply(b, mode, sphere(20.0), at(inside), red);
        CHECK(other.blocksComputed > 0);
        CHECK(b.materialAt({5, -3, 2}) == red);
        CHECK(b.materialAt({5, -3, 23}) == 1);
        CHECK(checkInvariants(b) == "");
    }
}

TEST_CASE("paint changes materials and keeps every surface crossing bit-exact", "[csg][paint]")
{
    Volume v(1.0);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f);
    const MaterialId red = defineMaterial(v, "red", 0.3f, {0.9f, 0.1f, 0.1f, 1.0f});
    apply(v, CsgMode::Add, sphere(14.0), at(kC), stone);
    apply(v, CsgMode::Add, box({5.0, 5.0, 5.0}, 1.0), at({13.0, 0.0, 0.0}, {0.0, 0.0, 20.0}), 1);
    REQUIRE(checkInvariants(v) == "");
    const Volume before = v.clone();
    const std::vector<EdgeRecord> edgesBefore = collectEdges(before);

    // A stroke across the surface, then a stamp that straddles both materials.
    applyCsg(v, SweptBrush(Brush(sphere(5.0), at(Vec3d(0.0))), {{0.0, 14.0, 0.0}, {0.0, 0.0, 14.0}}),
             op(CsgMode::Paint, red));
    apply(v, CsgMode::Paint, sphere(6.0), at({9.0, 3.0, 0.0}), red);
    REQUIRE(checkInvariants(v) == "");

    // Some voxels, on the surface and inside, carry the new id.
    const auto counts = solidVoxelsPerMaterial(v);
    CHECK(counts[red] > 200);
    CHECK(v.materialAt({0, 13, 0}) == red);
    CHECK(v.materialAt({0, 10, 4}) == red);

    // No voxel changed occupancy.
    const VolumeStats s = before.stats();
    int occupancyChanged = 0, materialChanged = 0;
    for (int i = s.bboxMin[0] - 2; i <= s.bboxMax[0] + 2; ++i)
        for (int j = s.bboxMin[1] - 2; j <= s.bboxMax[1] + 2; ++j)
            for (int k = s.bboxMin[2] - 2; k <= s.bboxMax[2] + 2; ++k) {
                const MaterialId m0 = before.materialAt({i, j, k}), m1 = v.materialAt({i, j, k});
                if ((m0 != kEmptyMaterial) != (m1 != kEmptyMaterial)) ++occupancyChanged;
                if (m0 != m1) {
                    ++materialChanged;
                    CHECK(m1 == red);
                }
            }
    CHECK(occupancyChanged == 0);
    CHECK(materialChanged > 200);
    CHECK(v.stats().bboxMin == s.bboxMin);
    CHECK(v.stats().bboxMax == s.bboxMax);

    // Every solid/empty crossing keeps its sample bit for bit.
    std::map<std::tuple<int32_t, int32_t, int32_t, int>, EdgeRecord> after;
    for (const EdgeRecord& e : collectEdges(v)) after[{e.voxel[0], e.voxel[1], e.voxel[2], e.axis}] = e;
    int surfaceEdges = 0, lost = 0, changed = 0;
    for (const EdgeRecord& e : edgesBefore) {
        if (!e.crossesSurface()) continue;
        ++surfaceEdges;
        const auto it = after.find({e.voxel[0], e.voxel[1], e.voxel[2], e.axis});
        if (it == after.end() || !it->second.crossesSurface()) {
            ++lost;
            continue;
        }
        if (it->second.sample != e.sample) ++changed;
    }
    int surfaceEdgesAfter = 0;
    for (const auto& entry : after) surfaceEdgesAfter += entry.second.crossesSurface() ? 1 : 0;
    INFO("surface edges lost " << lost << ", changed " << changed);
    CHECK(lost == 0);
    CHECK(changed == 0);
    CHECK(surfaceEdgesAfter == surfaceEdges);

    // The mesh has the same shape: same closedness and the same enclosed volume to rounding.
    const MeshReport r0 = meshReport(before), r1 = meshReport(v);
    CHECK(r1.topology.watertight());
    CHECK(r1.triangles == r0.triangles);
    CHECK(r1.volume == Approx(r0.volume).epsilon(1e-9));
}

TEST_CASE("a script gives the same volume with 1 and 2 threads", "[csg][threads]")
{
    const StrokeScript script = parseStrokeScript(kExampleScript);
    auto run = [&](std::size_t threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        Volume v(0.5); // brush sizes are world units: radius 20 is 40 voxels here
        runStrokeScript(v, script);
        return v;
    };
    const Volume one = run(1);
    const Volume two = run(2);
    REQUIRE_FALSE(one.stats().empty);
    CHECK(checkInvariants(one) == "");
    CHECK(identical(one, two));
    const Volume twoAgain = run(2);
    CHECK(identical(two, twoAgain));
}

TEST_CASE("a fast stroke leaves no gaps", "[csg][stroke]")
{
    const double r = 3.0;
    const std::pair<Vec3d, Vec3d> paths[] = {
        {{-20.0, 0.3, 0.2}, {20.0, 0.3, 0.2}},                          // along x
        {{-11.0, -13.0, 7.0}, {-11.0 + 23.0, -13.0 + 28.0, 7.0 + 18.0}}, // oblique, length ~40.6
    };
    for (const auto& path : paths) {
        const Vec3d a = path.first, b = path.second; // plain variables: lambdas below capture them
        INFO("path " << a << " -> " << b);
        const double L = (b - a).length();
        REQUIRE(L >= 40.0);
        Volume v(1.0);
        applyCsg(v, SweptBrush(Brush(sphere(r), at(Vec3d(0.0))), {a, b}), op(CsgMode::Add));
        REQUIRE(checkInvariants(v) == "");

        auto segmentDistance = [&](const Vec3d& p) {
            const Vec3d ab = b - a;
            const double t = std::clamp((p - a).dot(ab) / ab.dot(ab), 0.0, 1.0);
            return (p - (a + ab * t)).length();
        };
        int gaps = 0, overshoot = 0, inner = 0;
        for (int i = int(std::floor(std::min(a.x(), b.x()) - r)) - 1; i <= int(std::ceil(std::max(a.x(), b.x()) + r)) + 1; ++i)
            for (int j = int(std::floor(std::min(a.y(), b.y()) - r)) - 1; j <= int(std::ceil(std::max(a.y(), b.y()) + r)) + 1; ++j)
                for (int k = int(std::floor(std::min(a.z(), b.z()) - r)) - 1; k <= int(std::ceil(std::max(a.z(), b.z()) + r)) + 1; ++k) {
                    const double d = segmentDistance(Vec3d(i, j, k));
                    const bool solid = v.materialAt({i, j, k}) != kEmptyMaterial;
                    if (d < r - 0.5) {
                        ++inner;
                        if (!solid) ++gaps;
                    }
                    if (d > r + 0.5 && solid) ++overshoot;
                }
        INFO("voxels that must be solid " << inner);
        CHECK(inner > 700);
        CHECK(gaps == 0);
        CHECK(overshoot == 0);
        checkClosedMesh(v, kPi * r * r * (4.0 * r / 3.0 + L), 0.03);
    }
}

TEST_CASE("erosion follows the documented rule: soft material goes faster than tough", "[csg][erode]")
{
    Volume v(1.0);
    const float toughness[3] = {0.1f, 0.9f, 1.0f};
    MaterialId ids[3];
    ids[0] = defineMaterial(v, "soft", toughness[0]);
    ids[1] = defineMaterial(v, "tough", toughness[1]);
    ids[2] = defineMaterial(v, "unerodable", toughness[2]);
    const double xs[3] = {-30.0, 0.0, 30.0};
    for (int m = 0; m < 3; ++m) apply(v, CsgMode::Add, sphere(10.0), at(kC + Vec3d(xs[m], 0.0, 0.0)), ids[m]);
    const Volume before = v.clone();
    const auto countsBefore = solidVoxelsPerMaterial(before);

    // One stroke across the tops of all three spheres.
    const double brushRadius = 8.0, strength = 1.0;
    const SweptBrush stroke(Brush(sphere(brushRadius), at(Vec3d(0.0))),
                            {kC + Vec3d(-40.0, 10.0, 0.0), kC + Vec3d(40.0, 10.0, 0.0)});
    REQUIRE(stroke.innerRadius() == brushRadius);
    applyCsg(v, stroke, op(CsgMode::Erode, 1, strength));
    REQUIRE(checkInvariants(v) == "");
    const auto countsAfter = solidVoxelsPerMaterial(v);

    // Voxel by voxel: removed exactly where d < -(1 - s (1 - toughness)) r (Csg.h).
    int mismatches = 0;
    const VolumeStats s = before.stats();
    for (int i = s.bboxMin[0]; i <= s.bboxMax[0]; ++i)
        for (int j = s.bboxMin[1]; j <= s.bboxMax[1]; ++j)
            for (int k = s.bboxMin[2]; k <= s.bboxMax[2]; ++k) {
                const MaterialId m = before.materialAt({i, j, k});
                if (m == kEmptyMaterial) continue;
                const double t = v.materials().at(m).toughness;
                const double d = stroke.distance(Vec3d(i, j, k));
                const bool removed = d + (1.0 - strength * (1.0 - t)) * brushRadius < 0.0;
                const MaterialId expected = removed ? kEmptyMaterial : m;
                if (v.materialAt({i, j, k}) != expected) ++mismatches;
            }
    CHECK(mismatches == 0);

    const uint64_t removedSoft = countsBefore[ids[0]] - countsAfter[ids[0]];
    const uint64_t removedTough = countsBefore[ids[1]] - countsAfter[ids[1]];
    const uint64_t removedHard = countsBefore[ids[2]] - countsAfter[ids[2]];
    INFO("removed voxels: soft " << removedSoft << ", tough " << removedTough << ", unerodable " << removedHard);
    CHECK(removedSoft > 300);
    CHECK(removedSoft > 20 * std::max<uint64_t>(removedTough, 1));
    CHECK(removedHard == 0);

    // The eroded volume still meshes closed, and it lost volume.
    const MeshReport r0 = meshReport(before), r1 = meshReport(v);
    CHECK(r1.topology.watertight());
    CHECK(r1.volume < r0.volume - 0.8 * double(removedSoft));
}

TEST_CASE("erosion that cannot bite changes nothing", "[csg][erode]")
{
    Volume v(1.0);
    const MaterialId hard = defineMaterial(v, "unerodable", 1.0f);
    apply(v, CsgMode::Add, sphere(10.0), at(kC), hard);
    apply(v, CsgMode::Add, sphere(6.0), at(kC + Vec3d(12.0, 0.0, 0.0)), 1);
    const Volume before = v.clone();
    SECTION("toughness 1 at full strength")
    {
        applyCsg(v, Brush(sphere(8.0), at(kC + Vec3d(-4.0, 8.0, 0.0))), op(CsgMode::Erode, 1, 1.0));
        CHECK(identical(before, v));
    }
    SECTION("strength 0 on soft and hard material")
    {
        applyCsg(v, Brush(sphere(8.0), at(kC + Vec3d(8.0, 4.0, 0.0))), op(CsgMode::Erode, 1, 0.0));
        CHECK(identical(before, v));
    }
    SECTION("an explicit depth below the brush's inner radius")
    {
        // The rule removes what lies deeper than the depth; toughness 1 and strength 0 must still
        // remove nothing, even where the brush reaches deeper than that.
        CsgOp shallow = op(CsgMode::Erode, 1, 1.0);
        shallow.erodeDepth = 2.0;
        applyCsg(v, Brush(sphere(8.0), at(kC + Vec3d(-4.0, 8.0, 0.0))), shallow);
        CHECK(identical(before, v));
        shallow.strength = 0.0;
        applyCsg(v, Brush(sphere(8.0), at(kC + Vec3d(8.0, 4.0, 0.0))), shallow);
        CHECK(identical(before, v));
    }
}

TEST_CASE("every brush shape alone gives a closed mesh of the analytic volume", "[csg][shapes]")
{
    struct Case {
        const char* name;
        Primitive primitive;
        Vec3d rotation;
        double volume;
    };
    const double rb = 2.0;
    const Vec3d hb(10.0, 8.0, 6.0);
    const Vec3d core = (hb - Vec3d(rb)) * 2.0; // edge lengths of the box the rounding grows from
    const double roundedBox = core.x() * core.y() * core.z() +
                              2.0 * (core.x() * core.y() + core.y() * core.z() + core.z() * core.x()) * rb +
                              kPi * rb * rb * (core.x() + core.y() + core.z()) + sphereVolume(rb);
    const Case cases[] = {
        {"sphere", sphere(12.0), Vec3d(0.0), sphereVolume(12.0)},
        {"rounded box", box(hb, rb), Vec3d(10.0, 20.0, 30.0), roundedBox},
        {"cylinder", cylinder(9.0, 20.0), Vec3d(30.0, 0.0, 15.0), kPi * 81.0 * 20.0},
        {"capsule", capsule(6.0, 16.0), Vec3d(0.0, 0.0, 40.0), kPi * 36.0 * (4.0 * 6.0 / 3.0 + 16.0)},
        {"torus", torus(11.0, 4.0), Vec3d(20.0, 0.0, 0.0), 2.0 * kPi * kPi * 11.0 * 16.0},
        {"cone", cone(12.0, 20.0), Vec3d(0.0, 30.0, 10.0), kPi * 144.0 * 20.0 / 3.0},
    };
    for (const Case& c : cases) {
        INFO(c.name);
        Volume v(1.0);
        const Brush brush(c.primitive, at(kC, c.rotation));
        applyCsg(v, brush, op(CsgMode::Add));
        // The voxels are exactly the centres inside the brush.
        CHECK(countSolidityMismatches(v, brush, {-20, -20, -20}, {20, 20, 20}) == 0);
        checkClosedMesh(v, c.volume, 0.03);
    }
}

TEST_CASE("world units follow the voxel size", "[csg][shapes]")
{
    Volume v(0.5);
    apply(v, CsgMode::Add, sphere(6.0), at({0.05, 0.1, 0.15})); // 12 voxels
    // Solid where |0.5 i - 0.05| < 6: i from -11 to 12 on the x axis.
    CHECK(v.materialAt({-11, 0, 0}) == 1);
    CHECK(v.materialAt({-12, 0, 0}) == kEmptyMaterial);
    CHECK(v.materialAt({12, 0, 0}) == 1);
    CHECK(v.materialAt({13, 0, 0}) == kEmptyMaterial);
    checkClosedMesh(v, sphereVolume(6.0), 0.01);
}

TEST_CASE("a composite blend brush gives a closed mesh", "[csg][blend]")
{
    std::vector<BrushPart> parts(3);
    parts[0].primitive = sphere(9.0);
    parts[1].primitive = box({5.0, 5.0, 5.0});
    parts[1].placement = at({8.0, 0.0, 0.0}, {0.0, 0.0, 45.0});
    parts[1].op = PartOp::Remove;
    parts[2].primitive = cylinder(3.0, 24.0);
    parts[2].placement = at({-2.0, 0.0, 0.0}, {90.0, 0.0, 0.0});
    Volume v(1.0);
    const Brush brush(parts, 2.0, at(kC, {0.0, 10.0, 0.0}, {1.0, 1.3, 1.0}));
    applyCsg(v, brush, op(CsgMode::Add));
    CHECK(countSolidityMismatches(v, brush, {-20, -20, -20}, {20, 20, 20}) == 0);
    REQUIRE(checkInvariants(v) == "");
    const MeshReport r = meshReport(v);
    CHECK(r.topology.watertight());
    // Bounded by the union of the added parts (scaled) and larger than the sphere minus the box.
    CHECK(r.volume > 0.5 * sphereVolume(9.0));
    CHECK(r.volume < 1.3 * (sphereVolume(9.0) + kPi * 9.0 * 24.0));
}

TEST_CASE("applyCsg rejects ops that make no sense", "[csg]")
{
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(5.0), at(Vec3d(0.0)));
    const Volume before = v.clone();
    const Brush b(sphere(3.0), at({4.0, 0.0, 0.0}));
    CHECK_THROWS_AS(applyCsg(v, b, op(CsgMode::Add, 7)), std::invalid_argument);
    CHECK_THROWS_AS(applyCsg(v, b, op(CsgMode::Paint, 0)), std::invalid_argument);
    CHECK_THROWS_AS(applyCsg(v, b, op(CsgMode::Erode, 1, 1.5)), std::invalid_argument);
    CHECK_THROWS_AS(applyCsg(v, b, op(CsgMode::Erode, 1, -0.1)), std::invalid_argument);
    CHECK_THROWS_AS(applyCsg(v, Brush(halfSpace({1.0, 0.0, 0.0}), at(Vec3d(0.0))), op(CsgMode::Add)),
                    std::invalid_argument);
    CHECK(identical(before, v));
}

TEST_CASE("a tangled stroke's distance is the nearest segment's where it matters, a bound below it elsewhere", "[csg][stroke]")
{
    // Long random segments crossing one region many times: its cells hold hundreds of pieces and are split.
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> coordinate(-40.0, 40.0);
    std::vector<Vec3d> path;
    for (int i = 0; i < 300; ++i) path.emplace_back(coordinate(random), coordinate(random), coordinate(random));
    const double radius = 3.0;
    const SweptBrush swept(Brush(sphere(radius), at(Vec3d(0.0))), path);
    const auto exact = [&](const Vec3d& x) {
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i + 1 < path.size(); ++i) {
            const Vec3d ab = path[i + 1] - path[i];
            const double t = std::clamp((x - path[i]).dot(ab) / ab.lengthSqr(), 0.0, 1.0);
            best = std::min(best, (x - (path[i] + ab * t)).length() - radius);
        }
        return best;
    };
    // Below the smallest distance the grid may stop at: half a sub-cell (a sixth of the two-reach cell).
    const double floorDistance = 0.25 * radius;
    int near = 0;
    for (int n = 0; n < 20000; ++n) {
        const Vec3d x(coordinate(random), coordinate(random), coordinate(random));
        const double d = swept.distance(x), e = exact(x);
        INFO("at " << x << ": " << d << " against " << e);
        if (e < floorDistance) {
            CHECK(std::fabs(d - e) < 1e-9);
            ++near;
        } else {
            CHECK(d <= e + 1e-9);
            CHECK(d >= floorDistance - 1e-9);
        }
    }
    CHECK(near > 5000);
}
