#include "vdb_hermite/VolumeIO.h"

#include "vdb_hermite/FileStatus.h"

#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/PayloadCheck.h"
#include "vdb_hermite/PrintableText.h"

#include <openvdb/io/Stream.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

// OpenVDB trusts the sizes it reads, so a damaged file can corrupt memory while it is parsed. Every
// file we write therefore ends with a trailer holding the size and CRC-32 of everything before it,
// and a file is handed to OpenVDB only once both match. OpenVDB ignores bytes after the last grid.
constexpr std::array<char, 8> kTrailerMagic{'V', 'D', 'B', 'C', 'L', 'A', 'Y', '\0'};
struct Trailer {
    std::array<char, 8> magic;
    uint64_t payloadBytes;
    uint32_t crc;
    uint32_t formatVersion; // the same as the grid's metadata, readable before anything is parsed
};
static_assert(sizeof(Trailer) == 24, "the trailer is part of the file format");
constexpr uint64_t kTrailerBytes = sizeof(Trailer);

/// CRC-32 of the next `bytes` bytes of a stream.
uint32_t crcOfStream(std::istream& in, uint64_t bytes, const std::string& name)
{
    std::vector<char> buffer(std::size_t(std::min<uint64_t>(bytes, 1 << 20)) + 1);
    uLong crc = crc32(0L, Z_NULL, 0);
    while (bytes > 0) {
        const std::size_t chunk = std::size_t(std::min<uint64_t>(bytes, buffer.size()));
        in.read(buffer.data(), std::streamsize(chunk));
        if (std::size_t(in.gcount()) != chunk) throw VolumeIOError("cannot read '" + name + "'");
        crc = crc32(crc, reinterpret_cast<const Bytef*>(buffer.data()), uInt(chunk));
        bytes -= chunk;
    }
    return uint32_t(crc);
}

/// Appends the trailer to a stream that holds `payloadBytes` bytes of payload.
void appendTrailer(std::iostream& io, uint64_t payloadBytes, const std::string& name)
{
    io.clear();
    io.seekg(0);
    const Trailer trailer{kTrailerMagic, payloadBytes, crcOfStream(io, payloadBytes, name), uint32_t(kFormatVersion)};
    io.clear();
    io.seekp(std::streamoff(payloadBytes));
    io.write(reinterpret_cast<const char*>(&trailer), sizeof(trailer));
    io.flush();
    if (!io) throw VolumeIOError("cannot write '" + name + "' (disk full?)");
}

// OpenVDB writes a random UUID into every file header (36 ASCII characters after the magic number,
// the file and library versions and the grid-offsets flag), so two saves of one volume would differ.
// Saves replace it by one derived from the rest of the file: the same volume saves to the same bytes.
constexpr std::size_t kUuidOffset = 8 + 4 + 4 + 4 + 1, kUuidLength = 36;

/// A UUID (RFC 9562 version 8: custom) from two FNV-1a hashes of the file outside its UUID field.
void replaceUuidByContentHash(std::iostream& file, uint64_t bytes, const std::string& path)
{
    file.clear();
    file.seekg(0);
    std::vector<char> buffer(std::size_t(std::min<uint64_t>(bytes, 1 << 20)) + 1);
    uint64_t h1 = 0xcbf29ce484222325ull, h2 = 0x84222325cbf29ce4ull;
    char uuid[kUuidLength];
    for (uint64_t at = 0; at < bytes;) {
        const std::size_t chunk = std::size_t(std::min<uint64_t>(bytes - at, buffer.size()));
        file.read(buffer.data(), std::streamsize(chunk));
        if (std::size_t(file.gcount()) != chunk) throw VolumeIOError("cannot read back '" + path + "'");
        for (std::size_t i = 0; i < chunk; ++i, ++at) {
            if (at >= kUuidOffset && at < kUuidOffset + kUuidLength) {
                uuid[at - kUuidOffset] = buffer[i];
                continue;
            }
            const auto byte = uint8_t(buffer[i]);
            h1 = (h1 ^ byte) * 0x100000001b3ull;
            h2 = (h2 ^ byte) * 0x100000001b3ull + 0x9E37u;
        }
    }
    if (bytes < kUuidOffset + kUuidLength || uuid[8] != '-' || uuid[13] != '-' || uuid[18] != '-' || uuid[23] != '-')
        throw std::logic_error("OpenVDB's file header does not hold its UUID where expected");
    const uint64_t hi = (h1 & ~0xF000ull) | 0x8000ull;                          // version 8
    const uint64_t lo = (h2 & ~(uint64_t(3) << 62)) | (uint64_t(2) << 62);       // RFC variant
    char text[kUuidLength + 1];
    std::snprintf(text, sizeof(text), "%08x-%04x-%04x-%04x-%012llx", unsigned(hi >> 32), unsigned((hi >> 16) & 0xFFFF),
                  unsigned(hi & 0xFFFF), unsigned(lo >> 48), static_cast<unsigned long long>(lo & 0xFFFFFFFFFFFFull));
    file.clear();
    file.seekp(std::streamoff(kUuidOffset));
    file.write(text, std::streamsize(kUuidLength));
    file.flush();
    if (!file) throw VolumeIOError("cannot write '" + path + "' (disk full?)");
}

