// Benchmarks behind `vdbclay bench`: each runs our implementation and the OpenVDB baseline on the same
// data in the same process and prints both side by side (a Markdown table, or one JSON object).
#pragma once

#include <string>
#include <vector>

namespace vdbclay::bench {

/// "csg", "memory", "io", "mesh", "wavelet", "stream".
std::vector<std::string> benchNames();

/// Runs one benchmark; `quick` picks the small sizes used in CI. Prints to stdout and returns the exit
/// code (0). Throws std::invalid_argument for an unknown name and std::runtime_error on failures.
/// `memoryBudgetMb`: the budget of `stream` (0: its default, 192 MB, or 6 MB with `quick`).
/// `extents`: the terrains of `render` (empty: its defaults).
int runBench(const std::string& which, bool json, bool quick, double memoryBudgetMb = 0.0, const std::vector<int>& extents = {},
             const std::string& dir = {});

} // namespace vdbclay::bench
