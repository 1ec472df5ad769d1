// A ray in world units: the pointer's (or a controller's) line of sight, which places the brush.
#pragma once

#include <array>

namespace vdbclay {

struct Ray {
    std::array<double, 3> origin{0, 0, 0};
    std::array<double, 3> direction{0, 0, -1}; // unit length where a front end made it
};

} // namespace vdbclay
