// SPDX-License-Identifier: Apache-2.0
#include "calib_synth.h"

#include <math.h>
#include <string.h>

const double synth_camera[4] = {SYNTH_FOCAL_PX, SYNTH_FOCAL_PX, 1030.25, 1019.75};
/* Barrel distortion of a 6 mm lens on an 11 mm sensor: about -10 % at the
 * image corners, with a little decentring. */
const double synth_distortion[8] = {-0.08, 0.012, 1.5e-4, -1.0e-4, -0.002, 0, 0, 0};
const double synth_laser_offset[2] = {-50.0, 50.0};

static void distort(double x, double y, double *xd, double *yd) {
    const double *d = synth_distortion;
    const double r2 = x * x + y * y;
    const double radial = (1 + d[0] * r2 + d[1] * r2 * r2 + d[4] * r2 * r2 * r2) /
                          (1 + d[5] * r2 + d[6] * r2 * r2 + d[7] * r2 * r2 * r2);
    *xd = x * radial + 2 * d[2] * x * y + d[3] * (r2 + 2 * x * x);
    *yd = y * radial + d[2] * (r2 + 2 * y * y) + 2 * d[3] * x * y;
}

int synth_project(double x, double s, double z, double *u, double *v) {
    /* Camera at (0, -1140, 1140) looking at the origin: X_c = +x,
     * Y_c = (0, -1, -1)/sqrt 2 (image down), Z_c = (0, 1, -1)/sqrt 2. */
    const double h = SYNTH_CAMERA_HEIGHT_MM, r = 1 / sqrt(2.0);
    const double px = x, ps = s + h, pz = z - h;
    const double xc = px, yc = -r * ps - r * pz, zc = r * ps - r * pz;
    if (zc <= 0)
        return 0;
    double xd, yd;
    distort(xc / zc, yc / zc, &xd, &yd);
    *u = synth_camera[0] * xd + synth_camera[2];
    *v = synth_camera[1] * yd + synth_camera[3];
    return 1;
}

static uint64_t next(uint64_t *state) {
    uint64_t x = *state;
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    return *state = x;
}

double synth_uniform(uint64_t *state) {
    return (double)(next(state) >> 11) * (1.0 / 9007199254740992.0);
}

double synth_gauss(uint64_t *state) {
    const double a = synth_uniform(state), b = synth_uniform(state);
    return sqrt(-2 * log(1 - a)) * cos(6.283185307179586 * b);
}

void synth_ray_map(double *ray_map) {
    for (int v = 0; v < SYNTH_HEIGHT; ++v)
        for (int u = 0; u < SYNTH_WIDTH; ++u) {
            const double xd = (u - synth_camera[2]) / synth_camera[0];
            const double yd = (v - synth_camera[3]) / synth_camera[1];
            double x = xd, y = yd;
            for (int it = 0; it < 50; ++it) {
                /* Newton with a finite-difference Jacobian. */
                double fx, fy, ax, ay, bx, by;
                const double e = 1e-7;
                distort(x, y, &fx, &fy);
                distort(x + e, y, &ax, &ay);
                distort(x, y + e, &bx, &by);
                const double j00 = (ax - fx) / e, j10 = (ay - fy) / e;
                const double j01 = (bx - fx) / e, j11 = (by - fy) / e;
                const double rx = fx - xd, ry = fy - yd;
                const double det = j00 * j11 - j01 * j10;
                x -= (j11 * rx - j01 * ry) / det;
                y -= (-j10 * rx + j00 * ry) / det;
                if (fabs(rx) + fabs(ry) < 1e-15)
                    break;
            }
            ray_map[2 * ((size_t)v * SYNTH_WIDTH + u)] = x;
            ray_map[2 * ((size_t)v * SYNTH_WIDTH + u) + 1] = y;
        }
}

static void rotation(double rx, double ry, double rz, double r[9]) {
    const double cx = cos(rx), sx = sin(rx), cy = cos(ry), sy = sin(ry), cz = cos(rz), sz = sin(rz);
    /* R = Rz * Ry * Rx */
    r[0] = cz * cy, r[1] = cz * sy * sx - sz * cx, r[2] = cz * sy * cx + sz * sx;
    r[3] = sz * cy, r[4] = sz * sy * sx + cz * cx, r[5] = sz * sy * cx - cz * sx;
    r[6] = -sy, r[7] = cy * sx, r[8] = cy * cx;
}

