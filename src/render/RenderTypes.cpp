#include "render/RenderTypes.h"

#include "vdb_hermite/PrintableText.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vdbclay::render {

namespace {
constexpr struct {
    ViewMode mode;
    const char* name;
} kViewModes[] = {{ViewMode::Shaded, "shaded"}, {ViewMode::Lod, "lod"}, {ViewMode::Toughness, "toughness"}, {ViewMode::Normals, "normals"}, {ViewMode::Clay, "clay"}};
} // namespace

double Camera::tanHalfFovY() const
{
    if (asymmetric()) return std::max(fovTangents[2], -fovTangents[3]);
    return std::tan(0.5 * fovYDegrees * M_PI / 180.0);
}

const char* viewModeName(ViewMode mode)
{
    for (const auto& e : kViewModes)
        if (e.mode == mode) return e.name;
    return "?";
}

ViewMode parseViewMode(const std::string& name)
{
    for (const auto& e : kViewModes)
        if (name == e.name) return e.mode;
    throw std::invalid_argument("unknown view '" + printableText(name, 80) + "' (expected shaded, clay, lod, toughness or normals)");
}

double usableNearPlane(const Camera& camera)
{
    return camera.nearPlane > 0.0 && std::isfinite(camera.nearPlane) ? camera.nearPlane : 1e-3;
}

std::array<double, 3> usableUp(const Camera& camera)
{
    std::array<double, 3> f{};
    double fLength2 = 0.0;
    for (std::size_t a = 0; a < 3; ++a) {
        f[a] = camera.target[a] - camera.eye[a];
        fLength2 += f[a] * f[a];
    }
    const auto alongView = [&](const std::array<double, 3>& up) {
        const double c[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
        const double upLength2 = up[0] * up[0] + up[1] * up[1] + up[2] * up[2];
        const double sin2 = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / (fLength2 * upLength2);
        return !std::isfinite(sin2) || !(sin2 > 1e-12);
    };
    if (!alongView(camera.up)) return camera.up;
    if (!alongView({0.0, 1.0, 0.0})) return {0.0, 1.0, 0.0};
    return {0.0, 0.0, f[1] < 0.0 ? -1.0 : 1.0};
}

} // namespace vdbclay::render
