// What work may take of this machine's memory, stated before the work: a 745-byte file or a short
// command line can ask for more than the machine has, and the user should learn it in one line at
// once, not from the kernel minutes later.
#pragma once

#include "vdb_hermite/NumberText.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace vdbclay {

/// Work that would need more memory than this process may use.
class MemoryLimitError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The memory this process may use: the machine's physical memory, or less where an address-space or
/// data limit (ulimit -v, -d) is set.
inline uint64_t usableMemoryBytes()
{
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
    uint64_t bytes = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : uint64_t(1) << 34;
    for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
        struct rlimit limit {};
        if (::getrlimit(resource, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) bytes = std::min<uint64_t>(bytes, limit.rlim_cur);
    }
    return bytes;
}

/// Throws MemoryLimitError when `bytes` exceed 80 % of `usable` (default usableMemoryBytes()): "WHAT
/// needs about X GB; this process may use Y GB: ADVICE".
inline void requireMemory(double bytes, const std::string& what, const std::string& advice, double usable = 0.0)
{
    if (!(usable > 0.0)) usable = double(usableMemoryBytes());
    if (bytes <= 0.8 * usable) return;
    const auto gb = [](double b) { return formatNumber(double(int64_t(b / 1e8)) / 10.0) + " GB"; };
    throw MemoryLimitError(what + " needs about " + gb(bytes) + " of memory; this process may use " + gb(usable) + ": " + advice);
}

} // namespace vdbclay
