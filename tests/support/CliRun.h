// Running the vdbclay binary from tests: its exit code, stdout and stderr; or started and stopped at a
// chosen moment (the kill tests).
#pragma once

#include "support/TestUtil.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cerrno>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <optional>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace vdbclay::test {

struct CommandResult {
    int exitCode = -1;   // exit status; 128 + signal when the command was killed by a signal
    std::string out;
    std::string err;
};

inline std::string quote(const std::string& s)
{
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// Runs `PROGRAM ARGS` (the vdbclay binary by default) with `dir` as the working directory and
/// `environment` ("NAME=value ..." assignments, quoted as a shell reads them) set, capturing stdout and stderr.
inline CommandResult runCli(const TempDir& dir, const std::string& args, const std::string& environment = "",
                            const std::string& program = kCli)
{
    const std::string outPath = dir.file(".stdout"), errPath = dir.file(".stderr");
    const std::string command = "cd " + quote(dir.path().string()) + " && " + (environment.empty() ? "" : "env " + environment + " ") +
                                quote(program) + " " + args + " >" + quote(outPath) + " 2>" + quote(errPath);
    const int status = std::system(command.c_str());
    CommandResult r;
    if (status != -1 && WIFEXITED(status)) r.exitCode = WEXITSTATUS(status);
    else if (status != -1 && WIFSIGNALED(status)) r.exitCode = 128 + WTERMSIG(status);
    const auto out = readBytes(outPath), err = readBytes(errPath);
    r.out.assign(out.begin(), out.end());
    r.err.assign(err.begin(), err.end());
    std::filesystem::remove(outPath);
    std::filesystem::remove(errPath);
    return r;
}

/// Starts the vdbclay binary with `args` (no shell) in `workingDir` (empty: this process's), its stdout
/// and stderr to `output` (empty: /dev/null); returns its pid, for finishCli.
inline pid_t startCli(const std::vector<std::string>& args, const std::string& output = "", const std::string& workingDir = "")
{
    // Everything the child needs is made before the fork: a threaded process's child may only make the
    // calls a signal handler may (chdir, open, dup2, exec).
    std::vector<std::string> words{kCli};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    const std::string sink = output.empty() ? "/dev/null" : output;
    const pid_t pid = ::fork();
    if (pid == 0) {
        if (!workingDir.empty() && ::chdir(workingDir.c_str()) != 0) ::_exit(127);
        const int out = ::open(sink.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(out, 1), ::dup2(out, 2);
        ::execv(kCli, argv.data());
        ::_exit(127);
    }
    return pid;
}

/// Waits for a run startCli began, killing it (SIGKILL) after `killAfter` when one is given; returns
/// waitpid's status.
inline int finishCli(pid_t pid, std::optional<std::chrono::microseconds> killAfter = std::nullopt)
{
    if (killAfter) {
        std::this_thread::sleep_for(*killAfter);
        ::kill(pid, SIGKILL);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
}

/// The command failed cleanly: a small non-zero exit code (no signal) and one error line on stderr.
inline void checkCleanFailure(const CommandResult& r)
{
    INFO("exit " << r.exitCode << ", stderr: " << r.err);
    CHECK(r.exitCode > 0);
    CHECK(r.exitCode < 128);
    CHECK(r.err.find("vdbclay: error: ") != std::string::npos);
}

inline nlohmann::json parseJsonOutput(const CommandResult& r)
{
    INFO("stdout: " << r.out);
    INFO("stderr: " << r.err);
    REQUIRE(r.exitCode == 0);
    nlohmann::json j;
    REQUIRE_NOTHROW(j = nlohmann::json::parse(r.out));
    REQUIRE(j.is_object());
    return j;
}

} // namespace vdbclay::test