enum class Integrity { Verified, NoTrailer };

/// Checks the trailer of a stream of `size` bytes. Throws for a trailer that does not match its
/// payload; reports streams without one.
Integrity checkIntegrity(std::istream& in, uint64_t size, const std::string& path)
{
    if (size < sizeof(Trailer)) return Integrity::NoTrailer;
    Trailer trailer{};
    in.clear();
    in.seekg(std::streamoff(size - sizeof(Trailer)));
    in.read(reinterpret_cast<char*>(&trailer), sizeof(trailer));
    if (!in) throw VolumeIOError("cannot read '" + path + "'");
    if (trailer.magic != kTrailerMagic) return Integrity::NoTrailer;
    if (trailer.formatVersion > uint32_t(kFormatVersion))
        throw VolumeIOError("'" + path + "' has VDBClay format version " + std::to_string(trailer.formatVersion) +
                            "; this build reads versions 1 to " + std::to_string(kFormatVersion));
    in.seekg(0);
    if (trailer.payloadBytes != size - sizeof(Trailer) || crcOfStream(in, trailer.payloadBytes, path) != trailer.crc)
        throw VolumeIOError("'" + path + "' is damaged (its checksum does not match its content)");
    return Integrity::Verified;
}

bool hasVdbMagic(std::istream& in)
{
    int32_t magic = 0;
    in.clear();
    in.seekg(0);
    in.read(reinterpret_cast<char*>(&magic), sizeof(magic));
    return in && magic == openvdb::OPENVDB_MAGIC;
}

/// OpenVDB's data for a volume, Blosc-compressed: everything but the UUID fix and the trailer.
void writePayload(const Volume& volume, std::ostream& os)
{
    initializeHermiteGrid();
    HermiteGrid::Ptr out = openvdb::gridPtrCast<HermiteGrid>(volume.impl().grid->copyGrid()); // shares the tree
    out->insertMeta(kFormatVersionKey, openvdb::Int32Metadata(kFormatVersion));
    out->insertMeta(kMaterialsKey, openvdb::StringMetadata(volume.materials().toJson()));
    if (volume.mask().any()) out->insertMeta(kMaskKey, openvdb::StringMetadata(volume.mask().encode()));
    openvdb::io::Stream stream(os);
    stream.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    stream.write(openvdb::GridCPtrVec{out});
}

