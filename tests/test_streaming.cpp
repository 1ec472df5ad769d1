// Streaming a store by view under a memory budget: which bricks a view selects, the budget held over a
// flight, dirty bricks that survive eviction, a budget too small for one brick, and autosave against
// SIGKILL at random moments.
#include "mesher/MeshMetrics.h"
#include "render/BrickMeshWorkers.h"
#include "render/Renderer.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/StreamingScene.h"
#include "scene/Synthesize.h"
#include "scene/ViewSelection.h"
#include "sculpt/StrokeScript.h"
#include "support/CliRun.h"
#include "support/HermiteProbe.h"
#include "support/PyramidCompare.h"
#include "support/TerrainStore.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeRegions.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <map>
#include <memory>
#include <limits>
#include <optional>
#include <random>
#include <set>
#include <thread>
#include <unordered_set>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// A terrain store of 256 voxels with its levels of detail.
std::string makeTerrain(const TempDir& dir, const std::string& name = "t.vdbclay")
{
    return terrainStore(dir, name, 256, 6, 3);
}

Viewer lookingAt(const std::array<double, 3>& from, const std::array<double, 3>& to)
{
    Viewer v;
    v.position = from;
    v.target = to;
    return v;
}

/// A view from just above the terrain's middle, and a budget that holds all it asks for.
Viewer groundView() { return lookingAt({128, 40, 128}, {129, 30, 128}); }
/// Frames (waiting for the loads) until the view is settled and nothing is pending.
void settleView(StreamingScene& scene, const Viewer& view)
{
    FrameReport report;
    for (int i = 0; i < 50 && !(report.settled && report.pending == 0); ++i) {
        report = scene.frame(view);
        scene.waitForLoads();
    }
}

StreamingOptions roomyOptions()
{
    StreamingOptions options;
    options.memoryBudgetBytes = 256ull << 20;
    return options;
}

/// A roomy budget, and edits allowed.
StreamingOptions roomyEditableOptions()
{
    StreamingOptions options = roomyOptions();
    options.access = StoreAccess::ReadWrite;
    return options;
}

std::string stampScript(int count, uint64_t seed, double from = 8.0, double to = 248.0)
{
    std::mt19937 rng{unsigned(seed)};
    std::uniform_real_distribution<double> xz(from, to), y(20.0, 50.0), r(2.0, 6.0);
    nlohmann::json ops = nlohmann::json::array();
    for (int i = 0; i < count; ++i)
        ops.push_back({{"mode", i % 3 == 2 ? "remove" : "add"}, {"brush", {{"shape", "sphere"}, {"radius", r(rng)}}},
                       {"at", {xz(rng), y(rng), xz(rng)}}});
    return nlohmann::json{{"ops", ops}}.dump();
}

} // namespace

TEST_CASE("a view selects coarse bricks far away and fine ones close by, only in its frustum", "[streaming]")
{
    std::vector<std::set<IndexCoord>> stored(3);
    for (int x = 0; x < 8; ++x)
        for (int z = 0; z < 8; ++z) stored[0].insert({x, 0, z});
    for (const IndexCoord& b : stored[0]) stored[1].insert(parentBrick(b));
    for (const IndexCoord& b : stored[1]) stored[2].insert(parentBrick(b));
    SelectionOptions options;
    options.levels = 2;
    options.pixelTolerance = 1.0;
    // Far away: the coarsest level everywhere.
    const auto far = selectBricks(lookingAt({256, 30, 200000}, {256, 30, 256}), options, stored);
    REQUIRE(!far.empty());
    for (const SelectedBrick& b : far) CHECK(b.key.level == 2);
    // Close by: level 0 next to the eye, every selected brick within the tolerance or at level 0.
    const auto near = selectBricks(lookingAt({40, 30, 40}, {400, 30, 400}), options, stored);
    bool fine = false;
    for (const SelectedBrick& b : near) {
        fine = fine || b.key.level == 0;
        CHECK((b.key.level == 0 || b.screenError <= options.pixelTolerance));
    }
    CHECK(fine);
    // From the middle of the lattice looking along +x: no brick wholly behind the eye is selected, and
    // the bricks straight ahead are.
    const auto middle = selectBricks(lookingAt({256, 30, 288}, {600, 30, 288}), options, stored);
    bool ahead = false;
    for (const SelectedBrick& b : middle) {
        const int edge = 64 << b.key.level, scale = 1 << b.key.level;
        CHECK((b.key.brick[0] + 1) * edge >= 256); // its box reaches the eye's plane or beyond
        ahead = ahead || (b.key.brick[0] == 6 / scale && b.key.brick[2] == 4 / scale);
    }
    CHECK(ahead);
    // Each region is selected at one level only.
    std::set<IndexCoord> covered;
    for (const SelectedBrick& b : near) {
        const int scale = 1 << b.key.level;
        for (int x = 0; x < scale; ++x)
            for (int z = 0; z < scale; ++z) {
                const IndexCoord fine0{b.key.brick[0] * scale + x, 0, b.key.brick[2] * scale + z};
                if (stored[0].count(fine0)) CHECK(covered.insert(fine0).second);
            }
    }
    CHECK_THROWS_AS(selectBricks(lookingAt({1, 2, 3}, {1, 2, 3}), options, stored), std::invalid_argument);
}

namespace {

/// The renderer's matrix for a viewer (what a frame drawn from it would have used).
std::array<double, 16> drawnWith(const Viewer& v)
{
    render::Camera c;
    c.eye = v.position;
    c.target = v.target;
    c.fovYDegrees = v.fovDegrees;
    c.nearPlane = 0.5;
    return render::viewProjectionExact(c, double(v.viewport[0]) / double(v.viewport[1]));
}

/// Whether a box lies behind every tile its projected corners' outline covers, read tile by tile.
bool hiddenTileByTile(const std::array<double, 16>& m, int columns, int rows, const std::vector<float>& farthest,
                      const std::array<double, 3>& lo, const std::array<double, 3>& hi)
{
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, nearest = 1e300;
    for (int c = 0; c < 8; ++c) {
        const double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
        double clip[4];
        for (int i = 0; i < 4; ++i) clip[i] = m[std::size_t(i)] * p[0] + m[std::size_t(4 + i)] * p[1] + m[std::size_t(8 + i)] * p[2] + m[std::size_t(12 + i)];
        if (clip[3] <= 0.0) return false;
        x0 = std::min(x0, clip[0] / clip[3]), x1 = std::max(x1, clip[0] / clip[3]);
        y0 = std::min(y0, clip[1] / clip[3]), y1 = std::max(y1, clip[1] / clip[3]);
        nearest = std::min(nearest, clip[3]);
    }
    if (x1 < -1.0 || x0 > 1.0 || y1 < -1.0 || y0 > 1.0) return false;
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < columns; ++c) {
            // The tile's span in NDC overlaps the outline.
            const double tx0 = 2.0 * c / columns - 1.0, tx1 = 2.0 * (c + 1) / columns - 1.0;
            const double ty0 = 2.0 * r / rows - 1.0, ty1 = 2.0 * (r + 1) / rows - 1.0;
            if (tx1 < x0 || tx0 > x1 || ty1 < y0 || ty0 > y1) continue;
            if (!(nearest > double(farthest[std::size_t(r * columns + c)]))) return false;
        }
    return true;
}

} // namespace

