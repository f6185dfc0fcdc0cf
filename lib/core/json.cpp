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

class parser {
  public:
    parser(const char *text, std::size_t length, const char *document)
        : p_(text), end_(text + length), document_(document) {}

    node parse_document() {
        skip_space();
        if (p_ == end_)
            format_error(std::string(document_) + " is empty");
        node root = parse_value("(top level)", 0);
        skip_space();
        if (p_ != end_)
            format_error("line " + std::to_string(line_) + ": unexpected text after the end of " +
                         document_);
        return root;
    }

  private:
    const char *p_, *end_;
    const char *document_;
    int line_ = 1;

    void skip_space() {
        while (p_ != end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) {
            if (*p_ == '\n')
                ++line_;
            ++p_;
        }
    }

    [[noreturn]] void truncated(const std::string &path) const {
        format_error(std::string(document_) + " ends early (truncated?) inside '" + path +
                     "' at line " + std::to_string(line_));
    }

    [[noreturn]] void unexpected(const std::string &path, const char *expected) const {
        const std::string found = p_ == end_ ? "end of file" : std::string("'") + *p_ + "'";
        format_error("line " + std::to_string(line_) + ": in '" + path + "' expected " + expected +
                     ", found " + found);
    }

    node parse_value(const std::string &path, int depth) {
        if (depth > 16)
            format_error("'" + path + "' is nested too deeply");
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
                std::string child;
                if (path != "(top level)") {
                    child = path;
                    child += '.';
                }
                child += key;
                node value = parse_value(child, depth + 1);
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
                n.items.push_back(
                    parse_value(path + "[" + std::to_string(n.items.size()) + "]", depth + 1));
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
        return n;
    }

    std::string parse_string(const std::string &path) {
        ++p_;  // opening quote
        std::string s;
        while (p_ != end_ && *p_ != '"') {
            if (*p_ == '\n')
                format_error("line " + std::to_string(line_) + ": a string in '" + path +
                             "' runs past the end of the line");
            if (*p_ == '\\')
                format_error("line " + std::to_string(line_) + ": escapes are not used in " +
                             document_ + " ('" + path + "')");
            s += *p_++;
        }
        if (p_ == end_)
            truncated(path);
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

node parse(const char *text, std::size_t length, const char *document) {
    return parser(text, length, document).parse_document();
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
