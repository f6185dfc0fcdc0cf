// SPDX-License-Identifier: Apache-2.0
// lib/extraction/peak_kernels: the eight-column kernel against the
// one-column kernel, through the internal interface (compiled into this
// test; the shared library exports only flt_*). On random columns (lines
// thin and wide, faint and saturated, at the band's ends, over bright and
// sloping backgrounds, with a second peak beside them, with noise) every
// lane column_peaks measures must hold the bits column_peak gives for that
// column: the row and the shape. The lanes it leaves are column_peak's
// anyway, so the extractor's results do not depend on which kernel read a
// column; and the kernel built for the baseline x86-64 must give the bits
// of its AVX2 build, which the extractor runs where the CPU has it (Linux
// and Windows alike). Most lanes of a clean line must be measured, or the kernel would
// buy nothing (and this test could not fail).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>

#include <cmocka.h>
}

#include "extraction/peak_kernels.hpp"

namespace {

// The build of the kernels the extractor runs on this CPU.
const char *dispatched_build() {
#if FLT_PEAK_AVX2
    return flt::cpu_has_avx2() ? "AVX2" : "baseline";
#else
    return "baseline";
#endif
}

bool same_bits(double a, double b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// An odd derivative filter of half width h (a least-squares slope, which is
// the order-2 Savitzky-Golay derivative); the equality does not depend on
// the taps.
std::vector<float> slope_taps(int h) {
    std::vector<float> taps(std::size_t(2 * h + 1));
    double norm = 0;
    for (int j = 1; j <= h; ++j)
        norm += 2.0 * j * j;
    for (int j = -h; j <= h; ++j)
        taps[std::size_t(j + h)] = float(j / norm);
    return taps;
}

struct tally {
    std::size_t columns = 0, clean = 0, measured = 0, clean_measured = 0, mismatches = 0;
};

// One random frame of `width` columns and `height` rows; the band is rows
// [first, first + rows). Returns the tally of the comparison.
template <class Pixel>
void compare_frame(std::mt19937 &rng, std::uint32_t full_scale, int h, int max_width,
                   double min_peak, tally *t) {
    constexpr std::uint32_t width = 64, height = 200, first = 30, rows = 128;
    const std::size_t stride = width * sizeof(Pixel) + 16;  // padded rows, as cameras give
    std::vector<unsigned char> frame(stride * height);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::vector<bool> clean(width);
    // A line that wanders across the columns, as a laser line does.
    double centre = first + rows * (0.05 + 0.9 * unit(rng));
    const double slope = 0.6 * (unit(rng) - 0.5);
    for (std::uint32_t u = 0; u < width; ++u) {
        centre += slope + 0.3 * gauss(rng);
        // Mostly clean thin lines; the rest every case column_peak handles.
        const int kind = int(unit(rng) * 10);
        const double fs = double(full_scale);
        double sigma = 0.7 + 2.0 * unit(rng), amplitude = fs * (0.2 + 0.6 * unit(rng));
        double background = fs * 0.15 * unit(rng), gradient = 0, noise = 0.004 * fs;
        double second = 0, second_at = centre + 6 + 20 * unit(rng);
        double line_at = centre;
        switch (kind) {
            case 0:
                amplitude = fs * 3.0;
                break;  // saturated
            case 1:
                amplitude = fs * 0.02 * unit(rng);
                break;  // faint or none
            case 2:
                sigma = 4.0 + 10.0 * unit(rng);
                break;  // wide
            case 3:
                line_at = first + 4 * unit(rng);
                break;  // at the band's top end
            case 4:
                line_at = first + rows - 1 - 4 * unit(rng);
                break;  // bottom end
            case 5:
                second = amplitude * (0.5 + unit(rng));
                break;  // a second peak
            case 6:
                gradient = fs * 0.004 * (unit(rng) - 0.5);
                break;  // sloping background
            case 7:
                noise = 0.05 * fs;
                break;  // noisy
            default:
                break;
        }
        clean[u] = kind >= 8 && line_at > first + 30 && line_at < first + rows - 30;
        for (std::uint32_t v = 0; v < height; ++v) {
            const double a = (v - line_at) / sigma, b = (v - second_at) / 1.5;
            double value = background + gradient * (double(v) - line_at) +
                           amplitude * std::exp(-0.5 * a * a) + second * std::exp(-0.5 * b * b) +
                           noise * gauss(rng);
            value = std::min(std::max(std::round(value), 0.0), fs);
            const Pixel count = Pixel(value);
            std::memcpy(frame.data() + v * stride + u * sizeof(Pixel), &count, sizeof count);
        }
    }
    const std::vector<float> taps = slope_taps(h);
    const flt::peak_params p{h,
                             taps.data(),
                             std::uint32_t(std::ceil(min_peak * full_scale)),
                             full_scale,
                             max_width,
                             height,
                             long(3 * h / 2),
                             long(std::max(3 * h / 2, h + 3))};
    std::vector<std::uint16_t> best_value(width), best_row(width);
    flt::band_maximum<Pixel>(frame.data(), stride, width, first, rows, best_value.data(),
                             best_row.data());
    // The band maximum of the baseline build: the same (it is whole counts,
    // but the AVX2 build's blends must pick the same first maximum).
    std::vector<std::uint16_t> base_value(width), base_row(width);
    flt::band_maximum_base<Pixel>(frame.data(), stride, width, first, rows, base_value.data(),
                                  base_row.data());
    if ((base_value != best_value || base_row != best_row) && t->mismatches++ < 5)
        std::fprintf(stderr, "band maximum: the baseline build differs\n");
    for (std::uint32_t u0 = 0; u0 < width; u0 += flt::k_peak_lanes) {
        double block_rows[flt::k_peak_lanes];
        flt::peak_shape block_shape[flt::k_peak_lanes];
        const unsigned measured =
            flt::column_peaks<Pixel>(frame.data(), stride, u0, first, rows, &best_value[u0],
                                     &best_row[u0], p, block_rows, block_shape);
        // The kernel as compiled here, for the baseline x86-64 (SSE2): what
        // a CPU without AVX2 runs (column_peaks above took the AVX2 build
        // where the CPU has it).
        double plain_rows[flt::k_peak_lanes];
        flt::peak_shape plain_shape[flt::k_peak_lanes];
        const unsigned plain =
            flt::column_peaks_body<Pixel>(frame.data(), stride, u0, first, rows, &best_value[u0],
                                          &best_row[u0], p, plain_rows, plain_shape);
        if (plain != measured && t->mismatches++ < 5)
            std::fprintf(stderr, "columns %u..: lanes measured %#x, baseline build %#x\n", u0,
                         measured, plain);
        for (int l = 0; l < flt::k_peak_lanes; ++l) {
            const std::uint32_t u = u0 + std::uint32_t(l);
            if (((plain >> l) & 1u) &&
                !(same_bits(plain_rows[l], block_rows[l]) &&
                  same_bits(plain_shape[l].width, block_shape[l].width) &&
                  same_bits(plain_shape[l].skew, block_shape[l].skew) &&
                  same_bits(plain_shape[l].area, block_shape[l].area)) &&
                t->mismatches++ < 5)
                std::fprintf(stderr, "column %u: the baseline build reads it differently\n", u);
            bool suspect = false, saturated = false;
            flt::peak_shape shape{-1, -1, -1};
            const double row =
                flt::column_peak<Pixel>(frame.data(), stride, u, first, rows, best_value[u],
                                        best_row[u], p, true, &suspect, &saturated, &shape);
            ++t->columns;
            t->clean += clean[u];
            if (!((measured >> l) & 1u))
                continue;
            ++t->measured;
            t->clean_measured += clean[u];
            const bool same = same_bits(row, block_rows[l]) &&
                              same_bits(shape.width, block_shape[l].width) &&
                              same_bits(shape.skew, block_shape[l].skew) &&
                              same_bits(shape.area, block_shape[l].area) && !suspect && !saturated;
            if (!same && t->mismatches++ < 5)
                std::fprintf(stderr,
                             "column %u (h %d, max_width %d): column_peak %.17g width %.17g "
                             "skew %.17g area %.17g suspect %d saturated %d; column_peaks "
                             "%.17g width %.17g skew %.17g area %.17g\n",
                             u, h, max_width, row, shape.width, shape.skew, shape.area, suspect,
                             saturated, block_rows[l], block_shape[l].width, block_shape[l].skew,
                             block_shape[l].area);
        }
    }
}

template <class Pixel> void compare_many(std::uint32_t full_scale) {
    std::mt19937 rng(20261207u + full_scale);
    tally t, narrow;  // max_width at least the default's 12; narrower
    // Every window create allows (3..31 rows), the default max_width (12),
    // narrow ones that stop the walks and wide ones that let them leave the
    // tile, and three thresholds.
    const int max_widths[] = {2, 5, 12, 40};
    const double min_peaks[] = {0.0, 0.1, 0.3};
    for (int h = 1; h <= 15; ++h)
        for (int max_width : max_widths)
            for (double min_peak : min_peaks)
                for (int frame = 0; frame < 4; ++frame)
                    compare_frame<Pixel>(rng, full_scale, h, max_width, min_peak,
                                         max_width >= 12 ? &t : &narrow);
    std::printf("%u-count frames (%s build against the baseline): %zu columns, %zu measured by "
                "column_peaks (%zu of %zu clean lines), %zu differ; max_width < 12: %zu columns, "
                "%zu measured, %zu differ\n",
                full_scale, dispatched_build(), t.columns, t.measured, t.clean_measured, t.clean,
                t.mismatches, narrow.columns, narrow.measured, narrow.mismatches);
    assert_int_equal(t.mismatches + narrow.mismatches, 0);
    // Clean lines (thin, unsaturated, clear of the band's ends) are the
    // eight-column kernel's: 93-97 % of them per setting here (the rest a
    // noisy derivative crossing beyond row +- 3 or a walk past the tile);
    // at least 85 % over all. (A max_width of 2 or 5 makes most of these
    // lines too wide: column_peak's, and not counted.)
    assert_true(double(t.clean_measured) >= 0.85 * double(t.clean));
    assert_true(t.clean > 2000 && narrow.measured > 1000);
}

void mono8_columns_are_read_alike(void **state) {
    (void)state;
    compare_many<std::uint8_t>(255);
}

void mono16_columns_are_read_alike(void **state) {
    (void)state;
    compare_many<std::uint16_t>(4095);  // 12 bits, as Mono12 unpacked
    compare_many<std::uint16_t>(65535);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mono8_columns_are_read_alike),
        cmocka_unit_test(mono16_columns_are_read_alike),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
