// Saves that respect the file system: links are followed, what is not a writable regular file is
// refused, modes carry over, stale temporary files of killed saves are cleaned up, and the same volume
// always saves to the same bytes.
#include "support/Sculpt.h"
#include "support/TestUtil.h"
#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/VolumeIO.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace vdbclay;
using namespace vdbclay::test;
namespace fs = std::filesystem;

namespace {

Volume ball(double radius)
{
    Volume v(1.0);
    apply(v, CsgMode::Add, sphere(radius), at({0.25, 0.0, 0.5}), 1);
    return v;
}

mode_t modeOf(const std::string& path)
{
    struct stat st;
    REQUIRE(::stat(path.c_str(), &st) == 0);
    return st.st_mode & 07777;
}

/// A PID that belonged to a process which has ended (a child that exited and was reaped).
pid_t deadPid()
{
    const pid_t child = ::fork();
    if (child == 0) ::_exit(0);
    int status = 0;
    ::waitpid(child, &status, 0);
    return child;
}

} // namespace

TEST_CASE("the same volume saves to the same bytes, another volume does not", "[io][saves]")
{
    TempDir dir;
    saveVolume(ball(6.0), dir.file("a.vdb"));
    saveVolume(ball(6.0), dir.file("b.vdb"));
    saveVolume(ball(7.0), dir.file("c.vdb"));
    const auto a = readBytes(dir.file("a.vdb")), b = readBytes(dir.file("b.vdb")), c = readBytes(dir.file("c.vdb"));
    CHECK((a == b));
    CHECK_FALSE((a == c));
    // The header's UUID (offset 21) is derived from the content, so it differs between the volumes.
    CHECK_FALSE(std::equal(a.begin() + 21, a.begin() + 57, c.begin() + 21));
    CHECK(identical(loadVolume(dir.file("a.vdb")), ball(6.0)));
}

TEST_CASE("a save through a symbolic link replaces the link's target and keeps the link", "[io][saves]")
{
    TempDir dir;
    saveVolume(ball(5.0), dir.file("real.vdb"));
    fs::create_symlink("real.vdb", dir.file("link.vdb"));
    fs::create_directory(dir.path() / "sub");
    fs::create_symlink("../link.vdb", dir.file("sub/chain.vdb")); // a link to a link, relative to its folder
    saveVolume(ball(8.0), dir.file("sub/chain.vdb"));
    CHECK(fs::is_symlink(dir.file("link.vdb")));
    CHECK(fs::is_symlink(dir.file("sub/chain.vdb")));
    CHECK(identical(loadVolume(dir.file("real.vdb")), ball(8.0)));
    // A dangling link gets its target created.
    fs::create_symlink("new.vdb", dir.file("dangling.vdb"));
    saveVolume(ball(4.0), dir.file("dangling.vdb"));
    CHECK(fs::is_symlink(dir.file("dangling.vdb")));
    CHECK(identical(loadVolume(dir.file("new.vdb")), ball(4.0)));
    // A loop of links is refused.
    fs::create_symlink("loop2.vdb", dir.file("loop1.vdb"));
    fs::create_symlink("loop1.vdb", dir.file("loop2.vdb"));
    CHECK_THROWS_WITH(saveVolume(ball(4.0), dir.file("loop1.vdb")), Catch::Contains("loop of symbolic links"));
}

TEST_CASE("saves refuse FIFOs, directories and read-only files, and leave them as they were", "[io][saves]")
{
    TempDir dir;
    REQUIRE(::mkfifo(dir.file("pipe.vdb").c_str(), 0644) == 0);
    CHECK_THROWS_WITH(saveVolume(ball(5.0), dir.file("pipe.vdb")), Catch::Contains("not a regular file"));
    CHECK(fs::is_fifo(dir.file("pipe.vdb")));

    saveVolume(ball(5.0), dir.file("frozen.vdb"));
    const auto before = readBytes(dir.file("frozen.vdb"));
    REQUIRE(::chmod(dir.file("frozen.vdb").c_str(), 0444) == 0);
    CHECK_THROWS_WITH(saveVolume(ball(9.0), dir.file("frozen.vdb")), Catch::Contains("read-only"));
    CHECK((readBytes(dir.file("frozen.vdb")) == before));
    CHECK(modeOf(dir.file("frozen.vdb")) == 0444);

    fs::create_directory(dir.path() / "folder.vdb");
    CHECK_THROWS_WITH(saveVolume(ball(5.0), dir.file("folder.vdb")), Catch::Contains("is a directory"));
    // Nothing else appeared: no temporary files either.
    CHECK(dir.entries() == std::vector<std::string>{"folder.vdb", "frozen.vdb", "pipe.vdb"});
}

TEST_CASE("a save keeps the mode of the file it replaces", "[io][saves]")
{
    TempDir dir;
    for (mode_t mode : {mode_t(0640), mode_t(0600), mode_t(0664), mode_t(0755)}) {
        const std::string path = dir.file("private.vdb");
        saveVolume(ball(5.0), path);
        REQUIRE(::chmod(path.c_str(), mode) == 0);
        saveVolume(ball(6.0), path);
        CHECK(modeOf(path) == mode);
        CHECK(identical(loadVolume(path), ball(6.0)));
    }
}

TEST_CASE("a save removes the temporary files killed saves left, and no one else's", "[io][saves]")
{
    TempDir dir;
    const std::string path = dir.file("scene.vdb");
    saveVolume(ball(5.0), path);
    const std::string dead = ".scene.vdb.vdbclay-tmp-" + std::to_string(deadPid()) + "-123";
    const std::string alive = ".scene.vdb.vdbclay-tmp-" + std::to_string(::getpid()) + "-456"; // this process runs
    const std::string other = ".scene.vdb.tmp-1-1";                 // not our naming
    const std::string otherTarget = ".other.vdb.vdbclay-tmp-" + std::to_string(deadPid()) + "-1"; // another file's
    for (const std::string& name : {dead, alive, other, otherTarget}) {
        std::ofstream(dir.file(name)) << "partial";
    }
    saveVolume(ball(6.0), path);
    std::vector<std::string> expected{alive, other, otherTarget, "scene.vdb"};
    std::sort(expected.begin(), expected.end());
    CHECK(dir.entries() == expected);
}
