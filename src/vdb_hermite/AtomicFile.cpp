#include "vdb_hermite/AtomicFile.h"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sys/stat.h>
#include <unistd.h>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

void syncPath(const std::string& path, bool directory)
{
    const int fd = ::open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0) {
        if (directory) return; // some filesystems do not allow opening directories; the rename still stands
        throw FileWriteError("cannot reopen '" + path + "' to flush it: " + std::strerror(errno));
    }
    const int rc = ::fsync(fd);
    const int err = errno;
    ::close(fd);
    if (rc != 0 && !directory) throw FileWriteError("cannot flush '" + path + "' to disk: " + std::strerror(err));
}

/// The file a path names once its symbolic links are followed (the path itself when it is none); the
/// file need not exist yet. A save replaces the link's target and keeps the link.
fs::path followLinks(const std::string& path)
{
    fs::path p(path);
    for (int hops = 0; hops < 40; ++hops) {
        struct stat st;
        if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return p;
        std::error_code ec;
        const fs::path target = fs::read_symlink(p, ec);
        if (ec) throw FileWriteError("cannot follow the link '" + path + "': " + ec.message());
        p = target.is_absolute() ? target : p.parent_path() / target;
    }
    throw FileWriteError("'" + path + "' is a loop of symbolic links");
}

// Temporary files are ".NAME.vdbclay-tmp-PID-RANDOM" beside the target: the PID tells whether the
// process that made one is still alive, so a later save can remove what a killed one left.
const char* const kTempMarker = ".vdbclay-tmp-";

std::string tempPrefix(const fs::path& target) { return "." + target.filename().string() + kTempMarker; }

/// removeStaleTemporaries within `dir`: other users' files and files of live processes stay.
void removeStaleTemporariesIn(const fs::path& dir, const fs::path& target)
{
    const std::string prefix = tempPrefix(target);
    DIR* d = ::opendir(dir.c_str());
    if (!d) return;
    while (const dirent* entry = ::readdir(d)) {
        const std::string name = entry->d_name;
        if (name.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string rest = name.substr(prefix.size());
        const std::size_t dash = rest.find('-');
        if (dash == 0 || dash == std::string::npos || rest.find_first_not_of("0123456789") != dash) continue;
        const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
        if (pid <= 0 || (::kill(pid_t(pid), 0) == 0 || errno != ESRCH)) continue; // alive, or not ours to judge
        const fs::path stale = dir / name;
        struct stat st;
        if (::lstat(stale.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::geteuid()) continue;
        ::unlink(stale.c_str());
    }
    ::closedir(d);
}

// The temporary file of the save in progress, for the signal handler: it removes the file and lets the
// signal end the process as it would have. Plain storage, as a handler may touch nothing else.
char gTempPath[4096];
volatile std::sig_atomic_t gTempArmed = 0;
constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};

extern "C" void removeTempAndReraise(int sig)
{
    if (gTempArmed) ::unlink(gTempPath);
    std::signal(sig, SIG_DFL);
    std::raise(sig);
}

/// Removes the temporary file if a signal ends the process while it exists.
class TempFileGuard {
public:
    explicit TempFileGuard(const std::string& temp)
    {
        if (temp.size() >= sizeof(gTempPath)) return;
        std::memcpy(gTempPath, temp.c_str(), temp.size() + 1);
        struct sigaction action {};
        action.sa_handler = removeTempAndReraise;
        sigemptyset(&action.sa_mask);
        for (std::size_t i = 0; i < std::size(kCleanupSignals); ++i) ::sigaction(kCleanupSignals[i], &action, &previous_[i]);
        gTempArmed = 1;
        armed_ = true;
    }
    ~TempFileGuard()
    {
        if (!armed_) return;
        gTempArmed = 0;
        for (std::size_t i = 0; i < std::size(kCleanupSignals); ++i) ::sigaction(kCleanupSignals[i], &previous_[i], nullptr);
    }
    TempFileGuard(const TempFileGuard&) = delete;
    TempFileGuard& operator=(const TempFileGuard&) = delete;

private:
    struct sigaction previous_[std::size(kCleanupSignals)] {};
    bool armed_ = false;
};

/// Where a save of `path` lands (links followed) and, when it replaces a file, that file's status.
struct SaveTarget {
    fs::path target, dir;
    std::optional<struct stat> existing;
};

/// requireReplaceable's checks, keeping what they found for the save.
SaveTarget checkSaveTarget(const std::string& path)
{
    if (fs::path(path).filename().empty()) throw FileWriteError("'" + path + "' is not a file name");
    SaveTarget t;
    t.target = followLinks(path);
    t.dir = t.target.has_parent_path() ? t.target.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(t.dir, ec)) throw FileWriteError("directory '" + t.dir.string() + "' does not exist");
    // What is replaced must be a regular file we may write.
    struct stat existing {};
    if (::stat(t.target.c_str(), &existing) != 0) return t;
    if (S_ISDIR(existing.st_mode)) throw FileWriteError("'" + path + "' is a directory");
    if (!S_ISREG(existing.st_mode))
        throw FileWriteError("'" + path + "' is not a regular file (a device, FIFO or socket); refusing to replace it");
    if ((existing.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0 || ::access(t.target.c_str(), W_OK) != 0)
        throw FileWriteError("'" + path + "' is read-only; refusing to replace it");
    t.existing = existing;
    return t;
}

} // namespace

