// SPDX-License-Identifier: Apache-2.0
/*
 * The extractor on real photos of laser lines on flat boards, read from the
 * folder FLT_EXTERNAL_DATA names (the photos may not be redistributed and
 * are not part of the repository; each test skips with a message where they
 * are absent):
 *
 *   laser_images/zhaocongyang_structured_LineLight_calib/light_picture/
 *       light0..11.jpg: 1920 x 1080 colour photos of a red line laser on a
 *       flat circle-grid board, the line saturated over most of its length;
 *       Parameters.xml beside the folder: the camera's intrinsics and
 *       distortion (OpenCV's file format).
 *   laser_images/srv_desktop_3d_scanner/bcap1..6.jpg: webcam photos of a
 *       thin, well-exposed green line laser, vertical in the image (the
 *       test transposes them so that the line runs along rows, as the
 *       extractor expects: it searches each column for the line's row).
 *
 * and four further sets, found after the extractor was tuned, read from
 * the folder FLT_FURTHER_PHOTOS names (tests/further_photos lists and
 * fetches them; test_further_* below describe each).
 *
 * What is measured, per set (docs/sensor.md, "Real photos", has the
 * figures):
 *   1. Kept: of the columns the line crosses (found independently of the
 *      extractor: find_line()), the share where the extractor's peak
 *      (flt_extractor_peaks) lies on the line; "wrong" where it lies off
 *      it. Bounds: kept >= 80 %, wrong <= 1 % (the further sets:
 *      check_further()).
 *   2. Straightness: the board is flat, so the line's centres lie on a
 *      straight line in the undistorted image. The RMS distance of the
 *      extractor's centres from their least-squares line, against that of
 *      a plain centroid (centroid()) and a Gaussian 3-point fit
 *      (gaussian3()) on the same columns. Bound: extractor <= centroid.
 *      The green set has no intrinsics and its line bends over the frame:
 *      there the model is a cubic (test_green_exposed).
 *
 * The frames: the extractor takes monochrome frames (Mono8..Mono16), and
 * the library's image source refuses colour files, so the test decodes the
 * JPEG files itself with libjpeg (a C library; where the build has none,
 * as in the Windows cross build, the tests skip with a message), and the
 * BMP files of one further set with load_bmp(), and makes
 * one Mono8 frame of each photo: the green line's own channel (a
 * band-pass filter in front of a monochrome camera sees about that), and
 * for the saturated red line the grey image, not the red channel
 * (test_red_saturated says why).
 *
 * Run `ctest --preset dev -R real_laser -V` to see the figures.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "external_data.h"
#include "flatline/flatline.h"

#ifdef FLT_HAVE_JPEG
/* jpeglib.h needs size_t and FILE declared first (stddef.h, stdio.h). */
#  include <jpeglib.h>
#endif

#define ZHAO_DIR  "laser_images/zhaocongyang_structured_LineLight_calib"
#define GREEN_DIR "laser_images/srv_desktop_3d_scanner"

/* ---------------------------------------------------------------------- */
/* A decoded photo                                                        */
/* ---------------------------------------------------------------------- */

typedef struct photo {
    uint32_t width, height; /* of the Mono8 frame (after a transpose) */
    uint8_t *pixels;        /* width * height, rows contiguous */
} photo;

/* The Mono8 frame made of a colour photo: one channel, or the grey level
 * of ITU-R BT.601 (0.299 R + 0.587 G + 0.114 B, what OpenCV's and most
 * decoders' grey conversion gives). */
enum { RED = 0, GREEN = 1, GREY = 3 };

#ifdef FLT_HAVE_JPEG
typedef struct jpeg_fail {
    struct jpeg_error_mgr mgr;
    jmp_buf jump;
} jpeg_fail;

static void jpeg_fail_exit(j_common_ptr cinfo) {
    jpeg_fail *f = (jpeg_fail *)cinfo->err;
    char message[JMSG_LENGTH_MAX];
    (*cinfo->err->format_message)(cinfo, message);
    fprintf(stderr, "libjpeg: %s\n", message);
    longjmp(f->jump, 1);
}

/* Decodes `path` into a Mono8 frame, transposed when `transpose` is set:
 * colour channel `channel` (RED, GREEN) or the grey conversion (GREY). 0 on
 * success. */
static int load_channel(const char *path, int channel, int transpose, photo *out) {
    memset(out, 0, sizeof *out);
    FILE *file = fopen(path, "rb");
    if (file == NULL)
        return -1;
    struct jpeg_decompress_struct cinfo;
    jpeg_fail fail;
    uint8_t *volatile row = NULL;
    uint8_t *volatile pixels = NULL;
    cinfo.err = jpeg_std_error(&fail.mgr);
    fail.mgr.error_exit = jpeg_fail_exit;
    if (setjmp(fail.jump)) {
        jpeg_destroy_decompress(&cinfo);
        fclose(file);
        free(row);
        free(pixels);
        return -1;
    }
    jpeg_create_decompress(&cinfo);
    jpeg_stdio_src(&cinfo, file);
    jpeg_read_header(&cinfo, TRUE);
    cinfo.out_color_space = JCS_RGB;
    jpeg_start_decompress(&cinfo);
    const uint32_t w = cinfo.output_width, h = cinfo.output_height;
    row = malloc((size_t)w * 3);
    pixels = malloc((size_t)w * h);
    if (row == NULL || pixels == NULL || cinfo.output_components != 3)
        longjmp(fail.jump, 1);
    while (cinfo.output_scanline < h) {
        const uint32_t v = cinfo.output_scanline;
        JSAMPROW rows[1] = {row};
        jpeg_read_scanlines(&cinfo, rows, 1);
        for (uint32_t u = 0; u < w; ++u) {
            const uint8_t *rgb = row + 3 * (size_t)u;
            const uint8_t value =
                channel < 3 ? rgb[channel]
                            : (uint8_t)((299 * rgb[0] + 587 * rgb[1] + 114 * rgb[2] + 500) / 1000);
            if (transpose)
                pixels[(size_t)u * h + v] = value; /* column u becomes row u */
            else
                pixels[(size_t)v * w + u] = value;
        }
    }
    jpeg_finish_decompress(&cinfo);
    jpeg_destroy_decompress(&cinfo);
    fclose(file);
    free(row);
    out->width = transpose ? h : w;
    out->height = transpose ? w : h;
    out->pixels = pixels;
    return 0;
}
#endif

/* Little-endian fields of a BMP header. */
static uint32_t le32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint16_t le16(const uint8_t *p) {
    return (uint16_t)(p[0] | p[1] << 8);
}

