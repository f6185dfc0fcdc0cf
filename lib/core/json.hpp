// SPDX-License-Identifier: Apache-2.0
// Internal: the one small strict JSON reader of the library's data files:
// calibration files (lib/calibration), rule sets of tolerances
// (lib/verdict), leveler files (lib/advisor).
//
// Strict instead of general: every error names the field it concerns
// ("rules[2].bands[0].limit", with its line), which generic parsers do not
// do. Numbers keep their text until a field reads them, so a NaN or a
// fraction is reported against the field, not as a syntax error, and are
// read with std::from_chars (never the C locale's decimal point). Strings
// take no escapes. Errors are thrown as flt::error(FLT_ERR_FORMAT).
//
// Bounded work: a document is read in one pass over its bytes, at most 16
// levels deep, with at most `max_values` values (numbers, strings, words,
// objects, arrays; k_max_values unless the caller knows a tighter bound
// from its format): a file of millions of tiny values is refused when it
// passes the bound, before it costs more than that many nodes (about 100
// bytes each). Paths for messages are built only when an error needs one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace flt {
namespace json {

struct node {
    enum kind_t { number, string, word, object, array } kind = number;
    std::string text;                                   // number, string, word
    std::vector<std::pair<std::string, node>> members;  // object, in order
    std::vector<node> items;                            // array
    int line = 0;
};

// The values a document may hold unless its reader says fewer: 1,000,000
// (about 100 MB of nodes).
constexpr std::size_t k_max_values = 1000000;

// Parses a whole document; `document` names it in messages ("the
// tolerances file").
node parse(const char *text, std::size_t length, const char *document,
           std::size_t max_values = k_max_values);

[[noreturn]] void format_error(const std::string &message);

// "a.b" (or "b" at the top level).
std::string join(const std::string &path, const char *key);

void expect_kind(const node &n, node::kind_t kind, const std::string &path);

// The member `name` of an object, or nullptr.
const node *member(const node &obj, const char *name);

// Checks that obj has only fields among `required` and `optional`, each
// once, and every one of `required`; returns pointers in the order of
// required then optional (nullptr for an absent optional field).
std::vector<const node *> fields(const node &obj, const std::string &path,
                                 std::initializer_list<const char *> required,
                                 std::initializer_list<const char *> optional = {});

double number(const node &n, const std::string &path);
double positive(const node &n, const std::string &path);
std::uint64_t integer(const node &n, const std::string &path, double min_value, double max_value);
const std::string &string(const node &n, const std::string &path);

// The shortest text that reads back as v (locale-proof).
std::string text_of(double v);

}  // namespace json
}  // namespace flt