/* Inverse of a 3x3 matrix (row-major). */
static void inverse3(const double m[9], double out[9]) {
    const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                       m[2] * (m[3] * m[7] - m[4] * m[6]);
    out[0] = (m[4] * m[8] - m[5] * m[7]) / det;
    out[1] = (m[2] * m[7] - m[1] * m[8]) / det;
    out[2] = (m[1] * m[5] - m[2] * m[4]) / det;
    out[3] = (m[5] * m[6] - m[3] * m[8]) / det;
    out[4] = (m[0] * m[8] - m[2] * m[6]) / det;
    out[5] = (m[2] * m[3] - m[0] * m[5]) / det;
    out[6] = (m[3] * m[7] - m[4] * m[6]) / det;
    out[7] = (m[1] * m[6] - m[0] * m[7]) / det;
    out[8] = (m[0] * m[4] - m[1] * m[3]) / det;
}

/* Sub-samples per pixel side: 8 x 8 = 64 coverage levels per pixel, so an
 * edge's position is quantised to 1/64 px before 8-bit rounding. */
#define SUB 8

/* A board's grey level at board point (X, Y) mm. */
typedef double (*board_level)(const void *pattern, double X, double Y);

/* 1 with *level set when the pattern has one grey level over the whole box
 * [x0, x1] x [y0, y1] mm (inside the board), else 0. It must be sure: a
 * pixel whose sub-samples all fall in such a box is that level exactly,
 * as their mean would be, so the image is the same byte for byte. */
typedef int (*board_uniform)(const void *pattern, double x0, double y0, double x1, double y1,
                             double *level);

/* Renders a planar board spanning [0, w] x [0, h] mm in its own frame, with a
 * white margin of `margin` mm around it (grey 210) and background (100)
 * beyond, whose pattern is level(); the board's centre at t_mm after the
 * rotation (rx, ry, rz). Returns 0 if a corner of the margin falls outside
 * the image or behind the camera. */