/* Decodes an uncompressed 8-bit palette BMP (what monochrome cameras'
 * software writes) into a Mono8 frame, each pixel its palette entry's grey
 * level (ITU-R BT.601), transposed when `transpose` is set. Any other kind
 * of BMP, a header of more than 124 bytes, or sizes beyond 16384 px a
 * side or past the file's end, is refused: -1 (nothing is allocated before
 * the sizes are checked). 0 on success. */
static int load_bmp(const char *path, int transpose, photo *out) {
    memset(out, 0, sizeof *out);
    FILE *file = fopen(path, "rb");
    if (file == NULL)
        return -1;
    uint8_t head[54], palette[1024];
    int ok = fread(head, 1, sizeof head, file) == sizeof head && head[0] == 'B' && head[1] == 'M';
    const uint32_t offset = ok ? le32(head + 10) : 0, info = ok ? le32(head + 14) : 0;
    const int32_t w = ok ? (int32_t)le32(head + 18) : 0,
                  h_signed = ok ? (int32_t)le32(head + 22) : 0;
    const uint32_t colours = ok ? le32(head + 46) : 0;
    const uint32_t h = h_signed < 0 ? (uint32_t)(-(int64_t)h_signed) : (uint32_t)h_signed;
    ok = ok && info >= 40 && info <= 124 && le16(head + 26) == 1 && le16(head + 28) == 8 &&
         le32(head + 30) == 0 && w > 0 && w <= 16384 && h > 0 && h <= 16384 && colours <= 256;
    const uint32_t entries = colours ? colours : 256;
    ok = ok && offset >= 14 + info + 4 * entries && fseek(file, 14L + (long)info, SEEK_SET) == 0 &&
         fread(palette, 4, entries, file) == entries;
    const size_t stride = ((size_t)w + 3) / 4 * 4;
    uint8_t *row = ok ? malloc(stride) : NULL;
    uint8_t *pixels = ok ? malloc((size_t)w * h) : NULL;
    ok = ok && row != NULL && pixels != NULL && fseek(file, (long)offset, SEEK_SET) == 0;
    uint8_t grey[256] = {0};
    for (size_t i = 0; ok && i < entries; ++i) /* entries are B, G, R, 0 */
        grey[i] = (uint8_t)((299 * palette[4 * i + 2] + 587 * palette[4 * i + 1] +
                             114 * palette[4 * i] + 500) /
                            1000);
    for (uint32_t k = 0; ok && k < h; ++k) {
        ok = fread(row, 1, stride, file) == stride;
        const uint32_t v = h_signed < 0 ? k : h - 1 - k; /* positive height: bottom row first */
        for (uint32_t u = 0; ok && u < (uint32_t)w; ++u) {
            if (transpose)
                pixels[(size_t)u * h + v] = grey[row[u]];
            else
                pixels[(size_t)v * (uint32_t)w + u] = grey[row[u]];
        }
    }
    fclose(file);
    free(row);
    if (!ok) {
        free(pixels);
        return -1;
    }
    out->width = transpose ? h : (uint32_t)w;
    out->height = transpose ? (uint32_t)w : h;
    out->pixels = pixels;
    return 0;
}

/* A photo: BMP by its name, else JPEG. */
static int load_photo(const char *path, int channel, int transpose, photo *out) {
    const size_t n = strlen(path);
    if (n > 4 && strcmp(path + n - 4, ".bmp") == 0)
        return load_bmp(path, transpose, out);
#ifdef FLT_HAVE_JPEG
    return load_channel(path, channel, transpose, out);
#else
    (void)channel;
    return -1;
#endif
}

/* ---------------------------------------------------------------------- */
/* The columns the line crosses, independently of the extractor          */
/* ---------------------------------------------------------------------- */

/* The line's background in a column: the median of the rows within this
 * reach of its brightest pixel. The line with its glow covers up to 20
 * rows of these 65; the reach is local enough that a line crossing a black
 * circle of the board (40 rows tall) is measured against the black, not
 * against the white board above and below. */
#define BACKGROUND_REACH 32

/* Per column of rows [first, first + rows): the brightest row, the
 * maximum and the background (BACKGROUND_REACH). The brightest row of a
 * saturated line is the middle of its plateau: the rows from the first
 * maximum on that stay within 8 levels of it, up and down, across dips of
 * up to 2 rows (JPEG ripples there). */
typedef struct column_stats {
    double row; /* px */
    double max; /* grey levels */
    double median;
} column_stats;

static void stats_of(const photo *p, uint32_t first, uint32_t rows, column_stats *out) {
    unsigned histogram[256];
    const size_t w = p->width;
    for (uint32_t u = 0; u < p->width; ++u) {
        unsigned max = 0;
        uint32_t at = first;
        for (uint32_t v = first; v < first + rows; ++v) {
            const unsigned g = p->pixels[(size_t)v * w + u];
            if (g > max) {
                max = g;
                at = v;
            }
        }
        uint32_t lo = at, hi = at;
        for (uint32_t v = at, dip = 0; v > first && dip <= 2;) {
            --v;
            if (p->pixels[(size_t)v * w + u] + 8u >= max) {
                lo = v;
                dip = 0;
            } else {
                ++dip;
            }
        }
        for (uint32_t v = at, dip = 0; v + 1 < first + rows && dip <= 2;) {
            ++v;
            if (p->pixels[(size_t)v * w + u] + 8u >= max) {
                hi = v;
                dip = 0;
            } else {
                ++dip;
            }
        }
        /* The background: the median of the rows within BACKGROUND_REACH
         * of the line, in the band. */
        const uint32_t b_lo = at < first + BACKGROUND_REACH ? first : at - BACKGROUND_REACH;
        const uint32_t b_hi =
            at + BACKGROUND_REACH >= first + rows ? first + rows - 1 : at + BACKGROUND_REACH;
        memset(histogram, 0, sizeof histogram);
        for (uint32_t v = b_lo; v <= b_hi; ++v)
            ++histogram[p->pixels[(size_t)v * w + u]];
        unsigned seen = 0, median = 0;
        for (; median < 256; ++median) {
            seen += histogram[median];
            if (2 * seen >= b_hi - b_lo + 1)
                break;
        }
        out[u].row = 0.5 * (lo + hi);
        out[u].max = max;
        out[u].median = median;
    }
}

/* ---------------------------------------------------------------------- */
/* The camera of the red set: Parameters.xml                               */
/* ---------------------------------------------------------------------- */

/* A decimal number (OpenCV writes "1.1444e+03", "0.", "-2.96e-02"), parsed
 * by hand so that the result cannot depend on the process's locale. Returns
 * the character after it, or NULL when there is no number at p. */
