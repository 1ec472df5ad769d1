// A structural check of a .vdb payload before OpenVDB parses it. OpenVDB's readers trust every count,
// length and size in a file; this walk reads the bytes the way OpenVDB 10 will (header, metadata, grid
// descriptors, transform, tree topology, leaf buffers) and refuses the file, with one clean line, where
// a count or length does not fit what is left of the payload or what VDBClay writes. What it checks is
// listed in docs/ARCHITECTURE.md ("Reading untrusted files").
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

namespace vdbclay {

struct PayloadSummary {
    uint64_t upperNodes = 0, lowerNodes = 0, leaves = 0;
    uint64_t estimatedMemoryBytes = 0; // what OpenVDB will allocate for the tree while reading
};

/// Reads `payloadBytes` bytes from `in` (positioned at the payload's start). Throws VolumeIOError naming
/// `path` and the first problem found. `hermiteGridType` is the type name of VDBClay's grid: a file
/// holding any other grid type is refused, as its layout cannot be checked.
PayloadSummary checkPayload(std::istream& in, uint64_t payloadBytes, const std::string& path,
                            const std::string& hermiteGridType);

} // namespace vdbclay
