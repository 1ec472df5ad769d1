#include "sculpt/StrokeScript.h"

#include "sculpt/MaskedEdit.h"

#include "sculpt/SoftPaint.h"
#include "sculpt/StrokePath.h"

#include "vdb_hermite/StrictJson.h"

#include "vdb_hermite/FileExtension.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/VolumeIO.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <memory>
#include <optional>
#include <sys/stat.h>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace vdbclay {

namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& where, const std::string& what) { throw ScriptError(where + ": " + what); }

void checkKeys(const json& obj, const std::string& where, std::initializer_list<const char*> allowed)
{
    if (!obj.is_object()) fail(where, "must be a JSON object");
    for (auto it = obj.begin(); it != obj.end(); ++it) {
        bool ok = false;
        for (const char* a : allowed) ok = ok || it.key() == a;
        if (!ok) fail(where, "unknown key '" + printableText(it.key(), 80) + "'");
    }
}

double number(const json& obj, const char* key, const std::string& where, std::optional<double> fallback = {})
{
    if (!obj.contains(key)) {
        if (fallback) return *fallback;
        fail(where, std::string("missing '") + key + "'");
    }
    const json& v = obj.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(where + "." + key, "must be a finite number");
    return v.get<double>();
}

Vec3d vec3(const json& v, const std::string& where)
{
    if (!v.is_array() || v.size() != 3) fail(where, "must be an array of three numbers");
    Vec3d out;
    for (int i = 0; i < 3; ++i) {
        if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail(where, "must be an array of three numbers");
        out[i] = v[i].get<double>();
    }
    return out;
}

Vec3d vec3Or(const json& obj, const char* key, const std::string& where, const Vec3d& fallback)
{
    return obj.contains(key) ? vec3(obj.at(key), where + "." + key) : fallback;
}

std::string text(const json& obj, const char* key, const std::string& where)
{
    if (!obj.contains(key)) fail(where, std::string("missing '") + key + "'");
    if (!obj.at(key).is_string()) fail(where + "." + key, "must be a string");
    return obj.at(key).get<std::string>();
}

Primitive parsePrimitive(const json& b, const std::string& where)
{
    Primitive p;
    try {
        p.shape = parseShape(text(b, "shape", where));
    } catch (const std::invalid_argument& e) {
        fail(where + ".shape", e.what());
    }
    switch (p.shape) {
    case Shape::Sphere: p.radius = number(b, "radius", where); break;
    case Shape::Box:
        p.size = b.contains("size") ? vec3(b.at("size"), where + ".size") : Vec3d(number(b, "radius", where));
        p.rounding = number(b, "rounding", where, 0.0);
        break;
    case Shape::Cylinder:
    case Shape::Cone:
        p.radius = number(b, "radius", where);
        p.height = number(b, "height", where);
        break;
    case Shape::Capsule:
        p.radius = number(b, "radius", where);
        p.length = number(b, "length", where);
        break;
    case Shape::Torus:
        p.radius = number(b, "radius", where);
        p.minorRadius = number(b, "minor_radius", where);
        break;
    case Shape::HalfSpace: p.normal = vec3Or(b, "normal", where, Vec3d(0.0, 1.0, 0.0)); break;
    }
    try {
        p.validate();
    } catch (const std::invalid_argument& e) {
        fail(where, e.what());
    }
    return p;
}

constexpr std::initializer_list<const char*> kPrimitiveKeys = {"shape", "radius", "size", "rounding", "height",
                                                               "length", "minor_radius", "normal"};

Placement parsePlacement(const json& obj, const std::string& where, const Vec3d& at)
{
    Placement pl;
    pl.translation = at;
    pl.rotationDegrees = vec3Or(obj, "rotate", where, Vec3d(0.0));
    pl.scale = vec3Or(obj, "scale", where, Vec3d(1.0));
    for (int i = 0; i < 3; ++i) {
        if (!(pl.scale[i] > 0.0)) fail(where + ".scale", "scale factors must be positive");
    }
    return pl;
}

