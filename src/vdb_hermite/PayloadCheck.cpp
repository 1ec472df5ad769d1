#include "vdb_hermite/PayloadCheck.h"

#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeIO.h"

#include <openvdb/io/Compression.h>
#include <openvdb/version.h>

#include <blosc.h>
#include <zlib.h>

#include <array>
#include <bitset>
#include <cstring>
#include <istream>
#include <optional>
#include <set>
#include <tuple>
#include <vector>

namespace vdbclay {

namespace {

/// A bounded view of the payload: every read states what it reads, and nothing reads past the end.
class PayloadReader {
public:
    PayloadReader(std::istream& in, uint64_t size, const std::string& path) : in_(in), size_(size), path_(path) {}

    [[noreturn]] void fail(const std::string& what) const
    {
        throw VolumeIOError("'" + path_ + "' is corrupt: " + what + " (at byte " + std::to_string(pos_) + ")");
    }
    uint64_t remaining() const { return size_ - pos_; }
    uint64_t position() const { return pos_; }

    void read(void* out, uint64_t n, const char* what)
    {
        if (n > remaining()) fail(std::string(what) + " runs past the end of the payload");
        in_.read(static_cast<char*>(out), std::streamsize(n));
        if (!in_) fail(std::string("cannot read ") + what);
        pos_ += n;
    }
    void skip(uint64_t n, const char* what)
    {
        if (n > remaining()) fail(std::string(what) + " runs past the end of the payload");
        in_.seekg(std::streamoff(n), std::ios::cur);
        if (!in_) fail(std::string("cannot read ") + what);
        pos_ += n;
    }
    template<typename T>
    T value(const char* what)
    {
        T v;
        read(&v, sizeof(T), what);
        return v;
    }
    /// A length-prefixed string (uint32 length), at most `maxLength` bytes.
    std::string text(const char* what, uint32_t maxLength)
    {
        const uint32_t length = value<uint32_t>(what);
        if (length > maxLength) fail(std::string(what) + " is " + std::to_string(length) + " bytes long");
        if (length > remaining()) fail(std::string(what) + " runs past the end of the payload");
        std::string s(length, '\0');
        read(s.data(), length, what);
        return s;
    }

private:
    std::istream& in_;
    uint64_t size_;
    uint64_t pos_ = 0;
    const std::string& path_;
};

/// A name from the file as it may appear in a message.
std::string printable(const std::string& s) { return printableText(s, 64); }

/// What a grid's metadata says that the check needs.
struct GridMetadata {
    std::string gridClass;
    bool halfFloat = false;
};

/// Metadata of the file or of a grid (MetaMap): each value's size must match its type, whose reader
/// ignores the stored size for fixed-size types. Types OpenVDB does not know it reads as opaque bytes
/// of the stored size; VDBClay's own files have none.
GridMetadata checkMetadata(PayloadReader& r, bool foreign)
{
    GridMetadata out;
    const uint32_t count = r.value<uint32_t>("the metadata count");
    if (uint64_t(count) * 12 > r.remaining()) r.fail("the metadata count " + std::to_string(count) + " does not fit the file");
    static const std::array<std::pair<const char*, uint32_t>, 16> kFixed{
        {{"bool", 1}, {"int32", 4}, {"int64", 8}, {"float", 4}, {"double", 8}, {"vec2i", 8}, {"vec2s", 8}, {"vec2d", 16},
         {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16}, {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}}};
    for (uint32_t i = 0; i < count; ++i) {
        const std::string name = r.text("a metadata name", 4096);
        const std::string type = r.text("a metadata type name", 256);
        const uint32_t bytes = r.value<uint32_t>("a metadata size");
        bool known = type == "string";
        for (const auto& [fixedType, size] : kFixed) {
            if (type != fixedType) continue;
            known = true;
            if (bytes != size) r.fail("metadata '" + printable(name) + "' of type " + type + " has " + std::to_string(bytes) + " bytes");
        }
        if (!known && !foreign) r.fail("metadata '" + printable(name) + "' has a type VDBClay does not read ('" + printable(type) + "')");
        if (name == "class" && type == "string" && bytes <= 256) {
            out.gridClass.resize(bytes);
            r.read(out.gridClass.data(), bytes, "a grid's class");
        } else if (name == "is_saved_as_half_float" && type == "bool") {
            out.halfFloat = r.value<uint8_t>("a grid's half-float flag") != 0;
        } else {
            r.skip(bytes, "a metadata value");
        }
    }
    return out;
}

constexpr uint32_t kHermiteCompression = openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK;
constexpr uint32_t kStandardCompression = kHermiteCompression | openvdb::io::COMPRESS_ZIP;

void checkBloscHeader(PayloadReader& r, const unsigned char* header, uint64_t expectedBytes, int64_t stored)
{
    uint32_t nbytes, blocksize, cbytes;
    std::memcpy(&nbytes, header + 4, 4);
    std::memcpy(&blocksize, header + 8, 4);
    std::memcpy(&cbytes, header + 12, 4);
    if (nbytes != expectedBytes) r.fail("a compressed block expands to " + std::to_string(nbytes) + " bytes where " + std::to_string(expectedBytes) + " belong");
    if (cbytes != uint64_t(stored)) r.fail("a compressed block's header disagrees with its size");
    if (nbytes > 0 && blocksize == 0) r.fail("a compressed block has no block size");
}

/// One block of `expectedBytes` values as io::readData writes them with this compression. With
/// `decode`, compressed data is also decompressed here: OpenVDB throws where it does not decode, from
/// inside RootNode::readTopology, which then leaks the node it was reading.
void checkDataBlock(PayloadReader& r, uint64_t expectedBytes, uint32_t compression, bool decode)
{
    if (!(compression & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP))) {
        r.skip(expectedBytes, "an uncompressed block");
        return;
    }
    const int64_t stored = r.value<int64_t>("a compressed block's size");
    if (stored <= 0) {
        // Stored uncompressed: OpenVDB reads -stored bytes into a buffer of expectedBytes before it checks.
        const uint64_t raw = uint64_t(0) - uint64_t(stored); // -stored, defined for INT64_MIN too
        if (raw != expectedBytes)
            r.fail("an uncompressed block of " + std::to_string(raw) + " bytes where " + std::to_string(expectedBytes) + " belong");
        r.skip(expectedBytes, "an uncompressed block");
        return;
    }
    if (uint64_t(stored) > r.remaining()) r.fail("a compressed block of " + std::to_string(stored) + " bytes runs past the end of the payload");
    if (compression & openvdb::io::COMPRESS_ZIP) {
        if (!decode) {
            r.skip(uint64_t(stored), "a zip block"); // zlib fails where the data would not fit its buffer
            return;
        }
        std::string zipped(std::size_t(stored), '\0');
        r.read(zipped.data(), uint64_t(stored), "a zip block");
        std::string out(std::size_t(expectedBytes), '\0');
        uLongf size = uLongf(expectedBytes);
        if (uncompress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(zipped.data()), uLong(stored)) != Z_OK ||
            size != expectedBytes)
            r.fail("a zip block does not decompress to the " + std::to_string(expectedBytes) + " bytes it must hold");
        return;
    }
    // Blosc's header: version, versionlz, flags, typesize, then nbytes, blocksize, cbytes (uint32 each).
    unsigned char header[16];
    if (stored < 16) r.fail("a compressed block is shorter than its header");
    if (decode) {
        std::string block(std::size_t(stored), '\0');
        r.read(block.data(), uint64_t(stored), "a compressed block");
        std::memcpy(header, block.data(), sizeof(header));
        checkBloscHeader(r, header, expectedBytes, stored);
        std::string out(std::size_t(expectedBytes) + 1, '\0');
        if (expectedBytes > 0 && blosc_decompress_ctx(block.data(), out.data(), out.size(), 1) != int(expectedBytes))
            r.fail("a compressed block does not decompress to the " + std::to_string(expectedBytes) + " bytes it must hold");
        return;
    }
    r.read(header, sizeof(header), "a compressed block's header");
    checkBloscHeader(r, header, expectedBytes, stored);
    r.skip(uint64_t(stored) - sizeof(header), "a compressed block");
}