/// Reads a volume from `in`, which holds `size` bytes of what saveVolume writes; `path` names the
/// source in messages. The stream is checked before OpenVDB parses any of it.
Volume readVolume(std::istream& in, uint64_t size, const std::string& path)
{
    if (!hasVdbMagic(in)) throw VolumeIOError("'" + path + "' is not a .vdb file");
    // Without a trailer the file is foreign or damaged; it never reaches OpenVDB's parser, which
    // trusts the sizes it reads (junk can make it allocate gigabytes or corrupt memory).
    if (checkIntegrity(in, size, path) != Integrity::Verified) {
        throw VolumeIOError("'" + path + "' is not a VDBClay volume: it has no VDBClay checksum trailer "
                            "(a .vdb from another tool, or a truncated or damaged VDBClay file)");
    }
    // Every count and size OpenVDB will trust is checked first (PayloadCheck.h), and what it will
    // allocate is held to a small multiple of the file's size.
    const uint64_t payloadBytes = size - kTrailerBytes;
    in.clear();
    in.seekg(0);
    const PayloadSummary summary = checkPayload(in, payloadBytes, path, HermiteGrid::gridType());
    if (summary.estimatedMemoryBytes > 64 * payloadBytes + (64u << 20))
        throw VolumeIOError("'" + path + "' is corrupt: its tree would take " +
                            std::to_string(summary.estimatedMemoryBytes >> 20) + " MiB for a " +
                            std::to_string(payloadBytes >> 10) + " KiB file");
    // Parsed from a stream we own, so a read past the end (a payload that is shorter than its
    // structure says) shows up as a failed stream or a wrong end position.
    in.clear();
    in.seekg(0);
    openvdb::io::Stream stream(in, /*delayLoad=*/false);
    if (in.fail() || in.tellg() != std::streamoff(payloadBytes))
        throw VolumeIOError("'" + path + "' is damaged: its grids do not end where its checksum says");
    HermiteGrid::Ptr grid;
    std::string found;
    for (const auto& g : *stream.getGrids()) {
        found += (found.empty() ? "" : ", ") + g->getName() + " (" + g->type() + ")";
        if (g->type() != HermiteGrid::gridType() || (grid && grid->getName() == "hermite")) continue;
        grid = openvdb::gridPtrCast<HermiteGrid>(g);
    }
    if (!grid) {
        throw VolumeIOError("'" + path + "' is a .vdb file without a VDBClay Hermite grid" +
                            (found.empty() ? std::string() : "; it holds: " + found));
    }
    const auto version = grid->metaValue<int32_t>(kFormatVersionKey);
    if (version > kFormatVersion || version < 1) {
        throw VolumeIOError("'" + path + "' has VDBClay format version " + std::to_string(version) +
                            "; this build reads versions 1 to " + std::to_string(kFormatVersion));
    }
    MaterialTable materials = MaterialTable::fromJson(grid->metaValue<std::string>(kMaterialsKey));
    if (!grid->hasUniformVoxels() || !grid->transform().isLinear())
        throw VolumeIOError("'" + path + "': the Hermite grid needs a linear transform with cubic voxels");
    if (grid->background().id != kEmptyMaterial)
        throw VolumeIOError("'" + path + "': the Hermite grid's background must be empty");
    const auto undefinedMaterial = [&](MaterialValue v) { return v.id > materials.size(); };
    bool corrupt = false;
    for (auto leaf = grid->constTree().cbeginLeaf(); leaf && !corrupt; ++leaf) {
        const MaterialValue* values = leaf->buffer().data();
        corrupt = std::any_of(values, values + kLeafVoxels, undefinedMaterial);
    }
    forEachTile(grid->constTree(), [&](const CoordBBox&, MaterialValue v) { corrupt = corrupt || undefinedMaterial(v); });
    if (corrupt) throw VolumeIOError("'" + path + "' is corrupt: a voxel uses an undefined material id");
    VoxelMask mask;
    if (const auto maskMeta = grid->getMetadata<openvdb::StringMetadata>(kMaskKey)) {
        try {
            mask = VoxelMask::decode(maskMeta->value());
        } catch (const MaskFormatError& e) {
            throw VolumeIOError("'" + path + "': " + e.what());
        }
    }
    grid->removeMeta(kFormatVersionKey);
    grid->removeMeta(kMaterialsKey);
    grid->removeMeta(kMaskKey);
    Volume volume(grid->voxelSize()[0]);
    volume.impl().grid = grid;
    volume.materials() = std::move(materials);
    volume.mask() = std::move(mask);
    volume.impl().formatVersion = version;
    return volume;
}