TEST_CASE("occluder depth: a box is hidden only when it lies in the picture behind every tile it covers", "[streaming][occlusion]")
{
    // Looking down -z from the origin; a wall drawn 100 away over the whole picture but for a window.
    const Viewer view = lookingAt({0, 0, 0}, {0, 0, -1});
    const auto m = drawnWith(view);
    const int columns = 48, rows = 27;
    std::vector<float> wall(std::size_t(columns * rows), 100.0f);
    // The window: tiles 30..33 x 5..7 (right of centre, near the top) see nothing.
    for (int r = 5; r <= 7; ++r)
        for (int c = 30; c <= 33; ++c) wall[std::size_t(r * columns + c)] = std::numeric_limits<float>::infinity();
    const OccluderDepth depth(m, columns, rows, wall);
    CHECK(depth.columns() == columns);
    CHECK(depth.rows() == rows);
    CHECK(depth.hides({-1, -1, -150}, {1, 1, -140}));    // behind the wall, in the middle
    CHECK(!depth.hides({-1, -1, -90}, {1, 1, -80}));     // before it
    CHECK(!depth.hides({-1, -1, -105}, {1, 1, -95}));    // through it
    CHECK(depth.hides({-500, -1, -150}, {500, 1, -140}));  // reaching beyond the picture: by the part within
    CHECK(!depth.hides({400, -1, -150}, {500, 1, -140}));  // wholly beyond it
    CHECK(!depth.hides({-1, -1, 5}, {1, 1, 6}));         // behind the eye
    CHECK(!depth.hides({-1, -1, -150}, {1, 1, 6}));      // reaching the eye's plane
    CHECK(!depth.hides({-1, -1, -150}, {1, 1, -1e-12})); // a hair in front of it: corners far off the picture
    CHECK(!OccluderDepth().hides({-1, -1, -150}, {1, 1, -140}));
    // Where the window's tiles lie: a box behind them shows through it, one as far beside it does not.
    const auto atTile = [&](int c, int r, double distance, double half) {
        // The ray through the tile's centre at `distance` along the view (y up in the world, down in NDC).
        const double tanY = std::tan(view.fovDegrees * M_PI / 360.0), tanX = tanY * 16.0 / 9.0;
        const double nx = (c + 0.5) / columns * 2.0 - 1.0, ny = (r + 0.5) / rows * 2.0 - 1.0;
        const std::array<double, 3> centre{nx * tanX * distance, -ny * tanY * distance, -distance};
        return std::make_pair(std::array<double, 3>{centre[0] - half, centre[1] - half, centre[2] - half},
                              std::array<double, 3>{centre[0] + half, centre[1] + half, centre[2] + half});
    };
    const auto [windowLo, windowHi] = atTile(31, 6, 300.0, 1.0);
    CHECK(!depth.hides(windowLo, windowHi));
    const auto [besideLo, besideHi] = atTile(20, 6, 300.0, 1.0);
    CHECK(depth.hides(besideLo, besideHi));
    // Seen also from another view (a headset's other eye): hidden only where each view hides it.
    OccluderDepth both = depth;
    both.alsoSeenFrom(OccluderDepth(m, columns, rows, std::vector<float>(wall.size(), 100.0f)));
    CHECK(both.hides(besideLo, besideHi));
    CHECK(!both.hides(windowLo, windowHi));
    OccluderDepth seenPast = depth;
    seenPast.alsoSeenFrom(OccluderDepth(m, columns, rows, std::vector<float>(wall.size(), std::numeric_limits<float>::infinity())));
    CHECK(!seenPast.hides(besideLo, besideHi));
    // A large box over many tiles is read through the coarser levels: hidden only where every tile is.
    CHECK(!depth.hides({-150, -80, -400}, {150, 80, -300}));
    CHECK(depth.hides({-150, -100, -400}, {0, 20, -300}));
    // Against a tile-by-tile reading on random depths and boxes: the coarser levels only ever hide less.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<float> random(wall.size());
    for (float& d : random) d = u(rng) < 0.05 ? std::numeric_limits<float>::infinity() : float(50.0 + 100.0 * u(rng));
    const OccluderDepth rough(m, columns, rows, random);
    int hidden = 0, agreed = 0;
    for (int i = 0; i < 2000; ++i) {
        const int c = int(u(rng) * columns), r = int(u(rng) * rows);
        const double distance = 60.0 + 200.0 * u(rng), half = 0.5 + 8.0 * u(rng) * u(rng);
        const auto [lo, hi] = atTile(c, r, distance, half);
        const bool byTiles = hiddenTileByTile(m, columns, rows, random, lo, hi);
        const bool byLevels = rough.hides(lo, hi);
        if (byLevels) CHECK(byTiles);
        hidden += byLevels;
        agreed += byLevels == byTiles;
    }
    INFO("hidden " << hidden << ", agreeing with the tiles " << agreed << " of 2000");
    CHECK(hidden > 100);
    CHECK(agreed > 1800);
    CHECK_THROWS_AS(OccluderDepth(m, 0, rows, {}), std::invalid_argument);
    CHECK_THROWS_AS(OccluderDepth(m, columns, rows, std::vector<float>(3, 1.0f)), std::invalid_argument);
    std::vector<float> negative = wall;
    negative[7] = -1.0f;
    CHECK_THROWS_AS(OccluderDepth(m, columns, rows, negative), std::invalid_argument);
    negative[7] = std::nanf("");
    CHECK_THROWS_AS(OccluderDepth(m, columns, rows, negative), std::invalid_argument);
}

TEST_CASE("a view leaves bricks hidden behind the last frame's depth coarse, covers the same ground, and refines them when told to", "[streaming][occlusion]")
{
    std::vector<std::set<IndexCoord>> stored(5);
    for (int x = 0; x < 32; ++x)
        for (int z = 0; z < 32; ++z) stored[0].insert({x, 0, z});
    for (int k = 1; k < 5; ++k)
        for (const IndexCoord& b : stored[std::size_t(k - 1)]) stored[std::size_t(k)].insert(parentBrick(b));
    const BrickPresence presence(stored);
    SelectionOptions options;
    options.levels = 4;
    const Viewer view = lookingAt({100, 40, 100}, {1000, 20, 900});
    const std::vector<SelectedBrick> open = selectBricks(view, options, presence);
    // A wall drawn 600 along the view over the whole picture.
    const std::array<double, 16> m = drawnWith(view);
    const OccluderDepth wall(m, 64, 36, std::vector<float>(64 * 36, 600.0f));
    options.occluders = &wall;
    const std::vector<SelectedBrick> walled = selectBricks(view, options, presence);
    // The level-0 bricks each selection covers, once each.
    const auto covered = [&](const std::vector<SelectedBrick>& selection) {
        std::multiset<IndexCoord> out;
        for (const SelectedBrick& b : selection) {
            const int scale = 1 << b.key.level;
            for (int x = 0; x < scale; ++x)
                for (int z = 0; z < scale; ++z) {
                    const IndexCoord fine{b.key.brick[0] * scale + x, 0, b.key.brick[2] * scale + z};
                    if (stored[0].count(fine)) out.insert(fine);
                }
        }
        return out;
    };
    // No hole, nothing twice (a hidden brick may also cover children the frustum left out).
    const auto openCover = covered(open), walledCover = covered(walled);
    CHECK(std::set<IndexCoord>(openCover.begin(), openCover.end()).size() == openCover.size());
    CHECK(std::set<IndexCoord>(walledCover.begin(), walledCover.end()).size() == walledCover.size());
    CHECK(std::includes(walledCover.begin(), walledCover.end(), openCover.begin(), openCover.end()));
    // Hidden bricks: coarser than before, wholly beyond the wall (grown by their voxel); the rest as before.
    std::size_t hidden = 0;
    const std::set<BrickKey> openKeys = [&] {
        std::set<BrickKey> k;
        for (const SelectedBrick& b : open) k.insert(b.key);
        return k;
    }();
    for (const SelectedBrick& b : walled) {
        if (!b.hidden) {
            CHECK(openKeys.count(b.key));
            continue;
        }
        ++hidden;
        CHECK(!openKeys.count(b.key));
        CHECK(b.key.level > 0);
        CHECK(b.screenError == 0.0);
        const double edge = 64.0 * double(1 << b.key.level), grow = double(1 << b.key.level);
        const std::array<double, 3> lo{b.key.brick[0] * edge - grow, b.key.brick[1] * edge - grow, b.key.brick[2] * edge - grow};
        const std::array<double, 3> hi{lo[0] + edge + 2 * grow, lo[1] + edge + 2 * grow, lo[2] + edge + 2 * grow};
        CHECK(hiddenTileByTile(m, 64, 36, std::vector<float>(64 * 36, 600.0f), lo, hi));
    }
    CHECK(hidden > 0);
    CHECK(walled.size() < open.size());
    // An empty depth hides nothing.
    const OccluderDepth none;
    options.occluders = &none;
    const std::vector<SelectedBrick> unhidden = selectBricks(view, options, presence);
    REQUIRE(unhidden.size() == open.size());
    for (std::size_t i = 0; i < open.size(); ++i) CHECK(unhidden[i].key == open[i].key);
    // Bricks to refine whatever their error (above edited data) are refined even when hidden.
    std::unordered_set<BrickKey, BrickKeyHash> always;
    for (const SelectedBrick& b : walled)
        if (b.hidden) always.insert(b.key);
    options.occluders = &wall;
    options.refineAlways = &always;
    for (const SelectedBrick& b : selectBricks(view, options, presence)) CHECK(!always.count(b.key));
}

