// A structural check of a .vdb payload before OpenVDB parses it. OpenVDB's readers trust every count,
// length and size in a file; this walk reads the bytes the way OpenVDB 10 will (header, metadata, grid
// descriptors, transform, tree topology, leaf buffers) and refuses the file, with one clean line, where
// a count or length does not fit what is left of the payload or what VDBClay writes. What it checks is
// listed in docs/ARCHITECTURE.md ("Reading untrusted files").
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace vdbclay {

/// What the file says about one grid, before its tree.
struct GridHeader {
    std::string name;
    std::string type;      // OpenVDB's grid type name, e.g. Tree_float_5_4_3
    std::string valueType; // float, double, int32, ... ("" where the type is not a tree of 5_4_3 nodes)
    std::string gridClass; // level set, fog volume, ... ("" where the file does not say)
    std::string transform; // the map's type name
    bool halfFloat = false;
    bool treeChecked = false; // false: a type VDBClay does not read, skipped by its stream positions
};

struct PayloadSummary {
    uint64_t upperNodes = 0, lowerNodes = 0, leaves = 0;
    uint64_t estimatedMemoryBytes = 0; // what OpenVDB will allocate for the trees while reading
    std::vector<GridHeader> grids;
};

/// Which grids a payload may hold.
enum class AcceptedGrids {
    Hermite,  // only VDBClay's grid (hermiteGridType), as VDBClay writes it
    Standard, // files of other tools: float, double, int32, int64 and vec3 grids are checked; other
              // types are skipped (their headers still are checked), as are files with no checkable grid
};

/// Reads `payloadBytes` bytes from `in` (positioned at the payload's start). Throws VolumeIOError naming
/// `path` and the first problem found. `hermiteGridType` is the type name of VDBClay's grid.
PayloadSummary checkPayload(std::istream& in, uint64_t payloadBytes, const std::string& path,
                            const std::string& hermiteGridType, AcceptedGrids accepted = AcceptedGrids::Hermite);

} // namespace vdbclay
