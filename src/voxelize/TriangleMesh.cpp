#include "voxelize/TriangleMesh.h"

#include "vdb_hermite/FileExtension.h"
#include "vdb_hermite/FileStatus.h"
#include "vdb_hermite/PrintableText.h"
#include "voxelize/AssimpMeshReader.h"

#include <fcntl.h>
#include <spawn.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <optional>
#include <type_traits>

namespace vdbclay {

namespace {

using Clock = std::chrono::steady_clock;

/// The child's answer on the pipe: a tag, then either the soup's parts (counts first, so the parent can
/// size its vectors) or the one-line reason Assimp gave for refusing the file.
enum class Answer : uint8_t { Soup = 1, Refused = 2 };

class PipeWriter {
public:
    explicit PipeWriter(int fd) : fd_(fd) {}
    void bytes(const void* data, std::size_t size)
    {
        const char* p = static_cast<const char*>(data);
        while (size > 0) {
            const ssize_t n = ::write(fd_, p, size);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) ::_exit(3); // the parent has gone or given up
            p += n, size -= std::size_t(n);
        }
    }
    template<typename T> void value(const T& v)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes(&v, sizeof v);
    }
    template<typename T> void vector(const std::vector<T>& v)
    {
        value(uint64_t(v.size()));
        bytes(v.data(), v.size() * sizeof(T));
    }
    void text(const std::string& s)
    {
        value(uint64_t(s.size()));
        bytes(s.data(), s.size());
    }

private:
    int fd_;
};

/// Reads what the child writes, giving up at a deadline (a parser in an endless loop).
class PipeReader {
public:
    PipeReader(int fd, Clock::time_point deadline) : fd_(fd), deadline_(deadline) {}
    void bytes(void* data, std::size_t size)
    {
        char* p = static_cast<char*>(data);
        while (size > 0) {
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - Clock::now()).count();
            if (left <= 0) throw Timeout{};
            pollfd waiting{fd_, POLLIN, 0};
            const int ready = ::poll(&waiting, 1, int(std::min<long long>(left, 1000)));
            if (ready < 0 && errno != EINTR) throw Ended{};
            if (ready <= 0) continue;
            const ssize_t n = ::read(fd_, p, size);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) throw Ended{};
            p += n, size -= std::size_t(n);
        }
    }
    template<typename T> T value()
    {
        T v{};
        bytes(&v, sizeof v);
        return v;
    }
    template<typename T> void vector(std::vector<T>& v, uint64_t maxCount)
    {
        const uint64_t count = value<uint64_t>();
        if (count > maxCount) throw Ended{};
        v.resize(std::size_t(count));
        bytes(v.data(), v.size() * sizeof(T));
    }
    std::string text()
    {
        std::string s(std::size_t(std::min<uint64_t>(value<uint64_t>(), 4096)), '\0');
        bytes(s.data(), s.size());
        return s;
    }

    struct Timeout {};
    struct Ended {}; // the child stopped writing early: it crashed

private:
    int fd_;
    Clock::time_point deadline_;
};

void sendSoup(PipeWriter& out, const TriangleSoup& soup)
{
    out.value(Answer::Soup);
    out.vector(soup.positions);
    out.vector(soup.triangles);
    out.vector(soup.triangleMaterials);
    out.value(uint64_t(soup.materials.size()));
    for (const MeshMaterial& m : soup.materials) {
        out.text(m.name);
        out.value(m.color);
    }
    out.value(soup.droppedTriangles);
    out.value(uint64_t(soup.colourMaterials));
    out.value(uint8_t(soup.colourBinned));
}

TriangleSoup receiveSoup(PipeReader& in)
{
    constexpr uint64_t kMaxItems = uint64_t(1) << 36; // far beyond memory: only a garbled stream reaches it
    TriangleSoup soup;
    in.vector(soup.positions, kMaxItems);
    in.vector(soup.triangles, kMaxItems);
    in.vector(soup.triangleMaterials, kMaxItems);
    soup.materials.resize(std::size_t(std::min<uint64_t>(in.value<uint64_t>(), kMaxItems)));
    for (MeshMaterial& m : soup.materials) {
        m.name = in.text();
        m.color = in.value<std::array<float, 4>>();
    }
    soup.droppedTriangles = in.value<uint64_t>();
    soup.colourMaterials = std::size_t(in.value<uint64_t>());
    soup.colourBinned = in.value<uint8_t>() != 0;
    // The voxelizer indexes with these: a stream that does not add up is refused like a crash.
    bool consistent = soup.triangleMaterials.size() == soup.triangles.size();
    for (std::size_t t = 0; consistent && t < soup.triangles.size(); ++t)
        consistent = soup.triangleMaterials[t] < soup.materials.size() &&
                     std::all_of(soup.triangles[t].begin(), soup.triangles[t].end(), [&](uint32_t v) { return v < soup.positions.size(); });
    if (!consistent) throw PipeReader::Ended{};
    return soup;
}

