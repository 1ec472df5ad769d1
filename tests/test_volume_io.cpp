// Native .vdb files: bit-exact round trips, rejection of bad files, atomic saves.
#include "support/HermiteProbe.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <csignal>
#include <cstring>
#include <random>
#include <set>
#include <sys/resource.h>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

/// Several CSG ops, three materials, voxel size 0.5 (brush sizes below are world units).
Volume makeSculpted()
{
    Volume v(0.5);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f, {0.6f, 0.6f, 0.6f, 1.0f});
    const MaterialId clay = defineMaterial(v, "clay", 0.2f, {0.7f, 0.4f, 0.3f, 1.0f});
    apply(v, CsgMode::Add, sphere(8.0), at({0.1, 0.2, 0.3}), stone);
    apply(v, CsgMode::Remove, box({3.0, 3.0, 10.0}, 0.5), at({5.0, 0.0, 0.0}, {0.0, 0.0, 30.0}));
    apply(v, CsgMode::Add, cylinder(3.0, 12.0), at({0.0, -8.0, 0.0}, {20.0, 0.0, 0.0}), clay);
    apply(v, CsgMode::Paint, sphere(3.0), at({0.0, 0.0, 8.0}), 1);
    apply(v, CsgMode::Add, box({2.0, 2.0, 2.0}), at({12.0, 0.0, 0.0}), 1);
    return v;
}

/// A small, different volume.
Volume makeSmall()
{
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(5.0), at({0.3, 0.0, 0.0}), 1);
    return v;
}

/// Compares byte buffers without printing them on failure.
bool sameBytes(const std::vector<char>& a, const std::vector<char>& b)
{
    INFO("sizes " << a.size() << " and " << b.size());
    return a == b;
}

void requireRejected(const std::string& path)
{
    INFO("file " << path);
    try {
        (void)loadVolume(path);
        FAIL("loadVolume accepted a bad file");
    } catch (const VolumeIOError& e) {
        INFO("message: " << e.what());
        CHECK(std::string(e.what()).size() > 0);
        CHECK(std::string(e.what()).find('\n') == std::string::npos);
    }
}

} // namespace

TEST_CASE("a leaf's active voxels are those with a crossing edge, and each edge finds its own sample", "[io]")
{
    std::mt19937_64 rng(1203);
    for (const double density : {0.0, 0.002, 0.05, 0.3, 0.9, 1.0}) {
        for (int round = 0; round < 20; ++round) {
            HermiteLeafData data;
            std::bernoulli_distribution crosses(density);
            for (int bit = 0; bit < kEdgeBits; ++bit) {
                if (!crosses(rng)) continue;
                data.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                data.samples.push_back(PackedSample{uint16_t(bit), uint16_t(bit * 7), uint16_t(round)});
            }
            HermiteLeaf leaf;
            leaf.assign(HermiteLeafData(data));
            for (Index n = 0; n < Index(kLeafVoxels); ++n) {
                bool anyEdge = false;
                for (int axis = 0; axis < 3; ++axis) {
                    const int bit = HermiteLeaf::edgeBit(n, axis);
                    const bool set = (data.edgeBits[std::size_t(bit >> 6)] >> (bit & 63)) & 1u;
                    anyEdge = anyEdge || set;
                    const PackedSample* sample = leaf.sample(n, axis);
                    REQUIRE((sample != nullptr) == set);
                    if (sample) REQUIRE(sample->offset == uint16_t(bit));
                }
                REQUIRE(leaf.isValueOn(n) == anyEdge);
            }
        }
    }
}