/// How a tree's values are stored: `valueBytes` as written in compressed blocks (half floats where the
/// grid says so), `fullValueBytes` where OpenVDB writes one value at full size (backgrounds, tiles of
/// the root, inactive values); `hermite`: VDBClay's leaves, with edge masks and samples.
struct TreeLayout {
    uint64_t valueBytes = 2;
    uint64_t fullValueBytes = 2;
    bool hermite = true;
    bool half = false; // OpenVDB's half-float reader reads nothing for no values (no block header either)
    bool decode = false; // decompress every block (files of other tools)
};

/// A node's values as io::readCompressedValues reads them, for a node of `count` values with the given
/// value mask (bit i: value i is active).
template<std::size_t N>
void checkCompressedValues(PayloadReader& r, const std::bitset<N>& valueMask, uint32_t compression, const TreeLayout& layout)
{
    using openvdb::io::MASK_AND_NO_INACTIVE_VALS;
    using openvdb::io::MASK_AND_ONE_INACTIVE_VAL;
    using openvdb::io::MASK_AND_TWO_INACTIVE_VALS;
    using openvdb::io::NO_MASK_AND_ALL_VALS;
    using openvdb::io::NO_MASK_AND_ONE_INACTIVE_VAL;
    const int8_t metadata = r.value<int8_t>("a node's compression flag");
    if (metadata < 0 || metadata > NO_MASK_AND_ALL_VALS) r.fail("a node's compression flag is " + std::to_string(metadata));
    if (metadata == NO_MASK_AND_ONE_INACTIVE_VAL || metadata == MASK_AND_ONE_INACTIVE_VAL) r.skip(layout.fullValueBytes, "an inactive value");
    if (metadata == MASK_AND_TWO_INACTIVE_VALS) r.skip(2 * layout.fullValueBytes, "two inactive values");
    if (metadata == MASK_AND_NO_INACTIVE_VALS || metadata == MASK_AND_ONE_INACTIVE_VAL || metadata == MASK_AND_TWO_INACTIVE_VALS)
        r.skip(N / 8, "a selection mask");
    const bool maskCompressed = compression & openvdb::io::COMPRESS_ACTIVE_MASK;
    const uint64_t count = maskCompressed && metadata != NO_MASK_AND_ALL_VALS ? valueMask.count() : N;
    if (layout.half && count == 0) return;
    checkDataBlock(r, count * layout.valueBytes, compression, layout.decode);
}

