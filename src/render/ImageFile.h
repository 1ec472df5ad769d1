// Pictures on disk: PNG through stb_image_write (Debian's libstb).
#pragma once

#include "render/OffscreenTarget.h"

#include <string>

namespace vdbclay::render {

/// Writes `image` as an 8-bit RGBA PNG to `path` atomically (a temporary beside it, renamed over it).
/// Throws std::runtime_error naming the path when it cannot.
void writePng(const Image& image, const std::string& path);
constexpr int kMaxPictureSide = 16384;
/// Reads a PNG (or any picture stb reads) as RGBA; throws std::runtime_error when it cannot, or when it
/// is larger than kMaxPictureSide a side.
Image readImage(const std::string& path);

} // namespace vdbclay::render
