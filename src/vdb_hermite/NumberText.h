// A number as it appears in a message to the user: "0.5", "24", "2.2e+14", never "0.000100" or a
// 300-digit expansion of a limit.
#pragma once

#include <cstdio>
#include <string>

namespace vdbclay {

inline std::string formatNumber(double value)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return buf;
}

} // namespace vdbclay
