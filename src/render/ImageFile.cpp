#include "render/ImageFile.h"

#include "vdb_hermite/AtomicFile.h"

#include <stb_image.h>
#include <stb_image_write.h>

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

void writePng(const Image& image, const std::string& path)
{
    if (image.width <= 0 || image.height <= 0 || image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4)
        throw std::runtime_error("cannot write " + path + ": the picture is empty or malformed");
    std::string bytes;
    if (!stbi_write_png_to_func(&appendBytes, &bytes, image.width, image.height, 4, image.rgba.data(), image.width * 4))
        throw std::runtime_error("cannot encode the PNG for " + path);
    writeFileAtomically(path, [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); });
}

Image readImage(const std::string& path)
{
    int w = 0, h = 0, channels = 0;
    // Sizes first: a forged header must not make stb allocate gigabytes.
    if (stbi_info(path.c_str(), &w, &h, &channels) && (w > kMaxPictureSide || h > kMaxPictureSide))
        throw std::runtime_error("the picture " + path + " is " + std::to_string(w) + "x" + std::to_string(h) +
                                 ": larger than " + std::to_string(kMaxPictureSide) + " pixels a side");
    std::unique_ptr<stbi_uc, void (*)(void*)> pixels(stbi_load(path.c_str(), &w, &h, &channels, 4), stbi_image_free);
    if (!pixels) throw std::runtime_error("cannot read the picture " + path + ": " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown error"));
    Image image;
    image.width = w;
    image.height = h;
    image.rgba.assign(pixels.get(), pixels.get() + std::size_t(w) * std::size_t(h) * 4);
    return image;
}

} // namespace vdbclay::render
