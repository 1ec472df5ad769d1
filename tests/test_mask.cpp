// The sculptor's mask (issue 37): masked voxels and the crossings between them stay bit-identical under
// every brush, the mask is painted, inverted and cleared by script ops, saved with the scene in both forms,
// undone with its stroke, and replayed.
#include "editor/EditingSession.h"
#include "scene/SceneStore.h"
#include "sculpt/StrokeScript.h"
#include "support/CliRun.h"
#include "support/QuietSession.h"
#include "support/HermiteProbe.h"
#include "support/TestUtil.h"
#include "vdb_hermite/VolumeIO.h"
#include "vdb_hermite/VoxelMask.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <tuple>

using namespace vdbclay;
using namespace vdbclay::test;
using nlohmann::json;

namespace {

void run(Volume& v, const json& ops, const json& materials = json::array())
{
    runStrokeScript(v, parseStrokeScript(json{{"materials", materials}, {"ops", ops}}.dump()));
}

json sphereAt(double r, const std::array<double, 3>& at) { return {{"brush", {{"shape", "sphere"}, {"radius", r}}}, {"at", at}}; }

json op(const std::string& mode, double r, const std::array<double, 3>& at, const json& extra = json::object())
{
    json o = sphereAt(r, at);
    o["mode"] = mode;
    for (const auto& item : extra.items()) o[item.key()] = item.value();
    return o;
}

const json kRed = json::array({{{"name", "red"}, {"color", {0.9, 0.1, 0.1}}}});

/// A ball of radius 16 with a second material defined.
Volume ball()
{
    Volume v(1.0);
    run(v, json::array({op("add", 16.0, {0, 0, 0})}), kRed);
    return v;
}

/// How the masked part of two volumes differs: masked voxels whose material differs, and edges between
/// two masked voxels whose crossing differs (present in one only, or another sample). Only voxels in
/// [lo, hi] are looked at.
struct MaskedDifference {
    uint64_t voxels = 0, edges = 0, maskedVoxels = 0;
};

MaskedDifference maskedDifference(const Volume& a, const Volume& b, const VoxelMask& mask, int lo, int hi)
{
    MaskedDifference d;
    for (int x = lo; x <= hi; ++x)
        for (int y = lo; y <= hi; ++y)
            for (int z = lo; z <= hi; ++z) {
                if (!mask.masked({x, y, z})) continue;
                ++d.maskedVoxels;
                d.voxels += a.materialAt({x, y, z}) != b.materialAt({x, y, z});
            }
    using Key = std::tuple<int32_t, int32_t, int32_t, int>;
    const auto edgesOf = [&](const Volume& v) {
        std::map<Key, EdgeRecord> out;
        for (const EdgeRecord& e : collectEdges(v)) {
            std::array<int32_t, 3> w = e.voxel;
            ++w[std::size_t(e.axis)];
            if (mask.masked(e.voxel) && mask.masked(w)) out[{e.voxel[0], e.voxel[1], e.voxel[2], e.axis}] = e;
        }
        return out;
    };
    const auto ea = edgesOf(a), eb = edgesOf(b);
    for (const auto& [key, e] : ea) {
        const auto it = eb.find(key);
        d.edges += it == eb.end() || !(it->second.sample == e.sample);
    }
    for (const auto& [key, e] : eb) d.edges += !ea.count(key);
    return d;
}

/// Solid voxels that differ in material between two volumes in [lo, hi]^3 and are not masked.
uint64_t freeVoxelsChanged(const Volume& a, const Volume& b, const VoxelMask& mask, int lo, int hi)
{
    uint64_t n = 0;
    for (int x = lo; x <= hi; ++x)
        for (int y = lo; y <= hi; ++y)
            for (int z = lo; z <= hi; ++z)
                if (!mask.masked({x, y, z})) n += a.materialAt({x, y, z}) != b.materialAt({x, y, z});
    return n;
}

/// A brush of every mode over the point (16, 0, 0) of the ball's surface, reaching beyond the mask.
std::vector<json> everyMode()
{
    const std::array<double, 3> at{16, 0, 0};
    return {
        op("add", 7.0, {19, 0, 0}),
        op("add", 7.0, {19, 0, 0}, {{"blend", 3.0}}),
        op("remove", 7.0, at),
        op("paint", 9.0, at, {{"material", "red"}}),
        op("paint", 9.0, at, {{"material", "red"}, {"strength", 0.6}, {"falloff", "linear"}}),
        op("erode", 9.0, at, {{"depth", 3.0}}),
        op("intersect", 15.0, {0, 0, 0}),
        op("smooth", 9.0, at, {{"strength", 1.0}}),
        op("flatten", 9.0, at, {{"strength", 1.0}}),
        op("inflate", 9.0, at, {{"distance", 2.0}}),
        op("deflate", 9.0, at, {{"distance", 2.0}}),
        op("move", 8.0, at, {{"offset", {4.0, 1.0, 0.0}}}),
        [] {
            json o = op("add", 5.0, {18, 0, 0});
            o.erase("at");
            o["path"] = {{18, -8, 0}, {18, 8, 0}};
            return o;
        }(),
    };
}

} // namespace