static int render_board(const double *ray_map, double w, double hgt, double margin,
                        board_level level, board_uniform uniform, const void *pattern, double rx,
                        double ry, double rz, const double t_mm[3], uint8_t *image) {
    double r[9], g[9], ginv[9];
    rotation(rx, ry, rz, r);
    /* Board (X, Y, 1) -> camera ray: G = [r1 r2 t]. */
    g[0] = r[0], g[1] = r[1], g[2] = t_mm[0];
    g[3] = r[3], g[4] = r[4], g[5] = t_mm[1];
    g[6] = r[6], g[7] = r[7], g[8] = t_mm[2];
    /* t_mm is the board's centre: its origin sits at t - R (w/2, h/2, 0). */
    const double half_w = w / 2, half_h = hgt / 2;
    g[2] -= r[0] * half_w + r[1] * half_h;
    g[5] -= r[3] * half_w + r[4] * half_h;
    g[8] -= r[6] * half_w + r[7] * half_h;
    inverse3(g, ginv);
    /* The margin's corners must be in the image. */
    for (int k = 0; k < 4; ++k) {
        const double X = (k & 1) ? w + margin : -margin;
        const double Y = (k & 2) ? hgt + margin : -margin;
        const double cxr = g[0] * X + g[1] * Y + g[2], cyr = g[3] * X + g[4] * Y + g[5],
                     czr = g[6] * X + g[7] * Y + g[8];
        if (czr <= 0)
            return 0;
        double xd, yd;
        distort(cxr / czr, cyr / czr, &xd, &yd);
        const double u = synth_camera[0] * xd + synth_camera[2];
        const double v = synth_camera[1] * yd + synth_camera[3];
        if (u < 2 || v < 2 || u > SYNTH_WIDTH - 3 || v > SYNTH_HEIGHT - 3)
            return 0;
    }
    const size_t npx = (size_t)SYNTH_WIDTH * SYNTH_HEIGHT;
    for (size_t i = 0; i < npx; ++i) {
        const double *ray = ray_map + 2 * i;
        const int u = (int)(i % SYNTH_WIDTH), v = (int)(i / SYNTH_WIDTH);
        /* Board coordinates of the pixel centre and, from the neighbouring
         * pixels' rays, their derivatives in u and v. */
        double bx[3], by[3];
        const double *rays[3] = {ray, ray_map + 2 * (i + (u + 1 < SYNTH_WIDTH ? 1 : -1)),
                                 ray_map +
                                     2 * (i + (v + 1 < SYNTH_HEIGHT ? SYNTH_WIDTH : -SYNTH_WIDTH))};
        int behind = 0;
        for (int k = 0; k < 3; ++k) {
            const double a = rays[k][0], b = rays[k][1];
            const double X = ginv[0] * a + ginv[1] * b + ginv[2];
            const double Y = ginv[3] * a + ginv[4] * b + ginv[5];
            const double W = ginv[6] * a + ginv[7] * b + ginv[8];
            if (W <= 0)
                behind = 1;
            bx[k] = X / W, by[k] = Y / W;
        }
        if (behind) {
            image[i] = 100;
            continue;
        }
        const double su = u + 1 < SYNTH_WIDTH ? 1 : -1, sv = v + 1 < SYNTH_HEIGHT ? 1 : -1;
        const double dxu = (bx[1] - bx[0]) * su, dyu = (by[1] - by[0]) * su;
        const double dxv = (bx[2] - bx[0]) * sv, dyv = (by[2] - by[0]) * sv;
        /* Most pixels lie inside one square, circle or the margin: their 64
         * sub-samples (each an affine function of its offsets, so inside the
         * box of the four outermost, widened by far more than rounding) all
         * have one level, which is then the pixel's. */
        const double reach = (SUB - 1) / (2.0 * SUB), slack = 1e-9;
        const double ex = reach * (fabs(dxu) + fabs(dxv)) + slack;
        const double ey = reach * (fabs(dyu) + fabs(dyv)) + slack;
        const double x0 = bx[0] - ex, x1 = bx[0] + ex, y0 = by[0] - ey, y1 = by[0] + ey;
        double one_level;
        if (x1 < -margin || y1 < -margin || x0 > w + margin || y0 > hgt + margin) {
            image[i] = 100; /* background beyond the board */
            continue;
        }
        if (x0 >= -margin && y0 >= -margin && x1 <= w + margin && y1 <= hgt + margin) {
            if (x1 < 0 || y1 < 0 || x0 >= w || y0 >= hgt) {
                image[i] = 210; /* white margin */
                continue;
            }
            if (x0 >= 0 && y0 >= 0 && x1 < w && y1 < hgt &&
                uniform(pattern, x0, y0, x1, y1, &one_level)) {
                image[i] = (uint8_t)lround(one_level);
                continue;
            }
        }
        double sum = 0;
        for (int a = 0; a < SUB; ++a)
            for (int b = 0; b < SUB; ++b) {
                const double ou = (a - (SUB - 1) / 2.0) / SUB;
                const double ov = (b - (SUB - 1) / 2.0) / SUB;
                const double X = bx[0] + dxu * ou + dxv * ov;
                const double Y = by[0] + dyu * ou + dyv * ov;
                if (X < -margin || Y < -margin || X > w + margin || Y > hgt + margin)
                    sum += 100; /* background beyond the board */
                else if (X < 0 || Y < 0 || X >= w || Y >= hgt)
                    sum += 210; /* white margin */
                else
                    sum += level(pattern, X, Y);
            }
        image[i] = (uint8_t)lround(sum / (SUB * SUB));
    }
    return 1;
}

static double chessboard_level(const void *pattern, double X, double Y) {
    const double square_mm = *(const double *)pattern;
    return (((int)floor(X / square_mm) + (int)floor(Y / square_mm)) & 1) ? 210 : 40;
}

/* One square holds the whole box (floor of X / square is monotonic). */
static int chessboard_uniform(const void *pattern, double x0, double y0, double x1, double y1,
                              double *level) {
    const double square_mm = *(const double *)pattern;
    if (floor(x0 / square_mm) != floor(x1 / square_mm) ||
        floor(y0 / square_mm) != floor(y1 / square_mm))
        return 0;
    *level = chessboard_level(pattern, x0, y0);
    return 1;
}

int synth_render_chessboard(const double *ray_map, int squares_x, int squares_y, double square_mm,
                            double rx, double ry, double rz, const double t_mm[3], uint8_t *image) {
    return render_board(ray_map, squares_x * square_mm, squares_y * square_mm, square_mm,
                        chessboard_level, chessboard_uniform, &square_mm, rx, ry, rz, t_mm, image);
}

