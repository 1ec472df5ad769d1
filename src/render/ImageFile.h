// Pictures on disk: PNG through stb_image_write (Debian's libstb).
#pragma once

#include "render/OffscreenTarget.h"

#include <cstdint>
#include <memory>
#include <string>

namespace vdbclay::render {

/// Writes `image` as an 8-bit RGBA PNG to `path` atomically (a temporary beside it, renamed over it).
/// Throws std::runtime_error naming the path when it cannot.
void writePng(const Image& image, const std::string& path);
/// `image` as PNG bytes (thumbnails kept in a database). Throws std::runtime_error for an empty picture.
std::string encodePng(const Image& image);
/// A picture from bytes in memory (a PNG encodePng made, or any picture stb reads); throws
/// std::runtime_error when they are not one or it is larger than kMaxPictureSide a side.
Image decodeImage(const std::string& bytes);
constexpr int kMaxPictureSide = 16384;
/// A picture as stb decoded it (RGBA, rows from the top), held where stb put it: a 16384^2 picture is
/// a gigabyte, not to be copied.
struct DecodedPicture {
    int width = 0, height = 0;
    std::unique_ptr<uint8_t, void (*)(void*)> rgba{nullptr, [](void*) {}};
};
/// What readImage decodes, with its checks, without the copy into an Image.
DecodedPicture decodePicture(const std::string& path);

/// Reads a PNG (or any picture stb reads) as RGBA; throws std::runtime_error when it cannot, when it is
/// not a regular file, or when it is larger than kMaxPictureSide a side. A palette PNG's indices past its
/// palette read opaque black (padPngPalette).
Image readImage(const std::string& path);

/// Pads the palette of a palette PNG (in memory) with opaque black up to the 2^depth entries its indices
/// can name: stb_image reads such indices from memory the palette never filled, a random colour. Other
/// files are left as they are.
void padPngPalette(std::string& png);

} // namespace vdbclay::render
