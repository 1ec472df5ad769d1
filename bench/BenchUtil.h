// Helpers shared by the benchmarks: timing, medians, thread count, Markdown tables.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <ostream>
#include <filesystem>
#include <string>
#include <vector>

namespace vdbclay::bench {

using Clock = std::chrono::steady_clock;

inline double millisecondsSince(Clock::time_point start)
{
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Times one call of `f` in milliseconds.
template<typename F>
double timeMs(F&& f)
{
    const auto start = Clock::now();
    f();
    return millisecondsSince(start);
}

double median(std::vector<double> values);
double maximum(const std::vector<double>& values);
/// The smallest value at or above the fraction p (0..1] of the sorted values.
double percentile(std::vector<double> values, double p);
double mean(const std::vector<double>& values);

/// Worker threads TBB uses now (default concurrency, or the --threads limit).
int threadCount();

/// "10.0.1"
std::string openvdbVersion();

std::string fixed(double value, int decimals);
std::string megabytes(double bytes); // "12.34 MB" (10^6 bytes)

/// A temporary folder for a benchmark's files (vdbclay-bench-NAME-PID), removed with everything in it.
class ScratchDir {
public:
    explicit ScratchDir(const std::string& name);
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

/// The benches' terrain of `extent` voxels (seed 7, bench stream's kind) as a store with its levels of detail, written into `dir`; returns its path.
std::string terrainStoreWithLod(const std::filesystem::path& dir, int extent);
/// Its ground's height at world (x, z): where a viewer stands clear of it.
double terrainGroundHeight(int extent, double x, double z);

/// A table printed in Markdown, so a run can be pasted into docs/BENCHMARKS.md.
struct Table {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
    void print(std::ostream& os) const;
};

/// First line of every human-readable report: benchmark, sizes, threads, OpenVDB version.
void printPreamble(std::ostream& os, const std::string& name, bool quick);
/// Fields every JSON report starts with.
nlohmann::json jsonPreamble(const std::string& name, bool quick);

} // namespace vdbclay::bench
