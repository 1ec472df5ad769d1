// Crash-safe file replacement, shared by every writer of user files (volumes, meshes, scripts).
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace vdbclay {

/// A file could not be written; the message names the file and the cause.
class FileWriteError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Flushes a written file to disk (fsync); throws FileWriteError when it cannot.
void syncFileToDisk(const std::string& path);

/// The checks writeFileAtomically makes before it writes: a file name in a directory that exists and,
/// where a file is replaced, a regular file that may be written. Throws FileWriteError. Commands call
/// it to refuse an unusable output before long work.
void requireReplaceable(const std::string& path);

/// A new temporary file name beside `target` (a file name, links already followed):
/// ".NAME.vdbclay-tmp-PID-RANDOM", whose PID lets a later save tell a killed writer's leftovers.
std::string temporaryPathFor(const std::string& target);

/// Removes this user's temporaries of `target` (with their SQLite -wal and -shm files) whose writing
/// process no longer runs: what a save or store import killed by SIGKILL or a crash left behind.
void removeStaleTemporaries(const std::string& target);

/// Replaces `path` so that a crash leaves either its old content or the complete new one: `write`
/// fills a temporary file beside it, `finish` (optional) may then append to that file by path, and
/// the file is flushed to disk, renamed over `path`, and the directory flushed. The temporary file is
/// removed on any failure. Throws FileWriteError for an unusable path or a failed write, flush or
/// rename; exceptions from `write` and `finish` pass through unchanged.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                         const std::function<void(const std::string& tempPath, uint64_t bytes)>& finish = {});

} // namespace vdbclay
