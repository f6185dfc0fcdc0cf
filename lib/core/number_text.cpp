// SPDX-License-Identifier: Apache-2.0
#include "core/number_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <system_error>

namespace flt {

std::string format_double(double v) {
    // 32 bytes hold the longest shortest-round-trip double
    // ("-2.2250738585072014e-308" is 24).
    char buffer[32];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, r.ptr);
}

bool parse_double(std::string_view text, double &out) {
    if (text.empty())
        return false;
    std::string_view t = text;
    // from_chars takes '-' but not '+'; a '+' must be followed by the digits.
    if (t[0] == '+') {
        t.remove_prefix(1);
        if (t.empty() || t[0] == '-' || t[0] == '+')
            return false;
    }
    // from_chars would also read "nan", "inf" and (with chars_format::hex)
    // hexadecimal; none of them is a number in our files.
    for (char c : t)
        if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
            return false;
    double v = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v, std::chars_format::general);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
        return false;
    out = v;
    return true;
}

namespace {

// Appends to a caller's buffer the way vsnprintf does: writes what fits,
// counts everything.
struct sink {
    char *out;
    std::size_t size;
    std::size_t length = 0;

    void put(const char *s, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i, ++length)
            if (length + 1 < size)
                out[length] = s[i];
    }
    void pad(char c, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i, ++length)
            if (length + 1 < size)
                out[length] = c;
    }
    // Room for snprintf to write in place (it NUL-terminates what fits).
    char *here() const { return length + 1 < size ? out + length : nullptr; }
    std::size_t room() const { return length + 1 < size ? size - length : 0; }
    void finish() const {
        if (size > 0)
            out[length < size ? length : size - 1] = '\0';
    }
};

struct spec {
    bool left = false, plus = false, space = false, alt = false, zero = false;
    int width = 0;
    int precision = -1;  // -1: none given
    char length[3] = {0, 0, 0};
    char conversion = 0;
};

// One floating conversion, written with to_chars ('.' whatever the locale).
void put_double(sink &s, const spec &f, double v) {
    char digits[400];  // %.17f of 1e308 is 327 characters
    const char c = f.conversion;
    const bool upper = c >= 'A' && c <= 'Z';
    const char lower = char(upper ? c - 'A' + 'a' : c);
    const int precision = f.precision >= 0 ? f.precision : 6;
    char *first = digits, *last = digits + sizeof digits;
    char sign = 0;
    if (std::signbit(v)) {
        sign = '-';
        v = -v;
    } else if (f.plus) {
        sign = '+';
    } else if (f.space) {
        sign = ' ';
    }
    std::to_chars_result r{};
    if (std::isnan(v) || std::isinf(v)) {
        const char *word = std::isnan(v) ? "nan" : "inf";
        std::memcpy(first, word, 3);
        r.ptr = first + 3;
        r.ec = std::errc();
    } else if (lower == 'f') {
        r = std::to_chars(first, last, v, std::chars_format::fixed, precision);
    } else if (lower == 'e') {
        r = std::to_chars(first, last, v, std::chars_format::scientific, precision);
    } else if (lower == 'g') {
        r = std::to_chars(first, last, v, std::chars_format::general, precision);
    } else {  // 'a': printf writes the "0x" that to_chars leaves out
        std::memcpy(first, "0x", 2);
        first += 2;
        r = f.precision >= 0 ? std::to_chars(first, last, v, std::chars_format::hex, precision)
                             : std::to_chars(first, last, v, std::chars_format::hex);
        first = digits;
    }
    if (r.ec != std::errc()) {  // cannot happen with 400 bytes; say so rather than cut
        static const char fallback[] = "(number)";
        std::memcpy(digits, fallback, sizeof fallback);
        r.ptr = digits + sizeof fallback - 1;
    }
    std::size_t n = std::size_t(r.ptr - digits);
    if (upper)
        for (std::size_t i = 0; i < n; ++i)
            if (digits[i] >= 'a' && digits[i] <= 'z')
                digits[i] = char(digits[i] - 'a' + 'A');
    const std::size_t total = n + (sign ? 1 : 0);
    const std::size_t fill = f.width > 0 && std::size_t(f.width) > total ? f.width - total : 0;
    const bool zeros = f.zero && !f.left && std::isfinite(v);
    if (!f.left && !zeros)
        s.pad(' ', fill);
    if (sign)
        s.put(&sign, 1);
    if (zeros) {
        // "0x" stays in front of the zeros of a %0a.
        const std::size_t prefix = lower == 'a' ? 2 : 0;
        s.put(digits, prefix);
        s.pad('0', fill);
        s.put(digits + prefix, n - prefix);
    } else {
        s.put(digits, n);
    }
    if (f.left)
        s.pad(' ', fill);
}

