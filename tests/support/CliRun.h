// Running the vdbclay binary from tests: its exit code, stdout and stderr.
#pragma once

#include "support/TestUtil.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <sys/wait.h>

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
