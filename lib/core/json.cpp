// SPDX-License-Identifier: Apache-2.0
// A small strict JSON reader (see json.hpp).
#include "core/json.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <system_error>

#include "core/error.hpp"
#include "flatline/common.h"

namespace flt {
namespace json {
namespace {

const char *kind_name(node::kind_t k) {
    switch (k) {
        case node::number:
            return "a number";
        case node::string:
            return "a string";
        case node::word:
            return "a bare word";
        case node::object:
            return "an object";
        case node::array:
            return "an array";
    }
    return "?";
}

bool is_json_number(const std::string &t) {
    std::size_t i = 0;
    const std::size_t n = t.size();
    auto digits = [&] {
        const std::size_t b = i;
        while (i < n && t[i] >= '0' && t[i] <= '9')
            ++i;
        return i > b;
    };
    if (i < n && t[i] == '-')
        ++i;
    if (!digits())
        return false;
    if (i < n && t[i] == '.') {
        ++i;
        if (!digits())
            return false;
    }
    if (i < n && (t[i] == 'e' || t[i] == 'E')) {
        ++i;
        if (i < n && (t[i] == '+' || t[i] == '-'))
            ++i;
        if (!digits())
            return false;
    }
    return i == n;
}

// Where a value is, for messages: a chain from the value to the top,
// rendered ("rules[2].bands[0].limit") only when an error names it.
struct path_ref {
    const path_ref *parent = nullptr;
    const std::string *key = nullptr;  // a member's name, or
    std::size_t index = 0;             // an array item's index
};

std::string render(const path_ref *p) {
    if (p == nullptr)
        return "(top level)";
    std::vector<const path_ref *> chain;
    for (; p != nullptr; p = p->parent)
        chain.push_back(p);
    std::string out;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        if ((*it)->key != nullptr) {
            if (!out.empty())
                out += '.';
            out += *(*it)->key;
        } else {
            if (out.empty())
                out = "(top level)";
            out += "[" + std::to_string((*it)->index) + "]";
        }
    }
    return out;
}

class parser {
  public:
    parser(const char *text, std::size_t length, const char *document, std::size_t max_values)
        : p_(text), end_(text + length), document_(document), max_values_(max_values) {}

    node parse_document() {
        skip_space();
        if (p_ == end_)
            format_error(std::string(document_) + " is empty");
        node root = parse_value(nullptr, 0);
        skip_space();
        if (p_ != end_)
            format_error("line " + std::to_string(line_) + ": unexpected text after the end of " +
                         document_);
        return root;
    }

  private:
    const char *p_, *end_;
    const char *document_;
    std::size_t max_values_;
    std::size_t values_ = 0;
    int line_ = 1;

    void skip_space() {
        while (p_ != end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) {
            if (*p_ == '\n')
                ++line_;
            ++p_;
        }
    }

    [[noreturn]] void truncated(const path_ref *path) const {
        format_error(std::string(document_) + " ends early (truncated?) inside '" + render(path) +
                     "' at line " + std::to_string(line_));
    }

    [[noreturn]] void unexpected(const path_ref *path, const char *expected) const {
        const std::string found = p_ == end_ ? "end of file" : std::string("'") + *p_ + "'";
        format_error("line " + std::to_string(line_) + ": in '" + render(path) + "' expected " +
                     expected + ", found " + found);
    }

    node parse_value(const path_ref *path, int depth) {
        if (depth > 16)
            format_error("'" + render(path) + "' is nested too deeply");
        if (++values_ > max_values_)
            format_error(std::string(document_) + " holds more than " +
                         std::to_string(max_values_) + " values (line " + std::to_string(line_) +
                         ", '" + render(path) + "'): more than its format can have");
        skip_space();
        if (p_ == end_)
            truncated(path);
        node n;
        n.line = line_;
        const char c = *p_;
        if (c == '{') {
            n.kind = node::object;
            ++p_;
            skip_space();
            if (p_ == end_)
                truncated(path);
            if (*p_ == '}') {
                ++p_;
                return n;
            }
            for (;;) {
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ != '"')
                    unexpected(path, "a field name in quotes");
                std::string key = parse_string(path);
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ != ':')
                    unexpected(path, "':' after a field name");
                ++p_;
                path_ref child;
                child.parent = path;
                child.key = &key;
                node value = parse_value(&child, depth + 1);
                n.members.emplace_back(std::move(key), std::move(value));
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ == ',') {
                    ++p_;
                    continue;
                }
                if (*p_ == '}') {
                    ++p_;
                    return n;
                }
                unexpected(path, "',' or '}'");
            }
        }
        if (c == '[') {
            n.kind = node::array;
            ++p_;
            skip_space();
            if (p_ == end_)
                truncated(path);
            if (*p_ == ']') {
                ++p_;
                return n;
            }
            for (;;) {
                path_ref child;
                child.parent = path;
                child.index = n.items.size();
                n.items.push_back(parse_value(&child, depth + 1));
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ == ',') {
                    ++p_;
                    continue;
                }
                if (*p_ == ']') {
                    ++p_;
                    return n;
                }
                unexpected(path, "',' or ']'");
            }
        }
        if (c == '"') {
            n.kind = node::string;
            n.text = parse_string(path);
            return n;
        }
        // A number or a bare word (true, null, nan, inf, ...): the token runs
        // to the next delimiter; the field that reads it judges it.
        const char *start = p_;
        while (p_ != end_ && std::strchr(" \t\r\n,]}:", *p_) == nullptr)
            ++p_;
        if (p_ == start)
            unexpected(path, "a value");
        n.text.assign(start, p_);
        n.kind = is_json_number(n.text) ? node::number : node::word;
        // A number cut off by the end of the file looks complete; the
        // enclosing object's missing '}' reports the truncation.
        return n;
    }

    std::string parse_string(const path_ref *path) {
        ++p_;  // opening quote
        const char *start = p_;
        while (p_ != end_ && *p_ != '"') {
            if (*p_ == '\n')
                format_error("line " + std::to_string(line_) + ": a string in '" + render(path) +
                             "' runs past the end of the line");
            if (*p_ == '\\')
                format_error("line " + std::to_string(line_) + ": escapes are not used in " +
                             document_ + " ('" + render(path) + "')");
            ++p_;
        }
        if (p_ == end_)
            truncated(path);
        std::string s(start, p_);
        ++p_;  // closing quote
        return s;
    }
};

}  // namespace