TEST_CASE("mask: voxels masked, freed, inverted and cleared, and its bytes read back exactly or refused", "[sculpt][mask]")
{
    VoxelMask m;
    CHECK_FALSE(m.any());
    m.set({-1, 0, 7}, true);
    m.set({8, 8, 8}, true);
    m.set({9, 8, 8}, true);
    CHECK(m.masked({-1, 0, 7}));
    CHECK(m.masked({9, 8, 8}));
    CHECK_FALSE(m.masked({-1, 0, 6}));
    CHECK(m.listedLeaves().size() == 2);
    m.set({8, 8, 8}, false);
    m.set({9, 8, 8}, false);
    CHECK(m.listedLeaves().size() == 1); // a leaf with nothing left is dropped
    m.invert();
    CHECK_FALSE(m.masked({-1, 0, 7}));
    CHECK(m.masked({1000, -5000, 3}));
    m.set({1000, -5000, 3}, false);
    CHECK_FALSE(m.masked({1000, -5000, 3}));
    CHECK(m.masked({1001, -5000, 3}));

    const std::string bytes = m.encode();
    CHECK(VoxelMask::decode(bytes) == m);
    CHECK(VoxelMask::decode(VoxelMask{}.encode()) == VoxelMask{});
    CHECK_THROWS_AS(VoxelMask::decode(bytes.substr(0, bytes.size() - 1)), MaskFormatError);
    CHECK_THROWS_AS(VoxelMask::decode(""), MaskFormatError);
    std::string wrongFlag = bytes;
    wrongFlag[5] = 7;
    CHECK_THROWS_AS(VoxelMask::decode(wrongFlag), MaskFormatError);
    std::string offLattice = bytes;
    offLattice[14] = 3; // the first leaf's x: no longer a multiple of 8
    CHECK_THROWS_AS(VoxelMask::decode(offLattice), MaskFormatError);
    std::string count = bytes;
    count[6] = 9;
    CHECK_THROWS_AS(VoxelMask::decode(count), MaskFormatError);
    m.clear();
    CHECK_FALSE(m.any());

    // Whole leaves at once, as a mask brush marks the leaves inside it.
    m.setLeaf({16, -8, 0}, true);
    CHECK(m.masked({23, -1, 7}));
    CHECK(m.masked({16, -8, 0}));
    CHECK_FALSE(m.masked({24, -1, 7}));
    m.set({20, -4, 4}, false);
    CHECK_FALSE(m.masked({20, -4, 4}));
    m.setLeaf({16, -8, 0}, false);
    CHECK_FALSE(m.any());
    m.invert();
    m.setLeaf({0, 0, 0}, false);
    CHECK_FALSE(m.masked({7, 7, 7}));
    CHECK(m.masked({8, 7, 7}));
}

TEST_CASE("mask: a masked region is bit-identical after a brush of every mode over it, and the rest changes", "[sculpt][mask]")
{
    Volume masked = ball();
    run(masked, json::array({op("mask", 5.0, {16, 0, 0})}));
    const VoxelMask& mask = masked.mask();
    REQUIRE(mask.any());
    CHECK(mask.masked({16, 0, 0}));
    CHECK(mask.masked({12, 2, 2}));
    CHECK_FALSE(mask.masked({10, 0, 0}));
    // Masking changes no voxel.
    CHECK(changedBlocks(masked, ball()).empty());

    for (const json& o : everyMode()) {
        INFO(o.dump());
        Volume v = masked.clone();
        run(v, json::array({o}));
        CHECK(checkInvariants(v).empty());
        const MaskedDifference d = maskedDifference(masked, v, mask, -30, 30);
        CHECK(d.maskedVoxels > 400);
        CHECK(d.voxels == 0);
        CHECK(d.edges == 0);
        // The brush did its work around the mask (its region reaches beyond it).
        Volume plain = ball();
        run(plain, json::array({o}));
        CHECK_FALSE(changedBlocks(plain, ball()).empty());
        CHECK_FALSE(changedBlocks(v, masked).empty());
    }
}

