#include "scene/CameraPath.h"

#include "vdb_hermite/FileStatus.h"
#include "vdb_hermite/StrictJson.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace vdbclay {

namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& where, const std::string& what)
{
    throw std::invalid_argument("camera path: " + where + ": " + what);
}

double number(const json& j, const std::string& where)
{
    if (!j.is_number()) fail(where, "must be a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(where, "must be finite");
    return v;
}

std::array<double, 3> vec3(const json& j, const std::string& where)
{
    if (!j.is_array() || j.size() != 3) fail(where, "must be an array of three numbers");
    return {number(j[0], where + "[0]"), number(j[1], where + "[1]"), number(j[2], where + "[2]")};
}

} // namespace

std::vector<CameraFrame> parseCameraPath(const std::string& text)
{
    const json root = parseStrictJson(text, "camera path");
    if (!root.is_object()) fail("top level", "must be an object");
    for (const auto& [key, value] : root.items())
        if (key != "fov_degrees" && key != "viewport" && key != "frames") fail(printableText(key, 80), "unknown key");
    Viewer base;
    if (root.contains("fov_degrees")) base.fovDegrees = number(root["fov_degrees"], "fov_degrees");
    if (!(base.fovDegrees > 0.0 && base.fovDegrees < 180.0)) fail("fov_degrees", "the field of view must lie in (0, 180) degrees");
    if (root.contains("viewport")) {
        const json& v = root["viewport"];
        if (!v.is_array() || v.size() != 2 || !v[0].is_number_integer() || !v[1].is_number_integer())
            fail("viewport", "must be two integers [width, height]");
        const int64_t w = v[0].get<int64_t>(), h = v[1].get<int64_t>();
        if (w < 1 || h < 1 || w > 65536 || h > 65536) fail("viewport", "each side must lie in 1 .. 65536 pixels");
        base.viewport = {int(w), int(h)};
    }
    if (!root.contains("frames") || !root["frames"].is_array() || root["frames"].empty())
        fail("frames", "must be a non-empty array");
    if (root["frames"].size() > 1000000) fail("frames", "at most 1,000,000 frames");
    std::vector<CameraFrame> frames;
    double previous = -1.0;
    for (std::size_t i = 0; i < root["frames"].size(); ++i) {
        const json& f = root["frames"][i];
        const std::string where = "frames[" + std::to_string(i) + "]";
        if (!f.is_object()) fail(where, "must be an object");
        for (const auto& [key, value] : f.items())
            if (key != "position" && key != "target" && key != "t") fail(where + "." + printableText(key, 80), "unknown key");
        if (!f.contains("position") || !f.contains("target")) fail(where, "needs \"position\" and \"target\"");
        CameraFrame frame;
        frame.viewer = base;
        frame.viewer.position = vec3(f["position"], where + ".position");
        frame.viewer.target = vec3(f["target"], where + ".target");
        frame.time = f.contains("t") ? number(f["t"], where + ".t") : double(i) / kDefaultFrameRate;
        if (frame.time < 0.0 || frame.time <= previous) fail(where + ".t", "times must start at 0 or later and increase");
        if (!(frame.time <= kMaxFlightSeconds))
            fail(where + ".t", "a flight replays in real time: times must stay within " + std::to_string(int(kMaxFlightSeconds)) +
                                   " s (one hour)");
        previous = frame.time;
        try {
            validateViewer(frame.viewer);
        } catch (const std::invalid_argument& e) {
            fail(where, e.what());
        }
        frames.push_back(frame);
    }
    return frames;
}

std::vector<CameraFrame> loadCameraPath(const std::string& path)
{
    std::error_code ec;
    if (const auto why = unreachableFile(path)) throw std::invalid_argument("camera path: " + *why);
    if (!std::filesystem::is_regular_file(path, ec)) throw std::invalid_argument("camera path '" + path + "' is not a regular file");
    if (std::filesystem::file_size(path, ec) > (256u << 20)) throw std::invalid_argument("camera path '" + path + "' is larger than 256 MB");
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return parseCameraPath(text.str());
}

} // namespace vdbclay
