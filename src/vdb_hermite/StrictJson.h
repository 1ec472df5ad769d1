// JSON as VDBClay's own files are read (stroke scripts, camera paths): a key given twice in one object
// is refused (JSON keeps the last one silently; in a hand-written file that is a typo or a merge gone
// wrong), and the parser's quote of the text it stopped at comes back printable.
#pragma once

#include "vdb_hermite/PrintableText.h"

#include <nlohmann/json.hpp>

#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay {

/// Parses `text`; throws std::invalid_argument "WHAT is not valid JSON: ..." or "WHAT: the key 'K'
/// appears twice in one object".
inline nlohmann::json parseStrictJson(const std::string& text, const std::string& what)
{
    using nlohmann::json;
    std::vector<std::set<std::string>> openObjects;
    std::string duplicate;
    const json::parser_callback_t noDuplicateKeys = [&](int, json::parse_event_t event, json& parsed) {
        if (event == json::parse_event_t::object_start) openObjects.emplace_back();
        else if (event == json::parse_event_t::object_end && !openObjects.empty()) openObjects.pop_back();
        else if (event == json::parse_event_t::key && !openObjects.empty() &&
                 !openObjects.back().insert(parsed.get<std::string>()).second && duplicate.empty())
            duplicate = parsed.get<std::string>();
        return true;
    };
    json root;
    try {
        root = json::parse(text, noDuplicateKeys);
    } catch (const json::exception& e) { // a syntax error, or a number too large for a double
        throw std::invalid_argument(what + " is not valid JSON: " + printableText(e.what()));
    }
    if (!duplicate.empty()) throw std::invalid_argument(what + ": the key '" + printableText(duplicate, 80) + "' appears twice in one object");
    return root;
}

} // namespace vdbclay