TEST_CASE("brick presence: children and neighbour masks, ordered levels and additions equal a presence built afresh", "[streaming]")
{
    constexpr int kLevels = 4;
    std::mt19937 rng(20261206);
    std::uniform_int_distribution<int32_t> coord(-9, 9);
    const auto withParents = [](std::vector<std::set<IndexCoord>> stored) {
        for (std::size_t k = 1; k < stored.size(); ++k)
            for (const IndexCoord& b : stored[k - 1]) stored[k].insert(parentBrick(b));
        return stored;
    };
    const auto same = [&](const BrickPresence& p, const std::vector<std::set<IndexCoord>>& stored) {
        REQUIRE(p.levelCount() == int(stored.size()));
        for (int k = 0; k < p.levelCount(); ++k) {
            CAPTURE(k);
            CHECK(p.bricks(k) == std::vector<IndexCoord>(stored[std::size_t(k)].begin(), stored[std::size_t(k)].end()));
            for (const IndexCoord& b : stored[std::size_t(k)]) {
                CHECK(p.contains(k, b));
                uint8_t expected = 0;
                for (int c = 0; c < 8 && k > 0; ++c)
                    if (stored[std::size_t(k - 1)].count({2 * b[0] + (c & 1), 2 * b[1] + ((c >> 1) & 1), 2 * b[2] + ((c >> 2) & 1)}))
                        expected = uint8_t(expected | (1u << c));
                CHECK(int(p.children(k, b)) == int(expected));
                uint32_t around = 0;
                for (int d = 0; d < 27; ++d)
                    if (d != 13 && stored[std::size_t(k)].count(neighbourBrick(b, d))) around |= 1u << d;
                CHECK(p.neighbours(k, b) == around);
            }
            CHECK(p.neighbours(k, {1000, 0, 0}) == 0u);
        }
    };
    std::vector<std::set<IndexCoord>> stored(kLevels + 1);
    for (int i = 0; i < 60; ++i) stored[0].insert({coord(rng), coord(rng) / 3, coord(rng)});
    stored = withParents(stored);
    BrickPresence presence(stored);
    same(presence, stored);
    CHECK_FALSE(presence.contains(0, {100, 0, 0}));
    CHECK(presence.children(0, *stored[0].begin()) == 0); // level 0 has no children
    // Additions at level 0 (an edit in empty space) and at coarse levels (an LOD update), new or not.
    for (int i = 0; i < 200; ++i) {
        const int level = i % 5 == 4 ? 1 + int(rng() % kLevels) : 0;
        const IndexCoord b{coord(rng) * 2 >> level, coord(rng) >> level, coord(rng) * 2 >> level};
        const bool fresh = stored[std::size_t(level)].insert(b).second;
        CHECK(presence.add(level, b) == fresh);
        stored = withParents(stored);
    }
    same(presence, stored);
    CHECK_THROWS_AS(presence.add(kLevels + 1, {0, 0, 0}), std::invalid_argument);
}

TEST_CASE("what a view needs: each selected brick and its ancestors once, coarse first", "[streaming]")
{
    // A cut through a two-level pyramid: two level-0 bricks under level-1 brick (0,0,0), level-1 brick
    // (1,0,0), and level-0 brick (4,0,0) under level-1 (2,0,0) and level-2 (1,0,0).
    const std::vector<SelectedBrick> cut{{{0, {0, 0, 0}}}, {{0, {1, 0, 0}}}, {{1, {1, 0, 0}}}, {{0, {4, 0, 0}}}};
    const ViewNeeds needs = viewNeeds(cut, 2);
    const std::vector<BrickKey> bricks{{0, {0, 0, 0}}, {1, {0, 0, 0}}, {2, {0, 0, 0}}, {0, {1, 0, 0}},
                                       {1, {1, 0, 0}}, {0, {4, 0, 0}}, {1, {2, 0, 0}}, {2, {1, 0, 0}}};
    CHECK(needs.bricks == bricks);
    constexpr uint32_t none = ViewNeeds::kNone;
    CHECK(needs.parent == std::vector<uint32_t>{1, 2, none, 1, 2, 6, 7, none});
    CHECK(needs.selected == std::vector<uint32_t>{0, 3, 4, 5});
    CHECK(needs.order == std::vector<uint32_t>{2, 7, 1, 4, 6, 0, 3, 5});

    // The same properties on a real selection of a terrain-like lattice.
    std::vector<std::set<IndexCoord>> stored(4);
    for (int x = 0; x < 16; ++x)
        for (int z = 0; z < 16; ++z) stored[0].insert({x, 0, z});
    for (int k = 1; k < 4; ++k)
        for (const IndexCoord& b : stored[std::size_t(k - 1)]) stored[std::size_t(k)].insert(parentBrick(b));
    SelectionOptions options;
    options.levels = 3;
    const std::vector<SelectedBrick> selected = selectBricks(lookingAt({60, 30, 60}, {900, 10, 700}), options, stored);
    REQUIRE(selected.size() > 8);
    const ViewNeeds real = viewNeeds(selected, options.levels);
    CHECK(std::set<BrickKey>(real.bricks.begin(), real.bricks.end()).size() == real.bricks.size());
    for (std::size_t i = 0; i < selected.size(); ++i) CHECK(real.bricks[real.selected[i]] == selected[i].key);
    for (std::size_t n = 0; n < real.bricks.size(); ++n) {
        const BrickKey& b = real.bricks[n];
        if (b.level == options.levels) {
            CHECK(real.parent[n] == none);
            continue;
        }
        REQUIRE(real.parent[n] != none);
        CHECK(real.bricks[real.parent[n]] == BrickKey{b.level + 1, parentBrick(b.brick)});
    }
    std::vector<uint32_t> sorted = real.order;
    std::sort(sorted.begin(), sorted.end());
    for (uint32_t i = 0; i < sorted.size(); ++i) CHECK(sorted[i] == i);
    for (std::size_t i = 1; i < real.order.size(); ++i)
        CHECK(real.bricks[real.order[i - 1]].level >= real.bricks[real.order[i]].level);
}

