#include "panels/FileBrowser.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace vdbclay {

namespace fs = std::filesystem;

namespace {

std::string lowered(std::string s)
{
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

bool hasExtension(const std::string& name, const std::vector<std::string>& extensions)
{
    if (extensions.empty()) return true;
    const std::string lower = lowered(name);
    return std::any_of(extensions.begin(), extensions.end(), [&](const std::string& e) {
        const std::string ext = lowered(e);
        return lower.size() > ext.size() && lower.compare(lower.size() - ext.size(), ext.size(), ext) == 0;
    });
}

} // namespace

std::vector<FolderEntry> browseFolder(const std::string& folder, const std::vector<std::string>& extensions)
{
    std::vector<FolderEntry> folders, files;
    for (const fs::directory_entry& e : fs::directory_iterator(folder, fs::directory_options::skip_permission_denied)) {
        const std::string name = e.path().filename().string();
        if (name.empty() || name[0] == '.') continue;
        std::error_code ec;
        if (e.is_directory(ec)) folders.push_back({name, true});
        else if (hasExtension(name, extensions)) files.push_back({name, false});
    }
    const auto byName = [](const FolderEntry& a, const FolderEntry& b) { return a.name < b.name; };
    std::sort(folders.begin(), folders.end(), byName);
    std::sort(files.begin(), files.end(), byName);
    folders.insert(folders.end(), files.begin(), files.end());
    return folders;
}

void FileBrowser::open(const std::string& title, const std::string& folder, const std::vector<std::string>& extensions, bool saving,
                       const std::string& name)
{
    open_ = opening_ = true;
    saving_ = saving;
    title_ = title;
    extensions_ = extensions;
    name_ = name;
    std::error_code ec;
    const fs::path start = fs::absolute(folder.empty() ? fs::current_path(ec) : fs::path(folder), ec);
    enter(start.lexically_normal().string());
}

void FileBrowser::enter(const std::string& folder)
{
    try {
        entries_ = browseFolder(folder, extensions_);
        folder_ = folder;
        error_.clear();
    } catch (const fs::filesystem_error& e) {
        error_ = std::string("cannot read this folder: ") + e.code().message();
        if (folder_.empty()) folder_ = folder;
    }
}

std::optional<std::string> FileBrowser::draw()
{
    if (!open_) return std::nullopt;
    if (opening_) {
        ImGui::OpenPopup(title_.c_str());
        opening_ = false;
    }
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowSize(ImVec2(std::min(640.0f, io.DisplaySize.x - 40.0f), std::min(480.0f, io.DisplaySize.y - 40.0f)), ImGuiCond_Appearing);
    ImGui::SetNextWindowPos(ImGui::GetMainViewport()->GetCenter(), ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
    if (!ImGui::BeginPopupModal(title_.c_str(), &open_)) {
        if (!ImGui::IsPopupOpen(title_.c_str())) open_ = false;
        return std::nullopt;
    }
    std::optional<std::string> chosen;
    ImGui::TextWrapped("%s", folder_.c_str());
    if (ImGui::Button("Up") && fs::path(folder_).has_parent_path()) enter(fs::path(folder_).parent_path().string());
    if (!error_.empty()) {
        ImGui::SameLine();
        ImGui::TextColored(ImVec4(1.0f, 0.5f, 0.4f, 1.0f), "%s", error_.c_str());
    }
    const float footer = ImGui::GetFrameHeightWithSpacing() * 2.0f;
    if (ImGui::BeginChild("entries", ImVec2(0, -footer), true)) {
        std::string enterFolder;
        for (const FolderEntry& e : entries_) {
            const std::string label = e.folder ? e.name + "/" : e.name;
            if (ImGui::Selectable(label.c_str(), !e.folder && e.name == name_, ImGuiSelectableFlags_AllowDoubleClick)) {
                if (e.folder) {
                    if (ImGui::IsMouseDoubleClicked(0)) enterFolder = (fs::path(folder_) / e.name).string();
                } else {
                    name_ = e.name;
                    if (ImGui::IsMouseDoubleClicked(0)) chosen = (fs::path(folder_) / name_).string();
                }
            }
        }
        if (!enterFolder.empty()) enter(enterFolder);
    }
    ImGui::EndChild();
    ImGui::SetNextItemWidth(-200.0f);
    const bool typed = ImGui::InputText("Name", &name_, ImGuiInputTextFlags_EnterReturnsTrue);
    ImGui::SameLine();
    const bool confirm = ImGui::Button(saving_ ? "Save" : "Open") || typed;
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) open_ = false;
    if (confirm && !name_.empty()) {
        // A typed name may be a path of its own: absolute, or relative to the folder shown.
        const fs::path typedPath(name_);
        const fs::path full = typedPath.is_absolute() ? typedPath : fs::path(folder_) / typedPath;
        std::error_code ec;
        if (fs::is_directory(full, ec)) {
            enter(full.lexically_normal().string());
            name_.clear();
        } else {
            chosen = full.lexically_normal().string();
        }
    }
    if (chosen) open_ = false;
    if (!open_) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
    return chosen;
}

} // namespace vdbclay