Brush parseBrush(const json& b, const std::string& where, const Placement& placement)
{
    if (!b.is_object()) fail(where, "must be a JSON object");
    if (b.contains("shape") && b.at("shape") == "blend") {
        checkKeys(b, where, {"shape", "smoothness", "parts"});
        const double smoothness = number(b, "smoothness", where, 0.0);
        if (smoothness < 0.0) fail(where + ".smoothness", "must be zero or positive");
        if (!b.contains("parts") || !b.at("parts").is_array() || b.at("parts").empty())
            fail(where, "a blend brush needs a non-empty 'parts' array");
        if (b.at("parts").size() > kMaxBlendParts)
            fail(where + ".parts", "has " + std::to_string(b.at("parts").size()) + " parts; a blend may have at most " +
                                       std::to_string(kMaxBlendParts));
        std::vector<BrushPart> parts;
        for (std::size_t i = 0; i < b.at("parts").size(); ++i) {
            const json& pj = b.at("parts")[i];
            const std::string pw = where + ".parts[" + std::to_string(i) + "]";
            std::vector<const char*> keys(kPrimitiveKeys);
            if (!pj.is_object()) fail(pw, "must be a JSON object");
            for (auto it = pj.begin(); it != pj.end(); ++it) {
                const std::string& k = it.key();
                const bool known = k == "at" || k == "rotate" || k == "scale" || k == "op" ||
                                   std::find_if(keys.begin(), keys.end(), [&](const char* s) { return k == s; }) != keys.end();
                if (!known) fail(pw, "unknown key '" + printableText(k, 80) + "'");
            }
            BrushPart part;
            part.primitive = parsePrimitive(pj, pw);
            part.placement = parsePlacement(pj, pw, vec3Or(pj, "at", pw, Vec3d(0.0)));
            const std::string op = pj.contains("op") ? text(pj, "op", pw) : "add";
            if (op == "add") part.op = PartOp::Add;
            else if (op == "remove") part.op = PartOp::Remove;
            else fail(pw + ".op", "must be \"add\" or \"remove\"");
            if (i == 0 && part.op != PartOp::Add) fail(pw + ".op", "the first part must add");
            if (part.primitive.shape == Shape::HalfSpace && part.op == PartOp::Add)
                fail(pw, "a half-space part can only remove");
            parts.push_back(part);
        }
        try {
            return Brush(std::move(parts), smoothness, placement);
        } catch (const std::invalid_argument& e) {
            fail(where, e.what());
        }
    }
    checkKeys(b, where, kPrimitiveKeys);
    const Primitive prim = parsePrimitive(b, where);
    try {
        return Brush(prim, placement);
    } catch (const std::invalid_argument& e) {
        fail(where, e.what());
    }
}

int parseAxis(const json& v, const std::string& where)
{
    if (v.is_string()) {
        const std::string a = v.get<std::string>();
        if (a == "x") return 0;
        if (a == "y") return 1;
        if (a == "z") return 2;
    }
    fail(where, "must be \"x\", \"y\" or \"z\"");
}

Symmetry parseSymmetry(const json& s, const std::string& where)
{
    if (!s.is_object()) fail(where, "must be an object with 'mirror', 'radial' and/or 'center'");
    checkKeys(s, where, {"mirror", "radial", "center"});
    Symmetry out;
    if (s.contains("mirror")) {
        const json& m = s.at("mirror");
        if (!m.is_array()) fail(where + ".mirror", "must be an array of axes, e.g. [\"x\"]");
        for (std::size_t i = 0; i < m.size(); ++i) {
            const int a = parseAxis(m[i], where + ".mirror[" + std::to_string(i) + "]");
            if (out.mirror[std::size_t(a)]) fail(where + ".mirror", "names an axis twice");
            out.mirror[std::size_t(a)] = true;
        }
    }
    if (s.contains("radial")) {
        const json& r = s.at("radial");
        if (!r.is_object()) fail(where + ".radial", "must be an object {\"axis\": \"y\", \"count\": N}");
        checkKeys(r, where + ".radial", {"axis", "count"});
        out.radialAxis = r.contains("axis") ? parseAxis(r.at("axis"), where + ".radial.axis") : 1;
        const double count = number(r, "count", where + ".radial");
        if (!(count >= 1.0 && count <= double(kMaxRadialCopies)) || count != std::floor(count))
            fail(where + ".radial.count", "must be a whole number from 1 to " + std::to_string(kMaxRadialCopies));
        out.radialCount = int(count);
    }
    out.center = vec3Or(s, "center", where, Vec3d(0.0));
    return out;
}

std::optional<MaskEdit> parseMaskEdit(const std::string& mode)
{
    if (mode == "mask") return MaskEdit::Mask;
    if (mode == "unmask") return MaskEdit::Unmask;
    if (mode == "mask_invert") return MaskEdit::Invert;
    if (mode == "mask_clear") return MaskEdit::Clear;
    return std::nullopt;
}

