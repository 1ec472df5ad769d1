// A file browser in Dear ImGui for open, save as, import and export: folders to walk, the files of the
// kinds the action takes, a name to type, and the whole path shown, so that a file lands where the user
// sees and never relative to wherever the editor was started.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace vdbclay {

struct FolderEntry {
    std::string name;
    bool folder = false;
};

/// What `folder` holds that a browser shows: its folders, then the files ending in one of `extensions`
/// (all files when empty; case-insensitive), each group sorted by name; hidden entries left out.
/// Throws std::filesystem::filesystem_error when the folder cannot be read.
std::vector<FolderEntry> browseFolder(const std::string& folder, const std::vector<std::string>& extensions);

class FileBrowser {
public:
    /// Shows the browser (a modal window titled `title`) from the next draw(), in `folder`, for files with
    /// one of `extensions`; `saving` asks for a name that may not exist yet.
    void open(const std::string& title, const std::string& folder, const std::vector<std::string>& extensions, bool saving,
              const std::string& name = "");
    /// Draws the browser while it is open (between ImGui::NewFrame and ImGui::Render); the absolute path
    /// chosen, once, when the user confirms.
    std::optional<std::string> draw();
    bool isOpen() const { return open_; }
    /// What the browser was opened for (its title), to route the chosen path.
    const std::string& title() const { return title_; }

private:
    void enter(const std::string& folder);

    bool open_ = false, opening_ = false, saving_ = false;
    std::string title_, folder_, name_, error_;
    std::vector<std::string> extensions_;
    std::vector<FolderEntry> entries_;
};

} // namespace vdbclay