TEST_CASE("streaming holds the memory budget over a flight, and a large budget refines the view", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    for (const uint64_t budgetMB : {2ull, 64ull}) {
        StreamingOptions options;
        options.memoryBudgetBytes = budgetMB << 20;
        StreamingScene scene(path, options);
        bool complete = false, limited = false, coarse = false;
        for (int i = 0; i < 24; ++i) {
            const double a = i / 24.0 * 3.14159;
            const FrameReport r = scene.frame(lookingAt({128 + 150 * std::cos(a), 90, 128 + 150 * std::sin(a)}, {128, 30, 128}));
            // Loads finish, and the next frames budget with what the loaded bricks really take: within a few
            // rounds everything the budget admits is resident.
            FrameReport settled;
            for (int round = 0; round < 8 && !settled.settled; ++round) {
                scene.waitForLoads();
                settled = scene.frame(lookingAt({128 + 150 * std::cos(a), 90, 128 + 150 * std::sin(a)}, {128, 30, 128}));
                CHECK(settled.residentBytes <= options.memoryBudgetBytes);
            }
            INFO("budget " << budgetMB << " MB, frame " << i);
            CHECK(r.residentBytes <= options.memoryBudgetBytes);
            CHECK(settled.residentBytes <= options.memoryBudgetBytes);
            CHECK(scene.residentBytes() <= options.memoryBudgetBytes);
            CHECK(settled.settled);
            CHECK(settled.pending == 0);
            complete = complete || settled.complete;
            limited = limited || settled.budgetLimited;
            coarse = coarse || settled.coarseComplete;
        }
        CHECK(coarse);
        if (budgetMB == 2) CHECK(limited);
        if (budgetMB == 64) CHECK(complete);
    }
    // What streams in is what the store holds.
    StreamingScene scene(path, roomyOptions());
    scene.frame(groundView());
    scene.waitForLoads();
    const Volume resident = scene.residentLevel0();
    const Volume stored = loadScene(path);
    for (const IndexCoord& b : occupiedBoxes(resident, kBrickEdge))
        CHECK_FALSE(compareRegion(resident, stored, {b, kBrickEdge}).any());
}

TEST_CASE("a frame reports what the view shows: nothing at first, then every brick at its own level", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    const Viewer view = groundView();
    const StreamingOptions options = roomyOptions();
    StreamingScene scene(path, options);
    const FrameReport first = scene.frame(view);
    REQUIRE(first.requested > 0);
    CHECK(first.hits == 0);
    CHECK_FALSE(first.coarseComplete);
    CHECK_FALSE(first.complete);
    CHECK(first.screenError == 0.0); // nothing shown
    CHECK(first.targetError > 0.0);
    scene.waitForLoads();
    const FrameReport loaded = scene.frame(view);
    CHECK(loaded.requested == first.requested);
    CHECK(loaded.hits == loaded.requested);
    CHECK(loaded.coarseComplete);
    CHECK(loaded.complete);
    CHECK(loaded.settled);
    CHECK(loaded.pending == 0);
    CHECK(loaded.screenError == loaded.targetError); // each brick at the level it asked for
    uint64_t resident = 0;
    for (uint64_t n : loaded.residentPerLevel) resident += n;
    CHECK(resident >= loaded.requested); // the selection and the ancestors that stood in for it
    CHECK(loaded.residentPerLevel.back() > 0);
}

TEST_CASE("a damaged brick is reported, shown by its ancestors and not read again every frame", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    const Viewer view = groundView();
    const StreamingOptions options = roomyOptions();
    IndexCoord broken{};
    {
        // A level-0 brick the view shows (not one loaded beside it for its points), then one byte of its
        // payload flipped (its checksum fails).
        StreamingScene probe(path, options);
        probe.frame(view);
        probe.waitForLoads();
        REQUIRE(probe.frame(view).complete);
        SceneStore scene = SceneStore::open(path, StoreAccess::ReadWrite);
        std::optional<BrickRecord> record;
        for (const BrickKey& key : probe.shownBricks()) {
            if (key.level != 0) continue;
            record = scene.bricks().get(key);
            broken = key.brick;
            if (record && !record->uniform) break;
        }
        REQUIRE((record && !record->uniform));
        record->payload[record->payload.size() / 2] ^= 0x5a;
        StoreTransaction transaction(scene.bricks());
        scene.bricks().put({0, broken}, *record);
        transaction.commit();
    }
    StreamingScene scene(path, options);
    for (int frame = 0; frame < 10; ++frame) {
        scene.frame(view);
        scene.waitForLoads();
    }
    const FrameReport report = scene.frame(view);
    CHECK(report.damagedBricks == 1);
    CHECK(report.coarseComplete); // its ancestors stand in for it
    CHECK_FALSE(report.complete);
    CHECK(report.hits + 1 == report.requested); // every other brick the view asked for is shown at its level
    CHECK(report.screenError > 0.0);
    CHECK(report.pending == 0);   // not queued again: it would be read and fail every frame
}

TEST_CASE("a budget smaller than one brick is a clear error", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingOptions options;
    options.memoryBudgetBytes = 64 << 10;
    try {
        StreamingScene scene(path, options);
        FAIL("opened with a 64 KB budget");
    } catch (const std::invalid_argument& e) {
        CHECK(std::string(e.what()).find("cannot hold one brick") != std::string::npos);
    }
}

TEST_CASE("edits page bricks in, and dirty bricks evicted for the view lose nothing", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    Volume reference = loadScene(path);
    const StrokeScript script = parseStrokeScript(stampScript(30, 3, 8.0, 90.0)); // a corner of four bricks
    const StrokeScript again = parseStrokeScript(stampScript(10, 5, 8.0, 50.0));
    {
        StreamingOptions options;
        options.access = StoreAccess::ReadWrite;
        options.memoryBudgetBytes = 6 << 20; // a few bricks: the flight below evicts the edited ones
        StreamingScene scene(path, options);
        const StreamingScene::EditReport edit = scene.sculpt(script);
        CHECK(edit.bricksPagedIn > 0);
        CHECK(edit.bricksChanged > 0);
        CHECK(scene.dirtyBricks() > 0);
        // A flight looking away from the edited corner, meshing what it shows as a frame does: what it
        // needs crowds the edited bricks out.
        uint64_t evictions = 0;
        for (int i = 0; i < 12; ++i) {
            evictions += scene.frame(lookingAt({400.0, 60, 100.0 + 10 * i}, {300, 30, 300})).evictions;
            scene.waitForLoads();
            for (const BrickKey& key : scene.shownBricks()) scene.meshBrick(key);
        }
        evictions += scene.frame(lookingAt({400.0, 60, 220.0}, {300, 30, 300})).evictions;
        CHECK(evictions > 0);
        // Evicting an edited brick committed every edit first (the store never holds half an edit).
        CHECK(scene.committedEditsStored() == script.ops.size());
        scene.autosave();
        CHECK(scene.dirtyBricks() == 0);
        CHECK(scene.committedEditsStored() == script.ops.size());
        // Edits there again: the bricks the first edit kept a copy of were evicted and come back from
        // the store.
        CHECK(scene.sculpt(again).bricksPagedIn > 0);
        scene.autosave();
    }
    runStrokeScript(reference, script);
    runStrokeScript(reference, again);
    CHECK(identical(loadScene(path), reference));
    // The autosaves kept the pyramid current.
    SceneStore scene = SceneStore::open(path, StoreAccess::ReadOnly);
    CHECK_FALSE(scene.lodStale());
    CHECK(pyramidEqualsRebuild(scene, dir.file("rebuilt.vdbclay")));
}