TEST_CASE("mask: seeded random masks and brushes, on and off the lattice, inverted or not, keep every masked voxel and crossing", "[sculpt][mask]")
{
    for (unsigned seed = 1; seed <= 6; ++seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        const auto onSurface = [&](double r, bool lattice) {
            std::array<double, 3> p{u(rng), u(rng), u(rng)};
            const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) + 1e-9;
            for (double& c : p) c = c / n * r;
            if (lattice)
                for (double& c : p) c = std::round(c);
            return p;
        };
        Volume v = ball();
        json masks = json::array();
        for (int i = 0; i < 3; ++i) masks.push_back(op(i == 2 ? "unmask" : "mask", 3.0 + 4.0 * std::fabs(u(rng)), onSurface(16.0, i == 0)));
        if (seed % 2 == 0) masks.push_back(json{{"mode", "mask_invert"}});
        run(v, masks);
        const std::vector<json> modes = everyMode();
        for (int k = 0; k < 4; ++k) {
            json o = modes[std::size_t(rng() % modes.size())];
            if (o.contains("at")) o["at"] = onSurface(16.0 + 2.0 * u(rng), k % 2 == 0);
            INFO("seed " << seed << ", op " << o.dump());
            const Volume before = v.clone();
            run(v, json::array({o}));
            REQUIRE(checkInvariants(v).empty());
            const MaskedDifference d = maskedDifference(before, v, v.mask(), -30, 30);
            CHECK(d.voxels == 0);
            CHECK(d.edges == 0);
        }
    }
}

TEST_CASE("mask: unmask frees voxels, invert masks everything else, clear frees all, symmetry masks the mirror image", "[sculpt][mask]")
{
    Volume v = ball();
    run(v, json::array({op("mask", 5.0, {16, 0, 0}), op("unmask", 3.0, {16, 0, 0})}));
    CHECK(v.mask().masked({12, 0, 0}));
    CHECK_FALSE(v.mask().masked({16, 0, 0}));

    // Inverted, the brush changes the old mask's voxels only.
    Volume inverted = ball();
    run(inverted, json::array({op("mask", 5.0, {16, 0, 0}), json{{"mode", "mask_invert"}}}));
    CHECK_FALSE(inverted.mask().masked({16, 0, 0}));
    CHECK(inverted.mask().masked({0, 0, 0}));
    Volume before = inverted.clone();
    run(inverted, json::array({op("remove", 8.0, {16, 0, 0})}));
    CHECK(checkInvariants(inverted).empty());
    CHECK(maskedDifference(before, inverted, inverted.mask(), -24, 24).voxels == 0);
    CHECK(maskedDifference(before, inverted, inverted.mask(), -24, 24).edges == 0);
    CHECK(freeVoxelsChanged(before, inverted, inverted.mask(), -24, 24) > 50);
    // An unbounded brush (a half-space) under an inverted mask too.
    Volume half = before.clone();
    run(half, json::array({{{"mode", "remove"}, {"brush", {{"shape", "half-space"}, {"normal", {-1, 0, 0}}}}, {"at", {13, 0, 0}}}}));
    CHECK(checkInvariants(half).empty());
    CHECK(maskedDifference(before, half, half.mask(), -24, 24).voxels == 0);
    CHECK(freeVoxelsChanged(before, half, half.mask(), -24, 24) > 20);

    // Cleared, nothing is kept.
    Volume cleared = inverted.clone();
    run(cleared, json::array({json{{"mode", "mask_clear"}}, op("remove", 8.0, {-16, 0, 0})}));
    CHECK_FALSE(cleared.mask().any());
    CHECK(freeVoxelsChanged(inverted, cleared, cleared.mask(), -24, 24) > 50);

    Volume mirrored = ball();
    run(mirrored, json::array({op("mask", 4.0, {16, 0, 0}, {{"symmetry", {{"mirror", {"x"}}}}})}));
    for (int x : {-16, 16}) CHECK(mirrored.mask().masked({x, 0, 0}));
    CHECK_FALSE(mirrored.mask().masked({0, 16, 0}));
}