/// Runs `read`, turning every library failure into a VolumeIOError of one printable line.
template<typename Read>
Volume guardedRead(const std::string& path, Read&& read)
{
    try {
        return read();
    } catch (const VolumeIOError&) {
        throw;
    } catch (const openvdb::TypeError&) {
        throw VolumeIOError("'" + path + "' lacks the VDBClay metadata (format version, materials)");
    } catch (const openvdb::LookupError&) {
        throw VolumeIOError("'" + path + "' lacks the VDBClay metadata (format version, materials)");
    } catch (const std::bad_alloc&) {
        throw VolumeIOError("'" + path + "' is corrupt (implausible sizes)");
    } catch (const std::exception& e) {
        std::string what = e.what();
        if (what.find("not a VDB file") != std::string::npos || what.find("magic number") != std::string::npos)
            throw VolumeIOError("'" + path + "' is not a .vdb file");
        throw VolumeIOError("'" + path + "' cannot be read: " + printableText(what)); // libraries quote the file's bytes
    }
}

} // namespace

std::string encodeVolume(const Volume& volume)
{
    std::stringstream bytes(std::ios::in | std::ios::out | std::ios::binary);
    writePayload(volume, bytes);
    const uint64_t written = uint64_t(bytes.tellp());
    replaceUuidByContentHash(bytes, written, "volume");
    appendTrailer(bytes, written, "volume");
    return bytes.str();
}

Volume decodeVolume(const std::string& bytes, const std::string& name)
{
    initializeHermiteGrid();
    std::istringstream in(bytes, std::ios::binary);
    return guardedRead(name, [&] { return readVolume(in, bytes.size(), name); });
}

void saveVolume(const Volume& volume, const std::string& path)
{
    try {
        // Written through a stream we own: OpenVDB's File does not check its writes, so a full disk
        // would otherwise go unnoticed.
        writeFileAtomically(
            path, [&](std::ostream& os) { writePayload(volume, os); },
            [](const std::string& temp, uint64_t written) {
                if (std::filesystem::file_size(temp) != written)
                    throw VolumeIOError("cannot write '" + temp + "' completely (disk full?)");
                std::fstream file(temp, std::ios::binary | std::ios::in | std::ios::out);
                replaceUuidByContentHash(file, written, temp);
                appendTrailer(file, written, temp);
            });
    } catch (const FileWriteError& e) {
        throw VolumeIOError(e.what());
    } catch (const VolumeIOError&) {
        throw;
    } catch (const std::exception& e) {
        throw VolumeIOError("cannot write '" + path + "': " + e.what());
    }
}

VdbFileKind classifyVdbFile(const std::string& path)
{
    std::error_code ec;
    if (const auto why = unreachableFile(path)) throw VolumeIOError(*why);
    if (!fs::is_regular_file(path, ec)) throw VolumeIOError("'" + path + "' is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw VolumeIOError("cannot open '" + path + "': " + std::strerror(errno));
    if (!hasVdbMagic(in)) return VdbFileKind::NotVdb;
    // A trailer marks VDBClay's files; whether it verifies is loadVolume's to say (damaged, newer).
    const uint64_t size = fs::file_size(path);
    Trailer trailer{};
    if (size >= sizeof(Trailer)) {
        in.clear();
        in.seekg(std::streamoff(size - sizeof(Trailer)));
        in.read(reinterpret_cast<char*>(&trailer), sizeof(trailer));
    }
    return in && trailer.magic == kTrailerMagic ? VdbFileKind::VdbClay : VdbFileKind::Other;
}

Volume loadVolume(const std::string& path)
{
    initializeHermiteGrid();
    std::error_code ec;
    if (const auto why = unreachableFile(path)) throw VolumeIOError(*why);
    if (!fs::is_regular_file(path, ec)) throw VolumeIOError("'" + path + "' is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw VolumeIOError("cannot open '" + path + "': " + std::strerror(errno));
    return guardedRead(path, [&] { return readVolume(in, fs::file_size(path), path); });
}

} // namespace vdbclay
