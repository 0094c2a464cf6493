/* The practical ceiling for fusemap's insertion loop, measured on the same machine:
 * a bare Amanatides-Woo traversal over a dense float32 log-odds array, reading a SCAN2D01
 * scan file (the format of the project's benchmark baselines). No tiles, no clamping, no
 * once-per-scan rule, no invalid-return bookkeeping: free update on every crossed cell,
 * occupied update on the end cell. Only the insertion loop is timed.
 *
 *   cc -O3 -march=native -o bare_traversal bare_traversal.c -lm
 *   ./bare_traversal SCANFILE
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc != 2) { fprintf(stderr, "usage: %s SCANFILE\n", argv[0]); return 2; }
    FILE *f = fopen(argv[1], "rb");
    if (!f) { perror(argv[1]); return 1; }
    char magic[8];
    int64_t h[4];
    double d[7];
    if (fread(magic, 1, 8, f) != 8 || memcmp(magic, "SCAN2D01", 8) || fread(h, 8, 4, f) != 4 || fread(d, 8, 7, f) != 7) {
        fprintf(stderr, "%s: bad header\n", argv[1]);
        return 1;
    }
    int64_t ns = h[0], nb = h[1], w = h[2], hh = h[3];
    double amin = d[0], ainc = d[1], rmin = d[2], rmax = d[3], res = d[4], ox = d[5], oy = d[6];
    size_t n = (size_t)ns * (size_t)(nb + 3);
    double *rec = malloc(n * sizeof(double));
    if (!rec || fread(rec, sizeof(double), n, f) != n) { fprintf(stderr, "short file\n"); return 1; }
    fclose(f);
    float *grid = calloc((size_t)w * hh, sizeof(float));
    const float lo = (float)log(0.9 / 0.1), lf = (float)log(0.4 / 0.6);
    uint64_t visits = 0, beams = 0;
    double t0 = now();
    for (int64_t s = 0; s < ns; ++s) {
        const double *r = rec + s * (nb + 3);
        double x = r[0], y = r[1], th = r[2];
        for (int64_t b = 0; b < nb; ++b) {
            double range = r[3 + b];
            ++beams;
            if (!(range > rmin && range < rmax)) continue;
            double a = th + amin + b * ainc;
            double u0 = (x - ox) / res, v0 = (y - oy) / res;
            double u1 = u0 + range * cos(a) / res, v1 = v0 + range * sin(a) / res;
            int64_t ix = (int64_t)floor(u0), iy = (int64_t)floor(v0);
            int64_t ex = (int64_t)floor(u1), ey = (int64_t)floor(v1);
            double dx = u1 - u0, dy = v1 - v0;
            int64_t sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
            double tdx = dx != 0 ? fabs(1.0 / dx) : INFINITY, tdy = dy != 0 ? fabs(1.0 / dy) : INFINITY;
            double tmx = dx > 0 ? (floor(u0) + 1 - u0) * tdx : (dx < 0 ? (u0 - floor(u0)) * tdx : INFINITY);
            double tmy = dy > 0 ? (floor(v0) + 1 - v0) * tdy : (dy < 0 ? (v0 - floor(v0)) * tdy : INFINITY);
            int64_t rx = llabs(ex - ix), ry = llabs(ey - iy);
            for (;;) {
                ++visits;
                if (rx == 0 && ry == 0) break;
                if (ix >= 0 && ix < w && iy >= 0 && iy < hh) grid[iy * w + ix] += lf;
                if (ry == 0 || (rx != 0 && tmx < tmy)) { ix += sx; tmx += tdx; --rx; }
                else { iy += sy; tmy += tdy; --ry; }
            }
            if (ix >= 0 && ix < w && iy >= 0 && iy < hh) grid[iy * w + ix] += lo;
        }
    }
    double dt = now() - t0;
    double sum = 0;
    for (int64_t i = 0; i < w * hh; ++i) sum += grid[i];
    printf("{\"system\":\"bare-c\",\"scans\":%lld,\"beams\":%llu,\"cell_visits\":%llu,\"insert_s\":%.6f,"
           "\"beams_per_s\":%.1f,\"cell_visits_per_s\":%.1f,\"checksum\":%.3f}\n",
           (long long)ns, (unsigned long long)beams, (unsigned long long)visits, dt, beams / dt, visits / dt, sum);
    return 0;
}