static const char *parse_number(const char *p, double *out) {
    while (*p == ' ' || *p == '\n' || *p == '\r' || *p == '\t')
        ++p;
    int negative = 0, digits = 0, exponent = 0;
    if (*p == '-' || *p == '+')
        negative = *p++ == '-';
    uint64_t mantissa = 0;
    for (; *p >= '0' && *p <= '9'; ++p, ++digits) {
        if (mantissa < UINT64_C(100000000000000000))
            mantissa = 10 * mantissa + (uint64_t)(*p - '0');
        else
            ++exponent; /* beyond 17 significant digits: only the scale */
    }
    if (*p == '.')
        for (++p; *p >= '0' && *p <= '9'; ++p, ++digits)
            if (mantissa < UINT64_C(100000000000000000)) {
                mantissa = 10 * mantissa + (uint64_t)(*p - '0');
                --exponent;
            }
    if (digits == 0)
        return NULL;
    if (*p == 'e' || *p == 'E') {
        ++p;
        int e_negative = 0, e = 0;
        if (*p == '-' || *p == '+')
            e_negative = *p++ == '-';
        if (*p < '0' || *p > '9')
            return NULL;
        for (; *p >= '0' && *p <= '9' && e < 1000; ++p)
            e = 10 * e + (*p - '0');
        exponent += e_negative ? -e : e;
    }
    const double value = (double)mantissa * pow(10.0, exponent);
    *out = negative ? -value : value;
    return p;
}

/* The `count` numbers of <name>'s <data> element in OpenCV's XML `text`.
 * 0 on success. */
static int xml_matrix(const char *text, const char *name, double *out, int count) {
    char open[64];
    snprintf(open, sizeof open, "<%s", name);
    const char *p = strstr(text, open);
    if (p == NULL || (p = strstr(p, "<data>")) == NULL)
        return -1;
    p += strlen("<data>");
    for (int i = 0; i < count; ++i)
        if ((p = parse_number(p, &out[i])) == NULL)
            return -1;
    return 0;
}

/* The red set's camera: {fx, fy, cx, cy} and the 8 distortion coefficients
 * in OpenCV's order (the file gives k1, k2, p1, p2, k3; k4..k6 are 0). */
static int read_parameters(const char *path, double camera[4], double distortion[8]) {
    FILE *f = fopen(path, "rb");
    if (f == NULL)
        return -1;
    char text[8192];
    const size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    double k[9], d[5];
    if (xml_matrix(text, "cameraMatrix", k, 9) || xml_matrix(text, "distCoeffs", d, 5))
        return -1;
    camera[0] = k[0];
    camera[1] = k[4];
    camera[2] = k[2];
    camera[3] = k[5];
    memset(distortion, 0, 8 * sizeof *distortion);
    memcpy(distortion, d, sizeof d);
    return 0;
}

/* ---------------------------------------------------------------------- */
/* The measurement                                                        */
/* ---------------------------------------------------------------------- */

/* A line column continues a run when its brightest row lies within this
 * many rows of the run's last column's: the lines here slope by less than
 * 0.05 row per column (3 rows over the widest gap) and one column's
 * brightest pixel may sit on the glow beside the line, up to about 10 rows
 * off; the line on another surface (the floor, a cabinet beside the
 * board) lies 35 rows or more away. */
#define LINE_STEP_ROWS   16.0
/* The line's reference row in a column: the median brightest row of the
 * run's columns within this many columns either side. */
#define REF_REACH        32
#define SLOPE_SPAN       8
/* Gaps of up to this many columns without a line column are bridged: where
 * the line crosses a black circle of the board (about 45 columns wide) it
 * may rise too little above the circle's neighbourhood. At most twice
 * REF_REACH, so every column of a gap has a reference row. */
#define LINE_GAP_COLUMNS 64
/* The extractor's band (and the centroid's): the line's rows +- this
 * margin. */
#define BAND_MARGIN      32
/* The plain centroid's half-window around the line's reference row, rows:
 * the extractor's default widest line (extract_max_width). */
#define CENTROID_HALF    12
/* A peak within this many rows of the line's reference row counts as
 * kept; one farther away is on something else (wrong). The reference is
 * good to 1-2 rows; anything else bright in the band (the board's white
 * field, the floor's line) lies 10 rows or more from the line. */
#define KEPT_TOLERANCE   4.0

typedef struct set_result {
    size_t line_columns, kept, wrong; /* summed over the photos */
    /* Sums of squared residuals, px^2: [straight line, cubic][extractor,
     * centroid, Gaussian 3-point], and the columns fitted. */
    double rss[2][3];
    size_t fitted;
} set_result;

/* The line: a line column rises at least `contrast` above its
 * background; the line is the longest run of line columns whose brightest
 * rows continue each other, across gaps of up to LINE_GAP_COLUMNS. It
 * crosses every column from the run's first to its last (the board is one
 * piece): line[u] = 1 there, and ref[u] is its reference row there
 * (REF_REACH). Returns the number of columns crossed. */