TEST_CASE("a sculpted volume survives save and load bit-exactly", "[io]")
{
    TempDir dir;
    const Volume a = makeSculpted();
    const VolumeStats sa = a.stats();
    REQUIRE_FALSE(sa.empty);
    REQUIRE(sa.tileCount > 0); // the round trip covers tiles as well as leaves
    REQUIRE(sa.samples > 0);
    REQUIRE(a.materials().size() == 3);
    REQUIRE(checkInvariants(a).empty());

    const std::string path = dir.file("sculpt.vdb");
    saveVolume(a, path);
    const Volume b = loadVolume(path);
    CHECK(identical(a, b));
    CHECK(b.voxelSize() == 0.5);
    CHECK(b.materials() == a.materials());
    CHECK(checkInvariants(b).empty());
    const VolumeStats sb = b.stats();
    CHECK(sb.activeVoxels == sa.activeVoxels);
    CHECK(sb.samples == sa.samples);
    CHECK(sb.leafCount == sa.leafCount);
    CHECK(sb.tileCount == sa.tileCount);
    CHECK(sb.bboxMin == sa.bboxMin);
    CHECK(sb.bboxMax == sa.bboxMax);
    CHECK(collectEdges(b).size() == collectEdges(a).size());

    // The comparison can fail: a different volume, or one more edit, is not identical.
    CHECK_FALSE(identical(a, makeSmall()));
    Volume c = b.clone();
    apply(c, CsgMode::Remove, sphere(1.0), at({0.0, 8.0, 0.0}));
    CHECK_FALSE(identical(a, c));
    Volume d = b.clone();
    defineMaterial(d, "extra", 0.5f);
    CHECK_FALSE(identical(a, d));

    // The loaded volume saves and loads again to the same content.
    const std::string again = dir.file("again.vdb");
    saveVolume(b, again);
    CHECK(identical(loadVolume(again), a));
}

TEST_CASE("an empty volume round-trips", "[io]")
{
    TempDir dir;
    const Volume a(0.25);
    saveVolume(a, dir.file("empty.vdb"));
    const Volume b = loadVolume(dir.file("empty.vdb"));
    CHECK(identical(a, b));
    CHECK(b.stats().empty);
    CHECK(b.voxelSize() == 0.25);
}

TEST_CASE("truncated copies of a saved file are rejected", "[io]")
{
    TempDir dir;
    const std::string good = dir.file("good.vdb");
    saveVolume(makeSculpted(), good);
    const std::vector<char> bytes = readBytes(good);
    const std::size_t n = bytes.size();
    REQUIRE(n > 2000);
    std::set<std::size_t> cuts = {0, 1, 4, 10, 16, 64, 100, 256, n / 8, n / 4, n / 3, n / 2, 2 * n / 3, 3 * n / 4,
                                  7 * n / 8, n - 1000, n - 100, n - 16, n - 2, n - 1};
    // A few more cut points spread evenly through the file.
    for (int i = 1; i < 8; ++i) cuts.insert(n * std::size_t(i) / 8 + 7);
    for (std::size_t cut : cuts) {
        const std::string path = dir.file("cut-" + std::to_string(cut) + ".vdb");
        writeBytes(path, bytes.data(), cut);
        requireRejected(path);
    }
}

TEST_CASE("a truncated payload under a valid trailer is rejected", "[io]")
{
    // What a short write would leave behind if the trailer still fit (openvdb::io::File::write does not
    // check its stream, so saveVolume cannot see a short write): the checksum matches, but the grid
    // data ends early. Cutting the last bytes must not load as a different volume.
    TempDir dir;
    const std::string good = dir.file("good.vdb");
    saveVolume(makeSculpted(), good);
    const std::vector<char> bytes = readBytes(good);
    const std::size_t payload = bytes.size() - 24; // saveVolume's trailer is 24 bytes
    for (std::size_t cut : {payload - 100, payload - 16, payload - 4, payload - 1}) {
        const std::string path = dir.file("short-" + std::to_string(cut) + ".vdb");
        writeBytes(path, bytes.data(), cut);
        appendIntegrityTrailer(path);
        requireRejected(path);
    }
}

TEST_CASE("files that are not VDBClay volumes are rejected", "[io]")
{
    TempDir dir;
    SECTION("random bytes")
    {
        const std::vector<char> junk = randomBytes(8192, 0x5eed0101);
        writeBytes(dir.file("junk.vdb"), junk.data(), junk.size());
        requireRejected(dir.file("junk.vdb"));
    }
    SECTION("an empty file")
    {
        writeBytes(dir.file("empty.vdb"), "", 0);
        requireRejected(dir.file("empty.vdb"));
    }
    SECTION("a text file")
    {
        writeText(dir.file("text.vdb"), "this is not a volume\n");
        requireRejected(dir.file("text.vdb"));
    }
    SECTION("a .vdb with only a standard FloatGrid")
    {
        writeFloatGridFile(dir.file("float.vdb"));
        requireRejected(dir.file("float.vdb"));
    }
    SECTION("a missing file")
    {
        requireRejected(dir.file("does-not-exist.vdb"));
    }
    SECTION("a directory")
    {
        std::filesystem::create_directory(dir.path() / "folder.vdb");
        requireRejected(dir.file("folder.vdb"));
    }
}