void syncFileToDisk(const std::string& path) { syncPath(path, false); }

std::string temporaryPathFor(const std::string& target)
{
    const fs::path t(target);
    std::random_device entropy;
    return (t.parent_path() / (tempPrefix(t) + std::to_string(::getpid()) + "-" + std::to_string(entropy() % 1000000000u))).string();
}

void removeStaleTemporaries(const std::string& target)
{
    const fs::path t(target);
    removeStaleTemporariesIn(t.has_parent_path() ? t.parent_path() : fs::path("."), t);
}

void requireReplaceable(const std::string& path) { (void)checkSaveTarget(path); }

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                         const std::function<void(const std::string&, uint64_t)>& finish)
{
    const SaveTarget checked = checkSaveTarget(path);
    const fs::path& target = checked.target;
    const fs::path& dir = checked.dir;
    std::error_code ec;
    removeStaleTemporariesIn(dir, target);
    const std::string temp = temporaryPathFor(target.string());
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666); // the umask applies
    if (fd < 0) throw FileWriteError("cannot create '" + temp + "': " + std::strerror(errno));
    TempFileGuard guard(temp);
    try {
        if (checked.existing) {
            // The replaced file's owner and mode carry over. Owner first: changing it can clear set-id
            // bits, which the mode then restores.
            if (::fchown(fd, checked.existing->st_uid, checked.existing->st_gid) != 0 && errno != EPERM)
                throw FileWriteError("cannot give '" + temp + "' the owner of '" + path + "': " + std::strerror(errno));
            if (::fchmod(fd, checked.existing->st_mode & 07777) != 0)
                throw FileWriteError("cannot give '" + temp + "' the mode of '" + path + "': " + std::strerror(errno));
        }
        ::close(fd);
        std::ofstream os(temp, std::ios::binary | std::ios::trunc);
        if (!os) throw FileWriteError("cannot open '" + temp + "': " + std::strerror(errno));
        write(os);
        os.flush();
        const std::streamoff written = os.tellp();
        os.close();
        if (!os || written < 0) throw FileWriteError("cannot write '" + path + "' (disk full?)");
        if (finish) finish(temp, uint64_t(written));
        syncFileToDisk(temp);
        fs::rename(temp, target, ec);
        if (ec) throw FileWriteError("cannot replace '" + path + "': " + ec.message());
    } catch (...) {
        ::unlink(temp.c_str());
        throw;
    }
    syncPath(dir.string(), true);
}

} // namespace vdbclay