// Any other conversion: the C library's snprintf with the one argument.
template <class T> void put_other(sink &s, const spec &f, T value) {
    char format[32];
    std::size_t k = 0;
    format[k++] = '%';
    if (f.left)
        format[k++] = '-';
    if (f.plus)
        format[k++] = '+';
    if (f.space)
        format[k++] = ' ';
    if (f.alt)
        format[k++] = '#';
    if (f.zero)
        format[k++] = '0';
    format[k++] = '*';
    if (f.precision >= 0) {
        format[k++] = '.';
        format[k++] = '*';
    }
    for (char c : f.length)
        if (c)
            format[k++] = c;
    format[k++] = f.conversion;
    format[k] = '\0';
    int n = 0;
    // The format is built here from a checked conversion, not the caller's text.
    if (f.precision >= 0)
        n = std::snprintf(s.here(), s.room(), format, f.width, f.precision, value);  // NOLINT
    else
        n = std::snprintf(s.here(), s.room(), format, f.width, value);  // NOLINT
    if (n > 0)
        s.length += std::size_t(n);
}

}  // namespace

// NOLINTNEXTLINE(readability-non-const-parameter): written through the sink
int vformat_c(char *out, std::size_t size, const char *format, va_list args) {
    sink s{out, size};
    const char *p = format;
    while (*p) {
        if (*p != '%') {
            const char *q = std::strchr(p, '%');
            const std::size_t n = q ? std::size_t(q - p) : std::strlen(p);
            s.put(p, n);
            p += n;
            continue;
        }
        ++p;
        if (*p == '%') {
            s.put("%", 1);
            ++p;
            continue;
        }
        spec f;
        for (;; ++p) {
            if (*p == '-')
                f.left = true;
            else if (*p == '+')
                f.plus = true;
            else if (*p == ' ')
                f.space = true;
            else if (*p == '#')
                f.alt = true;
            else if (*p == '0')
                f.zero = true;
            else
                break;
        }
        if (*p == '*') {
            f.width = va_arg(args, int);
            if (f.width < 0) {
                f.left = true;
                f.width = -f.width;
            }
            ++p;
        } else {
            while (*p >= '0' && *p <= '9')
                f.width = f.width * 10 + (*p++ - '0');
        }
        if (*p == '.') {
            ++p;
            f.precision = 0;
            if (*p == '*') {
                f.precision = va_arg(args, int);
                if (f.precision < 0)
                    f.precision = -1;
                ++p;
            } else {
                while (*p >= '0' && *p <= '9')
                    f.precision = f.precision * 10 + (*p++ - '0');
            }
        }
        int k = 0;
        while (k < 2 &&
               (*p == 'h' || *p == 'l' || *p == 'j' || *p == 'z' || *p == 't' || *p == 'L')) {
            f.length[k++] = *p++;
        }
        f.conversion = *p;
        if (!*p)
            break;
        ++p;
        const char *len = f.length;
        const bool ll = std::strcmp(len, "ll") == 0, l = std::strcmp(len, "l") == 0;
        switch (f.conversion) {
            case 'e':
            case 'E':
            case 'f':
            case 'F':
            case 'g':
            case 'G':
            case 'a':
            case 'A':
                put_double(
                    s, f, len[0] == 'L' ? double(va_arg(args, long double)) : va_arg(args, double));
                break;
            case 'd':
            case 'i':
                // NOLINTBEGIN(bugprone-branch-clone): the same type on LP64 Linux,
                // not on LLP64 Windows (long is 32 bits); va_arg needs the exact one.
                if (ll)
                    put_other(s, f, va_arg(args, long long));
                else if (l)
                    put_other(s, f, va_arg(args, long));
                else if (len[0] == 'j')
                    put_other(s, f, va_arg(args, std::intmax_t));
                else if (len[0] == 'z' || len[0] == 't')
                    put_other(s, f, va_arg(args, std::ptrdiff_t));
                else
                    put_other(s, f, va_arg(args, int));  // hh, h promote to int
                // NOLINTEND(bugprone-branch-clone)
                break;
            case 'u':
            case 'o':
            case 'x':
            case 'X':
                // NOLINTBEGIN(bugprone-branch-clone): as above
                if (ll)
                    put_other(s, f, va_arg(args, unsigned long long));
                else if (l)
                    put_other(s, f, va_arg(args, unsigned long));
                else if (len[0] == 'j')
                    put_other(s, f, va_arg(args, std::uintmax_t));
                else if (len[0] == 'z' || len[0] == 't')
                    put_other(s, f, va_arg(args, std::size_t));
                else
                    put_other(s, f, va_arg(args, unsigned));
                // NOLINTEND(bugprone-branch-clone)
                break;
            case 'c':
                put_other(s, f, va_arg(args, int));
                break;
            case 's':
                put_other(s, f, va_arg(args, const char *));
                break;
            case 'p':
                put_other(s, f, va_arg(args, void *));
                break;
            default:
                // %n and unknown conversions: written as they stand.
                s.put("%", 1);
                s.put(&f.conversion, 1);
                break;
        }
    }
    s.finish();
    return int(s.length);
}

// NOLINTNEXTLINE(cert-dcl50-cpp): printf-style on purpose, the format attribute checks it
int format_c(char *out, std::size_t size, const char *format, ...) {
    va_list args;
    va_start(args, format);
    const int n = vformat_c(out, size, format, args);
    va_end(args);
    return n;
}

}  // namespace flt
