#include "editor/BrushSettings.h"

#include "sculpt/FieldBrushes.h"
#include "vdb_hermite/PrintableText.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vdbclay {

namespace {

const char* pressureName(PressureTarget p) { return p == PressureTarget::Size ? "size" : p == PressureTarget::Strength ? "strength" : "none"; }

double number(const nlohmann::json& json, const char* key, double fallback)
{
    if (!json.contains(key)) return fallback;
    const nlohmann::json& v = json.at(key);
    if (!v.is_number()) throw std::invalid_argument(std::string("brush.") + key + ": must be a number");
    return v.get<double>();
}

std::string text(const nlohmann::json& json, const char* key, const std::string& fallback)
{
    if (!json.contains(key)) return fallback;
    const nlohmann::json& v = json.at(key);
    if (!v.is_string()) throw std::invalid_argument(std::string("brush.") + key + ": must be a string");
    return v.get<std::string>();
}

/// The falloff as scripts and sessions write it: its name, or a curve's weights.
nlohmann::json falloffJson(const BrushSettings& b)
{
    if (b.falloff == "curve") return b.falloffCurve;
    return b.falloff;
}

} // namespace

bool isReshapingMode(const std::string& mode)
{
    return mode == "smooth" || mode == "flatten" || mode == "inflate" || mode == "deflate" || mode == "move";
}

bool isMaskMode(const std::string& mode) { return mode == "mask" || mode == "unmask"; }

void checkBrushSettings(const BrushSettings& b)
{
    static const std::vector<std::string> modes{"add", "remove", "intersect", "paint", "erode", "smooth", "flatten", "inflate", "deflate", "move", "mask", "unmask"};
    if (std::find(modes.begin(), modes.end(), b.mode) == modes.end()) throw std::invalid_argument("brush.mode: unknown mode '" + printableText(b.mode, 80) + "'");
    if (!b.shape.is_object() || !b.shape.contains("shape")) throw std::invalid_argument("brush.shape: must be a script brush object");
    if (!(b.radius > 0.0) || !std::isfinite(b.radius)) throw std::invalid_argument("brush.radius: must be above 0");
    if (!(b.strength >= 0.0 && b.strength <= 1.0)) throw std::invalid_argument("brush.strength: must be in [0, 1]");
    if (b.falloff != "smooth" && b.falloff != "linear" && b.falloff != "constant" && b.falloff != "curve")
        throw std::invalid_argument("brush.falloff: smooth, linear, constant, or a curve of weights [0, 0.5, 1]");
    if (b.falloff == "curve") {
        try {
            checkFalloffCurve(b.falloffCurve);
        } catch (const std::invalid_argument& e) {
            throw std::invalid_argument(std::string("brush.falloff: ") + e.what());
        }
    }
    if (!(b.distance > 0.0) || !std::isfinite(b.distance)) throw std::invalid_argument("brush.distance: must be above 0");
    if (!(b.spacing >= 0.02 && b.spacing <= 4.0)) throw std::invalid_argument("brush.spacing: must be in [0.02, 4]");
    if (!b.symmetry.is_null() && !b.symmetry.is_object()) throw std::invalid_argument("brush.symmetry: must be an object or null");
    if (!(b.smoothness >= 0.0 && b.smoothness <= 1.0)) throw std::invalid_argument("brush.smoothness: must be in [0, 1]");
}

nlohmann::json brushSettingsJson(const BrushSettings& b)
{
    return {{"mode", b.mode}, {"shape", b.shape}, {"radius", b.radius}, {"strength", b.strength}, {"falloff", falloffJson(b)},
            {"material", b.material}, {"distance", b.distance}, {"spacing", b.spacing}, {"pressure", pressureName(b.pressure)},
            {"symmetry", b.symmetry}, {"accumulate", b.accumulate}, {"smoothness", b.smoothness}};
}

