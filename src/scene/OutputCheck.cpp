#include "scene/OutputCheck.h"

#include "scene/SceneStore.h"

#include "interop/LevelSetExport.h"
#include "mesher/MeshIO.h"
#include "vdb_hermite/AtomicFile.h"
#include "vdb_hermite/FileExtension.h"
#include "vdb_hermite/VolumeIO.h"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vdbclay {

namespace {

namespace fs = std::filesystem;

constexpr std::size_t kSniffBytes = 4096;

std::string firstBytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::string bytes(kSniffBytes, '\0');
    in.read(bytes.data(), std::streamsize(bytes.size()));
    bytes.resize(std::size_t(std::max<std::streamsize>(0, in.gcount())));
    return bytes;
}

bool startsWith(const std::string& s, const char* prefix, std::size_t n) { return s.size() >= n && std::memcmp(s.data(), prefix, n) == 0; }

/// An OBJ statement keyword (the first word of a line of an OBJ file).
bool isObjKeyword(const std::string& word)
{
    static const char* const kWords[] = {"v", "vt", "vn", "vp", "f", "l", "p", "o", "g", "s", "mtllib", "usemtl",
                                         "cstype", "deg", "curv", "curv2", "surf", "parm", "end", "bmat", "step"};
    return std::any_of(std::begin(kWords), std::end(kWords), [&](const char* w) { return word == w; });
}

FileContent sniffText(const std::string& bytes)
{
    std::istringstream lines(bytes);
    std::string line;
    while (std::getline(lines, line)) {
        const std::size_t first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos || line[first] == '#') continue;
        const char c = line[first];
        if (c == '{' || c == '[') return FileContent::Json;
        if (line.compare(first, 7, "frame,t") == 0) return FileContent::FlightCsv;
        const std::string word = line.substr(first, line.find_first_of(" \t\r", first) - first);
        if (word == "newmtl") return FileContent::MtlLibrary;
        if (isObjKeyword(word)) return FileContent::ObjMesh;
        return FileContent::OtherText;
    }
    return FileContent::CommentsOnly;
}

/// The kinds of existing file a form may replace (besides a missing or empty one).
bool mayReplace(OutputForm form, FileContent content)
{
    switch (form) {
    case OutputForm::NativeVolume: return content == FileContent::NativeVolume;
    case OutputForm::Store: return content == FileContent::Store;
    case OutputForm::StandardVdb: return content == FileContent::StandardVdbExport;
    case OutputForm::ObjMesh: return content == FileContent::ObjMesh || content == FileContent::CommentsOnly;
    case OutputForm::MtlLibrary: return content == FileContent::MtlLibrary || content == FileContent::CommentsOnly;
    case OutputForm::PlyMesh: return content == FileContent::PlyMesh;
    case OutputForm::GlbMesh: return content == FileContent::GlbMesh;
    case OutputForm::Csv: return content == FileContent::FlightCsv;
    case OutputForm::Png: return content == FileContent::Png;
    case OutputForm::Json: return content == FileContent::Json;
    }
    return false;
}

const char* formName(OutputForm form)
{
    switch (form) {
    case OutputForm::NativeVolume: return "a VDBClay volume";
    case OutputForm::Store: return "a VDBClay scene store";
    case OutputForm::StandardVdb: return "standard OpenVDB grids";
    case OutputForm::ObjMesh: return "an OBJ mesh";
    case OutputForm::MtlLibrary: return "an OBJ materials file";
    case OutputForm::PlyMesh: return "a PLY mesh";
    case OutputForm::GlbMesh: return "a glTF binary mesh";
    case OutputForm::Csv: return "a CSV table";
    case OutputForm::Png: return "a PNG picture";
    case OutputForm::Json: return "a JSON file";
    }
    return "a file";
}

void checkOne(const std::string& output, OutputForm form, const std::vector<std::string>& inputs)
{
    if (lowerCaseExtension(output) != formExtension(form))
        throw OutputRefused("'" + output + "': this command writes " + formName(form) + "; the file name must end in " +
                            formExtension(form));
    for (const std::string& input : inputs)
        if (!input.empty() && samePlace(output, input)) // a missing input may be made before the output is written
            throw OutputRefused("'" + output + "' is an input of this command ('" + input +
                                "'); write the output to another file");
    const FileContent existing = sniffFileContent(output);
    const std::string name = fs::path(output).filename().string();
    const std::size_t suffix = std::strlen(kWorkingStoreSuffix);
    if (existing == FileContent::Store && name.size() > suffix && name.compare(name.size() - suffix, suffix, kWorkingStoreSuffix) == 0)
        throw OutputRefused("'" + output + "' is the editor's working store of '" + name.substr(0, name.size() - suffix) +
                            "' (the edits autosaved there would be lost); write the output to another file");
    if (existing != FileContent::Missing && existing != FileContent::Empty && !mayReplace(form, existing))
        throw OutputRefused("'" + output + "' exists and holds " + describeContent(existing) + ", not " + formName(form) +
                            "; not replacing it (remove it first, or choose another name)");
    requireReplaceable(output);
}

} // namespace