ScriptOp parseOp(const json& o, const std::string& where)
{
    ScriptOp op;
    const std::string mode = text(o, "mode", where);
    if (const std::optional<MaskEdit> maskEdit = parseMaskEdit(mode)) {
        op.maskEdit = maskEdit;
        if (*maskEdit == MaskEdit::Invert || *maskEdit == MaskEdit::Clear) {
            checkKeys(o, where, {"mode"});
            return op;
        }
        checkKeys(o, where, {"mode", "brush", "at", "path", "rotate", "scale", "symmetry"});
    } else {
        checkKeys(o, where, {"mode", "brush", "at", "path", "rotate", "scale", "material", "strength", "depth", "falloff", "distance", "offset", "symmetry", "blend", "stroke"});
    }
    if (o.contains("symmetry")) op.symmetry = parseSymmetry(o.at("symmetry"), where + ".symmetry");
    if (op.maskEdit) {
    } else if (const std::optional<FieldMode> field = parseFieldMode(mode)) {
        op.field = FieldBrushOp{};
        op.field->mode = *field;
    } else {
        try {
            op.mode = parseCsgMode(mode);
        } catch (const std::invalid_argument& e) {
            fail(where + ".mode", std::string(e.what()) + ", a reshaping brush (smooth, flatten, inflate, deflate, move) or a mask op "
                                                          "(mask, unmask, mask_invert, mask_clear)");
        }
    }
    for (const char* key : {"falloff", "distance", "offset"})
        if (o.contains(key) && !op.field && !(op.mode == CsgMode::Paint && std::string(key) == "falloff"))
            fail(where + "." + key, std::string("belongs to reshaping brushes (smooth, flatten, inflate, deflate, move)") +
                                        (std::string(key) == "falloff" ? " and paint" : ""));
    // A falloff by name, or a curve: weights from the rim to the deepest point.
    const auto falloffOf = [&](FalloffCurve& curve) {
        const json& f = o.at("falloff");
        try {
            if (!f.is_array()) return parseFalloff(text(o, "falloff", where));
            for (const json& w : f) {
                if (!w.is_number()) throw std::invalid_argument("a falloff curve holds numbers");
                curve.push_back(w.get<double>());
            }
            checkFalloffCurve(curve);
            return Falloff::Curve;
        } catch (const std::invalid_argument& e) {
            fail(where + ".falloff", std::string(e.what()) + " (smooth, linear, constant, or a curve of weights [0, 0.5, 1])");
        }
    };
    if (!op.field && o.contains("falloff")) op.paintFalloff = falloffOf(op.falloffCurve);
    if (op.field) {
        const FieldMode m = op.field->mode;
        if (o.contains("depth")) fail(where + ".depth", "belongs to erode");
        if (o.contains("falloff")) {
            op.field->falloff = falloffOf(op.falloffCurve);
            op.field->curve = op.falloffCurve;
        }
        const bool moves = m == FieldMode::Inflate || m == FieldMode::Deflate;
        if (moves != o.contains("distance")) fail(where + ".distance", moves ? "inflate and deflate need a 'distance' (world units)" : "belongs to inflate and deflate");
        if (moves) {
            op.field->distance = number(o, "distance", where);
            if (!(op.field->distance > 0.0 && op.field->distance < 1e6)) fail(where + ".distance", "must be positive and below 1e6 (world units)");
        }
        if ((m == FieldMode::Move) != o.contains("offset")) fail(where + ".offset", m == FieldMode::Move ? "move needs an 'offset' [dx, dy, dz]" : "belongs to move");
        if (m == FieldMode::Move) {
            op.field->offset = vec3(o.at("offset"), where + ".offset");
            if (!(op.field->offset.length() < 1e6)) fail(where + ".offset", "is too long");
        }
    }
    if (o.contains("stroke")) {
        const bool moves = op.field && (op.field->mode == FieldMode::Inflate || op.field->mode == FieldMode::Deflate);
        if (!moves) fail(where + ".stroke", "belongs to inflate and deflate");
        if (text(o, "stroke", where) != "continue") fail(where + ".stroke", "must be \"continue\" (the op goes on with the stroke the op before it began)");
        op.continuesStroke = true;
    }
    if (o.contains("at") && o.contains("path")) fail(where, "give either 'at' or 'path', not both");
    if (o.contains("path")) {
        const json& p = o.at("path");
        if (!p.is_array() || p.empty()) fail(where + ".path", "must be a non-empty array of points");
        if (p.size() > kMaxPathPoints)
            fail(where + ".path", "has " + std::to_string(p.size()) + " points; a stroke may have at most " +
                                      std::to_string(kMaxPathPoints));
        for (std::size_t i = 0; i < p.size(); ++i) op.path.push_back(vec3(p[i], where + ".path[" + std::to_string(i) + "]"));
    }
    const Vec3d at = op.path.empty() ? vec3Or(o, "at", where, Vec3d(0.0)) : op.path.front();
    if (!o.contains("brush")) fail(where, "missing 'brush'");
    op.placement = parsePlacement(o, where, at);
    const json& brush = o.at("brush");
    const bool grid = brush.is_object() && brush.contains("shape") && brush.at("shape") == "grid";
    if (grid) {
        if (op.field) fail(where + ".brush", std::string(fieldModeName(op.field->mode)) + " takes an analytic brush, not a grid tool");
        if (op.maskEdit) fail(where + ".brush", std::string(mode) + " takes an analytic brush, not a grid tool");
        checkKeys(brush, where + ".brush", {"shape", "file"});
        op.toolFile = text(brush, "file", where + ".brush");
        if (op.toolFile.empty()) fail(where + ".brush.file", "must not be empty");
    } else {
        op.brush = parseBrush(brush, where + ".brush", op.placement);
    }
    if (op.maskEdit) {
        if (!op.brush.bounds().bounded()) fail(where, mode + " needs a bounded brush");
        if (op.path.size() > 1 && !std::isfinite(op.brush.boundingRadius())) fail(where + ".path", "an unbounded brush cannot follow a path");
        return op;
    }
    if (o.contains("material")) op.material = text(o, "material", where);
    if (op.mode == CsgMode::Paint && op.material.empty() && !grid)
        fail(where, "paint needs a 'material' (or a grid tool, which paints with its own)");
    op.strength = number(o, "strength", where, 1.0);
    if (op.strength < 0.0 || op.strength > 1.0) fail(where + ".strength", "must lie in [0,1]");
    if (op.field) {
        op.field->strength = op.strength;
        if (!op.brush.bounds().bounded()) fail(where, std::string(fieldModeName(op.field->mode)) + " needs a bounded brush");
        return op;
    }
    if (o.contains("depth")) {
        op.depth = number(o, "depth", where);
        if (!(*op.depth > 0.0)) fail(where + ".depth", "must be positive");
    }
    if (o.contains("blend")) {
        if (op.mode != CsgMode::Add) fail(where + ".blend", "belongs to add (the width of its smooth union with the surface)");
        op.blend = number(o, "blend", where);
        if (!(op.blend >= 0.0 && op.blend < 1e6)) fail(where + ".blend", "must be at least 0 and below 1e6 (world units)");
    }
    if (grid) return op; // bounded, with an inner radius: its checks wait for the tool's file
    if (op.mode == CsgMode::Erode && !op.depth && !std::isfinite(op.brush.innerRadius()))
        fail(where, "eroding with an unbounded brush (half-space) needs a 'depth'");
    if (op.path.size() > 1 && !std::isfinite(op.brush.boundingRadius()))
        fail(where + ".path", "an unbounded brush (half-space) cannot follow a path");
    if (op.mode == CsgMode::Add && !op.brush.bounds().bounded()) fail(where, "cannot add an unbounded brush (half-space)");
    return op;
}

} // namespace

