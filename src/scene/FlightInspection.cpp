#include "scene/FlightInspection.h"

#include "vdb_hermite/AtomicFile.h"

#include <plplot.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <thread>
#include <unistd.h>

namespace vdbclay {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

} // namespace

FlightInspection inspectFlight(StreamingScene& scene, const std::vector<CameraFrame>& flight, double settleSeconds,
                               const std::function<void(uint64_t, uint64_t)>& progress, const FrameObserver& observer)
{
    FlightInspection out;
    if (flight.empty()) return out;
    auto start = Clock::now();
    // The observer's time does not count: the flight's clock starts that much later.
    const auto observe = [&](std::size_t index, const Viewer& viewer) {
        if (!observer) return;
        const auto before = Clock::now();
        observer(index, viewer, out.frames.back());
        start += Clock::now() - before;
    };
    const auto record = [&](const Viewer& viewer, bool settling) {
        InspectedFrame f;
        f.settling = settling;
        f.report = scene.frame(viewer);
        f.time = since(start);
        FlightSummary& s = out.summary;
        s.peakResidentBytes = std::max(s.peakResidentBytes, f.report.residentBytes);
        s.bytesRead += f.report.bytesRead;
        s.loads += f.report.loads;
        s.evictions += f.report.evictions;
        s.maxScreenError = std::max(s.maxScreenError, f.report.screenError);
        s.budgetLimited = s.budgetLimited || f.report.budgetLimited;
        s.damagedBricks = std::max(s.damagedBricks, f.report.damagedBricks);
        if (f.report.coarseComplete && !s.firstCoarseComplete) s.firstCoarseComplete = f.time;
        if (f.report.complete && !s.firstComplete) s.firstComplete = f.time;
        if (f.report.settled && !s.firstSettled) s.firstSettled = f.time;
        out.frames.push_back(f);
        return f.report.complete;
    };
    for (std::size_t i = 0; i < flight.size(); ++i) {
        const double wait = flight[i].time - since(start);
        if (wait > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
        record(flight[i].viewer, false);
        observe(i, flight[i].viewer);
        if (progress) progress(i + 1, flight.size());
    }
    const double end = since(start) + settleSeconds;
    while (!out.frames.back().report.settled && since(start) < end) {
        std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / kDefaultFrameRate));
        record(flight.back().viewer, true);
    }
    observe(flight.size(), flight.back().viewer);
    FlightSummary& s = out.summary;
    s.frames = out.frames.size();
    s.seconds = since(start);
    double hits = 0.0;
    for (const InspectedFrame& f : out.frames) hits += f.report.hitRate();
    s.meanHitRate = hits / double(out.frames.size());
    return out;
}

void writeFlightCsv(const FlightInspection& inspection, const std::string& path)
{
    writeFileAtomically(path, [&](std::ostream& os) {
        const std::size_t levels = inspection.frames.empty() ? 0 : inspection.frames.front().report.residentPerLevel.size();
        os << "frame,time_s,resident_bytes,bytes_read,loads,evictions,requested,hits,hit_rate,screen_error_px,"
              "target_error_px,coarse_complete,complete,budget_limited,settled,pending,settling";
        for (std::size_t k = 0; k < levels; ++k) os << ",resident_level_" << k;
        os << '\n';
        for (std::size_t i = 0; i < inspection.frames.size(); ++i) {
            const InspectedFrame& f = inspection.frames[i];
            const FrameReport& r = f.report;
            char line[512];
            std::snprintf(line, sizeof(line), "%zu,%.6f,%llu,%llu,%llu,%llu,%llu,%llu,%.4f,%.4f,%.4f,%d,%d,%d,%d,%llu", i, f.time,
                          (unsigned long long)r.residentBytes, (unsigned long long)r.bytesRead, (unsigned long long)r.loads,
                          (unsigned long long)r.evictions, (unsigned long long)r.requested, (unsigned long long)r.hits,
                          r.hitRate(), r.screenError, r.targetError, int(r.coarseComplete), int(r.complete),
                          int(r.budgetLimited), int(r.settled), (unsigned long long)r.pending);
            os << line << ',' << int(f.settling);
            for (std::size_t k = 0; k < levels; ++k) os << ',' << (k < r.residentPerLevel.size() ? r.residentPerLevel[k] : 0);
            os << '\n';
        }
    });
}

void writeFlightPlot(const FlightInspection& inspection, uint64_t budgetBytes, const std::string& path)
{
    if (inspection.frames.empty()) throw std::invalid_argument("no frames to plot");
    const std::size_t n = inspection.frames.size();
    std::vector<PLFLT> t(n), resident(n), budget(n), read(n), loads(n), evictions(n), error(n);
    for (std::size_t i = 0; i < n; ++i) {
        const FrameReport& r = inspection.frames[i].report;
        t[i] = inspection.frames[i].time;
        resident[i] = double(r.residentBytes) / 1e6;
        budget[i] = double(budgetBytes) / 1e6;
        read[i] = double(r.bytesRead) / 1e6;
        loads[i] = double(r.loads);
        evictions[i] = double(r.evictions);
        error[i] = r.screenError;
    }
    const auto maxOf = [](const std::vector<PLFLT>& v) { return std::max(1e-9, *std::max_element(v.begin(), v.end())); };
    const PLFLT tMax = std::max(t.back(), 1e-3);
    // PLplot writes to a file name: a temporary beside the target, copied into the atomic save. PLplot
    // exits the process when it cannot open that file, so it is created here first.
    requireReplaceable(path);
    const std::string temp = path + ".plplot-" + std::to_string(::getpid());
    if (!std::ofstream(temp, std::ios::binary)) throw FileWriteError("cannot write '" + temp + "': " + std::strerror(errno));
    plsdev("pngcairo");
    plsfnam(temp.c_str());
    plsetopt("geometry", "1200x1000");
    plscolbg(255, 255, 255);
    plinit();
    plscol0(1, 0, 0, 0);
    plscol0(2, 31, 119, 180);
    plscol0(3, 214, 39, 40);
    plscol0(4, 44, 160, 44);
    plssub(1, 3);
    const auto panel = [&](const char* title, const char* ylabel, PLFLT yMax) {
        pladv(0);
        plvsta();
        plcol0(1);
        plwind(0.0, tMax, 0.0, yMax * 1.1);
        plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
        pllab("flight time (s)", ylabel, title);
    };
    panel("Resident bricks (blue) against the memory budget (red)", "MB", std::max(maxOf(resident), maxOf(budget)));
    plcol0(2), plline(PLINT(n), t.data(), resident.data());
    plcol0(3), plline(PLINT(n), t.data(), budget.data());
    panel("Per frame: MB read (blue), loads (green), evictions (red)", "count / MB", std::max({maxOf(read), maxOf(loads), maxOf(evictions)}));
    plcol0(2), plline(PLINT(n), t.data(), read.data());
    plcol0(4), plline(PLINT(n), t.data(), loads.data());
    plcol0(3), plline(PLINT(n), t.data(), evictions.data());
    panel("Screen-space error of the view shown", "pixels", maxOf(error));
    plcol0(2), plline(PLINT(n), t.data(), error.data());
    plend();
    try {
        writeFileAtomically(path, [&](std::ostream& os) {
            std::ifstream in(temp, std::ios::binary);
            if (!in) throw std::runtime_error("PLplot did not write the plot");
            os << in.rdbuf();
        });
    } catch (...) {
        std::error_code ec;
        std::filesystem::remove(temp, ec);
        throw;
    }
    std::error_code ec;
    std::filesystem::remove(temp, ec);
}

} // namespace vdbclay