bool sameFile(const std::string& a, const std::string& b)
{
    struct stat sa {}, sb {};
    if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

bool samePlace(const std::string& a, const std::string& b)
{
    if (sameFile(a, b)) return true;
    std::error_code ec1, ec2;
    const fs::path pa = fs::weakly_canonical(fs::absolute(a), ec1), pb = fs::weakly_canonical(fs::absolute(b), ec2);
    return !ec1 && !ec2 && pa.lexically_normal() == pb.lexically_normal();
}

void checkDistinctOutputs(const std::vector<std::pair<std::string, std::string>>& optionAndPath)
{
    for (std::size_t i = 0; i < optionAndPath.size(); ++i)
        for (std::size_t j = i + 1; j < optionAndPath.size(); ++j) {
            const auto& [optionA, a] = optionAndPath[i];
            const auto& [optionB, b] = optionAndPath[j];
            if (!a.empty() && !b.empty() && samePlace(a, b))
                throw OutputRefused(optionA + " '" + a + "' and " + optionB + " '" + b + "' name the same file: one would write over the other");
        }
}

void checkOutputFolder(const std::string& folder)
{
    std::error_code ec;
    const fs::path path = fs::absolute(folder, ec).lexically_normal();
    if (fs::is_directory(path, ec)) return;
    fs::path parent = path.parent_path();
    if (path.filename().empty()) parent = parent.parent_path(); // "dir/" names dir itself
    if (!fs::is_directory(parent, ec))
        throw OutputRefused("'" + folder + "': its parent folder '" + parent.string() +
                            "' does not exist; an output makes at most its own folder (create the parent first)");
}

FileContent sniffFileContent(const std::string& path)
{
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return FileContent::Missing;
    if (!S_ISREG(st.st_mode)) return FileContent::NotAFile;
    if (st.st_size == 0) return FileContent::Empty;
    const std::string bytes = firstBytes(path);
    if (startsWith(bytes, "SQLite format 3\0", 16)) {
        // The application id, big-endian at offset 68, marks VDBClay's stores ("VCLY").
        const bool ours = bytes.size() >= 72 && startsWith(bytes.substr(68), "VCLY", 4);
        return ours ? FileContent::Store : FileContent::OtherSqlite;
    }
    if (startsWith(bytes, "\x89PNG\r\n\x1a\n", 8)) return FileContent::Png;
    if (startsWith(bytes, "glTF", 4)) return FileContent::GlbMesh;
    if (startsWith(bytes, "ply\n", 4) || startsWith(bytes, "ply\r\n", 5)) return FileContent::PlyMesh;
    try {
        switch (classifyVdbFile(path)) {
        case VdbFileKind::VdbClay: return FileContent::NativeVolume;
        case VdbFileKind::Other:
            return bytes.find(kLevelSetExportMarker) != std::string::npos ? FileContent::StandardVdbExport : FileContent::ForeignVdb;
        case VdbFileKind::NotVdb: break;
        }
    } catch (const std::exception&) {
        return FileContent::OtherBinary; // unreadable: treat as something not ours to replace
    }
    if (bytes.find('\0') != std::string::npos) return FileContent::OtherBinary;
    return sniffText(bytes);
}

std::string describeContent(FileContent content)
{
    switch (content) {
    case FileContent::Missing: return "nothing";
    case FileContent::Empty: return "nothing (it is empty)";
    case FileContent::NativeVolume: return "a VDBClay volume";
    case FileContent::StandardVdbExport: return "standard grids exported by VDBClay";
    case FileContent::ForeignVdb: return "a .vdb of another tool";
    case FileContent::Store: return "a VDBClay scene store";
    case FileContent::OtherSqlite: return "an SQLite database";
    case FileContent::PlyMesh: return "a PLY mesh";
    case FileContent::GlbMesh: return "a glTF binary mesh";
    case FileContent::Png: return "a PNG picture";
    case FileContent::Json: return "JSON (a stroke script, camera path or report)";
    case FileContent::ObjMesh: return "an OBJ mesh";
    case FileContent::MtlLibrary: return "an OBJ materials file";
    case FileContent::FlightCsv: return "a flight CSV of 'lod inspect'";
    case FileContent::CommentsOnly: return "comment lines";
    case FileContent::OtherText: return "text of another kind";
    case FileContent::OtherBinary: return "binary data of another kind";
    case FileContent::NotAFile: return "no regular file (a directory, device, FIFO or socket)";
    }
    return "an unknown kind of data";
}

const char* formExtension(OutputForm form)
{
    switch (form) {
    case OutputForm::NativeVolume:
    case OutputForm::StandardVdb: return ".vdb";
    case OutputForm::Store: return ".vdbclay";
    case OutputForm::ObjMesh: return ".obj";
    case OutputForm::MtlLibrary: return ".mtl";
    case OutputForm::PlyMesh: return ".ply";
    case OutputForm::GlbMesh: return ".glb";
    case OutputForm::Csv: return ".csv";
    case OutputForm::Png: return ".png";
    case OutputForm::Json: return ".json";
    }
    return "";
}

OutputForm meshFormOf(const std::string& path)
{
    try {
        switch (meshFormatOf(path)) {
        case MeshFormat::Obj: return OutputForm::ObjMesh;
        case MeshFormat::Ply: return OutputForm::PlyMesh;
        case MeshFormat::Glb: return OutputForm::GlbMesh;
        }
    } catch (const MeshIOError& e) {
        throw OutputRefused(e.what());
    }
    throw OutputRefused("'" + path + "': no mesh format");
}

void checkOutput(const std::string& output, OutputForm form, const std::vector<std::string>& inputs)
{
    if (output.empty()) throw OutputRefused("the output file name is empty");
    checkOne(output, form, inputs);
    if (form == OutputForm::ObjMesh) checkOne(fs::path(output).replace_extension(".mtl").string(), OutputForm::MtlLibrary, inputs);
}

} // namespace vdbclay
