#include "voxelize/MeshHeaderCheck.h"

#include "vdb_hermite/FileExtension.h"
#include "vdb_hermite/PrintableText.h"
#include "voxelize/TriangleMesh.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace vdbclay {

namespace {

constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 20;

std::string lowerCase(std::string text)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text;
}

std::optional<uint64_t> parseCount(const std::string& word)
{
    if (word.empty() || word.size() > 19 || !std::all_of(word.begin(), word.end(), [](unsigned char c) { return std::isdigit(c); }))
        return std::nullopt;
    return std::stoull(word);
}

/// Bytes the smallest value of a PLY type takes: its size in a binary file; a digit and a separator in
/// an ASCII one.
uint64_t minimumPlyValueBytes(const std::string& type, bool ascii)
{
    if (ascii) return 2;
    for (const char* one : {"char", "uchar", "int8", "uint8"})
        if (type == one) return 1;
    for (const char* two : {"short", "ushort", "int16", "uint16"})
        if (type == two) return 2;
    for (const char* eight : {"double", "float64", "int64", "uint64"})
        if (type == eight) return 8;
    return 4;
}

void refuseTooMany(const std::string& path, const std::string& what, uint64_t count, long double neededBytes, uint64_t availableBytes)
{
    throw MeshImportError("'" + path + "' is damaged: its header states " + std::to_string(count) + " " + printableText(what, 40) +
                          ", at least " + std::to_string(static_cast<unsigned long long>(std::min(neededBytes, 1.8e19L))) +
                          " bytes, but only " + std::to_string(availableBytes) + " bytes follow the header");
}

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    uint64_t minimumBytes = 0; // of one element
};

void checkPly(const std::string& path, std::ifstream& in, uint64_t fileBytes)
{
    std::string line;
    std::getline(in, line);
    uint64_t headerBytes = line.size() + 1;
    bool ascii = false;
    std::vector<PlyElement> elements;
    while (headerBytes < kMaxHeaderBytes && std::getline(in, line)) {
        headerBytes += line.size() + 1;
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "end_header") {
            const uint64_t available = fileBytes > headerBytes ? fileBytes - headerBytes : 0;
            long double needed = 0;
            for (const PlyElement& element : elements) {
                needed += static_cast<long double>(element.count) * static_cast<long double>(element.minimumBytes);
                // One byte of slack: an ASCII file's last value may have no separator after it.
                if (needed > static_cast<long double>(available) + 1) refuseTooMany(path, element.name + " elements", element.count, needed, available);
            }
            return;
        }
        if (keyword == "format") {
            std::string form;
            words >> form;
            ascii = form == "ascii";
        } else if (keyword == "element") {
            std::string name, count;
            words >> name >> count;
            const std::optional<uint64_t> parsed = parseCount(count);
            if (!parsed) return; // Assimp's own error says what is wrong
            elements.push_back({name, *parsed, 0});
        } else if (keyword == "property" && !elements.empty()) {
            std::string type;
            words >> type;
            // A list's smallest instance is its count alone (no entries).
            if (type == "list") words >> type;
            elements.back().minimumBytes += minimumPlyValueBytes(lowerCase(type), ascii);
        }
    }
    throw MeshImportError("'" + path + "' is a PLY file whose header has no end_header line within its first MiB (truncated?)");
}

/// An OFF header: a keyword ending in OFF ("OFF", "COFF", "NOFF", "4OFF", ...), then the vertex, face
/// and edge counts, on the same line or the next one that is not a comment.
void checkOff(const std::string& path, std::ifstream& in, uint64_t fileBytes)
{
    std::vector<std::string> words;
    std::string line;
    uint64_t headerBytes = 0;
    while (words.size() < 3 && headerBytes < kMaxHeaderBytes && std::getline(in, line)) {
        headerBytes += line.size() + 1;
        std::istringstream stream(line.substr(0, line.find('#')));
        for (std::string word; stream >> word;) words.push_back(word);
    }
    if (words.size() < 3) return;
    const std::string keyword = lowerCase(words[0]);
    if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "off") != 0) return;
    const std::optional<uint64_t> vertices = parseCount(words[1]), faces = parseCount(words[2]);
    if (!vertices || !faces) return;
    const uint64_t available = fileBytes > headerBytes ? fileBytes - headerBytes : 0;
    // A vertex is at least three one-digit coordinates with separators; a face at least its corner count.
    const long double forVertices = static_cast<long double>(*vertices) * 6, forFaces = static_cast<long double>(*faces) * 2;
    if (forVertices > available + 1) refuseTooMany(path, "vertices", *vertices, forVertices, available);
    if (forVertices + forFaces > available + 1) refuseTooMany(path, "faces", *faces, forVertices + forFaces, available);
}

} // namespace

void refuseImplausibleMeshHeader(const std::string& path)
{
    std::error_code ec;
    const uint64_t fileBytes = std::filesystem::file_size(path, ec);
    std::ifstream in(path, std::ios::binary);
    if (ec || !in) return; // Assimp reports the file it cannot open
    std::string first;
    std::getline(in, first);
    in.seekg(0);
    if (first.rfind("ply", 0) == 0 && first.find_first_not_of(" \t\r", 3) == std::string::npos) {
        checkPly(path, in, fileBytes);
    } else if (lowerCaseExtension(path) == ".off") {
        checkOff(path, in, fileBytes);
    }
}

} // namespace vdbclay
