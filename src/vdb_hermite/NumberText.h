// Numbers as text: as they appear in a message to the user ("0.5", "24", "2.2e+14", never "0.000100" or
// a 300-digit expansion of a limit), and read strictly from a file's metadata.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

namespace vdbclay {

/// A finite decimal number written in full ("0.5", "-2e-3"), else nothing: no hexadecimal ("0x10"),
/// no "inf" or "nan", no spaces or trailing text (std::stod takes all of these).
inline std::optional<double> parseDecimal(const std::string& text)
{
    if (text.empty() || text.size() > 64 || text.find_first_not_of("0123456789.eE+-") != std::string::npos) return std::nullopt;
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
}

inline std::string formatNumber(double value)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return buf;
}

} // namespace vdbclay