template<std::size_t N>
std::bitset<N> readMask(PayloadReader& r, const char* what)
{
    std::array<uint64_t, N / 64> words;
    r.read(words.data(), sizeof(words), what);
    std::bitset<N> mask;
    for (std::size_t w = 0; w < words.size(); ++w)
        for (int b = 0; b < 64; ++b)
            if ((words[w] >> b) & 1u) mask.set(w * 64 + std::size_t(b));
    return mask;
}

// The tree: Tree<Root, Internal<5>, Internal<4>, Leaf<3>>.
constexpr std::size_t kUpperSize = 1u << 15, kLowerSize = 1u << 12, kLeafSize = 1u << 9;
constexpr uint64_t kUpperBytes = 8 * kUpperSize + 2 * kUpperSize / 8 + 64; // node table, masks, header
constexpr uint64_t kLowerBytes = 8 * kLowerSize + 2 * kLowerSize / 8 + 64;
constexpr uint64_t kHermiteLeafExtraBytes = 192 + 48; // edge mask, prefix counts

/// Returns where the tree's buffers (its leaves' values) begin.
uint64_t checkTree(PayloadReader& r, uint32_t compression, const TreeLayout& layout, PayloadSummary& summary)
{
    const uint32_t buffers = r.value<uint32_t>("the tree's buffer count");
    if (buffers != 1) r.fail("the tree has " + std::to_string(buffers) + " buffers per node (OpenVDB writes one)");
    if (layout.hermite) {
        const uint16_t background = r.value<uint16_t>("the background value");
        if (background != 0) r.fail("the background is material " + std::to_string(background) + ", not empty");
    } else {
        r.skip(layout.fullValueBytes, "the background value");
    }
    const uint32_t tiles = r.value<uint32_t>("the root's tile count");
    const uint32_t children = r.value<uint32_t>("the root's child count");
    if (uint64_t(tiles) * (13 + layout.fullValueBytes) > r.remaining()) r.fail(std::to_string(tiles) + " root tiles do not fit the file");
    if (uint64_t(children) * (12 + kUpperSize / 4) > r.remaining()) r.fail(std::to_string(children) + " root children do not fit the file");
    std::set<std::tuple<int32_t, int32_t, int32_t>> origins;
    auto checkOrigin = [&](const int32_t c[3], const char* what) {
        for (int a = 0; a < 3; ++a)
            if (c[a] % 4096 != 0) r.fail(std::string(what) + " at a position that is not a multiple of 4096");
        if (!origins.insert({c[0], c[1], c[2]}).second) r.fail(std::string("two ") + what + "s at one position");
    };
    for (uint32_t t = 0; t < tiles; ++t) {
        int32_t origin[3];
        r.read(origin, sizeof(origin), "a root tile's position");
        checkOrigin(origin, "root tile");
        r.skip(layout.fullValueBytes, "a root tile's value");
        const uint8_t active = r.value<uint8_t>("a root tile's state");
        if (active > 1) r.fail("a root tile's state is neither on nor off");
    }
    uint64_t leavesOfTree = 0;
    for (uint32_t c = 0; c < children; ++c) {
        int32_t origin[3];
        r.read(origin, sizeof(origin), "a root child's position");
        checkOrigin(origin, "root child");
        ++summary.upperNodes;
        const auto upperChildren = readMask<kUpperSize>(r, "an upper node's child mask");
        const auto upperValues = readMask<kUpperSize>(r, "an upper node's value mask");
        checkCompressedValues(r, upperValues, compression, layout);
        if (upperChildren.count() * (kLowerSize / 4) > r.remaining()) r.fail("an upper node's children do not fit the file");
        for (std::size_t i = 0; i < upperChildren.count(); ++i) {
            ++summary.lowerNodes;
            const auto lowerChildren = readMask<kLowerSize>(r, "a lower node's child mask");
            const auto lowerValues = readMask<kLowerSize>(r, "a lower node's value mask");
            checkCompressedValues(r, lowerValues, compression, layout);
            const std::size_t leaves = lowerChildren.count();
            if (leaves * (kLeafSize / 8) > r.remaining()) r.fail("a lower node's leaves do not fit the file");
            r.skip(leaves * (kLeafSize / 8), "leaf value masks");
            leavesOfTree += leaves;
        }
    }
    // The buffers: each leaf's value mask and values (and for Hermite leaves, edge mask and samples).
    const uint64_t buffersAt = r.position();
    for (uint64_t leaf = 0; leaf < leavesOfTree; ++leaf) {
        const auto values = readMask<kLeafSize>(r, "a leaf's value mask");
        checkCompressedValues(r, values, compression, layout);
        if (!layout.hermite) continue;
        std::array<uint64_t, 24> edges;
        r.read(edges.data(), sizeof(edges), "a leaf's edge mask");
        uint64_t crossings = 0;
        for (uint64_t w : edges) crossings += uint64_t(__builtin_popcountll(w));
        const uint32_t samples = r.value<uint32_t>("a leaf's sample count");
        if (samples != crossings) r.fail("a leaf holds " + std::to_string(samples) + " samples for " + std::to_string(crossings) + " crossing edges");
        if (samples > 0) checkDataBlock(r, uint64_t(samples) * 6, compression, layout.decode);
    }
    summary.leaves += leavesOfTree;
    const uint64_t leafBytes = layout.fullValueBytes * kLeafSize + 64 + 64 + (layout.hermite ? kHermiteLeafExtraBytes : 0);
    summary.estimatedMemoryBytes += leavesOfTree * leafBytes;
    return buffersAt;
}

