#include "desktop/DesktopSettings.h"

#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/StrictJson.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vdbclay {

std::string defaultConfigFolder()
{
    if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg && *xdg) return (std::filesystem::path(xdg) / "vdbclay").string();
    if (const char* home = std::getenv("HOME"); home && *home) return (std::filesystem::path(home) / ".config" / "vdbclay").string();
    return {};
}

DesktopSettings loadDesktopSettings(const std::string& folder, std::string* warning)
{
    DesktopSettings s;
    if (folder.empty()) return s;
    const std::string path = (std::filesystem::path(folder) / "settings.json").string();
    std::ifstream in(path);
    if (!in) return s;
    try {
        std::stringstream text;
        text << in.rdbuf();
        const nlohmann::json j = parseStrictJson(text.str(), "'" + path + "'");
        if (!j.is_object()) throw std::invalid_argument("not an object");
        DesktopSettings read;
        if (j.contains("brush")) read.brush = parseBrushSettings(j.at("brush"));
        if (j.contains("window")) {
            const auto w = j.at("window").get<std::array<int, 2>>();
            if (w[0] < 200 || w[1] < 150 || w[0] > render::kMaxViewportSide || w[1] > render::kMaxViewportSide)
                throw std::invalid_argument("window: a size from 200 x 150 to 8192 x 8192");
            read.windowSize = w;
        }
        read.showStats = j.value("stats", read.showStats);
        read.showHelp = j.value("help", read.showHelp);
        if (j.contains("look")) read.look = render::parseViewMode(j.at("look").get<std::string>());
        read.wireframe = j.value("wireframe", read.wireframe);
        read.stabilizerPixels = j.value("stabilizer", read.stabilizerPixels);
        if (!(read.stabilizerPixels >= 0.0 && read.stabilizerPixels <= 1000.0)) throw std::invalid_argument("stabilizer: 0 to 1000 pixels");
        s = read;
    } catch (const std::exception& e) {
        if (warning) *warning = "the settings in '" + path + "' were not used (" + e.what() + "); the defaults are";
    }
    return s;
}

void saveDesktopSettings(const DesktopSettings& s, const std::string& folder)
{
    if (folder.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) throw FileWriteError("cannot make the config folder '" + folder + "': " + ec.message());
    nlohmann::json j = {{"window", s.windowSize}, {"stats", s.showStats}, {"help", s.showHelp},
                        {"look", render::viewModeName(s.look)}, {"wireframe", s.wireframe},
                        {"stabilizer", s.stabilizerPixels}};
    if (s.brush) j["brush"] = brushSettingsJson(*s.brush);
    const std::string text = j.dump(2) + "\n";
    writeFileAtomically((std::filesystem::path(folder) / "settings.json").string(), [&](std::ostream& o) { o << text; });
}

} // namespace vdbclay