StrokeScript parseStrokeScript(const std::string& jsonText)
{
    json root;
    try {
        root = parseStrictJson(jsonText, "script");
    } catch (const std::invalid_argument& e) {
        throw ScriptError(e.what());
    }
    checkKeys(root, "script", {"materials", "ops"});
    StrokeScript script;
    if (root.contains("materials")) {
        const json& ms = root.at("materials");
        if (!ms.is_array()) fail("materials", "must be an array");
        std::set<std::string> seen;
        for (std::size_t i = 0; i < ms.size(); ++i) {
            const std::string where = "materials[" + std::to_string(i) + "]";
            checkKeys(ms[i], where, {"name", "color", "toughness", "texture"});
            Material m;
            m.name = text(ms[i], "name", where);
            if (m.name.empty()) fail(where + ".name", "must not be empty");
            if (!seen.insert(m.name).second) fail(where + ".name", "duplicate material '" + printableText(m.name, 80) + "'");
            if (ms[i].contains("color")) {
                const json& c = ms[i].at("color");
                if (!c.is_array() || (c.size() != 3 && c.size() != 4)) fail(where + ".color", "must be [r,g,b] or [r,g,b,a]");
                for (std::size_t k = 0; k < c.size(); ++k) {
                    if (!c[k].is_number() || c[k].get<double>() < 0.0 || c[k].get<double>() > 1.0)
                        fail(where + ".color", "components must be numbers in [0,1]");
                    m.color[k] = c[k].get<float>();
                }
            }
            m.toughness = float(number(ms[i], "toughness", where, 0.5));
            if (m.toughness < 0.0f || m.toughness > 1.0f) fail(where + ".toughness", "must lie in [0,1]");
            if (ms[i].contains("texture")) {
                m.texture = text(ms[i], "texture", where);
                if (m.texture.empty() || !isPrintableName(m.texture, kMaxTexturePathBytes))
                    fail(where + ".texture", "must be a path: printable text of 1 to 4096 bytes");
            }
            script.materials.push_back(m);
        }
    }
    if (!root.contains("ops") || !root.at("ops").is_array()) fail("script", "needs an 'ops' array");
    const json& ops = root.at("ops");
    for (std::size_t i = 0; i < ops.size(); ++i) {
        script.ops.push_back(parseOp(ops[i], "ops[" + std::to_string(i) + "]"));
        // A stroke is kept from its start only where inflate and deflate reach (bounded, a field brush's
        // region at most), so only they may make up a stroke.
        if (i > 0 && script.ops[i].continuesStroke) {
            const std::optional<FieldBrushOp>& before = script.ops[i - 1].field;
            if (!before || (before->mode != FieldMode::Inflate && before->mode != FieldMode::Deflate))
                fail("ops[" + std::to_string(i) + "].stroke", "continues a stroke only after an inflate or deflate op");
        }
    }
    return script;
}

