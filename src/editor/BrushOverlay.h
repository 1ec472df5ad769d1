// The brush as the renderer previews it: the shape of the brush's script op, at its size, placed at a point.
#pragma once

#include "editor/BrushSettings.h"
#include "render/RenderTypes.h"

#include <array>

namespace vdbclay {

/// The overlay of `brush` centred at `at` (world units).
render::BrushOverlay brushOverlay(const BrushSettings& brush, const std::array<double, 3>& at);

} // namespace vdbclay
