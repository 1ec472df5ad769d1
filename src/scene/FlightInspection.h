// Replaying a camera flight against a store (vdbclay lod inspect): each frame waits for its time, asks
// the streaming scene for its view, and records what the scene reports.
#pragma once

#include "scene/CameraPath.h"
#include "scene/StreamingScene.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

struct InspectedFrame {
    double time = 0.0; // seconds from the start of the flight, as replayed
    bool settling = false; // asked after the flight's last frame, waiting for it to refine
    FrameReport report;
};

struct FlightSummary {
    std::size_t frames = 0;
    double seconds = 0.0;
    uint64_t peakResidentBytes = 0;
    uint64_t bytesRead = 0, loads = 0, evictions = 0;
    double meanHitRate = 0.0;
    double maxScreenError = 0.0;
    std::optional<double> firstCoarseComplete; // seconds: first frame whose view showed some level everywhere
    std::optional<double> firstComplete;       // seconds: first frame fully refined
    std::optional<double> firstSettled;        // seconds: first frame refined as far as the budget allows
    bool budgetLimited = false;
    uint64_t damagedBricks = 0; // bricks the store could not give (the view shows their ancestors)
};

struct FlightInspection {
    std::vector<InspectedFrame> frames;
    FlightSummary summary;
};

/// Called after a frame was asked for: its index in the flight (the flight's size for the frames asked
/// after it, while the view settles), its viewer and what the scene reported. Time spent here (drawing
/// a picture of the frame) is left out of the flight's clock: the loaders keep working meanwhile.
using FrameObserver = std::function<void(std::size_t index, const Viewer& viewer, const InspectedFrame& frame)>;

/// Replays the flight in real time (frames at their "t"); after the last frame, keeps asking for its
/// view at 90 Hz for up to `settleSeconds` until it is complete. `progress` (optional) hears of each
/// frame replayed, out of the flight's frames.
FlightInspection inspectFlight(StreamingScene& scene, const std::vector<CameraFrame>& flight, double settleSeconds = 2.0,
                               const std::function<void(uint64_t done, uint64_t total)>& progress = {},
                               const FrameObserver& observer = {});

/// Writes the frames as CSV (one row per frame) and as a PNG plot (PLplot): resident bytes against the
/// budget, bytes read, loads and evictions, and screen-space error over the flight.
void writeFlightCsv(const FlightInspection& inspection, const std::string& path);
void writeFlightPlot(const FlightInspection& inspection, uint64_t budgetBytes, const std::string& path);

} // namespace vdbclay
