// Camera flights for `vdbclay lod inspect`: {"fov_degrees": 60, "viewport": [1920, 1080],
// "frames": [{"position": [x, y, z], "target": [x, y, z], "t": seconds}, ...]}, world units; frames
// without "t" follow each other at 90 Hz.
#pragma once

#include "scene/ViewSelection.h"

#include <string>
#include <vector>

namespace vdbclay {

struct CameraFrame {
    Viewer viewer;
    double time = 0.0; // seconds from the flight's start
};

constexpr double kDefaultFrameRate = 90.0;
/// The latest time a frame may have: a flight replays in real time.
constexpr double kMaxFlightSeconds = 3600.0;

/// Throws std::invalid_argument naming the offending place ("frames[3].target: ...").
std::vector<CameraFrame> parseCameraPath(const std::string& jsonText);
std::vector<CameraFrame> loadCameraPath(const std::string& path);

} // namespace vdbclay
