// Text from an untrusted file (a material or grid name, a parser's quote of a script or camera path) as
// it may reach a terminal: valid UTF-8 of printable characters stays as it is; control characters (ESC,
// BEL, newlines, C1 controls, OpenVDB's 0x1e separator) and bytes that are not UTF-8 appear as \xNN, so
// that a crafted file can neither retitle the terminal nor forge output lines. Cut at a length.
#pragma once

#include <cstddef>
#include <string>

namespace vdbclay {

namespace printable_detail {

/// The length of the valid UTF-8 sequence of a printable character at `s[i]`, 0 when there is none.
inline std::size_t printableSequence(const std::string& s, std::size_t i)
{
    const auto byte = [&](std::size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
    const unsigned c = byte(i);
    if (c >= 0x20 && c < 0x7f) return 1;
    std::size_t n = 0;
    unsigned cp = 0;
    if (c >= 0xc2 && c <= 0xdf) n = 2, cp = c & 0x1f;
    else if (c >= 0xe0 && c <= 0xef) n = 3, cp = c & 0x0f;
    else if (c >= 0xf0 && c <= 0xf4) n = 4, cp = c & 0x07;
    else return 0;
    for (std::size_t k = 1; k < n; ++k) {
        const unsigned t = byte(i + k);
        if ((t & 0xc0) != 0x80) return 0;
        cp = (cp << 6) | (t & 0x3f);
    }
    const bool overlong = (n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000);
    const bool invalid = cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff);
    const bool control = cp >= 0x80 && cp < 0xa0;
    return overlong || invalid || control ? 0 : n;
}

} // namespace printable_detail

inline std::string printableText(const std::string& text, std::size_t maxLength = 400)
{
    static const char kHex[] = "0123456789abcdef";
    std::string out;
    std::size_t i = 0;
    for (; i < text.size() && i < maxLength;) {
        if (const std::size_t n = printable_detail::printableSequence(text, i)) {
            out.append(text, i, n);
            i += n;
            continue;
        }
        const auto c = static_cast<unsigned char>(text[i++]);
        out += "\\x";
        out += kHex[c >> 4];
        out += kHex[c & 15];
    }
    return i < text.size() ? out + "..." : out;
}

/// Whether a name may be given to something users see (a material): printable UTF-8, no control
/// characters, at most `maxLength` bytes.
inline bool isPrintableName(const std::string& name, std::size_t maxLength = 256)
{
    if (name.size() > maxLength) return false;
    for (std::size_t i = 0; i < name.size();) {
        const std::size_t n = printable_detail::printableSequence(name, i);
        if (n == 0) return false;
        i += n;
    }
    return true;
}

} // namespace vdbclay