TEST_CASE("SIGKILL at any moment loses at most the edits since the last autosave", "[streaming][kill]")
{
    if (std::string(kCli).empty()) return; // no CLI in this build
    TempDir dir;
    const std::string original = makeTerrain(dir, "original.vdbclay");
    constexpr int kOps = 24, kEvery = 3;
    writeText(dir.file("ops.json"), stampScript(kOps, 8));
    const StrokeScript script = parseStrokeScript(stampScript(kOps, 8));
    // The scene after each number of ops.
    std::vector<Volume> after;
    after.push_back(loadScene(original));
    for (int i = 0; i < kOps; ++i) {
        Volume next = after.back().clone();
        StrokeScript one;
        one.ops = {script.ops[std::size_t(i)]};
        runStrokeScript(next, one);
        after.push_back(std::move(next));
    }
    const auto run = [&](const std::string& path, std::optional<std::chrono::microseconds> killAfter) {
        return finishCli(startCli({"sculpt", path, dir.file("ops.json"), "--autosave-every", std::to_string(kEvery), "--memory-budget", "16"}), killAfter);
    };
    // One run to the end: it applies every edit, and tells how long a run takes, so the kills below
    // land at moments spread over a run (a killed run ends early either way).
    const std::string path = dir.file("victim.vdbclay");
    std::filesystem::copy_file(original, path, std::filesystem::copy_options::overwrite_existing);
    const auto start = std::chrono::steady_clock::now();
    const int whole = run(path, std::nullopt);
    const auto runTime = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start);
    REQUIRE(WIFEXITED(whole));
    REQUIRE(WEXITSTATUS(whole) == 0);
    REQUIRE(identical(loadScene(path), after[kOps]));

    // The sanitizer build runs fewer trials (VDBCLAY_KILL_TRIALS, set by scripts/bootstrap.sh): each
    // run there is several times slower, and a dozen kills still land at different moments.
    const char* trialsText = std::getenv("VDBCLAY_KILL_TRIALS");
    const int trials = trialsText && std::atoi(trialsText) >= 6 ? std::atoi(trialsText) : 50;
    std::mt19937 rng(12);
    int killed = 0, finished = 0;
    std::set<uint64_t> seenCommitted;
    for (int trial = 0; trial < trials; ++trial) {
        std::filesystem::copy_file(original, path, std::filesystem::copy_options::overwrite_existing);
        const auto delay = std::chrono::microseconds(rng() % std::max<int64_t>(1, int64_t(runTime.count() * 9 / 10)));
        const int status = run(path, delay);
        (WIFSIGNALED(status) ? killed : finished)++;
        if (WIFEXITED(status)) REQUIRE(WEXITSTATUS(status) == 0);
        // The store reopens, for writing too, and holds the scene after the edits it committed.
        { SceneStore writable = SceneStore::open(path, StoreAccess::ReadWrite); }
        const SceneStore scene = SceneStore::open(path, StoreAccess::ReadOnly);
        const uint64_t committed = StreamingScene::committedEdits(scene);
        INFO("trial " << trial << ": " << committed << " edits committed");
        REQUIRE(committed <= uint64_t(kOps));
        CHECK((committed % kEvery == 0 || committed == uint64_t(kOps)));
        seenCommitted.insert(committed);
        REQUIRE(identical(scene.loadLevel(0), after[committed]));
    }
    CHECK(killed >= trials / 2);
    CHECK(seenCommitted.size() >= 3); // the kills landed at different moments
}

TEST_CASE("the scene keeps the shown bricks' meshes within the memory budget and drops them with the brick", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    for (const uint64_t budgetMB : {3ull, 64ull}) {
        StreamingOptions options;
        options.memoryBudgetBytes = budgetMB << 20;
        StreamingScene scene(path, options);
        std::map<BrickKey, std::shared_ptr<const StreamingScene::BrickMesh>> kept;
        uint64_t keptOverall = 0, shownOverall = 0;
        for (int i = 0; i < 10; ++i) {
            const double a = i / 10.0 * 3.14159;
            const Viewer view = lookingAt({128 + 150 * std::cos(a), 90, 128 + 150 * std::sin(a)}, {128, 30, 128});
            scene.frame(view);
            scene.waitForLoads();
            const FrameReport report = scene.frame(view);
            INFO("budget " << budgetMB << " MB, frame " << i);
            const std::vector<BrickKey> shown = scene.shownBricks();
            // Meshes of bricks that left the view, or were evicted, are gone from the count.
            uint64_t stillShown = 0;
            for (const auto& [key, mesh] : kept)
                if (std::binary_search(shown.begin(), shown.end(), key)) stillShown += mesh->bytes;
            CHECK(report.meshBytes == stillShown);
            CHECK(scene.residentMeshBytes() == stillShown);
            kept.clear();
            for (const BrickKey& key : shown) {
                const auto mesh = scene.meshBrick(key);
                REQUIRE(mesh);
                CHECK(mesh->bytes >= mesh->mesh.memoryBytes());
                CHECK(mesh->version == scene.brickVersion(key));
                CHECK(scene.residentBytes() <= options.memoryBudgetBytes);
                // Kept: asked again, the same mesh. The room one ask makes (evicting bricks) may only
                // be enough for the next ask's mesh, so ask until two asks agree.
                auto latest = mesh;
                for (int ask = 0; ask < 3; ++ask) {
                    const auto again = scene.meshBrick(key);
                    if (again == latest) {
                        kept[key] = latest;
                        break;
                    }
                    latest = again;
                }
            }
            uint64_t keptBytes = 0;
            for (const auto& [key, mesh] : kept) keptBytes += mesh->bytes;
            CHECK(scene.residentMeshBytes() == keptBytes);
            CHECK(scene.residentBytes() <= options.memoryBudgetBytes);
            keptOverall += kept.size();
            shownOverall += shown.size();
        }
        REQUIRE(shownOverall > 0);
        if (budgetMB == 64) CHECK(keptOverall == shownOverall); // a roomy budget keeps every shown mesh
        else CHECK(keptOverall > 0);
    }
}

namespace {

/// A stamp of radius 3: its mode and centre (with `onSurface`, its height taken from the surface there).
struct StampAt {
    std::string mode;
    std::array<double, 3> at;
    bool onSurface = true;
};

/// Random stamps across brick faces, then `besideCutEdge`'s, then a stamp inside one brick, with the given
/// view: every kept mesh must be the one its brick makes now, and the inside stamp must leave the other
/// bricks' versions.
void checkKeptMeshesAfterStamps(const Viewer& view, double pixelTolerance, std::size_t levelsShown,
                                const std::vector<StampAt>& besideCutEdge = {})
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingOptions options = roomyEditableOptions();
    options.pixelTolerance = pixelTolerance;
    StreamingScene scene(path, options);
    settleView(scene, view);
    std::vector<BrickKey> shown = scene.shownBricks();
    std::set<int> levels;
    for (const BrickKey& key : shown) levels.insert(key.level);
    REQUIRE(levels.size() == levelsShown);
    REQUIRE(levels.count(0));
    const auto meshAll = [&] {
        for (const BrickKey& key : scene.shownBricks()) REQUIRE(scene.meshBrick(key));
    };
    std::size_t inPieces = 0; // meshes made again for edits, from the leaves' pieces
    const auto checkKeptMeshes = [&](const std::string& after) {
        for (const BrickKey& key : scene.shownBricks()) {
            const auto kept = scene.meshBrick(key), fresh = scene.meshBrickAfresh(key);
            INFO(after << ": brick " << key.level << " " << key.brick[0] << "," << key.brick[1] << "," << key.brick[2]);
            REQUIRE(kept);
            inPieces += kept->pieces != nullptr;
            CHECK(kept->mesh == fresh->mesh);
            CHECK(kept->occlusion == fresh->occlusion);
            CHECK(kept->blend == fresh->blend);
            CHECK(kept->masked == fresh->masked);
        }
    };
    meshAll();
    // Moves a point down onto the surface, where the meshes are.
    const auto onSurface = [&](std::array<double, 3>& at) {
        const Volume now = scene.residentLevel0();
        for (int32_t y = 120; y > 0; --y)
            if (now.materialAt({int32_t(at[0]), y, int32_t(at[2])}) != kEmptyMaterial) {
                at[1] = y;
                return;
            }
    };

