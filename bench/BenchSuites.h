// The individual benchmarks (one translation unit each); see Bench.h.
#pragma once

#include <string>
#include <vector>

namespace vdbclay::bench {

int benchCsg(bool json, bool quick);
int benchMemory(bool json, bool quick);
int benchIo(bool json, bool quick);
int benchMesh(bool json, bool quick);
int benchWavelet(bool json, bool quick);
int benchStream(bool json, bool quick, double memoryBudgetMb);
int benchImport(bool json, bool quick);
int benchTool(bool json, bool quick);
int benchRender(bool json, bool quick, double memoryBudgetMb, const std::vector<int>& extents);
int benchEditor(bool json, bool quick, double memoryBudgetMb);
int benchInputs(bool json, bool quick);
int benchVr(bool json, bool quick, double memoryBudgetMb);
int benchRetrieval(bool json, bool quick, const std::string& dir);

} // namespace vdbclay::bench
