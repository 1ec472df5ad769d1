// Small helpers shared by the test files: temporary directories, file bytes, analytic volumes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay::test {

/// The `vdbclay` binary of this build, or "" when the build has none (tests/CMakeLists.txt).
#ifdef VDBCLAY_CLI
constexpr const char* kCli = VDBCLAY_CLI;
#else
constexpr const char* kCli = "";
#endif

constexpr double kPi = 3.14159265358979323846;

/// A fresh directory under $TMPDIR, removed with everything in it when the object goes away.
class TempDir {
public:
    TempDir()
    {
        std::string pattern = (std::filesystem::temp_directory_path() / "vdbclay-tests-XXXXXX").string();
        std::vector<char> buf(pattern.begin(), pattern.end());
        buf.push_back('\0');
        if (!::mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
        path_ = buf.data();
    }
    ~TempDir()
    {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::filesystem::path& path() const { return path_; }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    /// Names of the entries in the directory, sorted.
    std::vector<std::string> entries() const
    {
        std::vector<std::string> out;
        for (const auto& e : std::filesystem::directory_iterator(path_)) out.push_back(e.path().filename().string());
        std::sort(out.begin(), out.end());
        return out;
    }

private:
    std::filesystem::path path_;
};

inline std::vector<char> readBytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open " + path);
    return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void writeBytes(const std::string& path, const char* data, std::size_t size)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(data, std::streamsize(size));
    if (!out) throw std::runtime_error("cannot write " + path);
}

inline void writeText(const std::string& path, const std::string& text) { writeBytes(path, text.data(), text.size()); }

/// Deterministic junk: `size` pseudo-random bytes from `seed`.
inline std::vector<char> randomBytes(std::size_t size, uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::vector<char> bytes(size);
    for (char& c : bytes) c = char(rng() & 0xff);
    return bytes;
}

inline double sphereVolume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }
/// Volume of the cap of height h cut from a ball of radius r.
inline double sphereCapVolume(double r, double h) { return kPi * h * h * (3.0 * r - h) / 3.0; }

} // namespace vdbclay::test