/// Caps the child's address space at what it maps now (all it shares with the parent) plus `bytes`, so
/// that an allocation past it fails with std::bad_alloc instead of swapping the machine to a halt.
void capAddressSpace(uint64_t bytes)
{
    if (!meshReadMemoryIsCapped()) return;
    unsigned long long pages = 0;
    if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(statm, "%llu", &pages) != 1) pages = 0;
        std::fclose(statm);
    }
    if (pages == 0) return;
    const rlim_t cap = rlim_t(pages) * rlim_t(::sysconf(_SC_PAGESIZE)) + rlim_t(bytes);
    const struct rlimit limit{cap, cap};
    ::setrlimit(RLIMIT_AS, &limit);
}

std::string mebibytes(uint64_t bytes)
{
    return std::to_string(bytes >> 20) + " MiB";
}

} // namespace

bool isMeshPath(const std::string& path)
{
    const std::string ext = lowerCaseExtension(path);
    for (const char* known : {".obj", ".ply", ".stl", ".off", ".gltf", ".glb", ".fbx", ".dae"})
        if (ext == known) return true;
    return false;
}

bool meshReadMemoryIsCapped()
{
#if defined(__SANITIZE_ADDRESS__)
    return false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return false;
#endif
#endif
    return true;
}

MeshReadLimits meshReadLimits(const std::string& path)
{
    std::error_code ec;
    const uint64_t bytes = std::filesystem::file_size(path, ec);
    MeshReadLimits limits;
    if (!ec) {
        limits.time += std::chrono::seconds(bytes >> 20);
        limits.memoryBytes = std::max(limits.memoryBytes, bytes * 64);
    }
    return limits;
}

TriangleSoup loadTriangleMesh(const std::string& path)
{
    return loadTriangleMesh(path, meshReadLimits(path));
}

namespace {

/// The reader's side (a child process): caps its memory, reads, and answers on `fd`.
void answerOnPipe(int fd, const std::string& path, const std::function<TriangleSoup()>& read, uint64_t memoryBytes)
{
    PipeWriter out(fd);
    capAddressSpace(memoryBytes);
    try {
        const TriangleSoup soup = read();
        sendSoup(out, soup);
    } catch (const std::bad_alloc&) {
        out.value(Answer::Refused);
        out.text("reading '" + printableText(path, 200) + "' needed more than the " + mebibytes(memoryBytes) +
                 " it may take: the counts in the file are damaged, or the mesh is too large to import");
    } catch (const std::exception& e) {
        out.value(Answer::Refused);
        out.text(printableText(e.what(), 400)); // short: the parent reads it whole before reaping
    }
}

/// The parent's side: the child's answer on `fd` within the time limit, the child reaped either way.
TriangleSoup receiveFromChild(pid_t child, int fd, const std::string& path, const MeshReadLimits& limits)
{
    PipeReader in(fd, Clock::now() + limits.time);
    auto reap = [&](bool kill) {
        if (kill) ::kill(child, SIGKILL);
        int status = 0;
        while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
        }
        ::close(fd);
        return status;
    };
    try {
        const Answer answer = in.value<Answer>();
        if (answer == Answer::Refused) {
            const std::string reason = in.text();
            reap(true);
            throw MeshImportError(reason);
        }
        if (answer != Answer::Soup) throw PipeReader::Ended{};
        TriangleSoup soup = receiveSoup(in);
        reap(false);
        return soup;
    } catch (const PipeReader::Timeout&) {
        reap(true);
        throw MeshImportError("reading '" + path + "' took over " + std::to_string(limits.time.count()) +
                              " s and was stopped: the file is damaged or its reader cannot parse it");
    } catch (const PipeReader::Ended&) {
        const int status = reap(true); // a garbled stream may come from a child still writing: it must not block us
        throw MeshImportError("reading '" + path + "' failed (" +
                              (WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status)) : "exit " + std::to_string(WEXITSTATUS(status))) +
                              "): the file is damaged or in a form its reader cannot read");
    }
}

