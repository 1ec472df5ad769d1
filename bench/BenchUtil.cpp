#include "BenchUtil.h"

#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/Synthesize.h"

#include <openvdb/version.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

namespace vdbclay::bench {

double median(std::vector<double> values)
{
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double maximum(const std::vector<double>& values)
{
    return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}

double percentile(std::vector<double> v, double p)
{
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, std::size_t(std::max(1.0, std::ceil(p * double(v.size())))) - 1)];
}

double mean(const std::vector<double>& v)
{
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / double(v.size());
}

ScratchDir::ScratchDir(const std::string& name)
    : path_(std::filesystem::temp_directory_path() / ("vdbclay-bench-" + name + "-" + std::to_string(::getpid())))
{
    std::filesystem::create_directories(path_);
}

ScratchDir::~ScratchDir()
{
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

namespace {

SynthOptions terrainSynthOptions(int extent)
{
    SynthOptions synth;
    synth.kind = SynthKind::Terrain;
    synth.extent = extent;
    synth.seed = 7;
    return synth;
}

} // namespace

double terrainGroundHeight(int extent, double x, double z)
{
    return synthGroundHeight(terrainSynthOptions(extent), x, z);
}

std::string terrainStoreWithLod(const std::filesystem::path& dir, int extent)
{
    const std::string store = (dir / ("terrain-" + std::to_string(extent) + ".vdbclay")).string();
    synthesizeStore(terrainSynthOptions(extent), store);
    SceneStore scene = SceneStore::open(store, StoreAccess::ReadWrite);
    buildStoreLod(scene, 0);
    return store;
}

int threadCount()
{
    return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

std::string openvdbVersion() { return OPENVDB_LIBRARY_VERSION_STRING; }

std::string fixed(double value, int decimals)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
    return buf;
}

std::string megabytes(double bytes) { return fixed(bytes / 1e6, 2) + " MB"; }

void Table::print(std::ostream& os) const
{
    std::vector<std::size_t> width(header.size(), 3);
    for (std::size_t c = 0; c < header.size(); ++c) width[c] = std::max(width[c], header[c].size());
    for (const auto& row : rows) {
        for (std::size_t c = 0; c < row.size() && c < width.size(); ++c) width[c] = std::max(width[c], row[c].size());
    }
    auto line = [&](const std::vector<std::string>& cells, bool leftFirst) {
        os << '|';
        for (std::size_t c = 0; c < width.size(); ++c) {
            const std::string cell = c < cells.size() ? cells[c] : "";
            const std::string pad(width[c] - cell.size(), ' ');
            // First column left-aligned (labels), the others right-aligned (figures).
            os << ' ' << (c == 0 && leftFirst ? cell + pad : pad + cell) << " |";
        }
        os << '\n';
    };
    line(header, true);
    os << '|';
    for (std::size_t c = 0; c < width.size(); ++c) os << (c == 0 ? ' ' + std::string(width[c], '-') + " |" : ' ' + std::string(width[c] - 1, '-') + ": |");
    os << '\n';
    for (const auto& row : rows) line(row, true);
}

void printPreamble(std::ostream& os, const std::string& name, bool quick)
{
    const int threads = threadCount();
    os << "vdbclay bench " << name << " (" << (quick ? "quick" : "full") << " sizes, " << threads
       << (threads == 1 ? " thread" : " threads") << ", OpenVDB " << openvdbVersion() << ")\n\n";
}

nlohmann::json jsonPreamble(const std::string& name, bool quick)
{
    return {{"bench", name}, {"quick", quick}, {"threads", threadCount()}, {"openvdb_version", openvdbVersion()}};
}

} // namespace vdbclay::bench
