// The one check every command makes before it writes a file: an output may not be one of the command's
// inputs (compared as files, through symbolic links), its extension must name the form written, and an
// existing file is replaced only when it holds that same form (a mesh never replaces a store, a CSV
// never replaces a script, a standard grid export never replaces another tool's .vdb).
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace vdbclay {

/// What a command writes.
enum class OutputForm {
    NativeVolume, // VDBClay's .vdb
    Store,        // .vdbclay
    StandardVdb,  // export-levelset's standard grids (.vdb marked as VDBClay's export)
    ObjMesh,
    MtlLibrary, // the .mtl beside an OBJ
    PlyMesh,
    GlbMesh,
    Csv,
    Png,
    Json,
};

/// What an existing file holds, read from its first bytes (and a .vdb's trailer or metadata).
enum class FileContent {
    Missing,
    Empty,
    NativeVolume,
    StandardVdbExport, // written by export-levelset
    ForeignVdb,        // a .vdb of another tool
    Store,
    OtherSqlite,
    PlyMesh,
    GlbMesh,
    Png,
    Json,
    ObjMesh,
    MtlLibrary,
    FlightCsv, // lod inspect's CSV
    CommentsOnly, // text of '#' lines only (an OBJ or MTL whose body lies beyond what is read)
    OtherText,
    OtherBinary,
    NotAFile, // a directory, device, FIFO or socket
};

/// The output is refused: it is an input, names another form, or would replace another kind of file.
/// A wrong command line, so commands exit 2 on it.
class OutputRefused : public std::invalid_argument {
public:
    using std::invalid_argument::invalid_argument;
};

FileContent sniffFileContent(const std::string& path);
/// "a VDBClay scene store", "a JSON file (a stroke script or camera path?)", ...
std::string describeContent(FileContent content);

/// The extensions that name a form, for messages (".vdb", ".obj", ...).
const char* formExtension(OutputForm form);

/// The mesh form a path's extension names (.obj, .ply, .glb); throws OutputRefused for any other.
OutputForm meshFormOf(const std::string& path);

/// Throws OutputRefused unless `output` may receive `form`: its extension names the form, it is not
/// the same file as any of `inputs` (through links, or by its path when missing: an input a command makes), and, when it exists, it holds the
/// same form (or is empty). Then makes requireReplaceable's checks (FileWriteError). An OBJ's .mtl
/// beside it is checked the same way.
void checkOutput(const std::string& output, OutputForm form, const std::vector<std::string>& inputs = {});

/// Whether two paths name the same file once links are followed (false when either does not exist).
bool sameFile(const std::string& a, const std::string& b);

/// Whether two paths name the same file, existing or not: the same file once links are followed, or the
/// same place once made absolute and normalized (through the links of the folders that exist).
bool samePlace(const std::string& a, const std::string& b);

/// Throws OutputRefused when two of a command's outputs (empty ones skipped) name the same file: one would
/// write over the other.
void checkDistinctOutputs(const std::vector<std::pair<std::string, std::string>>& optionAndPath);

/// Throws OutputRefused unless `folder` exists or only its last part is missing: an output makes at most
/// its own folder, never a chain of them (a typo in a parent would scatter folders anywhere).
void checkOutputFolder(const std::string& folder);

} // namespace vdbclay