static int compare_doubles(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static size_t find_line(const column_stats *st, uint32_t width, double contrast, uint8_t *line,
                        double *ref) {
    /* run[u]: 1 + the index of the run line column u belongs to, else 0.
     * A column joins the latest run it continues (a stray bright pixel
     * elsewhere in a column starts a run of its own without breaking the
     * line's). */
    uint32_t *run = calloc(width, sizeof *run);
    uint32_t *run_last = calloc(width, sizeof *run_last);
    size_t *run_count = calloc(width, sizeof *run_count);
    assert_non_null(run);
    assert_non_null(run_last);
    assert_non_null(run_count);
    uint32_t runs = 0, best = 0;
    for (uint32_t u = 0; u < width; ++u) {
        if (st[u].max - st[u].median < contrast)
            continue;
        uint32_t joined = 0;
        for (uint32_t r = runs; r > 0 && u - run_last[r - 1] <= LINE_GAP_COLUMNS; --r)
            if (fabs(st[u].row - st[run_last[r - 1]].row) <= LINE_STEP_ROWS) {
                joined = r;
                break;
            }
        if (joined == 0)
            joined = ++runs;
        run[u] = joined;
        run_last[joined - 1] = u;
        if (++run_count[joined - 1] > (best ? run_count[best - 1] : 0))
            best = joined;
    }
    free(run_last);
    free(run_count);
    memset(line, 0, width);
    size_t crossed = 0;
    long run_first = -1, run_end = -1;
    for (uint32_t u = 0; u < width; ++u)
        if (best && run[u] == best) {
            if (run_first < 0)
                run_first = u;
            run_end = u;
        }
    /* ref[u]: the brightest rows of the run's columns within REF_REACH
     * columns, carried to u along the line's local slope, their median
     * (one column's brightest pixel may sit on the glow beside the line).
     * The slope: the median of the run's row steps over SLOPE_SPAN columns
     * in the window. Without it, a line at 35 degrees (0.7 rows per
     * column) would be referred 10 rows off at its ends, where the window
     * is one-sided. */
    double window[2 * REF_REACH + 1];
    for (long u = 0; u < (long)width; ++u) {
        ref[u] = NAN;
        if (run_first < 0 || u < run_first || u > run_end)
            continue;
        int n = 0;
        for (long k = u - REF_REACH; k + SLOPE_SPAN <= u + REF_REACH; ++k)
            if (k >= 0 && k + SLOPE_SPAN < (long)width && run[k] == best &&
                run[k + SLOPE_SPAN] == best)
                window[n++] = (st[k + SLOPE_SPAN].row - st[k].row) / SLOPE_SPAN;
        double slope = 0;
        if (n > 0) {
            qsort(window, (size_t)n, sizeof *window, compare_doubles);
            slope = window[n / 2];
        }
        n = 0;
        for (long k = u - REF_REACH; k <= u + REF_REACH; ++k)
            if (k >= 0 && k < (long)width && run[k] == best)
                window[n++] = st[k].row + slope * (double)(u - k);
        if (n == 0)
            continue; /* a gap wider than the reach: no reference there */
        qsort(window, (size_t)n, sizeof *window, compare_doubles);
        ref[u] = n % 2 ? window[n / 2] : 0.5 * (window[n / 2 - 1] + window[n / 2]);
        line[u] = 1;
        ++crossed;
    }
    free(run);
    return crossed;
}

/* The plain centroid of column u: the mean row of the line's pixels
 * weighted by their light above the background. The line's pixels: those
 * around the brightest pixel within CENTROID_HALF rows of the line's row
 * `row` (ref[u]) that lie above half way from the background to it (a
 * thresholded centroid: without the threshold the board's texture beside
 * the line would weigh in); the background: the higher of the lowest
 * pixels above and below it in that window (the line may lie on the edge
 * between a white and a black patch of the board). */
static double centroid(const photo *p, uint32_t u, double row, uint32_t first, uint32_t rows) {
    const long centre = lround(row);
    const long lo = centre - CENTROID_HALF < (long)first ? (long)first : centre - CENTROID_HALF;
    const long hi = centre + CENTROID_HALF > (long)(first + rows - 1) ? (long)(first + rows - 1)
                                                                      : centre + CENTROID_HALF;
#define PX(v) ((double)p->pixels[(size_t)(v)*p->width + u])
    long at = lo;
    for (long v = lo; v <= hi; ++v)
        if (PX(v) > PX(at))
            at = v;
    double low_above = PX(at), low_below = PX(at);
    for (long v = lo; v < at; ++v)
        low_above = fmin(low_above, PX(v));
    for (long v = at + 1; v <= hi; ++v)
        low_below = fmin(low_below, PX(v));
    const double background = fmax(low_above, low_below);
    if (!(PX(at) > background))
        return NAN;
    const double half = 0.5 * (PX(at) + background);
    long a = at, b = at;
    while (a > lo && PX(a - 1) >= half)
        --a;
    while (b < hi && PX(b + 1) >= half)
        ++b;
    double sum = 0, weighted = 0;
    for (long v = a; v <= b; ++v) {
        sum += PX(v) - background;
        weighted += (PX(v) - background) * (double)v;
    }
#undef PX
    return weighted / sum;
}

/* The Gaussian 3-point fit of column u: through the logarithms of the
 * brightest pixel within CENTROID_HALF rows of `row` and its two
 * neighbours, each less the background (as centroid(): the higher of the
 * lowest pixels above and below, and at least one level), the parabola's
 * vertex. Where the maximum is a saturated plateau, the brightest pixel is
 * the plateau's middle (its neighbours are then equal, and so is the
 * vertex). NaN where the maximum lies at the window's end. */
static double gaussian3(const photo *p, uint32_t u, double row, uint32_t first, uint32_t rows) {
    const long centre = lround(row);
    const long lo = centre - CENTROID_HALF < (long)first ? (long)first : centre - CENTROID_HALF;
    const long hi = centre + CENTROID_HALF > (long)(first + rows - 1) ? (long)(first + rows - 1)
                                                                      : centre + CENTROID_HALF;
#define PX(v) ((double)p->pixels[(size_t)(v)*p->width + u])
    long at = lo;
    for (long v = lo; v <= hi; ++v)
        if (PX(v) > PX(at))
            at = v;
    long end = at;
    while (end < hi && PX(end + 1) == PX(at))
        ++end;
    at = (at + end) / 2;
    if (at <= lo || at >= hi)
        return NAN;
    double low_above = PX(at), low_below = PX(at);
    for (long v = lo; v < at; ++v)
        low_above = fmin(low_above, PX(v));
    for (long v = at + 1; v <= hi; ++v)
        low_below = fmin(low_below, PX(v));
    const double background = fmax(low_above, low_below);
    const double a = log(fmax(1.0, PX(at - 1) - background));
    const double b = log(fmax(1.0, PX(at) - background));
    const double c = log(fmax(1.0, PX(at + 1) - background));
#undef PX
    const double curvature = a - 2 * b + c;
    return curvature < 0 ? (double)at + 0.5 * (a - c) / curvature : (double)at;
}

/* Least-squares polynomial of degree `degree` (1: a straight line, up to
 * 3) through n points (u, v); returns the sum of the squared residuals in
 * v, px^2. (The lines here slope by less than 0.05 row per column, so the
 * residual in v is the distance from the line to within 0.2 %.) */
static double fit_rss(const double *u, const double *v, size_t n, int degree) {
    double lo = u[0], hi = u[0];
    for (size_t i = 0; i < n; ++i) {
        lo = fmin(lo, u[i]);
        hi = fmax(hi, u[i]);
    }
    const double mid = 0.5 * (lo + hi), scale = hi > lo ? 2.0 / (hi - lo) : 1.0;
    const int m = degree + 1;
    double a[4][5] = {{0}};
    for (size_t i = 0; i < n; ++i) {
        const double t = (u[i] - mid) * scale;
        double pw[4] = {1, t, t * t, t * t * t};
        for (int r = 0; r < m; ++r) {
            for (int c = 0; c < m; ++c)
                a[r][c] += pw[r] * pw[c];
            a[r][m] += pw[r] * v[i];
        }
    }
    for (int c = 0; c < m; ++c) { /* Gauss-Jordan, partial pivoting */
        int pivot = c;
        for (int r = c + 1; r < m; ++r)
            if (fabs(a[r][c]) > fabs(a[pivot][c]))
                pivot = r;
        for (int k = 0; k <= m; ++k) {
            const double tmp = a[c][k];
            a[c][k] = a[pivot][k];
            a[pivot][k] = tmp;
        }
        for (int r = 0; r < m; ++r)
            if (r != c) {
                const double f = a[r][c] / a[c][c];
                for (int k = c; k <= m; ++k)
                    a[r][k] -= f * a[c][k];
            }
    }
    double rss = 0;
    for (size_t i = 0; i < n; ++i) {
        const double t = (u[i] - mid) * scale;
        double fit = 0, pw = 1;
        for (int k = 0; k < m; ++k, pw *= t)
            fit += a[k][m] / a[k][k] * pw;
        rss += (v[i] - fit) * (v[i] - fit);
    }
    return rss;
}

typedef struct set_spec {
    const char *name;
    const char *root;   /* the environment variable naming the folder: NULL, FLT_EXTERNAL_DATA */
    const char *folder; /* under it */
    const char *const *files;
    size_t count;
    int channel; /* RED, GREEN or GREY */
    int transpose;
    const char *parameters;       /* intrinsics file under the root, or NULL */
    const char *off_folder;       /* the same views with the laser off, or NULL */
    const char *const *off_files; /* NULL entries: no laser-off view of that photo */
    /* Only the columns [measure_first, measure_last] (after a transpose)
     * are measured, where the line lies on the flat board (0, 0: all). */
    uint32_t measure_first, measure_last;
    uint32_t search_first, search_rows; /* where the line is looked for */
    double contrast;                    /* a line column's least contrast, grey levels */
    double min_peak;                    /* extract_min_peak */
} set_spec;

static void measure_set(const set_spec *set, set_result *result) {
    memset(result, 0, sizeof *result);
#ifndef FLT_HAVE_JPEG
    /* Built without libjpeg (the Windows cross build has none): the
     * measurement's helpers are unused. */
    (void)set;
    (void)stats_of;
    (void)read_parameters;
    (void)find_line;
    (void)centroid;
    (void)gaussian3;
    (void)fit_rss;
    (void)load_photo;
    fprintf(stderr, "skipped: this build has no libjpeg to decode the photos\n");
    skip();
#else
    const char *root = set->root ? set->root : "FLT_EXTERNAL_DATA";
    char path[1024];
    double camera[4] = {0}, distortion[8] = {0};
    int undistort = 0;
    if (set->parameters) {
        if (!flt_external_path_in(root, set->parameters, path, sizeof path))
            skip();
        assert_int_equal(read_parameters(path, camera, distortion), 0);
        undistort = 1;
    }
    for (size_t i = 0; i < set->count; ++i) { /* all there, or skip before any output */
        char relative[512];
        snprintf(relative, sizeof relative, "%s/%s", set->folder, set->files[i]);
        if (!flt_external_path_in(root, relative, path, sizeof path))
            skip();
        if (set->off_folder && set->off_files[i]) {
            snprintf(relative, sizeof relative, "%s/%s", set->off_folder, set->off_files[i]);
            if (!flt_external_path_in(root, relative, path, sizeof path))
                skip();
        }
    }
    printf("%s (%s%s):\n", set->name,
           set->channel == GREY  ? "grey"
           : set->channel == RED ? "red channel"
                                 : "green channel",
           set->transpose ? ", transposed" : "");
    printf("                                        RMS from a line (px)      RMS from a cubic "
           "(px)\n");
    printf("  photo              crossed  kept  wrong sat.  extract centr. gauss3   extract "
           "centr. gauss3\n");
    for (size_t i = 0; i < set->count; ++i) {
        char relative[512];
        snprintf(relative, sizeof relative, "%s/%s", set->folder, set->files[i]);
        if (!flt_external_path_in(root, relative, path, sizeof path))
            skip();
        photo p;
        assert_int_equal(load_photo(path, set->channel, set->transpose, &p), 0);
        const uint32_t w = p.width, h = p.height;
        assert_true(set->search_first + set->search_rows <= h);

        /* The line, independently of the extractor. */
        column_stats *st = calloc(w, sizeof *st);
        uint8_t *line = calloc(w, 1);
        double *ref = calloc(w, sizeof *ref);
        assert_non_null(ref);
        assert_non_null(st);
        assert_non_null(line);
        /* Where the same view was also taken with the laser off, the line
         * is found in the difference (the board's own brightness cancels);
         * otherwise in the frame itself. */
        photo detect = p;
        if (set->off_folder && set->off_files[i]) {
            snprintf(relative, sizeof relative, "%s/%s", set->off_folder, set->off_files[i]);
            if (!flt_external_path_in(root, relative, path, sizeof path))
                skip();
            assert_int_equal(load_photo(path, set->channel, set->transpose, &detect), 0);
            assert_true(detect.width == w && detect.height == h);
            for (size_t k = 0; k < (size_t)w * h; ++k)
                detect.pixels[k] =
                    p.pixels[k] > detect.pixels[k] ? (uint8_t)(p.pixels[k] - detect.pixels[k]) : 0;
        }
        stats_of(&detect, set->search_first, set->search_rows, st);
        if (detect.pixels != p.pixels)
            free(detect.pixels);
        /* Columns outside the measured range take no part: no contrast. */
        if (set->measure_last > 0)
            for (uint32_t u = 0; u < w; ++u)
                if (u < set->measure_first || u > set->measure_last)
                    st[u].max = st[u].median;
        const size_t line_columns = find_line(st, w, set->contrast, line, ref);
        assert_true(
            line_columns > w / 4 ||
            (set->measure_last > 0 && line_columns > (set->measure_last - set->measure_first) / 4));
        double row_lo = 1e9, row_hi = -1e9;
        for (uint32_t u = 0; u < w; ++u)
            if (line[u]) {
                row_lo = fmin(row_lo, st[u].row);
                row_hi = fmax(row_hi, st[u].row);
            }
        const long first_l = (long)row_lo - BAND_MARGIN;
        const uint32_t first = first_l < 0 ? 0u : (uint32_t)first_l;
        const uint32_t last = (uint32_t)fmin((double)h - 1, row_hi + BAND_MARGIN);
        const uint32_t rows = last - first + 1;

        /* The extractor, on a calibration that maps the undistorted image
         * to the laser plane 1:1 (x = u mm, z = height - v mm): the peaks
         * are what is measured here, in image rows. */
        flt_calib *calib = NULL;
        assert_int_equal(flt_calib_create(&calib), FLT_OK);
        assert_int_equal(flt_calib_set_frame_size(calib, w, h), FLT_OK);
        const double own_camera[4] = {1000, 1000, 0.5 * w, 0.5 * h};
        assert_int_equal(flt_calib_set_intrinsics(calib, undistort ? camera : own_camera, 4,
                                                  undistort ? distortion : NULL, 8),
                         FLT_OK);
        const double hom[9] = {1, 0, 0, 0, -1, (double)h, 0, 0, 1};
        for (unsigned laser = 0; laser < 2; ++laser) {
            assert_int_equal(flt_calib_set_homography(calib, laser, hom, 9), FLT_OK);
            assert_int_equal(flt_calib_set_laser_offset(calib, laser, 100.0 * laser), FLT_OK);
        }
        assert_int_equal(flt_calib_set_encoder_scale(calib, 1.0), FLT_OK);
        assert_int_equal(flt_calib_set_fiber_grid(calib, 8.0, 8.0, (w - 16) / 8), FLT_OK);
        assert_int_equal(flt_calib_finish(calib), FLT_OK);
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        /* One band around the line; laser 1 reads the same band (the
         * photos show one laser; its readings are not used). */
        assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, first), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_ROWS, rows), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_FIRST_ROW, first), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, rows), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_MIN_PEAK, set->min_peak), FLT_OK);
        flt_extractor *ex = NULL;
        assert_int_equal(flt_extractor_create(calib, o, &ex), FLT_OK);
        flt_options_destroy(o);
        size_t fibers = 0;
        assert_int_equal(flt_extractor_fibers(ex, &fibers), FLT_OK);
        double *height = calloc(fibers, sizeof *height), *slope = calloc(fibers, sizeof *slope);
        double *peaks = calloc(2 * (size_t)w, sizeof *peaks);
        assert_non_null(height);
        assert_non_null(slope);
        assert_non_null(peaks);
        assert_int_equal(flt_extractor_process(ex, p.pixels, FLT_PIXEL_MONO8, w, h, w, 0.0, fibers,
                                               NULL, height, slope, NULL),
                         FLT_OK);
        assert_int_equal(flt_extractor_peaks(ex, w, peaks), FLT_OK);
        /* The share of the line's peaks the extractor measured as
         * saturated plateaus. */
        double saturated = 0;
        assert_int_equal(flt_extractor_saturation(ex, 0, NULL, NULL, &saturated), FLT_OK);

        /* Kept, and the three sets of centres on the same columns. */
        size_t kept = 0, wrong = 0, n = 0;
        double *pts = calloc(12 * (size_t)w, sizeof *pts);
        assert_non_null(pts);
        double *px[3] = {pts, pts + 2 * (size_t)w, pts + 4 * (size_t)w}; /* (u, v) pairs */
        double *uv = pts + 6 * (size_t)w;                                /* u, v per estimator */
        for (uint32_t u = 0; u < w; ++u) {
            if (!line[u] || !isfinite(peaks[u]))
                continue;
            if (fabs(peaks[u] - ref[u]) > KEPT_TOLERANCE) {
                ++wrong;
                continue;
            }
            ++kept;
            const double c = centroid(&p, u, ref[u], first, rows);
            const double g = gaussian3(&p, u, ref[u], first, rows);
            if (!isfinite(c) || !isfinite(g))
                continue;
            const double v[3] = {peaks[u], c, g};
            for (int k = 0; k < 3; ++k) {
                px[k][2 * n] = u;
                px[k][2 * n + 1] = v[k];
            }
            ++n;
        }
        assert_true(n >= 2);
        double rss[2][3]; /* [straight, cubic][extractor, centroid, Gaussian 3-point] */
        for (int k = 0; k < 3; ++k) {
            if (undistort)
                assert_int_equal(flt_calib_undistort(calib, n, px[k], px[k]), FLT_OK);
            for (size_t j = 0; j < n; ++j) {
                uv[j] = px[k][2 * j];
                uv[n + j] = px[k][2 * j + 1];
            }
            for (int f = 0; f < 2; ++f)
                rss[f][k] = fit_rss(uv, uv + n, n, f ? 3 : 1);
        }
        printf("  %-18s %7zu %5.1f %% %5zu %3.0f %%  %6.3f %6.3f %6.3f    %6.3f %6.3f %6.3f\n",
               set->files[i], line_columns, 100.0 * (double)kept / (double)line_columns, wrong,
               100.0 * saturated, sqrt(rss[0][0] / (double)n), sqrt(rss[0][1] / (double)n),
               sqrt(rss[0][2] / (double)n), sqrt(rss[1][0] / (double)n),
               sqrt(rss[1][1] / (double)n), sqrt(rss[1][2] / (double)n));
        result->line_columns += line_columns;
        result->kept += kept;
        result->wrong += wrong;
        for (int f = 0; f < 2; ++f)
            for (int k = 0; k < 3; ++k)
                result->rss[f][k] += rss[f][k];
        result->fitted += n;

        free(pts);
        free(peaks);
        free(height);
        free(slope);
        flt_extractor_destroy(ex);
        flt_calib_destroy(calib);
        free(ref);
        free(line);
        free(st);
        free(p.pixels);
    }
    const double fitted = (double)result->fitted;
    printf(
        "  all                %7zu %5.1f %% %5zu        %6.3f %6.3f %6.3f    %6.3f %6.3f %6.3f\n",
        result->line_columns, 100.0 * (double)result->kept / (double)result->line_columns,
        result->wrong, sqrt(result->rss[0][0] / fitted), sqrt(result->rss[0][1] / fitted),
        sqrt(result->rss[0][2] / fitted), sqrt(result->rss[1][0] / fitted),
        sqrt(result->rss[1][1] / fitted), sqrt(result->rss[1][2] / fitted));
