// Why a file a command reads cannot be reached, in the user's terms: missing, a loop of symbolic links,
// a folder on its path that may not be entered (std::filesystem says "does not exist" for all three).
#pragma once

#include <sys/stat.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>

namespace vdbclay {

/// Nothing when `path` names a file that stat() reaches (of any kind); else one line naming the path.
inline std::optional<std::string> unreachableFile(const std::string& path)
{
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) return std::nullopt;
    const int err = errno;
    if (err == ENOENT) return "'" + path + "' does not exist";
    if (err == ELOOP) return "'" + path + "' is a loop of symbolic links";
    if (err == ENOTDIR) return "'" + path + "' does not exist (a part of its path is not a folder)";
    return "cannot reach '" + path + "': " + std::strerror(err);
}

/// Nothing when `path` names a regular file of at most `maxBytes`; else one line saying why it cannot be
/// read as one (a FIFO or a device would be read forever, or without end).
inline std::optional<std::string> unreadableAsFile(const std::string& path, uint64_t maxBytes)
{
    if (auto why = unreachableFile(path)) return why;
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return "'" + path + "' is not a regular file (a folder, device, FIFO or socket)";
    if (uint64_t(st.st_size) > maxBytes)
        return "'" + path + "' is " + std::to_string(uint64_t(st.st_size)) + " bytes, more than the " + std::to_string(maxBytes) + " allowed";
    return std::nullopt;
}

} // namespace vdbclay
