// SPDX-License-Identifier: Apache-2.0
// lib/core/number_text: the locale-proof formatter and parser, through the
// internal interface (compiled into this test; the shared library exports
// only flt_*). vformat_c must write exactly what the C library's snprintf
// writes in the "C" locale, for every conversion the library uses, under
// any process locale; parse_double must read exactly what strtod reads in
// the "C" locale, and nothing more.
#include <clocale>
#include <cmath>
#include <cstdarg>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

extern "C" {
#include <setjmp.h>

#include <cmocka.h>
}

#include "core/number_text.hpp"

namespace {

bool g_german = false;

// Formats with both, in the C locale for snprintf, and compares the texts
// and the returned lengths.
#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
void same(const char *format, ...) {
    char expected[512], got[512];
    va_list a, b;
    va_start(a, format);
    va_copy(b, a);
    std::setlocale(LC_ALL, "C");
    const int n_expected = std::vsnprintf(expected, sizeof expected, format, a);
    if (g_german)
        std::setlocale(LC_ALL, "de_DE.UTF-8");
    const int n_got = flt::vformat_c(got, sizeof got, format, b);
    va_end(b);
    va_end(a);
    if (n_got != n_expected || std::strcmp(got, expected) != 0) {
        print_message("format \"%s\": expected \"%s\" (%d), got \"%s\" (%d)\n", format, expected,
                      n_expected, got, n_got);
        fail();
    }
}

void conversions(void) {
    const double values[] = {0.0,         -0.0,  1.5,    -2.25, 1090.9090909090909, 1e-5,
                             123456789.0, 1e300, 5e-324, 0.1,   2.0 / 3.0,          100.0};
    for (double v : values) {
        same("%g|%G|%e|%E|%f|%F", v, v, v, v, v, v);
        same("%.17g|%.0f|%.1f|%.3e|%.0e|%.10g|%.0g", v, v, v, v, v, v, v);
        same("[%12.3f][%-12.3f][%+g][% g][%012.3f][%+012.2e][%-+9.1f]", v, v, v, v, v, v, v);
        same("[%*.*f][%-*g]", 10, 2, v, 9, v);
    }
    const double inf = std::numeric_limits<double>::infinity();
    same("%g %f %e %G %5.1f %-6g|", inf, -inf, inf, -inf, inf, inf);
    // Not floating: the C library's, with every length modifier we use.
    same("%d %i %5d %-5d| %05d %+d %ld %lld %hd %hhd", 42, -7, 3, 4, 12, 9, -123456789L,
         (long long)-9e15, (short)-3, (signed char)5);
    same("%u %lu %llu %zu %zd %x %X %#x %o %#o %08x", 3u, 4ul, 18446744073709551615ull,
         (std::size_t)77, (std::ptrdiff_t)-77, 255u, 255u, 255u, 8u, 8u, 0xbeefu);
    same("%s|%10s|%-10s|%.3s|%.*s|%c|%%|%5c", "text", "right", "left", "truncated", 2, "ab", 'x',
         'y');
    same("a literal with no conversion");
    same("%s: argument '%s' = %g is not finite (%zu of %zu)", "flt_x", "s", 0.5, (std::size_t)3,
         (std::size_t)9);
}

void formats_like_the_c_locale(void **) {
    g_german = false;
    conversions();
}

void formats_like_the_c_locale_under_german(void **) {
    if (!std::setlocale(LC_ALL, "de_DE.UTF-8")) {
        print_message("SKIPPED: the de_DE.UTF-8 locale is not installed\n");
        skip();
    }
    char probe[8];
    std::snprintf(probe, sizeof probe, "%.1f", 1.5);
    assert_string_equal(probe, "1,5");  // the locale has a decimal comma
    g_german = true;
    conversions();
    g_german = false;
    std::setlocale(LC_ALL, "C");
}

void truncates_like_snprintf(void **) {
    char out[8];
    std::memset(out, 'z', sizeof out);
    assert_int_equal(flt::format_c(out, 6, "%s=%.3f", "pi", 3.14159), 8);
    assert_string_equal(out, "pi=3.");
    assert_int_equal(out[6], 'z');  // nothing past the size
    assert_int_equal(flt::format_c(nullptr, 0, "%g %s", 1.5, "abc"), 7);
    assert_int_equal(flt::format_c(out, 1, "%g", 1.5), 3);
    assert_int_equal(out[0], '\0');
}

void shortest_text_reads_back_bit_identical(void **) {
    std::uint64_t state = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 100000; ++i) {
        state ^= state << 13, state ^= state >> 7, state ^= state << 17;
        double v;
        std::memcpy(&v, &state, sizeof v);
        if (!std::isfinite(v))
            continue;
        const std::string text = flt::format_double(v);
        double back = 0;
        assert_true(flt::parse_double(text, back));
        assert_memory_equal(&back, &v, sizeof v);
        assert_null(std::strchr(text.c_str(), ','));
    }
    assert_string_equal(flt::format_double(0.1).c_str(), "0.1");
    assert_string_equal(flt::format_double(6 / 0.0055).c_str(), "1090.909090909091");
    assert_string_equal(flt::format_double(-0.0).c_str(), "-0");
}

void parses_only_c_numbers(void **) {
    double v = 7;
    const char *good[] = {"0", "-1.5", "+2e-3", "1090.909090909091", "1E+300", ".5", "5.", "-0"};
    const double want[] = {0, -1.5, 2e-3, 1090.909090909091, 1e300, 0.5, 5.0, -0.0};
    for (std::size_t i = 0; i < sizeof good / sizeof good[0]; ++i) {
        assert_true(flt::parse_double(good[i], v));
        assert_memory_equal(&v, &want[i], sizeof v);
    }
    const char *bad[] = {"",   "1,5", " 1",  "1 ", "nan",   "inf",   "-inf", "0x10",
                         "1e", "+-1", "--1", "+",  "1e999", "1.5.2", "abc",  "1e-400"};
    for (const char *text : bad) {
        v = 7;
        if (flt::parse_double(text, v)) {
            print_message("'%s' was read as %g\n", text, v);
            fail();
        }
        assert_true(v == 7);  // unchanged
    }
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(formats_like_the_c_locale),
        cmocka_unit_test(formats_like_the_c_locale_under_german),
        cmocka_unit_test(truncates_like_snprintf),
        cmocka_unit_test(shortest_text_reads_back_bit_identical),
        cmocka_unit_test(parses_only_c_numbers),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
