// Camera paths on crafted text: parsed and checked, or refused with one printable line.
#include "scene/CameraPath.h"
#include "vdb_hermite/PrintableText.h"

#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const std::vector<vdbclay::CameraFrame> frames = vdbclay::parseCameraPath(text);
        if (frames.empty()) std::abort(); // a path has a frame
        for (std::size_t i = 1; i < frames.size(); ++i)
            if (!(frames[i].time > frames[i - 1].time)) std::abort(); // times increase
        for (const vdbclay::CameraFrame& f : frames) vdbclay::validateViewer(f.viewer);
    } catch (const std::invalid_argument& e) {
        if (!vdbclay::isPrintableName(e.what(), std::string::npos)) std::abort(); // raw bytes or several lines
    }
    return 0;
}
