#include "editor/BrushOverlay.h"

#include <string>

namespace vdbclay {

render::BrushOverlay brushOverlay(const BrushSettings& brush, const std::array<double, 3>& at)
{
    using Shape = render::BrushOverlay::Shape;
    render::BrushOverlay o;
    const float r = float(brush.radius);
    const std::string shape = brush.shape.value("shape", std::string("sphere"));
    const auto value = [&](const char* key, double fallback) { return float(brush.shape.value(key, fallback)) * r; };
    o.shape = Shape::Sphere;
    o.params = {r, r, r, 0.0f};
    if (shape == "sphere") o.params[0] = value("radius", 1.0);
    else if (shape == "box" && brush.shape.contains("size") && brush.shape.at("size").is_array()) {
        o.shape = Shape::Box;
        for (std::size_t a = 0; a < 3; ++a) o.params[a] = float(brush.shape.at("size")[a].get<double>()) * r;
        o.params[3] = value("rounding", 0.0);
    } else if (shape == "cylinder" || shape == "cone" || shape == "capsule") {
        o.shape = shape == "cylinder" ? Shape::Cylinder : shape == "cone" ? Shape::Cone : Shape::Capsule;
        o.params[0] = value("radius", 1.0);
        o.height = shape == "capsule" ? value("length", 1.0) : value("height", 2.0);
    } else if (shape == "torus") {
        o.shape = Shape::Torus;
        o.params = {value("radius", 0.75), value("minor_radius", 0.25), 0.0f, 0.0f};
    }
    o.worldToLocal = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float(-at[0]), float(-at[1]), float(-at[2]), 1};
    const float reach = 2.0f * r;
    for (std::size_t a = 0; a < 3; ++a) {
        o.worldBoundsMin[a] = float(at[a]) - reach;
        o.worldBoundsMax[a] = float(at[a]) + reach;
    }
    return o;
}

} // namespace vdbclay