StrokeScript loadStrokeScript(const std::string& path)
{
    // A FIFO or a device would be read forever; a huge file is not a script.
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw ScriptError("cannot open script '" + printableText(path, 200) + "': " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw ScriptError("script '" + printableText(path, 200) + "' is not a regular file");
    if (uint64_t(st.st_size) > kMaxScriptBytes)
        throw ScriptError("script '" + printableText(path, 200) + "' is " + std::to_string(st.st_size) + " bytes; scripts may have at most " +
                          std::to_string(kMaxScriptBytes));
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ScriptError("cannot open script '" + printableText(path, 200) + "'");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw ScriptError("cannot read script '" + printableText(path, 200) + "'");
    StrokeScript script = parseStrokeScript(text.str());
    loadScriptTools(script, std::filesystem::path(path).parent_path().string());
    return script;
}

namespace {

/// What to run when a script names a scene that is not a tool file yet.
std::string toolFileHint(const std::string& file)
{
    const std::string ext = lowerCaseExtension(file);
    bool foreign = false;
    try {
        foreign = ext == ".vdb" && classifyVdbFile(file) == VdbFileKind::Other;
    } catch (const std::exception&) { // unreadable: the error says so already
    }
    if (ext == ".vdbclay") return " (a store: make a tool of it with 'vdbclay tool make " + printableText(file, 200) + " -o TOOL.vdb')";
    if (foreign) return " (bring it in with 'vdbclay import', then 'vdbclay tool make')";
    return "";
}

} // namespace

void loadScriptTools(StrokeScript& script, const std::string& folder)
{
    ToolCache loaded;
    loadScriptTools(script, folder, loaded);
}

void loadScriptTools(StrokeScript& script, const std::string& folder, ToolCache& loaded)
{
    for (std::size_t i = 0; i < script.ops.size(); ++i) {
        ScriptOp& op = script.ops[i];
        if (op.toolFile.empty()) continue;
        const std::filesystem::path named(op.toolFile);
        const std::string file = named.is_absolute() || folder.empty() ? named.string() : (std::filesystem::path(folder) / named).string();
        auto found = loaded.find(file);
        if (found == loaded.end()) {
            try {
                found = loaded.emplace(file, GridTool::load(file)).first;
            } catch (const std::exception& e) {
                throw ScriptError("ops[" + std::to_string(i) + "].brush.file: cannot use '" + printableText(file, 200) + "' as a tool: " + e.what() +
                                  toolFileHint(file));
            }
        }
        op.tool = found->second;
    }
}

const char* opModeName(const ScriptOp& op)
{
    if (op.maskEdit) {
        switch (*op.maskEdit) {
        case MaskEdit::Mask: return "mask";
        case MaskEdit::Unmask: return "unmask";
        case MaskEdit::Invert: return "mask_invert";
        case MaskEdit::Clear: return "mask_clear";
        }
    }
    return op.field ? fieldModeName(op.field->mode) : csgModeName(op.mode);
}

WorldBounds opBounds(const ScriptOp& op, double voxelSize)
{
    if (op.maskEdit == MaskEdit::Invert || op.maskEdit == MaskEdit::Clear) {
        WorldBounds none;
        none.min = Vec3d(0.0);
        none.max = Vec3d(-1.0);
        return none;
    }
    if (!op.toolFile.empty() && !op.tool) throw ScriptError("the tool '" + printableText(op.toolFile, 200) + "' is not loaded");
    WorldBounds one = op.tool ? PlacedTool(op.tool, op.placement).bounds() : op.brush.bounds();
    if (one.bounded() && op.field) {
        one = fieldBrushRegion(op.brush, *op.field, voxelSize);
    } else if (op.blend > 0.0) {
        one = blendedAddRegion(one, op.blend, voxelSize);
    }
    if (!one.bounded()) return one;
    WorldBounds b = one;
    const Vec3d first = op.path.empty() ? Vec3d(0.0) : op.path.front();
    for (const Vec3d& p : op.path)
        for (int i = 0; i < 3; ++i) {
            b.min[i] = std::min(b.min[i], one.min[i] + p[i] - first[i]);
            b.max[i] = std::max(b.max[i], one.max[i] + p[i] - first[i]);
        }
    if (!op.symmetry.any()) return b;
    WorldBounds all = b;
    for (const Mat3d& copy : symmetryCopies(op.symmetry)) {
        const WorldBounds c = transformBounds(b, copy, op.symmetry.center);
        for (int i = 0; i < 3; ++i) {
            all.min[i] = std::min(all.min[i], c.min[i]);
            all.max[i] = std::max(all.max[i], c.max[i]);
        }
    }
    return all;
}

namespace {

/// One application of the CSG kernel: a script op is one, or one per material of a tool that brings
/// its own.
struct OpStep {
    std::shared_ptr<const SdfField> field;
    CsgOp op;
    std::optional<FieldBrushOp> reshape; // a reshaping brush instead of the CSG op
    double blend = 0.0;                  // add: blended into the surface this wide (applyBlendedAdd)
    std::optional<MaskEdit> maskEdit;    // a mask op instead (its field null for invert and clear)
};

/// The field an op carves with, with the tool's region `region` where it uses a tool. A stroke follows its
/// path simplified within a small fraction of a voxel: its cost follows the voxels it covers, not how
/// densely its points were sampled.
std::shared_ptr<const SdfField> opField(const ScriptOp& s, MaterialId region, double voxelSize)
{
    std::shared_ptr<const PlaceableField> placed;
    if (s.tool) placed = std::make_shared<PlacedTool>(s.tool, s.placement, region);
    else placed = std::make_shared<Brush>(s.brush);
    if (s.path.size() > 1)
        return std::make_shared<SweptBrush>(std::move(placed), simplifyStrokePath(s.path, kStrokePathToleranceVoxels * voxelSize));
    return placed;
}

/// The steps of an op, then each again for every other copy of its symmetry (fields seen through the
/// copy, a move's offset turned with it).
std::vector<OpStep> withSymmetry(std::vector<OpStep> steps, const Symmetry& symmetry)
{
    if (!symmetry.any()) return steps;
    const std::vector<Mat3d> copies = symmetryCopies(symmetry);
    const std::size_t plain = steps.size();
    for (std::size_t c = 1; c < copies.size(); ++c)
        for (std::size_t i = 0; i < plain; ++i) {
            OpStep copy = steps[i];
            copy.field = std::make_shared<TransformedField>(steps[i].field, copies[c], symmetry.center);
            if (copy.reshape) copy.reshape->offset = copies[c] * copy.reshape->offset;
            steps.push_back(std::move(copy));
        }
    return steps;
}

std::vector<OpStep> compileOp(const ScriptOp& s, std::size_t index, MaterialTable& table, double voxelSize)
{
    const std::string where = "ops[" + std::to_string(index) + "]";
    if (!s.toolFile.empty() && !s.tool) throw ScriptError(where + ".brush.file: the tool '" + printableText(s.toolFile, 200) + "' is not loaded");
    CsgOp op;
    op.mode = s.mode;
    op.strength = s.strength;
    op.erodeDepth = s.depth;
    if (!s.material.empty()) {
        const auto id = table.find(s.material);
        if (!id) throw ScriptError(where + ".material: '" + printableText(s.material, 80) + "' is neither in the volume nor in the script's materials");
        op.material = *id;
    }
    std::vector<OpStep> plain;
    if (s.maskEdit) {
        if (*s.maskEdit == MaskEdit::Invert || *s.maskEdit == MaskEdit::Clear) return {{nullptr, op, std::nullopt, 0.0, s.maskEdit}};
        return withSymmetry({{opField(s, kEmptyMaterial, voxelSize), op, std::nullopt, 0.0, s.maskEdit}}, s.symmetry);
    }
    if (s.field) {
        FieldBrushOp reshape = *s.field;
        if (!s.material.empty()) reshape.material = op.material;
        plain = {{opField(s, kEmptyMaterial, voxelSize), op, reshape, 0.0, std::nullopt}};
    }
    const bool toolMaterials = s.tool && s.material.empty() && (s.mode == CsgMode::Add || s.mode == CsgMode::Paint);
    try {
        if (!s.field && !toolMaterials) {
            std::shared_ptr<const SdfField> field = opField(s, kEmptyMaterial, voxelSize);
            // Paint with a falloff, or below full strength, covers part of the brush (SoftPaint.h).
            if (s.mode == CsgMode::Paint && (s.paintFalloff || s.strength < 1.0))
                field = std::make_shared<SoftPaintField>(std::move(field), s.strength, s.paintFalloff.value_or(Falloff::Constant), voxelSize,
                                                         s.falloffCurve);
            plain = {{field, op, std::nullopt, s.blend, std::nullopt}};
        }
        if (!plain.empty()) return withSymmetry(std::move(plain), s.symmetry);
        // Each material of the tool over its own region: regions share their boundaries, so each
        // material boundary of the tool becomes one in the volume, with its crossings and normals.
        std::vector<OpStep> steps;
        for (MaterialId region : s.tool->regions()) {
            const Material& m = s.tool->materials().at(region);
            const auto existing = table.find(m.name);
            op.material = existing ? *existing : table.define(m);
            steps.push_back({opField(s, region, voxelSize), op, std::nullopt, s.blend, std::nullopt});
        }
        return withSymmetry(std::move(steps), s.symmetry);
    } catch (const std::invalid_argument& e) {
        throw ScriptError(where + ": " + e.what());
    }
}

} // namespace

namespace {

/// A mask brush's bounds must be finite and of a size a stroke can visit.
void checkMaskBrush(const SdfField& field, double voxelSize)
{
    const WorldBounds b = field.bounds();
    if (!b.bounded()) throw std::invalid_argument("a mask brush must be bounded");
    double leaves = 1.0;
    for (int a = 0; a < 3; ++a) leaves *= (b.max[a] - b.min[a]) / (voxelSize * kLeafDim) + 2.0;
    if (!(leaves <= kMaxMaskBrushLeaves))
        throw std::invalid_argument("the mask brush spans about " + std::to_string(uint64_t(std::min(leaves, 1e18))) + " leaves, more than " +
                                    std::to_string(uint64_t(kMaxMaskBrushLeaves)));
}

void applyMaskEdit(VoxelMask& mask, const OpStep& step, double voxelSize)
{
    switch (*step.maskEdit) {
    case MaskEdit::Mask: paintMask(mask, *step.field, voxelSize, true); break;
    case MaskEdit::Unmask: paintMask(mask, *step.field, voxelSize, false); break;
    case MaskEdit::Invert: mask.invert(); break;
    case MaskEdit::Clear: mask.clear(); break;
    }
}

/// The script's ops compiled into steps, each checked against the limits (on `table`, the materials once
/// the script's are defined; a tool's materials are added to it): a script is refused whole, before the
/// first op runs.
std::vector<std::vector<OpStep>> compileChecked(const StrokeScript& script, double voxelSize, MaterialTable& table)
{
    std::vector<std::vector<OpStep>> steps;
    for (std::size_t i = 0; i < script.ops.size(); ++i) {
        steps.push_back(compileOp(script.ops[i], i, table, voxelSize));
        for (const OpStep& step : steps.back()) {
            try {
                if (step.maskEdit) {
                    if (step.field) checkMaskBrush(*step.field, voxelSize);
                } else if (step.reshape) {
                    Volume probe(voxelSize); // the checks read the voxel size and the materials only
                    probe.materials() = table;
                    checkFieldBrush(probe, *step.field, *step.reshape);
                } else {
                    checkCsgLimits(voxelSize, table, *step.field, step.op);
                }
            } catch (const std::invalid_argument& e) {
                throw ScriptError("ops[" + std::to_string(i) + "]: " + e.what());
            }
        }
    }
    return steps;
}

MaterialTable withScriptMaterials(MaterialTable table, const StrokeScript& script)
{
    for (const Material& m : script.materials) table.define(m);
    return table;
}

} // namespace

double checkStrokeScript(const StrokeScript& script, double voxelSize, const MaterialTable& materials)
{
    double surface = 0.0;
    MaterialTable table = withScriptMaterials(materials, script);
    for (const auto& steps : compileChecked(script, voxelSize, table))
        for (const OpStep& step : steps)
            if (!step.maskEdit && step.field->bounds().bounded()) surface += step.field->surfaceAreaBound() / (voxelSize * voxelSize);
    return surface;
}

namespace {

/// The region a step reads, grown by two voxels (its write-back changes Hermite samples a voxel beside
/// what it covers), where it is prepared apart from writing: reshaping and blended adds; nullopt for
/// other steps.
std::optional<WorldBounds> preparedRegion(const OpStep& step, double voxelSize)
{
    if (step.maskEdit || !step.field || (!step.reshape && !(step.blend > 0.0))) return std::nullopt;
    if (!step.field->bounds().bounded()) return std::nullopt;
    WorldBounds r = step.reshape ? fieldBrushRegion(*step.field, *step.reshape, voxelSize) : blendedAddRegion(step.field->bounds(), step.blend, voxelSize);
    r.min -= Vec3d(2.0 * voxelSize);
    r.max += Vec3d(2.0 * voxelSize);
    return r;
}

/// Whether an op's steps (a symmetry's copies) may be prepared side by side: each prepared apart from
/// writing, and no step's region meets another's.
bool preparedApart(const std::vector<OpStep>& steps, double voxelSize)
{
    if (steps.size() < 2) return false;
    std::vector<WorldBounds> regions;
    for (const OpStep& step : steps) {
        const std::optional<WorldBounds> r = preparedRegion(step, voxelSize);
        if (!r) return false;
        for (const WorldBounds& other : regions) {
            bool apart = false;
            for (int a = 0; a < 3; ++a) apart = apart || r->max[a] < other.min[a] || other.max[a] < r->min[a];
            if (!apart) return false;
        }
        regions.push_back(*r);
    }
    return true;
}

} // namespace

std::vector<ScriptOpReport> runStrokeScript(Volume& volume, const StrokeScript& script,
                                            const std::function<void(const ScriptOpReport&)>& onOp, StrokeStart* stroke, bool copiesSideBySide)
{
    MaterialTable table = withScriptMaterials(volume.materials(), script);
    const std::vector<std::vector<OpStep>> steps = compileChecked(script, volume.voxelSize(), table);
    volume.materials() = table;

    std::vector<ScriptOpReport> reports;
    std::optional<StrokeStart> ownStroke; // a stroke the script holds whole
    for (std::size_t i = 0; i < script.ops.size(); ++i) {
        const bool continues = script.ops[i].continuesStroke;
        const bool continued = i + 1 < script.ops.size() && script.ops[i + 1].continuesStroke;
        if (!continues) {
            ownStroke.reset();
            if (stroke) *stroke = StrokeStart(volume.voxelSize());
            if (continued && !stroke) ownStroke.emplace(volume.voxelSize());
        }
        StrokeStart* keepIn = stroke ? stroke : ownStroke ? &*ownStroke : nullptr;
        const auto start = std::chrono::steady_clock::now();
        ScriptOpReport report;
        report.index = i;
        report.mode = script.ops[i].mode;
        report.modeName = opModeName(script.ops[i]);
        const WorldBounds reach = opBounds(script.ops[i], volume.voxelSize());
        if (copiesSideBySide && !volume.mask().any() && preparedApart(steps[i], volume.voxelSize())) {
            // Each copy reads only its region, which no other copy writes: prepared on the cores together
            // (the distance rebuilds that are most of a reshaping step), then written in order.
            for (const OpStep& step : steps[i])
                if (keepIn && step.reshape) keepIn->keep(volume, fieldBrushRegion(*step.field, *step.reshape, volume.voxelSize()));
            std::vector<EditWriteBack> writeBacks(steps[i].size());
            tbb::parallel_for(std::size_t(0), steps[i].size(), [&](std::size_t k) {
                const OpStep& step = steps[i][k];
                const Volume* began = continues && keepIn && step.reshape ? &keepIn->volume() : nullptr;
                writeBacks[k] = step.reshape ? prepareFieldBrush(volume, *step.field, *step.reshape, began)
                                             : prepareBlendedAdd(volume, *step.field, step.op, step.blend);
            });
            for (const EditWriteBack& writeBack : writeBacks) report.stats.append(writeBack(volume));
        } else {
            for (const OpStep& step : steps[i]) {
                if (step.maskEdit) {
                    applyMaskEdit(volume.mask(), step, volume.voxelSize());
                    continue;
                }
                // The mask is respected by putting back what it keeps once the brush has run.
                std::optional<MaskedVoxels> kept;
                if (volume.mask().any()) kept.emplace(volume, reach);
                if (keepIn && step.reshape) keepIn->keep(volume, fieldBrushRegion(*step.field, *step.reshape, volume.voxelSize()));
                const Volume* began = continues && keepIn && step.reshape ? &keepIn->volume() : nullptr;
                report.stats.append(step.reshape       ? applyFieldBrush(volume, *step.field, *step.reshape, began)
                                    : step.blend > 0.0 ? applyBlendedAdd(volume, *step.field, step.op, step.blend)
                                                       : applyCsg(volume, *step.field, step.op));
                if (kept) kept->restore(volume);
            }
        }
        report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (onOp) onOp(report);
        reports.push_back(std::move(report));
    }
    return reports;
}

} // namespace vdbclay