    // Random stamps at integer positions, two in three of them beside a brick face: crossing it, or
    // touching the voxels next to it, on either side.
    std::mt19937 rng{17};
    const char* modes[] = {"add", "remove", "paint", "smooth"};
    for (int i = 0; i < 28; ++i) {
        const int radius = std::uniform_int_distribution<int>(2, 6)(rng);
        std::array<double, 3> at{std::uniform_int_distribution<int>(8, 120)(rng) * 1.0, std::uniform_int_distribution<int>(20, 50)(rng) * 1.0,
                                 std::uniform_int_distribution<int>(8, 120)(rng) * 1.0};
        if (i % 3 != 0) {
            const int axis = i % 2 == 0 ? 0 : 2, side = std::uniform_int_distribution<int>(0, 1)(rng) * 2 - 1;
            const int gap = std::uniform_int_distribution<int>(-3, 4)(rng); // <= 0: the brush crosses the face
            at[std::size_t(axis)] = 64.0 + side * (radius + gap);
        }
        onSurface(at);
        nlohmann::json op{{"mode", modes[i % 4]}, {"brush", {{"shape", "sphere"}, {"radius", radius}}}, {"at", at}};
        if (i % 4 == 2) op["material"] = "red";
        const nlohmann::json materials = nlohmann::json::array({{{"name", "red"}, {"color", {0.8, 0.1, 0.1}}}});
        scene.sculpt(parseStrokeScript(nlohmann::json{{"materials", materials}, {"ops", {op}}}.dump()));
        scene.frame(view);
        if (i % 5 == 4) continue; // two edits before the next meshes
        checkKeptMeshes("stamp " + std::to_string(i) + " " + op.dump());
    }
    CHECK(inPieces > 0);

    // Stamps across and beside the planes where the cut ends inside the scene (space the view culls, or
    // does not show at any level), given: the meshes there close the cut with the coarsest level's cells
    // outside it, which read the voxels on those planes, and are kept while no edit reaches them.
    for (const StampAt& stamp : besideCutEdge) {
        std::array<double, 3> at = stamp.at;
        const std::string& mode = stamp.mode;
        if (stamp.onSurface) onSurface(at);
        const nlohmann::json materials = nlohmann::json::array({{{"name", "red"}, {"color", {0.8, 0.1, 0.1}}}});
        nlohmann::json op{{"mode", mode}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"at", at}};
        if (mode == "paint") op["material"] = "red";
        scene.sculpt(parseStrokeScript(nlohmann::json{{"materials", materials}, {"ops", {op}}}.dump()));
        scene.frame(view);
        checkKeptMeshes("a stamp at the cut's edge " + op.dump());
    }

    // A small stamp in the middle of a level-0 brick, on its surface: only that brick's mesh is made again.
    const Volume resident = scene.residentLevel0();
    std::optional<std::array<double, 3>> centre;
    BrickKey target;
    for (const BrickKey& key : scene.shownBricks()) {
        if (key.level != 0 || centre) continue;
        const LeafAlignedBox box = brickBox(key.brick);
        const int32_t x = box.min[0] + 32, z = box.min[2] + 32;
        for (int32_t y = box.min[1] + 52; y >= box.min[1] + 12; --y)
            if (resident.materialAt({x, y, z}) != kEmptyMaterial) {
                centre = std::array<double, 3>{double(x), double(y), double(z)};
                target = key;
                break;
            }
    }
    REQUIRE(centre);
    std::map<BrickKey, uint64_t> before;
    for (const BrickKey& key : scene.shownBricks()) before[key] = scene.brickVersion(key);
    const nlohmann::json op{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"at", *centre}};
    REQUIRE(scene.sculpt(parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump())).bricksChanged == 1);
    scene.frame(view);
    for (const BrickKey& key : scene.shownBricks()) {
        INFO("brick " << key.level << " " << key.brick[0] << "," << key.brick[1] << "," << key.brick[2]);
        if (key == target) CHECK(scene.brickVersion(key) != before.at(key));
        else CHECK(scene.brickVersion(key) == before.at(key));
    }
    checkKeptMeshes("the stamp inside one brick");
}

} // namespace

TEST_CASE("after stamps anywhere (across brick faces too), every kept mesh is the one its brick makes now (re-meshed per leaf), a stamp inside one brick leaves the others' meshes", "[streaming]")
{
    checkKeptMeshesAfterStamps(lookingAt({30, 70, 30}, {128, 30, 128}), 1.0, 1); // a terrain this small is all level 0 at 1 px
}

// Beside a coarser brick, meshes read points of bricks the cut does not show (the level-0 brick past a
// level-0 brick's face; the finer bricks on a coarse brick's faces, for its transition cells): a load or
// an eviction of those must give the meshes that read them new versions.
TEST_CASE("kept meshes beside a coarser brick after stamps are the ones the bricks make now", "[streaming]")
{
    checkKeptMeshesAfterStamps(lookingAt({-60, 80, -60}, {128, 30, 128}), 10.0, 2); // level 0 near, level 1 far
}

// This view shows level 0 near and level 1 far, and culls the level-0 brick at x 0..64, z 192..256,
// whose level-1 parent it shows in part: the cut ends on the planes z = 192 (x < 64) and x = 64
// (z > 192), inside the terrain.
TEST_CASE("kept meshes where the cut ends inside the scene after stamps across its edge are the ones the bricks make now", "[streaming]")
{
    checkKeptMeshesAfterStamps(lookingAt({-40, 45, 20}, {200, 30, 60}), 10.0, 2,
                               {{"add", {30, 0, 190}},
                                {"remove", {66, 0, 220}},
                                {"paint", {20, 0, 193}},
                                {"add", {67, 0, 230}},
                                {"add", {40, 0, 186}},
                                {"remove", {30, 0, 191}},
                                {"add", {63, 0, 194}},
                                {"add", {30, 3, 30}, false},
                                {"add", {100, 2, 40}, false},
                                {"remove", {40, 1, 100}, false},
                                {"paint", {20, 2, 20}, false},
                                {"add", {140, 0, 150}},
                                {"add", {130, 0, 200}},
                                {"remove", {150, 0, 130}},
                                {"add", {125, 0, 190}},
                                {"paint", {126, 0, 140}}});
}

TEST_CASE("an edit where the view shows a coarse level shows at level 0 until it is saved, then at the coarse level again", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingOptions options = roomyEditableOptions();
    options.pixelTolerance = 4.0; // from afar: the terrain shows at a coarse level
    StreamingScene scene(path, options);
    const Viewer view = lookingAt({-500, 200, -500}, {128, 30, 128});
    const auto levelShownAt = [&](const std::array<double, 3>& p) { return scene.shownLevelAt(p).value_or(-1); };
    settleView(scene, view);
    // A point on the surface shown at a coarse level.
    std::optional<std::array<double, 3>> at;
    for (const BrickKey& key : scene.shownBricks()) {
        if (key.level == 0 || at) continue;
        const double edge = double(kBrickEdge << key.level);
        for (double y = 60; y >= 10 && !at; y -= 2) {
            const std::array<double, 3> p{(key.brick[0] + 0.5) * edge, y, (key.brick[2] + 0.5) * edge};
            if (levelShownAt(p) <= 0) continue;
            const nlohmann::json op{{"mode", "remove"}, {"brush", {{"shape", "sphere"}, {"radius", 4}}}, {"at", p}};
            if (scene.sculpt(parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump())).bricksChanged > 0) at = p;
        }
    }
    REQUIRE(at);
    settleView(scene, view);
    CHECK(levelShownAt(*at) == 0);
    scene.autosave(); // rebuilds the levels above the edit
    settleView(scene, view);
    CHECK(levelShownAt(*at) > 0);
}