typedef struct circle_grid {
    int columns, rows, asymmetric;
    double pitch_mm, radius_mm, origin_mm; /* origin: centre of circle (0, 0) */
} circle_grid;

/* Dark circles (40) on white (210), centres in OpenCV's layout: symmetric
 * (j p, i p); asymmetric ((2 j + i % 2) p, i p). The nearest row is the only
 * one whose circle can hold the point (rows are p apart, radii < p / 2). */
static double circle_level(const void *pattern, double X, double Y) {
    const circle_grid *c = (const circle_grid *)pattern;
    const double x = X - c->origin_mm, y = Y - c->origin_mm, p = c->pitch_mm;
    const int i = (int)lround(y / p);
    if (i < 0 || i >= c->rows)
        return 210;
    const double shift = c->asymmetric ? (double)(i % 2) * p : 0.0;
    const double column_pitch = c->asymmetric ? 2 * p : p;
    const int j = (int)lround((x - shift) / column_pitch);
    if (j < 0 || j >= c->columns)
        return 210;
    const double dx = x - (shift + j * column_pitch), dy = y - i * p;
    return dx * dx + dy * dy <= c->radius_mm * c->radius_mm ? 40 : 210;
}

/* No circle touches the box (210), or one circle holds all of it (40).
 * Only circles of the rows and columns within a radius of the box can
 * reach it; the radius is widened (narrowed) by far more than rounding. A
 * point inside a circle is inside its nearest row and column's (radius <
 * pitch / 2), so circle_level() agrees. */
static int circle_uniform(const void *pattern, double x0, double y0, double x1, double y1,
                          double *level) {
    const circle_grid *c = (const circle_grid *)pattern;
    const double p = c->pitch_mm, r = c->radius_mm;
    const double column_pitch = c->asymmetric ? 2 * p : p;
    const double ax = x0 - c->origin_mm, bx = x1 - c->origin_mm;
    const double ay = y0 - c->origin_mm, by = y1 - c->origin_mm;
    int i_lo = (int)floor((ay - r) / p), i_hi = (int)ceil((by + r) / p);
    if (i_lo < 0)
        i_lo = 0;
    if (i_hi > c->rows - 1)
        i_hi = c->rows - 1;
    for (int i = i_lo; i <= i_hi; ++i) {
        const double shift = c->asymmetric ? (double)(i % 2) * p : 0.0;
        int j_lo = (int)floor((ax - shift - r) / column_pitch);
        int j_hi = (int)ceil((bx - shift + r) / column_pitch);
        if (j_lo < 0)
            j_lo = 0;
        if (j_hi > c->columns - 1)
            j_hi = c->columns - 1;
        for (int j = j_lo; j <= j_hi; ++j) {
            const double cx = shift + j * column_pitch, cy = i * p;
            /* The box's nearest and farthest points from the centre. */
            const double nx = cx < ax ? ax - cx : (cx > bx ? cx - bx : 0.0);
            const double ny = cy < ay ? ay - cy : (cy > by ? cy - by : 0.0);
            const double fx = fmax(fabs(ax - cx), fabs(bx - cx));
            const double fy = fmax(fabs(ay - cy), fabs(by - cy));
            if (nx * nx + ny * ny > r * r * (1 + 1e-9))
                continue; /* this circle misses the box */
            if (fx * fx + fy * fy < r * r * (1 - 1e-9)) {
                *level = 40; /* the box lies inside this circle */
                return 1;
            }
            return 0; /* an edge crosses the box */
        }
    }
    *level = 210;
    return 1;
}

int synth_render_circle_grid(const double *ray_map, int columns, int rows, double pitch_mm,
                             double radius_mm, int asymmetric, double rx, double ry, double rz,
                             const double t_mm[3], uint8_t *image) {
    const circle_grid c = {columns, rows, asymmetric, pitch_mm, radius_mm, pitch_mm};
    /* The board reaches one pitch beyond the outermost centres. */
    const double w = ((asymmetric ? 2 * (columns - 1) + 1 : columns - 1) + 2) * pitch_mm;
    const double hgt = (rows - 1 + 2) * pitch_mm;
    return render_board(ray_map, w, hgt, pitch_mm, circle_level, circle_uniform, &c, rx, ry, rz,
                        t_mm, image);
}