/// The reader program: VDBCLAY_MESH_READER, else vdbclay-read-mesh beside this executable; none when
/// neither is there to run, or when VDBCLAY_MESH_READER is "fork".
std::optional<std::string> meshReaderProgram()
{
    if (const char* given = std::getenv("VDBCLAY_MESH_READER"); given && *given)
        return std::string(given) != "fork" && ::access(given, X_OK) == 0 ? std::optional<std::string>(given) : std::nullopt;
    std::error_code ec;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec) return std::nullopt;
    const std::string beside = (self.parent_path() / kMeshReaderProgram).string();
    return ::access(beside.c_str(), X_OK) == 0 ? std::optional<std::string>(beside) : std::nullopt;
}

/// Runs the reader program on `path` (posix_spawn: no copy of this process, its threads or their locks).
TriangleSoup readWithProgram(const std::string& program, const std::string& path, const MeshReadLimits& limits)
{
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw MeshImportError("cannot read '" + path + "': " + std::strerror(errno));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1); // the answer goes to the reader's stdout
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    const std::string memory = std::to_string(limits.memoryBytes);
    std::vector<char*> argv{const_cast<char*>(program.c_str()), const_cast<char*>(path.c_str()), const_cast<char*>(memory.c_str()), nullptr};
    pid_t child = 0;
    const int spawned = ::posix_spawn(&child, program.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    if (spawned != 0) {
        ::close(fds[0]);
        throw MeshImportError("cannot read '" + path + "': cannot run " + program + ": " + std::strerror(spawned));
    }
    return receiveFromChild(child, fds[0], path, limits);
}

} // namespace

TriangleSoup loadTriangleMesh(const std::string& path, const MeshReadLimits& limits)
{
    std::error_code ec;
    if (const auto why = unreachableFile(path)) throw MeshImportError(*why);
    if (!std::filesystem::is_regular_file(path, ec)) throw MeshImportError("'" + path + "' is not a regular file");
    // Assimp runs in a child process: a crash or an endless loop on a damaged file (Debian's 5.2 has
    // both, on truncated PLY files) costs the child, and the user gets one line instead of losing the
    // session. The child is a program of its own where it is installed: a fork of a process whose
    // threads (TBB's, the renderer's) may hold a lock at that moment can leave the copy waiting forever.
    if (const auto program = meshReaderProgram()) return readWithProgram(*program, path, limits);
    return readInChildProcess(path, [&] { return readMeshWithAssimp(path); }, limits);
}

TriangleSoup readInChildProcess(const std::string& path, const std::function<TriangleSoup()>& read, const MeshReadLimits& limits)
{
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw MeshImportError("cannot read '" + path + "': " + std::strerror(errno));
    const pid_t child = ::fork();
    if (child < 0) {
        ::close(fds[0]), ::close(fds[1]);
        throw MeshImportError("cannot read '" + path + "': " + std::strerror(errno));
    }
    if (child == 0) {
        ::close(fds[0]);
        // A crash is the child's own: the parent's handlers (a test framework's, a crash reporter's)
        // must not run here as if the parent had crashed.
        for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGPIPE}) ::signal(sig, SIG_DFL);
        answerOnPipe(fds[1], path, read, limits.memoryBytes);
        ::_exit(0); // no atexit handlers or static destructors: they belong to the parent
    }
    ::close(fds[1]);
    return receiveFromChild(child, fds[0], path, limits);
}

int meshReaderMain(int argc, char** argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "%s: reads a mesh file for vdbclay and answers on stdout (usage: %s PATH MEMORY_BYTES)\n", argv[0], argv[0]);
        return 2;
    }
    const std::string path = argv[1];
    const uint64_t memoryBytes = std::strtoull(argv[2], nullptr, 10);
    ::signal(SIGPIPE, SIG_DFL);
    answerOnPipe(1, path, [&] { return readMeshWithAssimp(path); }, memoryBytes);
    std::fflush(stderr);
    ::_exit(0); // as the forked reader: no static destructors or leak report after the answer
}

} // namespace vdbclay
