// Stroke scripts: JSON lists of sculpting operations (docs/SCRIPTS.md describes the format).
#pragma once

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "sculpt/FieldBrushes.h"
#include "sculpt/Symmetry.h"
#include "sculpt/StrokeStart.h"
#include "sculpt/GridTool.h"
#include "vdb_hermite/Materials.h"
#include "vdb_hermite/Volume.h"

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay {

/// A malformed script; what() names the offending place, e.g. "ops[2].brush.radius: must be a number".
class ScriptError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Limits of what a script may hold; checked while parsing.
constexpr std::size_t kMaxPathPoints = 100000;
constexpr std::size_t kMaxBlendParts = 256;
constexpr uint64_t kMaxScriptBytes = 64ull << 20;

/// Ops on the mask (VoxelMask.h) rather than the surface: paint it with a brush ("mask", "unmask"), or
/// change it whole ("mask_invert", "mask_clear").
enum class MaskEdit { Mask, Unmask, Invert, Clear };

struct ScriptOp {
    CsgMode mode = CsgMode::Add; // unused by reshaping brushes (`field`) and mask ops
    std::optional<MaskEdit> maskEdit; // a mask op: changes the mask, never the surface
    std::optional<FieldBrushOp> field; // smooth, flatten, inflate, deflate, move (its material set when run)
    Brush brush;                 // placed at "at" (or at the first path point); unused with a tool
    std::string toolFile;        // {"shape": "grid", "file": ...}: the tool's file as the script names it
    Placement placement;         // the op's at (or first path point), rotate and scale
    std::shared_ptr<const GridTool> tool; // the loaded tool (loadScriptTools)
    std::vector<Vec3d> path;     // empty for a single stamp
    std::string material;        // empty: add uses the volume's first material
    double strength = 1.0;
    std::optional<double> depth; // erode depth override
    double blend = 0.0;          // add: the width of the smooth union with the surface (world units; 0: exact)
    std::optional<Falloff> paintFalloff; // paint: soft, its coverage strength x falloff (SoftPaint.h); absent: hard
    FalloffCurve falloffCurve;   // paint and reshaping brushes with a "falloff" curve
    Symmetry symmetry;           // the op runs once per copy (symmetryCopies), the plain one first
    bool continuesStroke = false; // inflate, deflate: "stroke": "continue", capped against the stroke's start (StrokeStart.h)
};

struct StrokeScript {
    std::vector<Material> materials;
    std::vector<ScriptOp> ops;
};

/// Parses a script; grid tools are named but not loaded (loadScriptTools).
StrokeScript parseStrokeScript(const std::string& jsonText);
/// Parses the script file and loads its tools (file names relative to the script's folder). ScriptError
/// also for unreadable files and tools.
StrokeScript loadStrokeScript(const std::string& path);
/// Loads each op's grid tool, once per file; relative names are taken from `folder`. Throws ScriptError
/// naming the op when a tool cannot be loaded.
void loadScriptTools(StrokeScript& script, const std::string& folder);
/// Tools built so far, by file name as resolved: a caller running many scripts (the editor) keeps one
/// so that a tool is built once, not once per stamp.
using ToolCache = std::map<std::string, std::shared_ptr<const GridTool>>;
void loadScriptTools(StrokeScript& script, const std::string& folder, ToolCache& cache);

/// The world bounds an op can change (a stroke's whole path included), and for a reshaping brush those
/// it reads (fieldBrushReach on a lattice of `voxelSize`): infinite for an unbounded brush. A mask op's
/// are those of the voxels it masks (none for invert and clear: an empty box, min > max).
WorldBounds opBounds(const ScriptOp& op, double voxelSize);
/// "add", "smooth", ...: the op's mode as scripts name it.
const char* opModeName(const ScriptOp& op);

struct ScriptOpReport {
    std::size_t index = 0;
    CsgMode mode = CsgMode::Add;
    const char* modeName = "add"; // as scripts name it (reshaping brushes included)
    EditStats stats;
    double seconds = 0.0;
};

/// Defines the script's materials in the volume, checks every op's material and limits
/// (checkCsgLimits), then applies the ops in order. Throws ScriptError, before touching the volume, when
/// an op names an unknown material, asks for more than the limits allow or names a tool not loaded.
/// A tool that adds or paints without a `material` brings its own: each of its materials is defined in
/// the volume (by name, unless the volume has it already) and applied over its region of the tool.
/// runStrokeScript's checks alone, on a lattice of `voxelSize` holding `materials`: throws ScriptError
/// as it would, without touching any volume (a caller that must page in what an op reaches checks first).
/// Returns a bound on the surface the script's brushes make, in square voxels (all ops and copies).
double checkStrokeScript(const StrokeScript& script, double voxelSize, const MaterialTable& materials);
/// Inflate and deflate ops marked "stroke": "continue" go on with the stroke the op before them began:
/// together they move the surface at most distance x strength from where the stroke found it
/// (applyFieldBrush's cap). `stroke`, when given, carries a stroke across calls (the editor sends a
/// stroke op by op): each op's reach is kept in it, and an op that does not continue starts it afresh.
/// The copies of a symmetric reshaping or blended op whose regions lie apart (two voxels or more, no
/// mask) are prepared side by side, then written one after the other: the same result as one by one,
/// which `copiesSideBySide` false keeps to.
std::vector<ScriptOpReport> runStrokeScript(Volume& volume, const StrokeScript& script,
                                            const std::function<void(const ScriptOpReport&)>& onOp = {},
                                            StrokeStart* stroke = nullptr, bool copiesSideBySide = true);

} // namespace vdbclay
