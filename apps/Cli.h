// Shared pieces of the `vdbclay` command: option structs of every subcommand, the functions that run
// them, errors mapped to exit codes, and small output helpers. Light header: no OpenVDB trees here.
#pragma once

#include "scene/OutputCheck.h"
#include "vdb_hermite/FileExtension.h"
#include "vdb_hermite/NumberText.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
class Validator;
}

namespace vdbclay {
struct ScriptOpReport;
}

namespace vdbclay::cli {

/// Bad command-line input detected after parsing (unknown shape, negative size, ...): exit code 2.
class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1; // the command ran and failed (unreadable file, bad script, ...)
constexpr int kExitUsage = 2;   // the command line itself is wrong

/// Writes "vdbclay: error: <message>" as one line to stderr.
void printError(const std::string& message);

/// Prints one compact JSON object and a newline on stdout.
void printJson(const nlohmann::json& object);

/// Prints "key: value" lines with the values aligned in one column, each indented by `indent`.
void printFields(const std::vector<std::pair<std::string, std::string>>& fields, std::size_t indent = 2);

/// Wall-clock seconds since `start` (a steady_clock reading).
inline double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// One stroke-script op as reported in --json output: index, mode, blocks computed, seconds.
nlohmann::json opReportJson(const ScriptOpReport& report);

/// Short human-readable forms.
std::string formatSeconds(double seconds); // "812 ms", "3.42 s"
std::string formatBytes(double bytes);     // "12.3 MiB"

/// Throws UsageError unless `path` ends in .vdb or .vdbclay (the forms a scene is written in).
void requireSceneExtension(const std::string& path);
/// An option check that refuses zero, negative and non-finite numbers with a short message
/// (CLI::PositiveNumber quotes the largest double as its limit).
const CLI::Validator& positiveNumber();
/// The same for zero and positive numbers (CLI::NonNegativeNumber lets NaN through).
const CLI::Validator& nonNegativeNumber();
/// A memory budget in MB: above 0, at most 1e9 (2^64 bytes overflowed into a budget of 0).
const CLI::Validator& memoryBudget();
/// The same for any finite number (an iso value).
const CLI::Validator& finiteNumber();
/// An option check for a whole number from 0 to 2^64 - 1 typed in decimal (a seed, an index): a larger
/// one would saturate and a negative one wrap around, silently.
const CLI::Validator& unsignedInteger();
/// An option check for a scene read by a command: a mesh file is refused with the import command that
/// brings it in.
const CLI::Validator& sceneInput();

/// A progress bar on stderr ("label [=====     ] 52%"), redrawn in place, when stderr is a terminal and
/// `enabled`; otherwise a function that does nothing. Call with done == total to end the line.
std::function<void(uint64_t done, uint64_t total)> terminalProgress(const std::string& label, bool enabled);

/// Adds "--threads N" (worker threads for TBB, 1 to 4096; absent: all cores) to a subcommand.
void addThreadsOption(CLI::App& command, int& threads);

// --- subcommands -------------------------------------------------------------------------------

struct NewOptions {
    std::string output;
    std::string shape;
    double size = 0.0;
    double voxelSize = 1.0;
    std::string material;
    bool json = false;
};
CLI::App* addNewCommand(CLI::App& parent, NewOptions& options);
int runNew(const NewOptions& options);

struct SculptOptions {
    std::string input;
    std::string script;
    std::string output;
    std::optional<double> memoryBudgetMB; // stores: stream under this budget, autosaving
    uint64_t autosaveEvery = 0;           // stores: commit every N ops (0: once at the end)
    bool json = false;
};
CLI::App* addSculptCommand(CLI::App& parent, SculptOptions& options);
int runSculpt(const SculptOptions& options);

struct MeshCommandOptions {
    std::string input;
    std::string output;
    std::string mesher = "cms";
    std::optional<double> angleDegrees;            // CMS only; MeshOptions' default when absent
    std::optional<double> subdivisionAngleDegrees; // adaptive CMS only
    std::optional<double> planeTolerance;          // adaptive CMS only, voxels
    bool uniform = false;
    std::optional<int> lod;
    bool json = false;
};
CLI::App* addMeshCommand(CLI::App& parent, MeshCommandOptions& options);
int runMesh(const MeshCommandOptions& options);

struct InfoOptions {
    std::string input;
    bool json = false;
};
CLI::App* addInfoCommand(CLI::App& parent, InfoOptions& options);
int runInfo(const InfoOptions& options);

struct DemoOptions {
    std::string outDir = "demo-out";
    bool json = false;
};
CLI::App* addDemoCommand(CLI::App& parent, DemoOptions& options);
int runDemo(const DemoOptions& options);

struct ImportOptions {
    std::string input;
    std::string output;
    std::string grid;                // a standard .vdb's grid (default: the first level set)
    std::optional<double> iso;       // a fog volume's iso value
    std::optional<double> voxelSize; // a mesh's voxel size, or resample a standard grid to it
    std::optional<int> resolution;   // a mesh: voxels along its longest side
    std::string material = "default";
    bool materialGiven = false;
    bool json = false;
};
CLI::App* addImportCommand(CLI::App& parent, ImportOptions& options);
int runImport(const ImportOptions& options);

struct ExportOptions {
    std::string input;
    std::string output;
    bool json = false;
};
CLI::App* addExportCommand(CLI::App& parent, ExportOptions& options);
int runExport(const ExportOptions& options);

struct ExportLevelSetOptions {
    std::string input;
    std::string output;
    double halfWidth = 3.0;
    bool fog = false;
    bool int32Material = false;
    bool json = false;
};
CLI::App* addExportLevelSetCommand(CLI::App& parent, ExportLevelSetOptions& options);
int runExportLevelSet(const ExportLevelSetOptions& options);

struct LodOptions {
    std::string scene;
    int levels = 0;
    bool json = false;
    // inspect
    std::string cameraPath;
    double memoryBudgetMB = 0.0;
    double pixelError = 1.0;
    std::string csv;
    std::string plot;
    std::string framesDir;        // pictures of the flight
    uint64_t every = 1;           // a picture every N frames
    std::string frameView = "lod";
    std::string frameSize;        // WxH; default: the flight's viewport, at most 640 wide
};
struct RenderOptions {
    std::string scene;
    std::string output;
    std::string size = "1280x720";
    std::string camera;
    std::string cameraPath;
    std::optional<uint64_t> frame;
    std::string view = "shaded";
    bool wireframe = false;
    double memoryBudgetMB = 512.0;
    double pixelError = 1.0;
    bool json = false;
};
CLI::App* addRenderCommand(CLI::App& parent, RenderOptions& options);
/// "WxH" in pixels, each 1 .. 8192; throws UsageError naming `option` otherwise.
std::pair<int, int> parsePictureSize(const std::string& text, const std::string& option);
int runRender(const RenderOptions& options);

struct LodCommands {
    CLI::App* build = nullptr;
    CLI::App* info = nullptr;
    CLI::App* inspect = nullptr;
};
LodCommands addLodCommand(CLI::App& parent, LodOptions& options);
int runLodBuild(const LodOptions& options);
int runLodInfo(const LodOptions& options);
int runLodInspect(const LodOptions& options);

struct ToolMakeOptions {
    std::string scene;
    std::vector<double> bbox; // x0 y0 z0 x1 y1 z1, world units; empty: the whole scene
    std::string output;
    bool json = false;
};
struct ToolCommands {
    CLI::App* make = nullptr;
};
ToolCommands addToolCommand(CLI::App& parent, ToolMakeOptions& options);
int runToolMake(const ToolMakeOptions& options);

struct SynthCommandOptions {
    std::string kind;
    int extent = 512;
    uint64_t seed = 1;
    double voxelSize = 1.0;
    std::string output;
    bool json = false;
};
CLI::App* addSynthCommand(CLI::App& parent, SynthCommandOptions& options);
int runSynth(const SynthCommandOptions& options);

struct DiffOptions {
    std::string a, b;
    std::optional<double> tolerance;
    bool json = false;
};
CLI::App* addDiffCommand(CLI::App& parent, DiffOptions& options);
int runDiff(const DiffOptions& options);

struct IndexOptions {
    std::string library;
    std::vector<std::string> inputs; // add: files and folders
    bool recursive = false;
    bool noRender = false;           // add: no light field or thumbnails (no renderer needed)
    std::string name;                // remove
    bool json = false;
};
struct IndexCommands {
    CLI::App* add = nullptr;
    CLI::App* info = nullptr;
    CLI::App* remove = nullptr;
};
IndexCommands addIndexCommand(CLI::App& parent, IndexOptions& options);
int runIndexAdd(const IndexOptions& options);
int runIndexInfo(const IndexOptions& options);
int runIndexRemove(const IndexOptions& options);

struct QueryOptions {
    std::string library;
    std::string input;
    std::size_t k = 10;
    std::string descriptor = "combined";
    std::string metric = "chi2";
    int lod = 0; // a scene's level of detail to mesh
    std::string thumbnails; // folder for the results' thumbnails
    bool json = false;
};
CLI::App* addQueryCommand(CLI::App& parent, QueryOptions& options);
int runQuery(const QueryOptions& options);

struct EditOptions {
    std::string scene;
    double memoryBudgetMB = 1024.0;
    std::string record;        // write every command with its frame and time
    std::string replay;        // apply a recorded session
    bool headless = false;     // no window: replay, save, screenshot
    std::optional<uint64_t> frames; // replay this many frames (default: all)
    std::string screenshot;    // PNG of the view after the replay
    std::string size;          // the screenshot's WxH (default: the record's viewport)
    std::string output;        // save the result here (.vdb or .vdbclay)
    std::string exportScript;  // the ops applied, as a stroke script
    bool discardRecovery = false;
    double autosaveSeconds = 5.0;
    bool json = false;
    bool vr = false;            // in a headset through OpenXR
    std::string hand = "right"; // VR: the hand that sculpts
};
CLI::App* addEditCommand(CLI::App& parent, EditOptions& options);
int runEdit(const EditOptions& options);

struct BenchCommandOptions {
    std::string which;
    bool json = false;
    bool quick = false;
    double memoryBudgetMb = 0.0; // stream, render and editor; 0: the benchmark's default
    std::vector<int> extents;    // render only; empty: the benchmark's default
    std::string dir;             // retrieval: one folder per class of models; empty: the synthetic set
};
CLI::App* addBenchCommand(CLI::App& parent, BenchCommandOptions& options);
int runBenchCommand(const BenchCommandOptions& options);

struct SelftestOptions {
    uint64_t scenes = 100;
    uint64_t seed = 1;
    uint64_t first = 0;
    std::string failurePath;
    bool keepGoing = false;
    bool sweep = false;
    double sweepFrom = 40.0, sweepTo = 100.0, sweepStep = 0.25;
    bool json = false;
};
CLI::App* addSelftestCommand(CLI::App& parent, SelftestOptions& options);
int runSelftest(const SelftestOptions& options);

} // namespace vdbclay::cli
