// JSON as VDBClay's own files are read (stroke scripts, camera paths): a key given twice in one object
// is refused (JSON keeps the last one silently; in a hand-written file that is a typo or a merge gone
// wrong), and the parser's quote of the text it stopped at comes back printable.
#pragma once

#include "vdb_hermite/PrintableText.h"

#include <nlohmann/json.hpp>

#include <unordered_set>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbclay {

namespace detail {

/// A SAX pass that finds the first key given twice in one object. Linear in the text: nlohmann's
/// callback parser looks through an object's parent at each object's end, quadratic in a long array.
class DuplicateKeyFinder : public nlohmann::json_sax<nlohmann::json> {
public:
    std::string duplicate;

    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(number_integer_t) override { return true; }
    bool number_unsigned(number_unsigned_t) override { return true; }
    bool number_float(number_float_t, const string_t&) override { return true; }
    bool string(string_t&) override { return true; }
    bool binary(binary_t&) override { return true; }
    bool start_object(std::size_t) override
    {
        open_.emplace_back();
        return true;
    }
    bool key(string_t& name) override
    {
        if (!open_.back().insert(name).second) {
            duplicate = name;
            return false; // the first one is reported; the rest need not be read
        }
        return true;
    }
    bool end_object() override
    {
        open_.pop_back();
        return true;
    }
    bool start_array(std::size_t) override { return true; }
    bool end_array() override { return true; }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override { return false; }

private:
    std::vector<std::unordered_set<std::string>> open_;
};

} // namespace detail

/// Parses `text`; throws std::invalid_argument "WHAT is not valid JSON: ..." or "WHAT: the key 'K'
/// appears twice in one object". Linear in the text's length.
inline nlohmann::json parseStrictJson(const std::string& text, const std::string& what)
{
    using nlohmann::json;
    json root;
    try {
        root = json::parse(text);
    } catch (const json::exception& e) { // a syntax error, or a number too large for a double
        throw std::invalid_argument(what + " is not valid JSON: " + printableText(e.what()));
    }
    detail::DuplicateKeyFinder finder;
    json::sax_parse(text, &finder);
    if (!finder.duplicate.empty())
        throw std::invalid_argument(what + ": the key '" + printableText(finder.duplicate, 80) + "' appears twice in one object");
    return root;
}

} // namespace vdbclay
