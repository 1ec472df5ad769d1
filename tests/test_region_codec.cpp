// The store's brick codec (RegionCodec.h): round trips against the volume the regions came from, the
// .vdb streams stores of format version 1 hold, and damaged or crafted bytes, which must be read whole
// or refused with one line.
#include "scene/SceneStore.h"
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "vdb_hermite/RegionCodec.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>

#include <map>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

std::vector<LeafAlignedBox> bricksOf(const Volume& v)
{
    std::vector<LeafAlignedBox> out;
    for (const IndexCoord& o : occupiedBoxes(v, kBrickEdge)) out.push_back({o, kBrickEdge});
    return out;
}

/// Decodes every box's bytes into a new volume with v's voxel size and materials.
Volume rebuild(const Volume& v, const std::vector<LeafAlignedBox>& boxes, const std::vector<std::string>& bytes)
{
    Volume out(v.voxelSize());
    out.materials() = v.materials();
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        DecodedRegion region = decodeRegion(bytes[i], boxes[i], v.voxelSize(), v.materials().size(), "region");
        const uint64_t memory = region.memoryBytes();
        pasteRegion(out, std::move(region));
        CHECK(memory == regionMemoryBytes(out, boxes[i]));
    }
    return out;
}

void requireRefused(const std::function<void()>& decode, const std::string& needle)
{
    try {
        decode();
        FAIL("decoded bytes that should have been refused");
    } catch (const VolumeIOError& e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find('\n') == std::string::npos);
        CHECK(what.find(needle) != std::string::npos);
    }
}

} // namespace

TEST_CASE("a region decodes to exactly what was encoded, in the same bytes every time", "[store]")
{
    const Volume v = multiBrickScene();
    const std::vector<LeafAlignedBox> boxes = bricksOf(v);
    std::vector<std::string> bytes;
    uint64_t leaves = 0;
    for (const LeafAlignedBox& box : boxes) {
        uint32_t count = 0;
        bytes.push_back(encodeRegion(v, box, &count));
        CHECK(encodeRegion(v, box) == bytes.back());
        leaves += count;
    }
    CHECK(leaves == v.stats().leafCount);
    const Volume rebuilt = rebuild(v, boxes, bytes);
    CHECK(checkInvariants(rebuilt).empty());
    CHECK(identical(rebuilt, v));
}

TEST_CASE("regions of stores of format version 1 (.vdb streams of a brick) decode to the same content", "[store]")
{
    const Volume v = multiBrickScene();
    const std::vector<LeafAlignedBox> boxes = bricksOf(v);
    std::vector<std::string> bytes;
    for (const LeafAlignedBox& box : boxes) bytes.push_back(encodeVolume(copyRegion(v, box)));
    CHECK(identical(rebuild(v, boxes, bytes), v));
}

TEST_CASE("a region for another box, voxel size or materials table, or damaged, is refused with one line", "[store]")
{
    const Volume v = multiBrickScene();
    LeafAlignedBox box;
    uint32_t leaves = 0;
    std::string bytes;
    for (const LeafAlignedBox& b : bricksOf(v)) {
        uint32_t count = 0;
        std::string encoded = encodeRegion(v, b, &count);
        if (count > leaves) box = b, leaves = count, bytes = std::move(encoded);
    }
    REQUIRE(leaves > 8);
    const double vs = v.voxelSize();
    const std::size_t materials = v.materials().size();
    auto decode = [&](const std::string& b, const LeafAlignedBox& where, double voxelSize, std::size_t count) {
        return [=] { (void)decodeRegion(b, where, voxelSize, count, "brick"); };
    };
    LeafAlignedBox elsewhere = box;
    elsewhere.min[1] += kBrickEdge;
    requireRefused(decode(bytes, elsewhere, vs, materials), "another region");
    requireRefused(decode(bytes, box, vs * 2.0, materials), "voxel size");
    requireRefused(decode(bytes, box, vs, 0), "undefined material");
    requireRefused(decode("", box, vs, materials), "not a VDBClay region");
    requireRefused(decode("hello, this is text", box, vs, materials), "not a VDBClay region");
    for (std::size_t cut = 0; cut < bytes.size(); cut += 1 + bytes.size() / 97)
        requireRefused(decode(bytes.substr(0, cut), box, vs, materials), "'brick'");
    std::mt19937 rng(17);
    for (int trial = 0; trial < 200; ++trial) {
        std::string damaged = bytes;
        damaged[rng() % damaged.size()] ^= char(1 + rng() % 255);
        requireRefused(decode(damaged, box, vs, materials), "'brick'");
    }
}