#endif
}

/* ---------------------------------------------------------------------- */
/* Tests                                                                  */
/* ---------------------------------------------------------------------- */

static const char *const k_red_files[] = {
    "light0.jpg", "light1.jpg", "light2.jpg", "light3.jpg", "light4.jpg",  "light5.jpg",
    "light6.jpg", "light7.jpg", "light8.jpg", "light9.jpg", "light10.jpg", "light11.jpg",
};
static const char *const k_red_off_files[] = {
    "calib0.jpg", "calib1.jpg", "calib2.jpg", "calib3.jpg", "calib4.jpg",  "calib5.jpg",
    "calib6.jpg", "calib7.jpg", "calib8.jpg", "calib9.jpg", "calib10.jpg", "calib11.jpg",
};
static const char *const k_green_files[] = {
    "bcap1.jpg", "bcap2.jpg", "bcap3.jpg", "bcap4.jpg", "bcap5.jpg", "bcap6.jpg",
};

/* The figures every set must reach: kept >= 80 % of the columns the line
 * crosses; at most 1 % of them with a peak off the line (a wrong reading
 * is worse than a missing one); and the extractor's centres at least as
 * close to the set's line model as the plain centroid's on the same
 * columns (degree 1: a straight line; 3: a cubic), without slack: the
 * RMS of each set comes from thousands of columns. */