/// OpenVDB names a grid saved with half floats after its type with this suffix.
const std::string kHalfFloatSuffix = "_HalfFloat";

bool halfFloatType(const std::string& gridType)
{
    return gridType.size() > kHalfFloatSuffix.size() &&
           gridType.compare(gridType.size() - kHalfFloatSuffix.size(), kHalfFloatSuffix.size(), kHalfFloatSuffix) == 0;
}

/// The value type of a tree of the standard configuration ("Tree_float_5_4_3" -> "float"), or "".
std::string valueTypeOf(std::string gridType)
{
    if (halfFloatType(gridType)) gridType.resize(gridType.size() - kHalfFloatSuffix.size());
    const std::string prefix = "Tree_", suffix = "_5_4_3";
    if (gridType.size() <= prefix.size() + suffix.size() || gridType.compare(0, prefix.size(), prefix) != 0 ||
        gridType.compare(gridType.size() - suffix.size(), suffix.size(), suffix) != 0)
        return "";
    return gridType.substr(prefix.size(), gridType.size() - prefix.size() - suffix.size());
}

/// The layout of the standard value types VDBClay reads, or nullopt.
std::optional<TreeLayout> standardLayout(const std::string& valueType, bool halfFloat)
{
    static const std::array<std::tuple<const char*, uint64_t, uint64_t>, 7> kTypes{
        {{"float", 4, 2}, {"double", 8, 2}, {"int32", 4, 4}, {"int64", 8, 8}, {"vec3s", 12, 6}, {"vec3d", 24, 6}, {"vec3i", 12, 12}}};
    for (const auto& [name, bytes, halfBytes] : kTypes)
        if (valueType == name) return TreeLayout{halfFloat && halfBytes != bytes ? halfBytes : bytes, bytes, false, halfFloat && halfBytes != bytes, true};
    return std::nullopt;
}

