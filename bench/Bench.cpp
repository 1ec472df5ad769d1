#include "Bench.h"

#include "BenchSuites.h"

#include <openvdb/openvdb.h>

#include <stdexcept>

namespace vdbclay::bench {

std::vector<std::string> benchNames() { return {"csg", "memory", "io", "mesh", "wavelet", "stream", "import", "tool", "render", "editor", "inputs", "vr", "retrieval"}; }

int runBench(const std::string& which, bool json, bool quick, double memoryBudgetMb, const std::vector<int>& extents, const std::string& dir)
{
    openvdb::initialize(); // the FloatGrid baselines need the standard grid types registered
    if (which == "csg") return benchCsg(json, quick);
    if (which == "memory") return benchMemory(json, quick);
    if (which == "io") return benchIo(json, quick);
    if (which == "mesh") return benchMesh(json, quick);
    if (which == "wavelet") return benchWavelet(json, quick);
    if (which == "stream") return benchStream(json, quick, memoryBudgetMb);
    if (which == "import") return benchImport(json, quick);
    if (which == "tool") return benchTool(json, quick);
    if (which == "render") return benchRender(json, quick, memoryBudgetMb, extents);
    if (which == "editor") return benchEditor(json, quick, memoryBudgetMb);
    if (which == "inputs") return benchInputs(json, quick);
    if (which == "vr") return benchVr(json, quick, memoryBudgetMb);
    if (which == "retrieval") return benchRetrieval(json, quick, dir);
    throw std::invalid_argument("unknown benchmark '" + which + "' (expected csg, memory, io, mesh, wavelet, stream, import, tool, render, editor, inputs, vr or retrieval)");
}

} // namespace vdbclay::bench