static void check_set(const set_result *r, int degree) {
    const double kept = (double)r->kept / (double)r->line_columns;
    const double wrong = (double)r->wrong / (double)r->line_columns;
    const int f = degree == 1 ? 0 : 1;
    const double rms_extractor = sqrt(r->rss[f][0] / (double)r->fitted);
    const double rms_centroid = sqrt(r->rss[f][1] / (double)r->fitted);
    const double rms_gaussian = sqrt(r->rss[f][2] / (double)r->fitted);
    printf("  kept %.1f %% (bound 80 %%), wrong %.2f %% (bound 1 %%); RMS from a %s: extractor "
           "%.3f px, centroid %.3f px, Gaussian 3-point %.3f px\n",
           100 * kept, 100 * wrong, degree == 1 ? "straight line" : "cubic", rms_extractor,
           rms_centroid, rms_gaussian);
    assert_true(kept >= 0.80);
    assert_true(wrong <= 0.01);
    assert_true(rms_extractor <= rms_centroid);
}

/* What the further sets must keep reaching. The aims for photos
 * the extractor was not tuned on are >= 90 % kept, no peak off the line and
 * a residual no larger than the better of the two peers'; each line
 * below says whether the set meets them. The asserted bounds are today's
 * figures less a margin (kept: 2-3 points, the residual's ratio: 0.07
 * above today's where the aim is not met), so that a change that loses
 * ground on photos it was never shown fails here; wrong <= 0.1 % (today
 * 0-1 columns of 1,300-10,000). */
