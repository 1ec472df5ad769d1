// Reading one grid of another tool's .vdb file, after describeStandardVdb checked the whole file.
// Heavy header (OpenVDB grids): for the interop sources only.
#pragma once

#include <openvdb/openvdb.h>

#include <string>

namespace vdbclay {

/// The grid named `name` of a file describeStandardVdb accepted, read by OpenVDB with every library
/// failure turned into a VolumeIOError of one line.
openvdb::GridBase::Ptr readStandardGrid(const std::string& path, const std::string& name);

/// Whether a transform only scales and translates (no rotation, shear or perspective).
inline bool axisAligned(const openvdb::math::Transform& xf)
{
    return xf.isLinear() && xf.baseMap()->getAffineMap()->isDiagonal();
}

} // namespace vdbclay
