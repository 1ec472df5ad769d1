// Session files (vdbclay edit --replay) on crafted text: parsed, written back and read again to the same
// commands, or refused with one printable line.
#include "editor/SessionCommand.h"
#include "vdb_hermite/PrintableText.h"

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const vdbclay::SessionRecord record = vdbclay::parseSessionRecord(text, "fuzz.json");
        for (std::size_t i = 1; i < record.commands.size(); ++i)
            if (record.commands[i].frame < record.commands[i - 1].frame) std::abort(); // frames never go back
        if (!record.commands.empty() && record.frames <= record.commands.back().frame) std::abort();
        const std::string written = vdbclay::sessionRecordJson(record).dump();
        const vdbclay::SessionRecord again = vdbclay::parseSessionRecord(written, "written.json");
        if (again.commands.size() != record.commands.size() || again.frames != record.frames || again.viewport != record.viewport)
            std::abort();
        for (std::size_t i = 0; i < record.commands.size(); ++i)
            if (vdbclay::commandJson(again.commands[i].command) != vdbclay::commandJson(record.commands[i].command)) std::abort();
    } catch (const vdbclay::SessionError& e) {
        if (!vdbclay::isPrintableName(e.what(), std::string::npos)) std::abort(); // raw bytes or several lines
    }
    return 0;
}