namespace {

/// The first `keep` bytes of a real file, then 4 KiB of random bytes.
void checkHeaderThenJunk(std::initializer_list<std::size_t> keeps)
{
    TempDir dir;
    saveVolume(makeSculpted(), dir.file("good.vdb"));
    const std::vector<char> bytes = readBytes(dir.file("good.vdb"));
    uint64_t seed = 0x5eed0102;
    for (std::size_t keep : keeps) {
        std::vector<char> mixed(bytes.begin(), bytes.begin() + std::ptrdiff_t(keep));
        const std::vector<char> junk = randomBytes(4096, seed++);
        mixed.insert(mixed.end(), junk.begin(), junk.end());
        const std::string path = dir.file("mixed-" + std::to_string(keep) + ".vdb");
        writeBytes(path, mixed.data(), mixed.size());
        requireRejected(path);
    }
}

} // namespace

TEST_CASE("the real file header followed by random bytes is rejected", "[io]")
{
    checkHeaderThenJunk({8, 32, 64});
}

// Junk that starts inside the grid descriptors: without a trailer the file never reaches OpenVDB's
// metadata reader, which would allocate strings of the random lengths it reads (gigabytes per file).
TEST_CASE("random bytes after the grid descriptors are rejected", "[io][fuzz]")
{
    checkHeaderThenJunk({200, 400});
}

// OpenVDB 10's stream readers trust the sizes stored in the file (before the checksum trailer, a few
// flipped bytes corrupted the heap inside openvdb::io::bloscFromStream); saveVolume's trailer now
// lets loadVolume refuse damaged files before OpenVDB parses their grids.
TEST_CASE("corrupted bytes inside a saved file are rejected", "[io]")
{
    TempDir dir;
    saveVolume(makeSculpted(), dir.file("good.vdb"));
    const std::vector<char> bytes = readBytes(dir.file("good.vdb"));
    std::mt19937_64 rng(0x5eed0103);
    int rejected = 0;
    for (int trial = 0; trial < 40; ++trial) {
        std::vector<char> bad = bytes;
        for (int k = 0; k < 4; ++k) bad[std::size_t(rng() % bad.size())] ^= char(1 + rng() % 255);
        const std::string path = dir.file("flip.vdb");
        writeBytes(path, bad.data(), bad.size());
        try {
            (void)loadVolume(path);
        } catch (const VolumeIOError&) {
            ++rejected;
        }
    }
    CHECK(rejected == 40);
}

TEST_CASE("VDBClay metadata is checked on load", "[io]")
{
    TempDir dir;
    const Volume v = makeSculpted();
    const std::string materials = v.materials().toJson();
    const int current = currentFormatVersion();

    // Control: the hand-written file with the right metadata loads, so the rejections below come from
    // the metadata alone.
    writeHermiteFile(v, dir.file("ok.vdb"), current, materials);
    CHECK(identical(loadVolume(dir.file("ok.vdb")), v));

    SECTION("a newer format version")
    {
        writeHermiteFile(v, dir.file("newer.vdb"), current + 1, materials);
        requireRejected(dir.file("newer.vdb"));
        CHECK_THROWS_WITH(loadVolume(dir.file("newer.vdb")), Catch::Matchers::Contains("version"));
    }
    SECTION("format version 0")
    {
        writeHermiteFile(v, dir.file("zero.vdb"), 0, materials);
        requireRejected(dir.file("zero.vdb"));
    }
    SECTION("no format version")
    {
        writeHermiteFile(v, dir.file("nover.vdb"), std::nullopt, materials);
        requireRejected(dir.file("nover.vdb"));
    }
    SECTION("no materials table")
    {
        writeHermiteFile(v, dir.file("nomat.vdb"), current, std::nullopt);
        requireRejected(dir.file("nomat.vdb"));
    }
    SECTION("a malformed materials table")
    {
        writeHermiteFile(v, dir.file("badmat.vdb"), current, "[{\"name\": 3}]");
        requireRejected(dir.file("badmat.vdb"));
    }
    SECTION("no integrity trailer")
    {
        writeHermiteFile(v, dir.file("notrailer.vdb"), current, materials, /*trailer=*/false);
        requireRejected(dir.file("notrailer.vdb"));
    }
    SECTION("voxels that use a material the table lacks")
    {
        writeHermiteFile(v, dir.file("short.vdb"), current, MaterialTable().toJson());
        requireRejected(dir.file("short.vdb"));
    }
}

