// The one apps translation unit that includes the OpenVDB-heavy HermiteGrid.h: it only reads a constant.
#include "Cli.h"

#include "vdb_hermite/HermiteGrid.h"

namespace vdbclay::cli {

int formatVersion() { return kFormatVersion; }

} // namespace vdbclay::cli