TEST_CASE("an edit in empty space, where no brick was stored, shows at once", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingOptions options = roomyEditableOptions();
    StreamingScene scene(path, options);
    // High above the terrain: the bricks there were never stored, at any level.
    const std::array<double, 3> at{100.0, 230.0, 100.0};
    const IndexCoord brick{int32_t(at[0]) / kBrickEdge, int32_t(at[1]) / kBrickEdge, int32_t(at[2]) / kBrickEdge};
    REQUIRE(scene.storedBricks({brick}).stats().empty);
    const Viewer view = lookingAt({100, 230, 160}, at);
    settleView(scene, view);
    const nlohmann::json op{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 6}}}, {"at", at}};
    REQUIRE(scene.sculpt(parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump())).bricksChanged == 1);
    settleView(scene, view);
    const std::vector<BrickKey> shown = scene.shownBricks();
    REQUIRE(std::find(shown.begin(), shown.end(), BrickKey{0, brick}) != shown.end());
    const auto mesh = scene.meshBrick({0, brick});
    REQUIRE(mesh);
    CHECK(mesh->mesh.triangleCount() > 100);
}

TEST_CASE("each edit and undo tells the edit listeners the level-0 bricks whose content it changed, outside the scene's locks", "[streaming][worker]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingScene scene(path, roomyEditableOptions());
    settleView(scene, lookingAt({400, 120, 400}, {128, 30, 128}));
    std::vector<std::vector<BrickKey>> heard;
    std::vector<std::map<BrickKey, uint64_t>> contentsHeard;
    const uint64_t id = scene.addEditListener([&](const std::vector<BrickKey>& changed) {
        heard.push_back(changed);
        // The scene's own calls work here: the listener runs outside its locks.
        std::map<BrickKey, uint64_t>& contents = contentsHeard.emplace_back();
        for (const BrickKey& key : changed) contents[key] = scene.brickContent(key).value_or(0);
    });
    // Every level-0 brick an edit could reach, and their contents before it.
    std::vector<BrickKey> candidates;
    for (int32_t x = 0; x < 4; ++x)
        for (int32_t y = 0; y < 2; ++y)
            for (int32_t z = 0; z < 4; ++z) candidates.push_back({0, {x, y, z}});
    const auto contents = [&] {
        std::map<BrickKey, uint64_t> out;
        for (const BrickKey& key : candidates) out[key] = scene.brickContent(key).value_or(0);
        return out;
    };
    const auto changedBetween = [&](const std::map<BrickKey, uint64_t>& before, const std::map<BrickKey, uint64_t>& after) {
        std::set<BrickKey> out;
        for (const auto& [key, content] : after)
            if (content != before.at(key)) out.insert(key);
        return out;
    };
    // Stamps across the faces between bricks (64, 128), and one in a single brick.
    for (const std::array<double, 3> at : {std::array<double, 3>{64.0, 30.0, 64.0}, {128.0, 25.0, 70.0}, {100.0, 30.0, 100.0}}) {
        const nlohmann::json op{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 9}}}, {"at", at}};
        const std::map<BrickKey, uint64_t> before = contents();
        std::vector<LeafChange> changes;
        heard.clear();
        contentsHeard.clear();
        const StreamingScene::EditReport report = scene.sculpt(parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump()), &changes);
        const std::set<BrickKey> changed = changedBetween(before, contents());
        INFO("a stamp at " << at[0] << "," << at[1] << "," << at[2]);
        REQUIRE(heard.size() == 1);
        CHECK(std::set<BrickKey>(heard[0].begin(), heard[0].end()) == changed);
        CHECK(heard[0].size() == report.bricksChanged);
        CHECK(!changed.empty());
        for (const auto& [key, content] : contentsHeard[0]) CHECK(content == contents().at(key)); // already committed
        // Undone: the same bricks again.
        std::vector<LeafImage> undo;
        for (const LeafChange& c : changes) undo.push_back({c.origin, c.before});
        const std::map<BrickKey, uint64_t> beforeUndo = contents();
        heard.clear();
        scene.restoreLeaves(undo);
        REQUIRE(heard.size() == 1);
        CHECK(std::set<BrickKey>(heard[0].begin(), heard[0].end()) == changedBetween(beforeUndo, contents()));
        CHECK(std::set<BrickKey>(heard[0].begin(), heard[0].end()) == changed);
    }
    // An edit that changes nothing tells nothing; a removed listener hears nothing.
    heard.clear();
    const nlohmann::json nothing{{"mode", "remove"}, {"brush", {{"shape", "sphere"}, {"radius", 3}}}, {"at", {100.0, 240.0, 100.0}}};
    CHECK(scene.sculpt(parseStrokeScript(nlohmann::json{{"ops", {nothing}}}.dump())).bricksChanged == 0);
    CHECK(heard.empty());
    scene.removeEditListener(id);
    const nlohmann::json op{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 5}}}, {"at", {40.0, 30.0, 40.0}}};
    CHECK(scene.sculpt(parseStrokeScript(nlohmann::json{{"ops", {op}}}.dump())).bricksChanged > 0);
    CHECK(heard.empty());
}