BrushSettings parseBrushSettings(const nlohmann::json& json)
{
    if (!json.is_object()) throw std::invalid_argument("brush: must be an object");
    static const std::vector<std::string> keys{"mode", "shape", "radius", "strength", "falloff", "material", "distance", "spacing", "pressure", "symmetry", "accumulate", "smoothness"};
    for (const auto& item : json.items())
        if (std::find(keys.begin(), keys.end(), item.key()) == keys.end()) throw std::invalid_argument("brush." + printableText(item.key(), 80) + ": unknown key");
    BrushSettings b;
    b.mode = text(json, "mode", b.mode);
    if (json.contains("shape")) b.shape = json.at("shape");
    b.radius = number(json, "radius", b.radius);
    b.strength = number(json, "strength", b.strength);
    if (json.contains("falloff") && json.at("falloff").is_array()) {
        b.falloff = "curve";
        for (const nlohmann::json& w : json.at("falloff")) {
            if (!w.is_number()) throw std::invalid_argument("brush.falloff: a curve holds numbers");
            b.falloffCurve.push_back(w.get<double>());
        }
    } else {
        b.falloff = text(json, "falloff", b.falloff);
        if (b.falloff == "curve") throw std::invalid_argument("brush.falloff: a curve is given as its weights, e.g. [0, 0.5, 1]");
    }
    b.material = text(json, "material", b.material);
    b.distance = number(json, "distance", b.distance);
    b.spacing = number(json, "spacing", b.spacing);
    const std::string pressure = text(json, "pressure", pressureName(b.pressure));
    if (pressure == "size") b.pressure = PressureTarget::Size;
    else if (pressure == "strength") b.pressure = PressureTarget::Strength;
    else if (pressure == "none") b.pressure = PressureTarget::None;
    else throw std::invalid_argument("brush.pressure: size, strength or none");
    if (json.contains("symmetry")) b.symmetry = json.at("symmetry");
    b.smoothness = number(json, "smoothness", 0.0); // absent: exact, as before the setting was
    if (json.contains("accumulate")) {
        if (!json.at("accumulate").is_boolean()) throw std::invalid_argument("brush.accumulate: must be true or false");
        b.accumulate = json.at("accumulate").get<bool>();
    }
    checkBrushSettings(b);
    return b;
}

double stampNormalOffset(const BrushSettings& b, double pressure)
{
    if (b.mode != "add" && b.mode != "remove") return 0.0;
    const double p = std::clamp(pressure, 0.05, 1.0);
    // The shape's own radius where it has one (a sphere of radius 0.5 at unit size), else its unit size.
    const auto unit = b.shape.find("radius");
    const double shapeRadius = unit != b.shape.end() && unit->is_number() && unit->get<double>() > 0.0 ? unit->get<double>() : 1.0;
    const double radius = shapeRadius * b.radius * (b.pressure == PressureTarget::Size ? p : 1.0);
    const double strength = b.strength * (b.pressure == PressureTarget::Strength ? p : 1.0);
    const double depth = (1.0 - strength) * radius;
    return b.mode == "add" ? -depth : depth;
}

nlohmann::json strokeOpJson(const BrushSettings& b, const std::vector<std::array<double, 3>>& points, double pressure,
                            const std::array<double, 3>& offset)
{
    const double p = std::clamp(pressure, 0.05, 1.0);
    nlohmann::json op = {{"mode", b.mode}, {"brush", b.shape}};
    const double scale = b.radius * (b.pressure == PressureTarget::Size ? p : 1.0);
    op["scale"] = {scale, scale, scale};
    if (points.size() == 1) op["at"] = points[0];
    else op["path"] = points;
    if (isMaskMode(b.mode)) { // the mask takes the brush's shape only
        if (!b.symmetry.is_null()) op["symmetry"] = b.symmetry;
        return op;
    }
    if (!b.material.empty()) op["material"] = b.material;
    else if (b.mode == "paint") op["material"] = "default"; // paint needs one: the volume's first, as add uses
    const double strength = b.strength * (b.pressure == PressureTarget::Strength ? p : 1.0);
    if (isReshapingMode(b.mode)) {
        op["strength"] = strength;
        op["falloff"] = falloffJson(b);
        if (b.mode == "inflate" || b.mode == "deflate") op["distance"] = b.distance;
        if (b.mode == "move") op["offset"] = offset;
    } else if (b.mode == "erode") {
        op["strength"] = strength;
    } else if (b.mode == "paint") {
        op["strength"] = strength;
        op["falloff"] = falloffJson(b);
    } else if (b.mode == "add" && b.smoothness > 0.0) {
        op["blend"] = b.smoothness * scale;
    }
    if (!b.symmetry.is_null()) op["symmetry"] = b.symmetry;
    return op;
}

} // namespace vdbclay