/// Doubles a transform of this map type writes, or 0 for a map VDBClay does not read.
uint64_t transformDoubles(const std::string& map, bool foreign)
{
    if (map == "UniformScaleMap") return 15;
    if (map == "UniformScaleTranslateMap") return 18;
    if (!foreign) return 0;
    if (map == "ScaleMap") return 15;
    if (map == "ScaleTranslateMap") return 18;
    if (map == "TranslationMap") return 3;
    if (map == "AffineMap" || map == "UnitaryMap") return 16;
    return 0;
}

} // namespace

PayloadSummary checkPayload(std::istream& in, uint64_t payloadBytes, const std::string& path, const std::string& hermiteGridType,
                            AcceptedGrids accepted)
{
    const bool foreign = accepted == AcceptedGrids::Standard;
    PayloadReader r(in, payloadBytes, path);
    PayloadSummary summary;
    if (r.value<int64_t>("the file's magic number") != openvdb::OPENVDB_MAGIC) r.fail("not a .vdb file");
    const uint32_t fileVersion = r.value<uint32_t>("the file format version");
    if (!foreign && fileVersion != openvdb::OPENVDB_FILE_VERSION)
        r.fail("OpenVDB file format " + std::to_string(fileVersion) + " where VDBClay writes " + std::to_string(openvdb::OPENVDB_FILE_VERSION));
    if (foreign && (fileVersion < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION || fileVersion > openvdb::OPENVDB_FILE_VERSION))
        throw VolumeIOError("'" + path + "' is in OpenVDB file format " + std::to_string(fileVersion) + "; VDBClay reads formats " +
                            std::to_string(openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) + " to " +
                            std::to_string(openvdb::OPENVDB_FILE_VERSION));
    r.skip(4 + 4, "the library version");
    // With grid offsets OpenVDB seeks to each grid's stream positions: they must be where its parts are.
    const bool offsets = r.value<uint8_t>("the grid-offsets flag") != 0;
    r.skip(36, "the file's UUID");
    checkMetadata(r, foreign);
    const uint32_t grids = r.value<uint32_t>("the grid count");
    if (grids == 0) r.fail("the file holds no grid");
    if (grids > 1024) r.fail("the grid count is " + std::to_string(grids));
    for (uint32_t g = 0; g < grids; ++g) {
        GridHeader header;
        header.name = r.text("a grid name", 4096);
        header.type = r.text("a grid type name", 256);
        header.valueType = valueTypeOf(header.type);
        if (!foreign && header.type != hermiteGridType)
            throw VolumeIOError("'" + path + "' is a .vdb file without a VDBClay Hermite grid; it holds: " + printable(header.name) +
                                " (" + printable(header.type) + ")");
        const bool instance = !r.text("a grid's instance parent", 4096).empty();
        if (instance && !foreign) r.fail("an instanced grid (VDBClay writes none)");
        const int64_t gridAt = r.value<int64_t>("a grid's position");
        const int64_t blocksAt = r.value<int64_t>("a grid's block position");
        const int64_t end = r.value<int64_t>("a grid's end position");
        if (offsets && gridAt != int64_t(r.position())) r.fail("a grid's position is not where its data begins");
        const uint32_t compression = r.value<uint32_t>("a grid's compression flags");
        if (compression & ~(foreign ? kStandardCompression : kHermiteCompression))
            r.fail("compression flags " + std::to_string(compression) + " VDBClay does not read");
        const GridMetadata meta = checkMetadata(r, foreign);
        header.gridClass = meta.gridClass;
        header.halfFloat = meta.halfFloat || halfFloatType(header.type);
        header.transform = r.text("the transform's map type", 256);
        const uint64_t doubles = transformDoubles(header.transform, foreign);
        if (doubles == 0) r.fail("a transform of type '" + printable(header.transform) + "' VDBClay does not read");
        r.skip(doubles * 8, "the transform");
        const std::optional<TreeLayout> layout =
            !foreign ? std::optional<TreeLayout>(TreeLayout{}) : instance ? std::nullopt : standardLayout(header.valueType, header.halfFloat);
        if (layout) {
            const uint64_t buffersAt = checkTree(r, compression, *layout, summary);
            if (offsets && blocksAt != int64_t(buffersAt)) r.fail("a grid's block position is not where its buffers begin");
            header.treeChecked = true;
        } else {
            // Skipped by the positions the file gives for it (OpenVDB seeks to them too).
            if (end <= int64_t(r.position()) || uint64_t(end) > payloadBytes || blocksAt < int64_t(r.position()) || blocksAt > end)
                r.fail("a grid of type '" + printable(header.type) + "' VDBClay cannot check, without valid stream positions");
            r.skip(uint64_t(end) - r.position(), "a grid VDBClay does not read");
        }
        if ((offsets || end != 0) && uint64_t(end) != r.position()) r.fail("a grid does not end where its descriptor says");
        summary.grids.push_back(std::move(header));
    }
    if (r.remaining() != 0) r.fail("the grids end " + std::to_string(r.remaining()) + " bytes before the end");
    summary.estimatedMemoryBytes += summary.upperNodes * kUpperBytes + summary.lowerNodes * kLowerBytes;
    return summary;
}

} // namespace vdbclay