TEST_CASE("mask: scripts refuse mask ops with keys that belong to other brushes, and mask ops reach no voxel", "[sculpt][mask][script]")
{
    CHECK_THROWS_WITH(parseStrokeScript(json{{"ops", {op("mask", 4.0, {0, 0, 0}, {{"material", "red"}})}}}.dump()),
                      Catch::Contains("ops[0]") && Catch::Contains("material"));
    CHECK_THROWS_WITH(parseStrokeScript(json{{"ops", {{{"mode", "mask_invert"}, {"at", {0, 0, 0}}}}}}.dump()), Catch::Contains("ops[0]"));
    CHECK_THROWS_WITH(parseStrokeScript(json{{"ops", {{{"mode", "mask"}, {"brush", {{"shape", "half-space"}}}}}}}.dump()),
                      Catch::Contains("bounded"));
    CHECK_THROWS_WITH(parseStrokeScript(json{{"ops", {{{"mode", "masks"}}}}}.dump()), Catch::Contains("mask_invert"));
    const StrokeScript s = parseStrokeScript(json{{"ops", {op("mask", 4.0, {0, 0, 0}), json{{"mode", "mask_clear"}}}}}.dump());
    CHECK(std::string(opModeName(s.ops[0])) == "mask");
    CHECK(std::string(opModeName(s.ops[1])) == "mask_clear");
    // A mask brush the size of a continent is refused before any work.
    CHECK_THROWS_AS(runStrokeScript(*std::make_unique<Volume>(1.0), parseStrokeScript(json{{"ops", {op("mask", 5e5, {0, 0, 0})}}}.dump())),
                    ScriptError);
}

TEST_CASE("mask: saved with the scene in a .vdb and in a store, read back exactly, and damaged mask bytes are refused", "[sculpt][mask][io]")
{
    TempDir dir;
    Volume v = ball();
    run(v, json::array({op("mask", 5.0, {16, 0, 0}), op("mask", 3.0, {0, 16, 0})}));
    saveVolume(v, dir.file("masked.vdb"));
    const Volume back = loadVolume(dir.file("masked.vdb"));
    CHECK(back.mask() == v.mask());
    CHECK(identical(back, v));

    writeStoreFile(v, dir.file("masked.vdbclay"));
    const Volume fromStore = loadScene(dir.file("masked.vdbclay"));
    CHECK(fromStore.mask() == v.mask());
    CHECK(identical(fromStore, v));

    // Without a mask, the files hold none.
    saveVolume(ball(), dir.file("plain.vdb"));
    CHECK_FALSE(loadVolume(dir.file("plain.vdb")).mask().any());

    // `info` tells both forms' masks.
    for (const char* name : {"masked.vdb", "masked.vdbclay", "plain.vdb"}) {
        const CommandResult r = runCli(dir, std::string("info --json ") + name);
        REQUIRE(r.exitCode == 0);
        const json info = json::parse(r.out);
        CHECK(info.at("mask").at("leaves").get<std::size_t>() == (std::string(name) == "plain.vdb" ? 0 : v.mask().listedLeaves().size()));
        CHECK_FALSE(info.at("mask").at("inverted").get<bool>());
    }

    // A store whose mask was damaged names the store.
    {
        SceneStore store = SceneStore::open(dir.file("masked.vdbclay"), StoreAccess::ReadWrite);
        store.bricks().begin();
        store.bricks().putMeta("mask", "VCMK\x01\x00garbage");
        store.bricks().commit();
    }
    CHECK_THROWS_WITH(loadScene(dir.file("masked.vdbclay")), Catch::Contains("masked.vdbclay") && Catch::Contains("mask"));
}

