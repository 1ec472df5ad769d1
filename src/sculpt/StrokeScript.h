// Stroke scripts: JSON lists of sculpting operations (docs/SCRIPTS.md describes the format).
#pragma once

#include "sculpt/Brush.h"
#include "sculpt/Csg.h"
#include "vdb_hermite/Materials.h"
#include "vdb_hermite/Volume.h"

#include <functional>
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

struct ScriptOp {
    CsgMode mode = CsgMode::Add;
    Brush brush;                 // placed at "at" (or at the first path point)
    std::vector<Vec3d> path;     // empty for a single stamp
    std::string material;        // empty: add uses the volume's first material
    double strength = 1.0;
    std::optional<double> depth; // erode depth override
};

struct StrokeScript {
    std::vector<Material> materials;
    std::vector<ScriptOp> ops;
};

StrokeScript parseStrokeScript(const std::string& jsonText);
StrokeScript loadStrokeScript(const std::string& path); // ScriptError also for unreadable files

struct ScriptOpReport {
    std::size_t index = 0;
    CsgMode mode = CsgMode::Add;
    EditStats stats;
    double seconds = 0.0;
};

/// Defines the script's materials in the volume, checks every op's material and limits
/// (checkCsgLimits), then applies the ops in order. Throws ScriptError, before touching the volume, when
/// an op names an unknown material or asks for more than the limits allow.
std::vector<ScriptOpReport> runStrokeScript(Volume& volume, const StrokeScript& script,
                                            const std::function<void(const ScriptOpReport&)>& onOp = {});

} // namespace vdbclay
