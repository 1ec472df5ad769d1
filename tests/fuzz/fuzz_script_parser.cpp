// The stroke-script parser and the limits check on arbitrary text: a script parses or is refused with a
// ScriptError of one printable line; a parsed script's ops pass or fail the limits with std::invalid_argument.
#include "sculpt/StrokeScript.h"
#include "vdb_hermite/PrintableText.h"

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const vdbclay::StrokeScript script = vdbclay::parseStrokeScript(text);
        vdbclay::MaterialTable table;
        for (const vdbclay::Material& m : script.materials) table.define(m);
        for (const vdbclay::ScriptOp& op : script.ops) {
            if (!op.toolFile.empty()) continue; // a grid tool: its limits wait for its file, which is not read here
            vdbclay::CsgOp csg;
            csg.mode = op.mode;
            csg.strength = op.strength;
            csg.erodeDepth = op.depth;
            try {
                if (op.path.size() > 1) vdbclay::checkCsgLimits(0.5, table, vdbclay::SweptBrush(op.brush, op.path), csg);
                else vdbclay::checkCsgLimits(0.5, table, op.brush, csg);
            } catch (const std::invalid_argument&) {
            }
        }
    } catch (const vdbclay::ScriptError& e) {
        if (!vdbclay::isPrintableName(e.what(), std::string::npos)) std::abort(); // raw bytes of the script reach a terminal
    } catch (const std::invalid_argument&) { // a material the table refuses (script materials are checked on parse)
    }
    return 0;
}