std::string text_of(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

node parse(const char *text, std::size_t length, const char *document, std::size_t max_values) {
    return parser(text, length, document, max_values).parse_document();
}

void format_error(const std::string &message) {
    throw error(FLT_ERR_FORMAT, message.c_str());
}

std::string join(const std::string &path, const char *key) {
    return path.empty() ? std::string(key) : path + "." + key;
}

void expect_kind(const node &n, node::kind_t kind, const std::string &path) {
    if (n.kind == kind)
        return;
    format_error("field '" + path + "' (line " + std::to_string(n.line) + ") must be " +
                 kind_name(kind) + ", found " + kind_name(n.kind) +
                 (n.kind == node::word ? " '" + n.text + "'" : std::string()));
}

const node *member(const node &obj, const char *name) {
    for (const auto &m : obj.members)
        if (m.first == name)
            return &m.second;
    return nullptr;
}

std::vector<const node *> fields(const node &obj, const std::string &path,
                                 std::initializer_list<const char *> required,
                                 std::initializer_list<const char *> optional) {
    expect_kind(obj, node::object, path.empty() ? "(top level)" : path);
    for (std::size_t i = 0; i < obj.members.size(); ++i) {
        const std::string &key = obj.members[i].first;
        bool known = false;
        for (const char *name : required)
            known = known || key == name;
        for (const char *name : optional)
            known = known || key == name;
        if (!known)
            format_error("unknown field '" + join(path, key.c_str()) + "' (line " +
                         std::to_string(obj.members[i].second.line) + ")");
        for (std::size_t j = 0; j < i; ++j)
            if (obj.members[j].first == key)
                format_error("duplicate field '" + join(path, key.c_str()) + "' (line " +
                             std::to_string(obj.members[i].second.line) + ")");
    }
    std::vector<const node *> out;
    for (const char *name : required) {
        const node *found = member(obj, name);
        if (found == nullptr)
            format_error("missing field '" + join(path, name) + "'");
        out.push_back(found);
    }
    for (const char *name : optional)
        out.push_back(member(obj, name));
    return out;
}

double number(const node &n, const std::string &path) {
    if (n.kind == node::word) {
        std::string lower;
        for (const char c : n.text)
            lower += char(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
        if (lower.find("nan") != std::string::npos)
            format_error("field '" + path + "' is NaN (line " + std::to_string(n.line) + ")");
        if (lower.find("inf") != std::string::npos)
            format_error("field '" + path + "' is infinite (line " + std::to_string(n.line) + ")");
    }
    expect_kind(n, node::number, path);
    double v = 0;
    const char *first = n.text.data();
    const char *last = first + n.text.size();
    // from_chars takes no leading '+' (JSON has none) and reads the sign.
    const auto r = std::from_chars(first, last, v);
    if (r.ec == std::errc::result_out_of_range || !std::isfinite(v))
        format_error("field '" + path + "' = " + n.text + " is outside the range of a double");
    if (r.ec != std::errc() || r.ptr != last)
        format_error("field '" + path + "' = " + n.text + " is not a number");
    return v;
}

double positive(const node &n, const std::string &path) {
    const double v = number(n, path);
    if (!(v > 0))
        format_error("field '" + path + "' = " + n.text + " must be > 0");
    return v;
}

std::uint64_t integer(const node &n, const std::string &path, double min_value, double max_value) {
    const double v = number(n, path);
    if (v != std::floor(v))
        format_error("field '" + path + "' = " + n.text + " must be a whole number");
    if (v < min_value || v > max_value)
        format_error("field '" + path + "' = " + n.text + " is outside [" + text_of(min_value) +
                     ", " + text_of(max_value) + "]");
    return std::uint64_t(v);
}

const std::string &string(const node &n, const std::string &path) {
    expect_kind(n, node::string, path);
    return n.text;
}

}  // namespace json
}  // namespace flt
