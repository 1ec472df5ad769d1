// Why a file a command reads cannot be reached, in the user's terms: missing, a loop of symbolic links,
// a folder on its path that may not be entered (std::filesystem says "does not exist" for all three).
#pragma once

#include <sys/stat.h>

#include <cerrno>
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

} // namespace vdbclay