TEST_CASE("meshes made on workers while edits, loads and evictions run beside them settle to the meshes each brick makes afresh", "[streaming][worker]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingOptions options = roomyEditableOptions();
    StreamingScene scene(path, options);
    const Viewer near = lookingAt({30, 70, 30}, {128, 30, 128}), away = lookingAt({250, 70, 250}, {128, 30, 128});
    settleView(scene, near);
    // What a frame thread draws: per brick, the version and hash of the last mesh it took.
    render::BrickMeshWorkers workers(scene, 2);
    std::map<BrickKey, std::pair<uint64_t, uint64_t>> drawn;
    const auto syncOnce = [&] {
        for (const render::BrickMeshWorkers::Finished& f : workers.takeFinished()) {
            drawn[f.key] = {f.version, f.hash};
            CHECK(f.packed.bytes.empty() == (f.packed.indexCount == 0));
        }
        const std::vector<BrickKey> shown = scene.shownBricks();
        const std::vector<uint64_t> versions = scene.brickVersions(shown);
        std::vector<BrickKey> stale;
        for (std::size_t i = 0; i < shown.size(); ++i) {
            const auto it = drawn.find(shown[i]);
            if (it == drawn.end() || it->second.first != versions[i]) stale.push_back(shown[i]);
        }
        workers.request(stale);
        return stale.size();
    };

    // Stamps across brick faces on one thread; on this one, frames that turn the view away and back (loads
    // and evictions), picks through the trees, and meshes asked for and taken.
    std::atomic<bool> editing{true};
    std::thread edits([&] {
        std::mt19937 rng{29};
        const char* modes[] = {"add", "remove", "paint", "smooth"};
        for (int i = 0; i < 16; ++i) {
            const int radius = std::uniform_int_distribution<int>(2, 6)(rng);
            std::array<double, 3> at{std::uniform_int_distribution<int>(8, 120)(rng) * 1.0, 30.0, std::uniform_int_distribution<int>(8, 120)(rng) * 1.0};
            if (i % 2 == 0) at[std::size_t(i % 4 == 0 ? 0 : 2)] = 64.0 + std::uniform_int_distribution<int>(-4, 4)(rng);
            nlohmann::json op{{"mode", modes[i % 4]}, {"brush", {{"shape", "sphere"}, {"radius", radius}}}, {"at", at}};
            if (i % 4 == 2) op["material"] = "red";
            const nlohmann::json materials = nlohmann::json::array({{{"name", "red"}, {"color", {0.8, 0.1, 0.1}}}});
            scene.sculpt(parseStrokeScript(nlohmann::json{{"materials", materials}, {"ops", {op}}}.dump()));
        }
        editing = false;
    });
    uint64_t frames = 0;
    while (editing) {
        scene.frame(frames++ % 40 < 30 ? near : away);
        // A pick's read of the trees, beside the edits' pastes and the meshes' reads.
        scene.visitResidentLevels([&](const std::vector<const Volume*>& levels, const StreamingScene::FinestResidentAt&) {
            REQUIRE(levels.size() == std::size_t(scene.levels()) + 1);
            (void)levels[0]->materialAt({64, 30, 64});
        });
        syncOnce();
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    edits.join();

    // Settled, every shown brick's last mesh is of its version and is what the brick makes afresh.
    std::size_t stale = 1;
    for (int i = 0; i < 100 && stale > 0; ++i) {
        scene.frame(near);
        scene.waitForLoads();
        stale = syncOnce();
        workers.waitIdle();
    }
    CHECK(stale == 0);
    CHECK(workers.takeFailures().empty());
    for (const BrickKey& key : scene.shownBricks()) {
        INFO("brick " << key.level << " " << key.brick[0] << "," << key.brick[1] << "," << key.brick[2]);
        const auto fresh = scene.meshBrickAfresh(key);
        REQUIRE(fresh);
        REQUIRE(drawn.count(key));
        CHECK(drawn.at(key).first == scene.brickVersion(key));
        CHECK(drawn.at(key).second == fresh->hash);
    }
}

TEST_CASE("a brick's error, where its store keeps one, lets a view show it coarser, and never coarser than its voxel allows", "[streaming]")
{
    // The bound without an error is the voxel; a data error adds what the mesh's cells may cut off (a
    // quarter voxel, or the coarse levels' plane tolerance where larger) and is capped there.
    CHECK(lodShownError(std::nullopt, 4.0, 0.5) == 4.0);
    CHECK(lodShownError(0.5, 4.0, 0.0) == 1.5);
    CHECK(lodShownError(0.5, 4.0, 0.5) == 2.5);
    CHECK(lodShownError(7.0, 4.0, 0.5) == 4.0);
    std::vector<std::set<IndexCoord>> stored(3);
    for (int x = 0; x < 8; ++x)
        for (int z = 0; z < 8; ++z) stored[0].insert({x, 0, z});
    for (int k = 1; k < 3; ++k)
        for (const IndexCoord& b : stored[std::size_t(k - 1)]) stored[std::size_t(k)].insert(parentBrick(b));
    BrickPresence presence(stored);
    SelectionOptions options;
    options.levels = 2;
    const Viewer view = lookingAt({-300, 200, -300}, {256, 0, 256});
    const auto levelCounts = [&] {
        std::array<int, 3> counts{};
        for (const SelectedBrick& b : selectBricks(view, options, presence)) ++counts[std::size_t(b.key.level)];
        return counts;
    };
    const std::array<int, 3> plain = levelCounts();
    REQUIRE(plain[0] > 0);
    // Smooth bricks (no data error: half a voxel for their meshes): fewer bricks, none finer than before.
    for (int k = 1; k < 3; ++k)
        for (const IndexCoord& b : stored[std::size_t(k)]) presence.setShownError(k, b, lodShownError(0.0, double(1 << k), 0.5));
    const std::array<int, 3> smooth = levelCounts();
    CHECK(smooth[0] < plain[0]);
    CHECK(smooth[0] + smooth[1] + smooth[2] < plain[0] + plain[1] + plain[2]);
    // Errors at the voxel bound select as without them.
    for (int k = 1; k < 3; ++k)
        for (const IndexCoord& b : stored[std::size_t(k)]) presence.setShownError(k, b, lodShownError(99.0, double(1 << k), 0.5));
    CHECK(levelCounts() == plain);
    CHECK_THROWS_AS(presence.setShownError(1, {100, 0, 0}, 1.0), std::invalid_argument);
    CHECK_THROWS_AS(presence.setShownError(1, *stored[1].begin(), -1.0), std::invalid_argument);
}

TEST_CASE("a view of level 0 beside level 1 is closed: the bricks beside it whose points its meshes read are loaded too", "[streaming]")
{
    TempDir dir;
    const std::string path = makeTerrain(dir);
    StreamingOptions options = roomyOptions();
    options.pixelTolerance = 10.0;
    StreamingScene scene(path, options);
    const Viewer view = lookingAt({-60, 80, -60}, {128, 30, 128});
    settleView(scene, view);
    std::set<int> levels;
    Mesh all;
    for (const BrickKey& key : scene.shownBricks()) {
        levels.insert(key.level);
        appendMesh(all, scene.meshBrick(key)->mesh.decoded());
    }
    REQUIRE(levels.size() == 2);
    // Welded a little wider than the kept meshes' lattice step: the bricks compute a shared vertex a
    // float's rounding apart, which may fall on either side of a lattice step's midpoint.
    const MeshTopology topology = analyzeTopology(all, 1.5 * scene.voxelSize() / StreamingScene::kMeshLatticePerVoxel);
    CHECK(topology.boundaryEdges == 0);
}

TEST_CASE("a budget-limited view of level 0 beside level 1 is closed too: it leaves room for the bricks beside it", "[streaming]")
{
    // The view above, refined further, under budgets that hold only part of it: the view refines only as
    // far as leaves room for the bricks its shown meshes read beside them. Before, a budget-limited view
    // loaded none of them (and showed whatever was left resident), and its level-0 bricks beside level-1
    // ones were capped by false walls, open at their edges (284 open edges in one of these views).
    TempDir dir;
    const std::string path = makeTerrain(dir);
    const Viewer view = lookingAt({-60, 80, -60}, {128, 30, 128});
    uint64_t whole = 0;
    {
        StreamingOptions options = roomyOptions();
        options.pixelTolerance = 2.0;
        StreamingScene scene(path, options);
        settleView(scene, view);
        for (const BrickKey& key : scene.shownBricks()) scene.meshBrick(key);
        whole = scene.residentBytes();
    }
    int limitedWithTwoLevels = 0;
    for (const double share : {0.3, 0.45, 0.6, 0.75, 0.9}) {
        StreamingOptions options = roomyOptions();
        options.pixelTolerance = 2.0;
        options.memoryBudgetBytes = uint64_t(double(whole) * share);
        StreamingScene scene(path, options);
        // Frames until the view holds (the meshes made tell the budget what meshes take).
        FrameReport report;
        std::vector<BrickKey> shown;
        for (int i = 0; i < 12; ++i) {
            shown = scene.shownBricks();
            settleView(scene, view);
            for (const BrickKey& key : scene.shownBricks()) scene.meshBrick(key);
            report = scene.frame(view);
            scene.waitForLoads();
            if (report.settled && scene.shownBricks() == shown) break;
        }
        INFO("budget " << options.memoryBudgetBytes << " bytes (" << share << " of the whole view's)");
        CHECK(scene.residentBytes() <= options.memoryBudgetBytes);
        std::set<int> levels;
        Mesh all;
        for (const BrickKey& key : scene.shownBricks()) {
            levels.insert(key.level);
            appendMesh(all, scene.meshBrick(key)->mesh.decoded());
        }
        if (!report.budgetLimited || levels.size() < 2) continue;
        ++limitedWithTwoLevels;
        const MeshTopology topology = analyzeTopology(all, 1.5 * scene.voxelSize() / StreamingScene::kMeshLatticePerVoxel);
        CHECK(topology.boundaryEdges == 0);
    }
    CHECK(limitedWithTwoLevels >= 2);
}
