// SPDX-License-Identifier: Apache-2.0
// The formula language of SwissKnife/Converter nodes: a precedence-climbing
// parser into a small expression tree, and its evaluation in integer or
// floating mode (see formula.hpp for the refusals and why).
#include "sources/genicam/formula.hpp"

#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>

#include "core/error.hpp"
#include "sources/genicam/text.hpp"

namespace flt::genicam {

namespace {

// Nesting limits: a formula nested deeper is refused while parsing, so that
// neither the parser nor the evaluation recurses without bound (a fuzzed
// description may hold anything).
constexpr int k_max_nesting = 100;
constexpr int k_max_tree_depth = 400;

bool ident_start(char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
}
bool ident_char(char c) {
    return ident_start(c) || (c >= '0' && c <= '9') || c == '.';
}

std::string upper(std::string_view s) {
    std::string u(s);
    for (char &c : u)
        if (c >= 'a' && c <= 'z')
            c = char(c - 'a' + 'A');
    return u;
}

std::string shown(const std::string &text) {
    return text.size() > 80 ? text.substr(0, 77) + "..." : text;
}

}  // namespace

struct formula::parser {
    formula &f;
    const std::string &s;
    std::size_t pos = 0;
    int nesting = 0;
    std::vector<int> depth;  // tree depth of each term

    [[noreturn]] void bad(const std::string &why) {
        throw error(FLT_ERR_FORMAT,
                    ("formula '" + shown(s) + "': " + why + " at column " + std::to_string(pos + 1))
                        .c_str());
    }
    void skip() {
        while (pos < s.size() &&
               (s[pos] == ' ' || s[pos] == '\t' || s[pos] == '\r' || s[pos] == '\n'))
            ++pos;
    }
    bool at(const char *token) {
        skip();
        const std::size_t n = std::strlen(token);
        return s.compare(pos, n, token) == 0;
    }
    int add(op what, int a = -1, int b = -1, int c = -1) {
        term t;
        t.what = what;
        t.a = a;
        t.b = b;
        t.c = c;
        int d = 0;
        for (int k : {a, b, c})
            if (k >= 0)
                d = std::max(d, depth[std::size_t(k)]);
        if (d + 1 > k_max_tree_depth)
            bad("more than " + std::to_string(k_max_tree_depth) + " operations deep");
        f.terms_.push_back(t);
        depth.push_back(d + 1);
        return int(f.terms_.size()) - 1;
    }
    struct nest {
        parser &p;
        explicit nest(parser &pp) : p(pp) {
            if (++p.nesting > k_max_nesting)
                p.bad("nested deeper than " + std::to_string(k_max_nesting) + " levels");
        }
        ~nest() { --p.nesting; }
    };

