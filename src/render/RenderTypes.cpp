#include "render/RenderTypes.h"

#include <stdexcept>

namespace vdbclay::render {

namespace {
constexpr struct {
    ViewMode mode;
    const char* name;
} kViewModes[] = {{ViewMode::Shaded, "shaded"}, {ViewMode::Lod, "lod"}, {ViewMode::Toughness, "toughness"}, {ViewMode::Normals, "normals"}};
} // namespace

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
    throw std::invalid_argument("unknown view '" + name + "' (expected shaded, lod, toughness or normals)");
}

} // namespace vdbclay::render
