// Text from an untrusted file (a name in a crafted .vdb, a parser's quote of a script) as it may appear
// in a one-line error message: printable ASCII only, other bytes as '?', cut at a length.
#pragma once

#include <cstddef>
#include <string>

namespace vdbclay {

inline std::string printableText(const std::string& text, std::size_t maxLength = 400)
{
    std::string out;
    for (char c : text.substr(0, maxLength)) out += (c >= 32 && c < 127) ? c : '?';
    return text.size() > maxLength ? out + "..." : out;
}

} // namespace vdbclay
