#include "Cli.h"

#include "sculpt/StrokeScript.h"
#include "voxelize/TriangleMesh.h"
#include "vdb_hermite/PrintableText.h"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <memory>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>

namespace vdbclay::cli {

void printError(const std::string& message)
{
    // One line: fold any embedded newlines (OpenVDB and JSON messages sometimes carry them).
    std::string line = message;
    std::replace(line.begin(), line.end(), '\n', ' ');
    std::cerr << "vdbclay: error: " << printableText(line, std::string::npos) << std::endl;
}

void printJson(const nlohmann::json& object)
{
    // Invalid UTF-8 in a user-supplied name must not throw here: replace it.
    std::cout << object.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
}

void printFields(const std::vector<std::pair<std::string, std::string>>& fields, std::size_t indent)
{
    // Values often quote a file's names: they reach the terminal only in printable form.
    std::vector<std::pair<std::string, std::string>> shown;
    std::size_t width = 0;
    for (const auto& f : fields) {
        shown.emplace_back(printableText(f.first, std::string::npos), printableText(f.second, std::string::npos));
        width = std::max(width, shown.back().first.size());
    }
    for (const auto& f : shown) {
        std::cout << std::string(indent, ' ') << f.first << ':' << std::string(width - f.first.size() + 1, ' ')
                  << f.second << '\n';
    }
    std::cout.flush();
}

nlohmann::json opReportJson(const ScriptOpReport& report)
{
    return {{"index", report.index},
            {"mode", report.modeName},
            {"blocks", report.stats.blocksComputed},
            {"seconds", report.seconds}};
}

std::string formatSeconds(double seconds)
{
    char buf[64];
    if (seconds < 1e-3) std::snprintf(buf, sizeof buf, "%.3f ms", seconds * 1e3);
    else if (seconds < 1.0) std::snprintf(buf, sizeof buf, "%.1f ms", seconds * 1e3);
    else std::snprintf(buf, sizeof buf, "%.2f s", seconds);
    return buf;
}

std::string formatBytes(double bytes)
{
    char buf[64];
    if (bytes < 1024.0) std::snprintf(buf, sizeof buf, "%.0f B", bytes);
    else if (bytes < 1024.0 * 1024.0) std::snprintf(buf, sizeof buf, "%.1f KiB", bytes / 1024.0);
    else if (bytes < 1024.0 * 1024.0 * 1024.0) std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / (1024.0 * 1024.0));
    else std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / (1024.0 * 1024.0 * 1024.0));
    return buf;
}

void requireSceneExtension(const std::string& path)
{
    const std::string ext = lowerCaseExtension(path);
    if (ext != ".vdb" && ext != ".vdbclay")
        throw UsageError("'" + path + "': the output's extension picks its form; end it in .vdb (native volume) or .vdbclay (store)");
}

namespace {

/// A check that the option's text is one finite number that `accept` takes, else "must be `wanted`".
CLI::Validator numberCheck(bool (*accept)(double), const std::string& wanted, const std::string& name)
{
    return CLI::Validator(
        [accept, wanted](const std::string& text) {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            const bool parsed = !text.empty() && end == text.c_str() + text.size();
            return parsed && std::isfinite(value) && accept(value) ? std::string() : "must be " + wanted + ", not " + text;
        },
        name);
}

} // namespace

const CLI::Validator& positiveNumber()
{
    static const CLI::Validator check = numberCheck([](double v) { return v > 0.0; }, "a positive number", "POSITIVE");
    return check;
}

const CLI::Validator& nonNegativeNumber()
{
    static const CLI::Validator check =
        numberCheck([](double v) { return v >= 0.0; }, "zero or a positive number", "NON-NEGATIVE");
    return check;
}

const CLI::Validator& memoryBudget()
{
    // Beyond a petabyte the budget is no limit at all, and its bytes (MB x 2^20) leave 64 bits.
    static const CLI::Validator check =
        numberCheck([](double v) { return v > 0.0 && v <= 1e9; }, "a number of MB above 0 and at most 1e9 (a petabyte)", "MB");
    return check;
}

const CLI::Validator& finiteNumber()
{
    static const CLI::Validator check = numberCheck([](double) { return true; }, "a finite number", "");
    return check;
}

const CLI::Validator& unsignedInteger()
{
    static const CLI::Validator check(
        [](const std::string& text) {
            const bool digits = !text.empty() && text.size() <= 20 &&
                                std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
            // 20 digits may still exceed 2^64 - 1: compare as text, both padded to 20 digits.
            const bool fits = digits && (text.size() < 20 || text <= "18446744073709551615");
            return fits ? std::string() : "must be a whole number from 0 to 18446744073709551615, not " + text;
        },
        ""); // the option's own type name (UINT) says it
    return check;
}

const CLI::Validator& sceneInput()
{
    static const CLI::Validator check(
        [](const std::string& path) {
            return isMeshPath(path) ? "'" + path + "' is a mesh, not a scene: bring it in first with 'vdbclay import " + path +
                                          " -o SCENE.vdb --resolution N'"
                                    : std::string();
        },
        "");
    return check;
}

std::function<void(uint64_t, uint64_t)> terminalProgress(const std::string& label, bool enabled)
{
    if (!enabled || !::isatty(STDERR_FILENO)) return [](uint64_t, uint64_t) {};
    auto last = std::make_shared<int>(-1);
    return [label, last](uint64_t done, uint64_t total) {
        const int percent = total == 0 ? 100 : int(std::min<uint64_t>(100, done * 100 / total));
        if (percent == *last) return;
        *last = percent;
        constexpr int kWidth = 30;
        const int filled = percent * kWidth / 100;
        std::cerr << '\r' << label << " [" << std::string(std::size_t(filled), '=') << std::string(std::size_t(kWidth - filled), ' ')
                  << "] " << percent << '%' << (percent == 100 ? "\n" : "") << std::flush;
    };
}

void addThreadsOption(CLI::App& command, int& threads)
{
    command.add_option("--threads", threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 4096).description(""))
        ->type_name("N");
}

} // namespace vdbclay::cli
