#include "render/ImageFile.h"

#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/FileStatus.h"

#include <stb_image.h>
#include <stb_image_write.h>

#include <zlib.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <memory>
#include <ostream>
#include <stdexcept>

namespace vdbclay::render {

namespace {
void appendBytes(void* context, void* data, int size)
{
    auto* out = static_cast<std::string*>(context);
    out->append(static_cast<const char*>(data), std::size_t(size));
}
} // namespace

std::string encodePng(const Image& image)
{
    if (image.width <= 0 || image.height <= 0 || image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4)
        throw std::runtime_error("cannot encode an empty or malformed picture");
    std::string bytes;
    if (!stbi_write_png_to_func(&appendBytes, &bytes, image.width, image.height, 4, image.rgba.data(), image.width * 4))
        throw std::runtime_error("cannot encode the picture as PNG");
    return bytes;
}

void writePng(const Image& image, const std::string& path)
{
    std::string bytes;
    try {
        bytes = encodePng(image);
    } catch (const std::runtime_error& e) {
        throw std::runtime_error("cannot write " + path + ": " + e.what());
    }
    writeFileAtomically(path, [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); });
}

namespace {

constexpr uint64_t kMaxPictureFileBytes = 1ull << 30;

uint32_t bigEndian32(const std::string& bytes, std::size_t at)
{
    return uint32_t(uint8_t(bytes[at])) << 24 | uint32_t(uint8_t(bytes[at + 1])) << 16 | uint32_t(uint8_t(bytes[at + 2])) << 8 |
           uint32_t(uint8_t(bytes[at + 3]));
}

void appendBigEndian32(std::string& out, uint32_t v)
{
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(char((v >> shift) & 0xFF));
}

} // namespace

void padPngPalette(std::string& png)
{
    static const char kSignature[] = "\x89PNG\r\n\x1a\n";
    if (png.size() < 33 || png.compare(0, 8, kSignature, 8) != 0 || png.compare(12, 4, "IHDR") != 0) return;
    const int depth = uint8_t(png[24]), colourType = uint8_t(png[25]);
    if (colourType != 3 || (depth != 1 && depth != 2 && depth != 4 && depth != 8)) return;
    const uint32_t full = 1u << depth;
    for (std::size_t at = 8; at + 12 <= png.size();) {
        const uint32_t length = bigEndian32(png, at);
        if (length > png.size() - at - 12) return; // truncated: stb reports it
        const std::string type = png.substr(at + 4, 4);
        if (type == "IDAT" || type == "IEND") return; // no palette before the pixels: stb refuses the file
        if (type == "PLTE") {
            if (length % 3 != 0 || length / 3 >= full) return;
            std::string chunk = "PLTE" + png.substr(at + 8, length) + std::string(std::size_t(full * 3 - length), '\0');
            std::string replaced;
            appendBigEndian32(replaced, uint32_t(chunk.size() - 4));
            replaced += chunk;
            appendBigEndian32(replaced, uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(chunk.data()), uInt(chunk.size()))));
            png.replace(at, 12 + length, replaced);
            return;
        }
        at += 12 + length;
    }
}

namespace {
DecodedPicture decodeBytes(std::string bytes, const std::string& path)
{
    padPngPalette(bytes);
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
    const int length = int(std::min<std::size_t>(bytes.size(), std::size_t(INT32_MAX)));
    DecodedPicture picture;
    int channels = 0;
    // Sizes first: a forged header must not make stb allocate gigabytes.
    if (stbi_info_from_memory(data, length, &picture.width, &picture.height, &channels) &&
        (picture.width > kMaxPictureSide || picture.height > kMaxPictureSide))
        throw std::runtime_error("the picture " + path + " is " + std::to_string(picture.width) + "x" + std::to_string(picture.height) +
                                 ": larger than " + std::to_string(kMaxPictureSide) + " pixels a side");
    picture.rgba = {stbi_load_from_memory(data, length, &picture.width, &picture.height, &channels, 4), stbi_image_free};
    if (!picture.rgba)
        throw std::runtime_error("cannot read the picture " + path + ": " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown error"));
    return picture;
}

Image imageOf(const DecodedPicture& picture)
{
    Image image;
    image.width = picture.width;
    image.height = picture.height;
    image.rgba.assign(picture.rgba.get(), picture.rgba.get() + std::size_t(picture.width) * std::size_t(picture.height) * 4);
    return image;
}
} // namespace

DecodedPicture decodePicture(const std::string& path)
{
    // A FIFO would block forever and a device would never end: only regular files are read.
    if (const auto why = unreadableAsFile(path, kMaxPictureFileBytes)) throw std::runtime_error("cannot read the picture: " + *why);
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad() || bytes.empty()) throw std::runtime_error("cannot read the picture " + path);
    return decodeBytes(std::move(bytes), path);
}

Image readImage(const std::string& path) { return imageOf(decodePicture(path)); }

Image decodeImage(const std::string& bytes)
{
    if (bytes.empty()) throw std::runtime_error("cannot read the picture: no bytes");
    return imageOf(decodeBytes(bytes, "in memory"));
}

} // namespace vdbclay::render