namespace {

void command(EditingSession& s, Command c) { s.apply(c); }

Command kindOf(Command::Kind kind)
{
    Command c;
    c.kind = kind;
    return c;
}

Command brushCommand(const std::string& mode, double radius)
{
    Command c;
    c.kind = Command::Kind::SetBrush;
    c.brush.emplace();
    c.brush->mode = mode;
    c.brush->radius = mode == "erode" ? 2.0 * radius : radius; // erode bites half its radius deep: past the mask
    c.brush->strength = 1.0;
    c.brush->material = mode == "paint" ? "red" : "";
    return c;
}

/// A short stroke along the ball's front (+z), placed by rays from the eye at (0, 0, 60).
void strokeAcross(EditingSession& s)
{
    for (int i = 0; i <= 4; ++i) {
        Command c;
        c.kind = i == 0 ? Command::Kind::StrokeBegin : Command::Kind::StrokeMove;
        const std::array<double, 3> eye{0, 0, 60}, aim{-2.0 + i, 0.5, 0.0};
        std::array<double, 3> d{aim[0] - eye[0], aim[1] - eye[1], aim[2] - eye[2]};
        const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (double& x : d) x /= n;
        c.ray = Ray{eye, d};
        s.apply(c);
    }
    Command end;
    end.kind = Command::Kind::StrokeEnd;
    s.apply(end);
}

} // namespace

TEST_CASE("editor: a masked region stays bit-identical under strokes of every mode, the mask is undone with its stroke and replays", "[editor][replay][mask]")
{
    TempDir dir;
    saveVolume(ball(), dir.file("ball.vdb"));
    SessionRecord record;
    VoxelMask maskAfter;
    Volume after(1.0);
    {
        EditingSession s(dir.file("ball.vdb"), quietSession());
        Command camera;
        camera.kind = Command::Kind::SetCamera;
        camera.camera.eye = {0, 0, 60};
        camera.camera.target = {0, 0, 0};
        command(s, camera);
        for (int i = 0; i < 3; ++i) {
            s.frame(0.0, {640, 480});
            s.scene().waitForLoads();
        }
        Command define;
        define.kind = Command::Kind::DefineMaterial;
        define.material = kRed[0];
        command(s, define);
        command(s, brushCommand("mask", 4.0));
        strokeAcross(s);
        const VoxelMask mask = s.scene().mask();
        REQUIRE(mask.any());
        CHECK(mask.masked({0, 0, 16}));
        CHECK(s.unsaved());
        // Undo takes the mask back, redo brings it again.
        command(s, kindOf(Command::Kind::Undo));
        CHECK_FALSE(s.scene().mask().any());
        command(s, kindOf(Command::Kind::Redo));
        CHECK(s.scene().mask() == mask);

        const Volume start = s.scene().residentLevel0();
        for (const char* mode : {"add", "remove", "paint", "erode", "smooth", "flatten", "inflate", "deflate", "move", "intersect"}) {
            INFO(mode);
            const Volume beforeStroke = s.scene().residentLevel0();
            command(s, brushCommand(mode, 7.0));
            strokeAcross(s);
            const Volume now = s.scene().residentLevel0();
            CHECK(checkInvariants(now).empty());
            const MaskedDifference d = maskedDifference(start, now, mask, -24, 24);
            CHECK(d.maskedVoxels > 100);
            CHECK(d.voxels == 0);
            CHECK(d.edges == 0);
            CHECK(freeVoxelsChanged(beforeStroke, now, mask, -24, 24) > 0);
        }
        // Inverted and cleared through commands, as the window's keys send them.
        Command invert;
        invert.kind = Command::Kind::ApplyOp;
        invert.op = {{"mode", "mask_invert"}};
        command(s, invert);
        CHECK(s.scene().mask().inverted());
        command(s, kindOf(Command::Kind::Undo));
        CHECK(s.scene().mask() == mask);
        command(s, kindOf(Command::Kind::Redo));
        s.frame(0.0, {640, 480}); // the record holds the commands of the frames drawn
        maskAfter = s.scene().mask();
        after = s.scene().residentLevel0();
        record = s.record();
        // Saved, the .vdb holds the mask.
        Command save;
        save.kind = Command::Kind::Save;
        command(s, save);
    }
    CHECK(loadVolume(dir.file("ball.vdb")).mask() == maskAfter);

    // The recorded session replays to the same scene and mask from the original ball.
    saveVolume(ball(), dir.file("again.vdb"));
    SessionOptions options = quietSession();
    options.refuseUnsaved = true;
    EditingSession replay(dir.file("again.vdb"), options);
    replaySession(replay, record);
    INFO("replayed mask: " << replay.scene().mask().listedLeaves().size() << " leaves, inverted " << replay.scene().mask().inverted()
                           << "; recorded: " << maskAfter.listedLeaves().size() << ", " << maskAfter.inverted() << "; commands "
                           << record.commands.size());
    CHECK(replay.scene().mask() == maskAfter);
    CHECK(changedBlocks(replay.scene().residentLevel0(), after).empty());
}
