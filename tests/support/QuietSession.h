// Session options for tests: no autosave unless asked, a budget that holds a test scene, and the
// session's notices on stderr (where a failing test's log shows them).
#pragma once

#include "editor/EditingSession.h"

#include <cstdio>
#include <string>

namespace vdbclay::test {

inline SessionOptions quietSession()
{
    SessionOptions o;
    o.memoryBudgetBytes = 256ull << 20;
    o.autosaveSeconds = 1e9;
    o.idleAutosaveSeconds = 1e9;
    o.message = [](const std::string& m) { std::fprintf(stderr, "session: %s\n", m.c_str()); };
    return o;
}

} // namespace vdbclay::test