TEST_CASE("crafted region bodies under a valid seal are read whole or refused with one line", "[store][fuzz]")
{
    const Volume v = multiBrickScene();
    const std::vector<LeafAlignedBox> boxes = bricksOf(v);
    std::mt19937 rng(23);
    int decoded = 0, refused = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const LeafAlignedBox& box = boxes[rng() % boxes.size()];
        std::string body = encodeRegionBody(v, box);
        switch (trial % 4) {
        case 0: body.resize(rng() % (body.size() + 1)); break;
        case 1: body += std::string(1 + rng() % 64, char(rng())); break;
        default:
            for (int i = 0, n = 1 + int(rng() % 8); i < n; ++i) body[rng() % body.size()] ^= char(1 + rng() % 255);
        }
        const std::string sealed = sealRegion(body, box, v.voxelSize());
        try {
            DecodedRegion region = decodeRegion(sealed, box, v.voxelSize(), v.materials().size(), "crafted");
            Volume out(v.voxelSize());
            out.materials() = v.materials();
            pasteRegion(out, std::move(region));
            ++decoded;
        } catch (const VolumeIOError& e) {
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
            ++refused;
        }
    }
    CHECK(refused > 0);
    CHECK(decoded > 0); // flips in materials and normals keep a body well-formed
}

TEST_CASE("compareRegion: its bounds are those of the voxels whose materials or samples differ, on random stamps", "[store]")
{
    std::mt19937 rng(29);
    const auto integer = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    int identicalBoxes = 0, differingBoxes = 0;
    for (int trial = 0; trial < 24; ++trial) {
        Volume a(1.0);
        const MaterialId second = defineMaterial(a, "second", 0.5f);
        // Each draw on its own (braces evaluate in order; a call's arguments do not), so every compiler
        // makes the same scenes.
        const double radius = integer(6, 14);
        const Vec3d centre{double(integer(-4, 4)), double(integer(-4, 4)), double(integer(-4, 4))};
        const Vec3d half{double(integer(2, 8)), double(integer(2, 8)), double(integer(2, 8))};
        const Vec3d boxAt{double(integer(-8, 8)), 0.0, double(integer(-8, 8))};
        apply(a, CsgMode::Add, sphere(radius), at(centre));
        apply(a, CsgMode::Add, box(half), at(boxAt));
        Volume b = a.clone();
        // A small stamp at an integer position: solids that touch, faces on lattice planes, and some
        // stamps that change nothing (inside the solid, or far away).
        const CsgMode mode = std::array<CsgMode, 3>{CsgMode::Add, CsgMode::Remove, CsgMode::Paint}[std::size_t(trial % 3)];
        const Vec3d where{double(integer(-16, 16)), double(integer(-16, 16)), double(integer(-16, 16))};
        const Vec3d size{double(integer(1, 4)), double(integer(1, 3)), double(integer(1, 3))};
        const EditStats stamp = trial % 2 ? apply(b, mode, sphere(size[0]), at(where), second) : apply(b, mode, box(size), at(where), second);
        // The kernel's own account of what it changed, per leaf, holds what the comparison finds.
        for (const BlockChange& change : stamp.blockChanges) {
            const RegionDifference d = compareRegion(a, b, {change.origin, kLeafDim});
            if (!d.any()) continue;
            for (std::size_t k = 0; k < 3; ++k) {
                CHECK(d.lo[k] >= change.origin[k] + change.min[k]);
                CHECK(d.hi[k] <= change.origin[k] + change.max[k]);
            }
        }

        // The reference: per voxel, the materials (materialAt) and the samples of its positive edges.
        std::map<std::pair<IndexCoord, int>, std::array<uint16_t, 3>> samplesA, samplesB;
        for (const EdgeRecord& e : collectEdges(a)) samplesA[{e.voxel, e.axis}] = {e.sample.offset, e.sample.normalU, e.sample.normalV};
        for (const EdgeRecord& e : collectEdges(b)) samplesB[{e.voxel, e.axis}] = {e.sample.offset, e.sample.normalU, e.sample.normalV};
        for (int32_t bz = -24; bz < 24; bz += 16)
            for (int32_t by = -24; by < 24; by += 16)
                for (int32_t bx = -24; bx < 24; bx += 16) {
                    const LeafAlignedBox region{{bx, by, bz}, 16};
                    IndexCoord lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
                    for (int32_t z = bz; z < bz + 16; ++z)
                        for (int32_t y = by; y < by + 16; ++y)
                            for (int32_t x = bx; x < bx + 16; ++x) {
                                const IndexCoord v{x, y, z};
                                bool differs = a.materialAt(v) != b.materialAt(v);
                                for (int axis = 0; axis < 3 && !differs; ++axis) {
                                    const auto sa = samplesA.find({v, axis}), sb = samplesB.find({v, axis});
                                    differs = (sa == samplesA.end()) != (sb == samplesB.end()) ||
                                              (sa != samplesA.end() && sa->second != sb->second);
                                }
                                if (!differs) continue;
                                for (std::size_t k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
                            }
                    const RegionDifference d = compareRegion(a, b, region);
                    INFO("trial " << trial << ", box at " << bx << "," << by << "," << bz);
                    CHECK(d.any() == (lo[0] <= hi[0]));
                    CHECK(d.lo == lo);
                    CHECK(d.hi == hi);
                    (d.any() ? differingBoxes : identicalBoxes)++;
                }
    }
    CHECK(differingBoxes > 20);
    CHECK(identicalBoxes > 20);
}