TEST_CASE("a file whose tiles hold a material the table lacks is rejected", "[io]")
{
    TempDir dir;
    Volume v(1.0);
    const MaterialId stone = defineMaterial(v, "stone", 0.9f);
    apply(v, CsgMode::Add, sphere(16.0), at({0.2, 0.1, 0.3}), 1);
    // Paint exactly the voxels [-8,7]^3: whole 8^3 blocks, so most "stone" voxels sit in tiles (only the
    // blocks on the +x/+y/+z faces stay leaves: they hold the samples of the edges leaving the region).
    apply(v, CsgMode::Paint, box({7.9, 7.9, 7.9}), at({-0.5, -0.5, -0.5}), stone);
    REQUIRE(v.materialAt({0, 0, 0}) == stone);
    REQUIRE(v.materialAt({-8, -8, -8}) == stone);
    REQUIRE(v.materialAt({-9, 0, 0}) == 1);
    REQUIRE(solidVoxelsPerMaterial(v)[stone] == 16u * 16u * 16u);
    REQUIRE(checkInvariants(v).empty());
    writeHermiteFile(v, dir.file("tiles.vdb"), currentFormatVersion(), MaterialTable().toJson());
    requireRejected(dir.file("tiles.vdb"));
}

TEST_CASE("saving over an existing file replaces it atomically", "[io]")
{
    TempDir dir;
    const std::string path = dir.file("vol.vdb");
    const Volume small = makeSmall();
    const Volume big = makeSculpted();
    saveVolume(small, path);
    const std::vector<char> oldBytes = readBytes(path);

    // A reader that opened the old file keeps reading the old content: the new file arrives by rename.
    std::ifstream reader(path, std::ios::binary);
    REQUIRE(reader);
    saveVolume(big, path);
    const std::vector<char> seen((std::istreambuf_iterator<char>(reader)), std::istreambuf_iterator<char>());
    CHECK(sameBytes(seen, oldBytes));

    CHECK(identical(loadVolume(path), big));
    CHECK(dir.entries() == std::vector<std::string>{"vol.vdb"});

    // And back again: still one file, holding the small volume.
    saveVolume(small, path);
    CHECK(identical(loadVolume(path), small));
    CHECK(dir.entries() == std::vector<std::string>{"vol.vdb"});
}

TEST_CASE("saving into a directory that does not exist throws and leaves nothing behind", "[io]")
{
    TempDir dir;
    const std::string path = (dir.path() / "missing" / "vol.vdb").string();
    CHECK_THROWS_AS(saveVolume(makeSmall(), path), VolumeIOError);
    CHECK_FALSE(std::filesystem::exists(dir.path() / "missing"));
    CHECK(dir.entries().empty());

    // A path naming a directory is refused too, and the directory is left alone.
    std::filesystem::create_directory(dir.path() / "sub");
    CHECK_THROWS_AS(saveVolume(makeSmall(), (dir.path() / "sub").string()), VolumeIOError);
    CHECK(std::filesystem::is_directory(dir.path() / "sub"));
    CHECK(dir.entries() == std::vector<std::string>{"sub"});
}

TEST_CASE("writeFileAtomically replaces a file whole or not at all", "[io][atomic]")
{
    TempDir dir;
    const std::string path = dir.file("notes.txt");
    writeFileAtomically(path, [](std::ostream& os) { os << "first"; });
    const std::vector<char> first{'f', 'i', 'r', 's', 't'};
    CHECK(readBytes(path) == first);

    // A writer that fails half-way leaves the old content and no temporary file.
    CHECK_THROWS_WITH(writeFileAtomically(path,
                                          [](std::ostream& os) {
                                              os << "half of the second";
                                              throw std::runtime_error("writer gave up");
                                          }),
                      "writer gave up");
    CHECK(readBytes(path) == first);
    CHECK(dir.entries() == std::vector<std::string>{"notes.txt"});

    // `finish` sees the temporary file with everything written so far and may append to it.
    writeFileAtomically(
        path, [](std::ostream& os) { os << "ab"; },
        [&](const std::string& temp, uint64_t bytes) {
            CHECK(bytes == 2);
            CHECK(temp != dir.file("notes.txt"));
            std::ofstream(temp, std::ios::binary | std::ios::app) << "c";
        });
    CHECK(readBytes(path) == std::vector<char>{'a', 'b', 'c'});
    CHECK(dir.entries() == std::vector<std::string>{"notes.txt"});

    CHECK_THROWS_AS(writeFileAtomically(dir.path().string(), [](std::ostream&) {}), FileWriteError);
    CHECK_THROWS_AS(writeFileAtomically(dir.file("missing/x.txt"), [](std::ostream&) {}), FileWriteError);
}

