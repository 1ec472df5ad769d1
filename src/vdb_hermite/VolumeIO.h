// Native .vdb files: the Hermite grid with its materials table and format version, Blosc-compressed.
#pragma once

#include "vdb_hermite/Volume.h"

#include <stdexcept>
#include <string>

namespace vdbclay {

/// Every failure to read or write a volume file; what() is one line meant for the user.
class VolumeIOError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Writes to a temporary file beside `path`, flushes it to disk, then renames it over `path`:
/// a crash at any point leaves either the old file or the new one, never a torn file.
void saveVolume(const Volume& volume, const std::string& path);

/// Reads the first VDBClay Hermite grid of a .vdb file (the one named "hermite" if there are several).
Volume loadVolume(const std::string& path);

/// What a file is: a native VDBClay volume (it ends in VDBClay's checksum trailer, which loadVolume
/// verifies), another .vdb file (made by another tool, or a VDBClay file truncated before its
/// trailer), or not a .vdb file at all.
enum class VdbFileKind { VdbClay, Other, NotVdb };
/// Throws VolumeIOError when the file cannot be opened.
VdbFileKind classifyVdbFile(const std::string& path);

/// The bytes saveVolume writes for `volume` (OpenVDB's data, Blosc-compressed, and the checksum
/// trailer), for volumes kept elsewhere than in their own file (the scene store's bricks).
std::string encodeVolume(const Volume& volume);

/// Reads bytes encodeVolume (or a saved file) holds, with every check loadVolume makes; `name` names
/// their source in messages.
Volume decodeVolume(const std::string& bytes, const std::string& name);

} // namespace vdbclay
