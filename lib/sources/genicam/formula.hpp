// SPDX-License-Identifier: Apache-2.0
// Internal: the formulas of SwissKnife, IntSwissKnife, Converter and
// IntConverter nodes (the GenICam standard's expression language).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace flt::genicam {

// A value inside a formula: a 64-bit integer or a double. Integer operands
// stay integers where the result is exact (+ - * and comparisons); '/' and
// the transcendental functions give doubles (in floating mode).
struct number {
    bool is_int = true;
    std::int64_t i = 0;
    double d = 0.0;
    static number of(std::int64_t v) {
        number n;
        n.i = v;
        return n;
    }
    static number of(double v) {
        number n;
        n.is_int = false;
        n.d = v;
        return n;
    }
    double as_double() const { return is_int ? double(i) : d; }
};

// One parsed formula.
//
// Operators, loosest first: ?: (right to left), ||, &&, |, ^, &, = <>,
// < > <= >=, << >>, + -, * / %, ** (right to left), unary - + ~; functions
// SGN NEG ABS SIN COS TAN ASIN ACOS ATAN EXP LN LG SQRT TRUNC FLOOR CEIL
// ROUND(x) ROUND(x, digits) (names in any case); numbers in decimal, hex
// (0x...) or with a fraction/exponent; identifiers of letters, digits, '_'
// and '.'. The node map gives identifiers their values (pVariable,
// Constant, Expression, TO/FROM, then the constants PI and E).
//
// Where implementations of the standard differ, the evaluation refuses
// instead of choosing: a non-integral double where an integer is needed
// (%, a truth value, a shift count, an integer formula's literal or
// intermediate), a shift outside 0..63, integer overflow, division by
// zero, a non-finite result. Refusals throw flt::error(FLT_ERR_NUMERIC).
// The bitwise operators truncate doubles toward zero, as every
// implementation does and files rely on ("(TO / 1.024 + 0.5) & 0xFFFF").
class formula {
  public:
    enum class mode { integer, floating };

    // Throws flt::error(FLT_ERR_FORMAT) naming the problem and its column.
    explicit formula(const std::string &text);

    const std::string &text() const { return text_; }
    // The distinct identifiers the formula reads, in order of appearance.
    const std::vector<std::string> &identifiers() const { return identifiers_; }

    // `variable(k)` gives identifiers()[k]'s value (it may throw).
    number evaluate(mode m, const std::function<number(std::size_t)> &variable) const;

  private:
    enum class op : std::uint8_t {
        constant,
        variable,
        ternary,
        logical_or,
        logical_and,
        bit_or,
        bit_xor,
        bit_and,
        equal,
        not_equal,
        less,
        greater,
        less_equal,
        greater_equal,
        shift_left,
        shift_right,
        add,
        subtract,
        multiply,
        divide,
        remainder,
        power,
        negate,
        plus,
        bit_not,
        f_sgn,
        f_neg,
        f_abs,
        f_sin,
        f_cos,
        f_tan,
        f_asin,
        f_acos,
        f_atan,
        f_exp,
        f_ln,
        f_lg,
        f_sqrt,
        f_trunc,
        f_floor,
        f_ceil,
        f_round,
        f_round_digits,
    };
    struct term {
        op what = op::constant;
        int a = -1, b = -1, c = -1;  // operands (terms_ indices)
        number value;                // op::constant
        std::size_t id = 0;          // op::variable
    };
    struct parser;
    number eval(int index, mode m, const std::function<number(std::size_t)> &variable) const;
    [[noreturn]] void refuse(const std::string &why) const;

    std::string text_;
    std::vector<std::string> identifiers_;
    std::vector<term> terms_;
    int root_ = -1;
};

}  // namespace flt::genicam
