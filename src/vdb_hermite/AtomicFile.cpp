#include "vdb_hermite/AtomicFile.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
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

} // namespace

void syncFileToDisk(const std::string& path) { syncPath(path, false); }

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                         const std::function<void(const std::string&, uint64_t)>& finish)
{
    const fs::path target(path);
    std::error_code ec;
    if (target.filename().empty()) throw FileWriteError("'" + path + "' is not a file name");
    if (fs::is_directory(target, ec)) throw FileWriteError("'" + path + "' is a directory");
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(dir, ec)) throw FileWriteError("directory '" + dir.string() + "' does not exist");

    const std::string temp = (dir / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()))).string();
    try {
        std::ofstream os(temp, std::ios::binary | std::ios::trunc);
        if (!os) throw FileWriteError("cannot create '" + temp + "': " + std::strerror(errno));
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
        std::error_code removeError;
        fs::remove(temp, removeError);
        throw;
    }
    syncPath(dir.string(), true);
}

} // namespace vdbclay