    int parse_all() {
        const int root = expression();
        skip();
        if (pos != s.size())
            bad(std::string("unexpected '") + s[pos] + "'");
        return root;
    }
    int expression() {  // ?: , right to left
        nest guard(*this);
        const int condition = binary(0);
        if (!at("?"))
            return condition;
        ++pos;
        const int yes = expression();
        if (!at(":"))
            bad("'?' without its ':'");
        ++pos;
        const int no = expression();
        return add(op::ternary, condition, yes, no);
    }
    // The binary operator at pos with its level (0 loosest), or false.
    bool peek_binary(op &what, int &level, std::size_t &length) {
        skip();
        struct entry {
            const char *token;
            op what;
            int level;
        };
        // Longest tokens first so that "<<" is not read as "<".
        static const entry table[] = {
            {"||", op::logical_or, 0},  {"&&", op::logical_and, 1},   {"<>", op::not_equal, 5},
            {"<=", op::less_equal, 6},  {">=", op::greater_equal, 6}, {"<<", op::shift_left, 7},
            {">>", op::shift_right, 7}, {"**", op::power, 10},        {"|", op::bit_or, 2},
            {"^", op::bit_xor, 3},      {"&", op::bit_and, 4},        {"=", op::equal, 5},
            {"<", op::less, 6},         {">", op::greater, 6},        {"+", op::add, 8},
            {"-", op::subtract, 8},     {"*", op::multiply, 9},       {"/", op::divide, 9},
            {"%", op::remainder, 9},
        };
        for (const entry &e : table) {
            const std::size_t n = std::strlen(e.token);
            if (s.compare(pos, n, e.token) == 0) {
                what = e.what;
                level = e.level;
                length = n;
                return true;
            }
        }
        return false;
    }
    int binary(int min_level) {
        int left = unary();
        for (;;) {
            op what;
            int level;
            std::size_t length;
            if (!peek_binary(what, level, length) || level < min_level)
                return left;
            pos += length;
            // ** groups right to left, everything else left to right.
            const int right = binary(what == op::power ? level : level + 1);
            left = add(what, left, right);
        }
    }
    int unary() {
        nest guard(*this);
        skip();
        if (pos < s.size() && (s[pos] == '-' || s[pos] == '+' || s[pos] == '~')) {
            const char c = s[pos++];
            const int operand = unary();
            return add(c == '-' ? op::negate : c == '+' ? op::plus : op::bit_not, operand);
        }
        return primary();
    }
    int primary() {
        skip();
        if (pos >= s.size())
            bad("an operand is missing");
        const char c = s[pos];
        if (c == '(') {
            ++pos;
            const int inner = expression();
            if (!at(")"))
                bad("'(' without its ')'");
            ++pos;
            return inner;
        }
        if ((c >= '0' && c <= '9') ||
            (c == '.' && pos + 1 < s.size() && s[pos + 1] >= '0' && s[pos + 1] <= '9'))
            return literal();
        if (ident_start(c))
            return identifier();
        bad(std::string("unexpected '") + c + "'");
    }
    int literal() {
        const std::size_t begin = pos;
        if (s.compare(pos, 2, "0x") == 0 || s.compare(pos, 2, "0X") == 0) {
            pos += 2;
            while (pos < s.size() && std::isxdigit(static_cast<unsigned char>(s[pos])))
                ++pos;
        } else {
            while (pos < s.size() && ((s[pos] >= '0' && s[pos] <= '9') || s[pos] == '.'))
                ++pos;
            if (pos < s.size() && (s[pos] == 'e' || s[pos] == 'E')) {
                std::size_t p = pos + 1;
                if (p < s.size() && (s[p] == '+' || s[p] == '-'))
                    ++p;
                if (p < s.size() && s[p] >= '0' && s[p] <= '9') {
                    pos = p;
                    while (pos < s.size() && s[pos] >= '0' && s[pos] <= '9')
                        ++pos;
                }
            }
        }
        const std::string_view token(s.data() + begin, pos - begin);
        if (pos < s.size() && ident_char(s[pos]))
            bad("a number runs into a name ('" + std::string(token) + s[pos] + "')");
        const int t = add(op::constant);
        std::int64_t i = 0;
        double d = 0.0;
        if (parse_int(token, i))
            f.terms_[std::size_t(t)].value = number::of(i);
        else if (token.find_first_of(".eE") != std::string_view::npos && parse_double(token, d))
            f.terms_[std::size_t(t)].value = number::of(d);
        else
            bad("'" + std::string(token) +
                "' is not a number (a decimal with a leading zero is "
                "octal to some readers and decimal to others)");
        return t;
    }
    int identifier() {
        const std::size_t begin = pos;
        while (pos < s.size() && ident_char(s[pos]))
            ++pos;
        const std::string name = s.substr(begin, pos - begin);
        if (at("(")) {
            const std::string u = upper(name);
            struct fn {
                const char *name;
                op what;
            };
            static const fn functions[] = {
                {"SGN", op::f_sgn},   {"NEG", op::f_neg},     {"ABS", op::f_abs},
                {"SIN", op::f_sin},   {"COS", op::f_cos},     {"TAN", op::f_tan},
                {"ASIN", op::f_asin}, {"ACOS", op::f_acos},   {"ATAN", op::f_atan},
                {"EXP", op::f_exp},   {"LN", op::f_ln},       {"LG", op::f_lg},
                {"SQRT", op::f_sqrt}, {"TRUNC", op::f_trunc}, {"FLOOR", op::f_floor},
                {"CEIL", op::f_ceil}, {"ROUND", op::f_round},
            };
            for (const fn &candidate : functions) {
                if (u != candidate.name)
                    continue;
                ++pos;  // '('
                const int argument = expression();
                if (candidate.what == op::f_round && at(",")) {
                    ++pos;
                    const int digits = expression();
                    if (!at(")"))
                        bad("ROUND( without its ')'");
                    ++pos;
                    return add(op::f_round_digits, argument, digits);
                }
                if (!at(")"))
                    bad(name + "( without its ')' (one argument)");
                ++pos;
                return add(candidate.what, argument);
            }
            bad("'" + name + "(' is no function of the GenICam formula language");
        }
        std::size_t id = 0;
        while (id < f.identifiers_.size() && f.identifiers_[id] != name)
            ++id;
        if (id == f.identifiers_.size())
            f.identifiers_.push_back(name);
        const int t = add(op::variable);
        f.terms_[std::size_t(t)].id = id;
        return t;
    }
};

formula::formula(const std::string &text) : text_(text) {
    parser p{*this, text_, 0, 0, {}};
    if (trim(text_).empty()) {
        p.bad("the formula is empty");
    }
    root_ = p.parse_all();
}

void formula::refuse(const std::string &why) const {
    throw error(FLT_ERR_NUMERIC, ("formula '" + shown(text_) + "': " + why).c_str());
}

namespace {

// The integer a double stands for, where one is needed; refuses a
// non-integral or out-of-range value (the standard's implementations
// disagree on truncation, rounding and wrapping).
bool integral(double d, std::int64_t &out) {
    if (!std::isfinite(d) || d != std::trunc(d) || d < -9223372036854775808.0 ||
        d >= 9223372036854775808.0)
        return false;
    out = std::int64_t(d);
    return true;
}

}  // namespace

number formula::evaluate(mode m, const std::function<number(std::size_t)> &variable) const {
    number r = eval(root_, m, variable);
    if (!r.is_int && !std::isfinite(r.d))
        refuse("the result is not a finite number");
    return r;
}

number formula::eval(int index, mode m, const std::function<number(std::size_t)> &variable) const {
    const term &t = terms_[std::size_t(index)];
    const bool int_mode = m == mode::integer;
    auto need_int = [&](const number &v, const char *what) -> std::int64_t {
        if (v.is_int)
            return v.i;
        std::int64_t i = 0;
        if (!integral(v.d, i))
            refuse(std::string(what) + " needs an integer, not " + format_double(v.d));
        return i;
    };
    // In integer mode every value is an integer: a variable is truncated
    // toward zero (an IntSwissKnife reading a Float), a literal or an
    // intermediate result must be integral.
    auto in_mode = [&](number v, const char *what) -> number {
        if (!int_mode || v.is_int)
            return v;
        if (!std::isfinite(v.d))
            refuse(std::string(what) + " is not a finite number");
        return number::of(need_int(v, what));
    };
    // The bitwise operators truncate a double toward zero: files rely on it
    // ("(TO / 1.024 + 0.5) & 0xFFFF" rounds), and implementations agree.
    auto bits = [&](const number &v, const char *what) -> std::int64_t {
        if (v.is_int)
            return v.i;
        if (!std::isfinite(v.d) || std::fabs(v.d) >= 9.2e18)
            refuse(std::string(what) + " of " + format_double(v.d) +
                   ", which has no integer value");
        return std::int64_t(std::trunc(v.d));
    };
    auto sub = [&](int k) {
        return eval(k, m, variable);
    };
    auto truth = [&](int k) {
        return need_int(sub(k), "a condition") != 0;
    };
    auto both_int = [](const number &a, const number &b) {
        return a.is_int && b.is_int;
    };
    auto finite = [&](double d, const char *what) {
        if (!std::isfinite(d))
            refuse(std::string(what) + " gives a value that is not a finite number");
        return number::of(d);
    };

    switch (t.what) {
        case op::constant:
            return in_mode(t.value, "an integer formula's constant");
        case op::variable: {
            number v = variable(t.id);
            if (int_mode && !v.is_int) {
                if (!std::isfinite(v.d) || std::fabs(v.d) >= 9.2e18)
                    refuse("variable '" + identifiers_[t.id] + "' = " + format_double(v.d) +
                           " has no integer value");
                v = number::of(std::int64_t(std::trunc(v.d)));
            }
            return v;
        }
        case op::ternary:
            return truth(t.a) ? sub(t.b) : sub(t.c);
        case op::logical_or:
            return number::of(std::int64_t(truth(t.a) || truth(t.b)));
        case op::logical_and:
            return number::of(std::int64_t(truth(t.a) && truth(t.b)));
        case op::negate:
        case op::f_neg: {
            const number v = sub(t.a);
            if (!v.is_int)
                return number::of(-v.d);
            if (v.i == std::numeric_limits<std::int64_t>::min())
                refuse("negating -2^63 overflows");
            return number::of(-v.i);
        }
        case op::plus:
            return sub(t.a);
        case op::bit_not:
            return number::of(~bits(sub(t.a), "~"));
        case op::f_sgn: {
            const double v = sub(t.a).as_double();
            return number::of(std::int64_t(v > 0 ? 1 : v < 0 ? -1 : 0));
        }
        case op::f_abs: {
            const number v = sub(t.a);
            if (!v.is_int)
                return number::of(std::fabs(v.d));
            if (v.i == std::numeric_limits<std::int64_t>::min())
                refuse("ABS(-2^63) overflows");
            return number::of(v.i < 0 ? -v.i : v.i);
        }
        case op::f_sin:
        case op::f_cos:
        case op::f_tan:
        case op::f_asin:
        case op::f_acos:
        case op::f_atan:
        case op::f_exp:
        case op::f_ln:
        case op::f_lg:
        case op::f_sqrt:
        case op::f_trunc:
        case op::f_floor:
        case op::f_ceil:
        case op::f_round: {
            const double x = sub(t.a).as_double();
            double y = 0.0;
            switch (t.what) {
                case op::f_sin:
                    y = std::sin(x);
                    break;
                case op::f_cos:
                    y = std::cos(x);
                    break;
                case op::f_tan:
                    y = std::tan(x);
                    break;
                case op::f_asin:
                    y = std::asin(x);
                    break;
                case op::f_acos:
                    y = std::acos(x);
                    break;
                case op::f_atan:
                    y = std::atan(x);
                    break;
                case op::f_exp:
                    y = std::exp(x);
                    break;
                case op::f_ln:
                    y = std::log(x);
                    break;
                case op::f_lg:
                    y = std::log10(x);
                    break;
                case op::f_sqrt:
                    y = std::sqrt(x);
                    break;
                case op::f_trunc:
                    y = std::trunc(x);
                    break;
                case op::f_floor:
                    y = std::floor(x);
                    break;
                case op::f_ceil:
                    y = std::ceil(x);
                    break;
                default:
                    y = std::round(x);
                    break;  // half away from zero
            }
            return in_mode(finite(y, "a function"), "a function's result");
        }
        case op::f_round_digits: {
            const double x = sub(t.a).as_double();
            const std::int64_t digits = need_int(sub(t.b), "ROUND's digits");
            if (digits < -15 || digits > 15)
                refuse("ROUND to " + std::to_string(digits) + " digits");
            const double scale = std::pow(10.0, double(digits));
            return in_mode(finite(std::round(x * scale) / scale, "ROUND"), "ROUND's result");
        }
        default:
            break;
    }

    // Binary operators.
    const number a = sub(t.a), b = sub(t.b);
    switch (t.what) {
        case op::bit_or:
            return number::of(bits(a, "|") | bits(b, "|"));
        case op::bit_xor:
            return number::of(bits(a, "^") ^ bits(b, "^"));
        case op::bit_and:
            return number::of(bits(a, "&") & bits(b, "&"));
        case op::shift_left:
        case op::shift_right: {
            const std::int64_t x = bits(a, "a shift"), n = need_int(b, "a shift's bit count");
            if (n < 0 || n > 63)
                refuse("a shift by " + std::to_string(n) + " bits");
            if (t.what == op::shift_left) {
                // Integer overflow is refused: 1 << 63 does not fit a signed
                // 64-bit value (it would wrap to its most negative one), nor
                // does any shift that pushes bits out or into the sign.
                const std::int64_t shifted = std::int64_t(std::uint64_t(x) << n);
                if ((shifted >> n) != x)
                    refuse(std::to_string(x) + " << " + std::to_string(n) +
                           " overflows a signed 64-bit integer");
                return number::of(shifted);
            }
            return number::of(x >> n);  // arithmetic: sign bits come in
        }
        case op::equal:
        case op::not_equal:
        case op::less:
        case op::greater:
        case op::less_equal:
        case op::greater_equal: {
            int order;  // -1, 0, 1
            if (both_int(a, b)) {
                order = a.i < b.i ? -1 : a.i > b.i ? 1 : 0;
            } else {
                const double x = a.as_double(), y = b.as_double();
                if (!(x == x) || !(y == y))
                    refuse("a comparison with a value that is not a number");
                order = x < y ? -1 : x > y ? 1 : 0;
            }
            bool r = false;
            switch (t.what) {
                case op::equal:
                    r = order == 0;
                    break;
                case op::not_equal:
                    r = order != 0;
                    break;
                case op::less:
                    r = order < 0;
                    break;
                case op::greater:
                    r = order > 0;
                    break;
                case op::less_equal:
                    r = order <= 0;
                    break;
                default:
                    r = order >= 0;
                    break;
            }
            return number::of(std::int64_t(r));
        }
        case op::add:
        case op::subtract:
        case op::multiply: {
            if (both_int(a, b)) {
                std::int64_t r = 0;
                bool overflow = false;
                if (t.what == op::add)
                    overflow = __builtin_add_overflow(a.i, b.i, &r);
                else if (t.what == op::subtract)
                    overflow = __builtin_sub_overflow(a.i, b.i, &r);
                else
                    overflow = __builtin_mul_overflow(a.i, b.i, &r);
                if (overflow)
                    refuse("64-bit integer overflow");
                return number::of(r);
            }
            const double x = a.as_double(), y = b.as_double();
            const double r = t.what == op::add ? x + y : t.what == op::subtract ? x - y : x * y;
            return in_mode(finite(r, "+, - or *"), "an intermediate result");
        }
        case op::divide: {
            if (int_mode) {
                // Both are integers here; C division truncates toward zero.
                if (b.i == 0)
                    refuse("division by zero");
                if (a.i == std::numeric_limits<std::int64_t>::min() && b.i == -1)
                    refuse("64-bit integer overflow");
                return number::of(a.i / b.i);
            }
            const double y = b.as_double();
            if (y == 0.0)
                refuse("division by zero");
            return finite(a.as_double() / y, "/");
        }
        case op::remainder: {
            const std::int64_t x = need_int(a, "%"), y = need_int(b, "%");
            if (y == 0)
                refuse("remainder of a division by zero");
            if (x == std::numeric_limits<std::int64_t>::min() && y == -1)
                return number::of(std::int64_t(0));
            return number::of(x % y);
        }
        case op::power: {
            if (int_mode) {
                std::int64_t base = a.i, e = b.i, r = 1;
                if (e < 0) {
                    if (base == 1 || base == -1)
                        return number::of(std::int64_t(e % 2 == 0 ? 1 : base));
                    refuse("an integer power with a negative exponent is not an integer");
                }
                while (e > 0) {
                    if ((e & 1) && __builtin_mul_overflow(r, base, &r))
                        refuse("64-bit integer overflow in **");
                    e >>= 1;
                    if (e > 0 && __builtin_mul_overflow(base, base, &base))
                        refuse("64-bit integer overflow in **");
                }
                return number::of(r);
            }
            return finite(std::pow(a.as_double(), b.as_double()), "**");
        }
        default:
            break;
    }
    refuse("an operation this evaluator does not know");  // unreachable
}

}  // namespace flt::genicam
