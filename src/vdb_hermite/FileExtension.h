// A file's extension as the formats are told apart: ".vdb" for "Scene.VDB" (users and Windows tools
// write either case).
#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace vdbclay {

inline std::string lowerCaseExtension(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

} // namespace vdbclay