static void check_further(const set_result *r, int degree, double kept_bound, double ratio_bound) {
    const double kept = (double)r->kept / (double)r->line_columns;
    const double wrong = (double)r->wrong / (double)r->line_columns;
    const int f = degree == 1 ? 0 : 1;
    const double rms_extractor = sqrt(r->rss[f][0] / (double)r->fitted);
    const double rms_peer = sqrt(fmin(r->rss[f][1], r->rss[f][2]) / (double)r->fitted);
    printf(
        "  kept %.1f %% (bound %.0f %%, aim 90 %%: %s), wrong %.2f %% (bound 0.1 %%); RMS from a "
        "%s: extractor %.3f px, %.2fx the better peer's (bound %.2fx, aim 1: %s)\n",
        100 * kept, 100 * kept_bound, kept >= 0.90 ? "met" : "NOT met", 100 * wrong,
        degree == 1 ? "straight line" : "cubic", rms_extractor, rms_extractor / rms_peer,
        ratio_bound, rms_extractor <= rms_peer ? "met" : "NOT met");
    assert_true(kept >= kept_bound);
    assert_true(wrong <= 0.001);
    assert_true(rms_extractor <= ratio_bound * rms_peer);
}

/* The red line: 12 views of a flat circle-grid board, the line saturated
 * (its white core at full scale in all three channels) across the board;
 * the camera's intrinsics from Parameters.xml; each view also taken with
 * the laser off (calib_picture/), where the line is found independently.
 *
 * Grey, not the red channel: the laser is so bright that its core is
 * white, while its red glow saturates the red channel over as much as 15
 * rows, and how far depends on the board under it: over a white field the
 * glow saturates, over a black circle it does not (light9.jpg, column 800:
 * red at full scale in rows 565-579, the white core in rows 572-578 where
 * a circle starts at row 579). A plateau's middle in the red channel thus
 * moves by up to 5 px with the board's print; in grey the core alone
 * saturates. Default extractor options: the core is 5-9 rows wide. */
static void test_red_saturated(void **state) {
    (void)state;
    const set_spec set = {
        .name = "red line, saturated, on a circle-grid board",
        .folder = ZHAO_DIR "/light_picture",
        .files = k_red_files,
        .count = sizeof k_red_files / sizeof *k_red_files,
        .channel = GREY,
        .transpose = 0,
        .parameters = ZHAO_DIR "/Parameters.xml",
        .off_folder = ZHAO_DIR "/calib_picture",
        .off_files = k_red_off_files,
        /* The line lies in rows 540-620 in every view; the cabinet's and
         * the floor's lines beside the board lie outside the longest run. */
        .search_first = 440,
        .search_rows = 300,
        /* In the difference from the laser-off view the board cancels to
         * within 10-20 levels (the views were not taken at quite the same
         * exposure); the line rises 30-200 above it. */
        .contrast = 24.0,
        .min_peak = 0.1, /* the default */
    };
    set_result r;
    measure_set(&set, &r);
    /* The board is flat: after undistortion the line is straight. */
    check_set(&r, 1);
}

/* The green line: 6 webcam views of a thin line on a chessboard and a
 * card, vertical (transposed here), well exposed: the green channel, the
 * laser's own. No intrinsics are given, and the line bends by 1-3 px over
 * the frame's 1080 columns (the residual from a straight line is 0.6-1.4 px
 * for both methods alike: lens distortion, or card and board not quite
 * in one plane). So the check is the residual from a cubic, which takes
 * out such a smooth bend and leaves the centres' own scatter.
 * extract_min_peak 0.05: in bcap6.jpg the line rises only 15-20 levels
 * (6-8 % of full scale) above a background of 15-45. */
static void test_green_exposed(void **state) {
    (void)state;
    const set_spec set = {
        .name = "green line, well exposed, on a chessboard and card",
        .folder = GREEN_DIR,
        .files = k_green_files,
        .count = sizeof k_green_files / sizeof *k_green_files,
        .channel = GREEN,
        .transpose = 1,
        .parameters = NULL,
        .off_folder = NULL,
        .off_files = NULL,
        .search_first = 0,
        .search_rows = 1920,
        /* The scene is dark (10-45); the line rises 15-180 above it. */
        .contrast = 12.0,
        .min_peak = 0.05,
    };
    set_result r;
    measure_set(&set, &r);
    check_set(&r, 3);
}

/* ---------------------------------------------------------------------- */
/* Further sets: photos found after the extractor was tuned               */
/* ---------------------------------------------------------------------- */