TEST_CASE("a failed save leaves the existing file intact and no temporary files", "[io]")
{
    TempDir dir;
    const std::string path = dir.file("vol.vdb");
    const Volume small = makeSmall();
    saveVolume(small, path);
    const std::vector<char> before = readBytes(path);

    // Measure how big the new file would be, then make writes fail halfway through it.
    const Volume big = makeSculpted();
    saveVolume(big, dir.file("probe.vdb"));
    const auto bigSize = std::filesystem::file_size(dir.file("probe.vdb"));
    std::filesystem::remove(dir.file("probe.vdb"));
    REQUIRE(bigSize > before.size() + 1000);

    struct rlimit saved {};
    REQUIRE(::getrlimit(RLIMIT_FSIZE, &saved) == 0);
    auto oldHandler = std::signal(SIGXFSZ, SIG_IGN); // a too-large write fails with EFBIG instead of killing us
    struct rlimit limited = saved;
    limited.rlim_cur = rlim_t(bigSize / 2);
    REQUIRE(::setrlimit(RLIMIT_FSIZE, &limited) == 0);
    bool threwIOError = false;
    std::string message;
    try {
        saveVolume(big, path);
    } catch (const VolumeIOError& e) {
        threwIOError = true;
        message = e.what();
    } catch (...) {
    }
    ::setrlimit(RLIMIT_FSIZE, &saved);
    std::signal(SIGXFSZ, oldHandler);

    INFO("message: " << message);
    CHECK(threwIOError);
    CHECK(sameBytes(readBytes(path), before));
    CHECK(identical(loadVolume(path), small));
    CHECK(dir.entries() == std::vector<std::string>{"vol.vdb"});
}

// Files whose payload was changed and whose trailer was recomputed (what anyone can craft): every one
// loads or is refused with one printable line, and none may crash, hang or allocate gigabytes. The
// sanitizer build in CI runs this with ASan, which turns any out-of-bounds access into a failure.
TEST_CASE("crafted files under a valid trailer load or are refused cleanly", "[io][fuzz]")
{
    TempDir dir;
    saveVolume(makeSculpted(), dir.file("good.vdb"));
    std::vector<char> bytes = readBytes(dir.file("good.vdb"));
    bytes.resize(bytes.size() - 24); // the payload, without its trailer
    std::mt19937_64 rng(0x5eed0201);
    const int64_t interesting[] = {0, 1, -1, 2, 255, 65535, 0x7fffffff, -0x7fffffffll - 1, 0x7fffffffffffffffll, 4096, -4096};
    int loaded = 0, refused = 0;
    for (int trial = 0; trial < 1500; ++trial) {
        std::vector<char> bad = bytes;
        const int mutations = 1 + int(rng() % 3);
        for (int m = 0; m < mutations; ++m) {
            const std::size_t at = std::size_t(rng() % bad.size());
            switch (rng() % 5) {
            case 0: bad[at] ^= char(1 + rng() % 255); break;
            case 1: { // a count or size replaced by an extreme value
                const int64_t v = interesting[rng() % std::size(interesting)];
                const std::size_t width = rng() % 2 ? 4 : 8;
                if (at + width <= bad.size()) std::memcpy(&bad[at], &v, width);
                break;
            }
            case 2: bad.resize(at + 1); break;                               // truncated
            case 3: bad.insert(bad.begin() + long(at), rng() % 64, char(rng())); break; // inserted junk
            default: bad.erase(bad.begin() + long(at), bad.begin() + long(std::min(bad.size(), at + rng() % 64))); break;
            }
        }
        const std::string path = dir.file("crafted.vdb");
        writeBytes(path, bad.data(), bad.size());
        appendIntegrityTrailer(path);
        try {
            (void)loadVolume(path);
            ++loaded;
        } catch (const VolumeIOError& e) {
            ++refused;
            const std::string what = e.what();
            INFO("trial " << trial << ": " << what);
            CHECK(what.find('\n') == std::string::npos);
            CHECK(std::all_of(what.begin(), what.end(), [](char c) { return c >= 32 && c < 127; }));
        }
    }
    CHECK(loaded + refused == 1500);
    CHECK(refused > 1000);
}