/* Four sets of photos from public projects, found in public repositories
 * after the extractor's defaults were set (docs/sensor.md, "Real photos",
 * gives their origins and licences; tests/further_photos fetches them into
 * the folder FLT_FURTHER_PHOTOS names). None was used to choose anything in
 * the extractor: they measure how it does on lines it was never shown.
 * Default options throughout (extract_min_peak 0.1). */

static const char *const k_stripe_files[] = {
    "0_right.jpg", "1_right.jpg", "2_right.jpg", "3_right.jpg", "4_right.jpg", "5_right.jpg",
};
static const char *const k_plane_files[] = {
    "0_.bmp",  "1_.bmp",  "2_.bmp",  "3_.bmp",  "4_.bmp",  "5_.bmp",  "6_.bmp",
    "7_.bmp",  "8_.bmp",  "9_.bmp",  "10_.bmp", "11_.bmp", "12_.bmp", "13_.bmp",
    "14_.bmp", "15_.bmp", "16_.bmp", "17_.bmp", "18_.bmp", "19_.bmp",
};
/* The same poses with the laser off; photo 8 has none (the repository's
 * laser-off file of that number shows another pose). */
static const char *const k_plane_off_files[] = {
    "0_.bmp",  "1_.bmp",  "2_.bmp",  "3_.bmp",  "4_.bmp",  "5_.bmp",  "6_.bmp",
    "7_.bmp",  NULL,      "9_.bmp",  "10_.bmp", "11_.bmp", "12_.bmp", "13_.bmp",
    "14_.bmp", "15_.bmp", "16_.bmp", "17_.bmp", "18_.bmp", "19_.bmp",
};
static const char *const k_floor_files[] = {
    "img0058.jpg", "img0062.jpg", "img0066.jpg", "img0070.jpg",
    "img0074.jpg", "img0078.jpg", "img0082.jpg", "img0086.jpg",
};
static const char *const k_bed_files[] = {
    "StillSnapshot000000.jpg", "StillSnapshot000032.jpg", "StillSnapshot000064.jpg",
    "StillSnapshot000065.jpg", "StillSnapshot000073.jpg", "StillSnapshot000081.jpg",
    "StillSnapshot000089.jpg", "StillSnapshot000097.jpg", "StillSnapshot000105.jpg",
    "StillSnapshot000113.jpg", "StillSnapshot000121.jpg", "StillSnapshot000129.jpg",
};

/* A green line across a hand-held printed chessboard, near-vertical
 * (transposed here), 640 x 480 webcam photos, not saturated. Only image
 * rows 100-340 are measured: above them the line is on the wall behind,
 * below on the floor, bent where it leaves the board. No usable intrinsics:
 * the model is a cubic. */
static void test_further_green_chessboard(void **state) {
    (void)state;
    const set_spec set = {
        .name = "further: green line on a hand-held chessboard",
        .root = "FLT_FURTHER_PHOTOS",
        .folder = "hjamal3_Light-Stripe-Calibration",
        .files = k_stripe_files,
        .count = sizeof k_stripe_files / sizeof *k_stripe_files,
        .channel = GREEN,
        .transpose = 1,
        .measure_first = 100,
        .measure_last = 340,
        .search_first = 220,
        .search_rows = 140,
        .contrast = 20.0,
        .min_peak = 0.1,
    };
    set_result r;
    measure_set(&set, &r);
    check_further(&r, 3, 0.68, 1.0);
}

/* A line from a monochrome camera (1292 x 964 BMP), saturated, on a
 * chessboard glued to a flat plate, from vertical to 35 degrees
 * (transposed here); each view but one also with the laser off. Image
 * rows 0-590 are measured: below them the line leaves the plate in
 * several views. The lens's correction is in a MATLAB file: the model is
 * a cubic. */
static void test_further_mono_plate(void **state) {
    (void)state;
    const set_spec set = {
        .name = "further: saturated line on a chessboard plate, mono camera",
        .root = "FLT_FURTHER_PHOTOS",
        .folder = "MozhiJiawei_Matlab_Calculate_Lightplane",
        .files = k_plane_files,
        .count = sizeof k_plane_files / sizeof *k_plane_files,
        .channel = GREY,
        .transpose = 1,
        .off_folder = "MozhiJiawei_Matlab_Calculate_Lightplane/off",
        .off_files = k_plane_off_files,
        .measure_first = 0,
        .measure_last = 590,
        .search_first = 480,
        .search_rows = 720,
        .contrast = 24.0,
        .min_peak = 0.1,
    };
    set_result r;
    measure_set(&set, &r);
    check_further(&r, 3, 0.79, 1.0);
}

/* A thin, dim red line across a concrete floor (a robot's laser, 640 x 480
 * photos, barrel distortion bows the line by 2.5-3.5 px, no intrinsics:
 * the model is a cubic); the laser's own channel, as a band-pass filter
 * in front of a monochrome camera would see it. */
static void test_further_red_floor(void **state) {
    (void)state;
    const set_spec set = {
        .name = "further: dim red line on a concrete floor",
        .root = "FLT_FURTHER_PHOTOS",
        .folder = "NeilKhera_laser_line_striping",
        .files = k_floor_files,
        .count = sizeof k_floor_files / sizeof *k_floor_files,
        .channel = RED,
        .transpose = 0,
        .search_first = 225,
        .search_rows = 80,
        .contrast = 15.0,
        .min_peak = 0.1,
    };
    set_result r;
    measure_set(&set, &r);
    check_further(&r, 3, 0.95, 1.18);
}

/* A red line with a saturated white core on an empty, near-black scan bed,
 * vertical (transposed here), 640 x 480; grey, for the reason the red set
 * gives (the red glow saturates the red channel far wider than the
 * core). The bed is flat and the lens long: a straight line. */
static void test_further_red_bed(void **state) {
    (void)state;
    const set_spec set = {
        .name = "further: saturated red line on a dark scan bed",
        .root = "FLT_FURTHER_PHOTOS",
        .folder = "Anugrah-T-Sebastian_3D_Scanner_Laser_Triangulation",
        .files = k_bed_files,
        .count = sizeof k_bed_files / sizeof *k_bed_files,
        .channel = GREY,
        .transpose = 1,
        .search_first = 270,
        .search_rows = 100,
        .contrast = 40.0,
        .min_peak = 0.1,
    };
    set_result r;
    measure_set(&set, &r);
    check_further(&r, 1, 0.97, 1.0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_red_saturated),
        cmocka_unit_test(test_green_exposed),
        cmocka_unit_test(test_further_green_chessboard),
        cmocka_unit_test(test_further_mono_plate),
        cmocka_unit_test(test_further_red_floor),
        cmocka_unit_test(test_further_red_bed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
