// Seam-aware source reads: nearest, bilinear and clamped Catmull-Rom (bicubic) filters.
//
// A tap is a source texel. A tap inside the sample's own (grown) cell, and for disk layouts
// inside the readable radius, is read directly. Any other tap is never read as stored: its
// centre is mapped with the cell's continued mapping to a direction, and the texel that owns
// that direction is read instead. Taps past a cube face's edge thus read the neighbouring face,
// lat-long taps wrap and continue over the poles, and taps past a disk read across the rim.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "cells.h"

namespace envconv {

// kArea integrates the box reconstruction over each pixel's footprint (area.h); the others
// read the source at sub-sample points.
enum FilterCode : int { kNearest = 0, kBilinear = 1, kBicubic = 2, kArea = 3 };

// A read-only (H, W, C) float32 image, C-contiguous.
struct Image {
    const float* data;
    int64_t height, width, channels;
    const float* texel(int64_t iy, int64_t ix) const {
        return data + (iy * width + ix) * channels;
    }
};

// True when texel (ix, iy) lies in `cell`'s readable region.
inline bool tap_ok(const Geometry& g, int64_t cell, int64_t ix, int64_t iy) {
    int64_t cw = g.cell_width(), ch = g.cell_height();
    int64_t x0 = (cell % g.columns) * cw, y0 = (cell / g.columns) * ch;
    if (ix < x0 || ix >= x0 + cw || iy < y0 || iy >= y0 + ch) return false;
    if (g.disk()) {
        double n = double(g.n);
        double a = 2.0 * (double(ix) + 0.5 - double(x0 + g.guard)) / n - 1.0;
        double b = 2.0 * (double(iy) + 0.5 - double(y0 + g.guard)) / n - 1.0;
        double r = 1.0 + 2.0 * double(g.guard) / n;
        return a * a + b * b <= r * r;
    }
    return true;
}

// Texel that holds the continued direction of a foreign tap (ix, iy) of `cell`.
inline void remap_tap(const Geometry& g, int64_t cell, int64_t ix, int64_t iy, int64_t& jx,
                      int64_t& jy) {
    double a, b;
    cell_local(g, cell, double(ix) + 0.5, double(iy) + 0.5, a, b);
    Vec3 d = face_to_dir(g, g.cell_face[cell], a, b);
    FacePoint f = dir_to_face(g, d.x, d.y, d.z);
    ImagePoint p = face_to_image(g, f.face, f.a, f.b);
    int64_t x0 = (p.cell % g.columns) * g.cell_width() + g.guard;
    int64_t y0 = (p.cell / g.columns) * g.cell_height() + g.guard;
    jx = std::min(std::max(floor_index(p.x), x0), x0 + g.nx - 1);
    jy = std::min(std::max(floor_index(p.y), y0), y0 + g.n - 1);
}

inline void fetch(const Geometry& g, int64_t cell, int64_t ix, int64_t iy, bool fast,
                  int64_t& jx, int64_t& jy) {
    if (fast || tap_ok(g, cell, ix, iy)) {
        jx = ix;
        jy = iy;
        return;
    }
    remap_tap(g, cell, ix, iy, jx, jy);
}

// True when every texel of [x_lo, x_hi] x [y_lo, y_hi] is directly readable.
inline bool block_inside(const Geometry& g, int64_t cell, int64_t x_lo, int64_t y_lo,
                         int64_t x_hi, int64_t y_hi) {
    int64_t cw = g.cell_width(), ch = g.cell_height();
    int64_t x0 = (cell % g.columns) * cw, y0 = (cell / g.columns) * ch;
    if (x_lo < x0 || x_hi >= x0 + cw || y_lo < y0 || y_hi >= y0 + ch) return false;
    if (g.disk()) {
        return tap_ok(g, cell, x_lo, y_lo) && tap_ok(g, cell, x_hi, y_lo) &&
               tap_ok(g, cell, x_lo, y_hi) && tap_ok(g, cell, x_hi, y_hi);
    }
    return true;
}

// Catmull-Rom weights for offsets -1, 0, 1, 2 at fraction t.
inline void cubic_weights(double t, double w[4]) {
    double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

// Add w x (filtered source at image point (px, py) of `cell`) to acc[0 .. C); `tmp` is scratch
// of 3 C doubles (the bicubic sum and clamping bounds).
inline void accumulate_sample(const Image& src, const Geometry& g, int64_t cell, double px,
                              double py, int filter, double w, double* acc, double* tmp) {
    const int64_t nch = src.channels;
    int64_t jx, jy;
    if (filter == kNearest) {
        fetch(g, cell, floor_index(px), floor_index(py), false, jx, jy);
        const float* t = src.texel(jy, jx);
        for (int64_t c = 0; c < nch; ++c) acc[c] += w * double(t[c]);
        return;
    }
    double fx = px - 0.5, fy = py - 0.5;
    int64_t x0 = floor_index(fx), y0 = floor_index(fy);
    double tx = fx - double(x0), ty = fy - double(y0);
    if (filter == kBilinear) {
        bool fast = block_inside(g, cell, x0, y0, x0 + 1, y0 + 1);
        int64_t ax, ay, bx, by, cx, cy, dx, dy;
        fetch(g, cell, x0, y0, fast, ax, ay);
        fetch(g, cell, x0 + 1, y0, fast, bx, by);
        fetch(g, cell, x0, y0 + 1, fast, cx, cy);
        fetch(g, cell, x0 + 1, y0 + 1, fast, dx, dy);
        double w00 = w * (1.0 - tx) * (1.0 - ty), w10 = w * tx * (1.0 - ty);
        double w01 = w * (1.0 - tx) * ty, w11 = w * tx * ty;
        const float *p00 = src.texel(ay, ax), *p10 = src.texel(by, bx);
        const float *p01 = src.texel(cy, cx), *p11 = src.texel(dy, dx);
        for (int64_t c = 0; c < nch; ++c) {
            acc[c] += w00 * double(p00[c]) + w10 * double(p10[c]) + w01 * double(p01[c]) +
                      w11 * double(p11[c]);
        }
        return;
    }
    // Catmull-Rom over 4 x 4 taps, clamped to the range of the central 2 x 2 taps so that it
    // cannot ring past its neighbours (no new negatives next to an HDR highlight).
    bool fast = block_inside(g, cell, x0 - 1, y0 - 1, x0 + 2, y0 + 2);
    double wx[4], wy[4];
    cubic_weights(tx, wx);
    cubic_weights(ty, wy);
    double *sum = tmp, *lo = tmp + nch, *hi = tmp + 2 * nch;
    for (int64_t c = 0; c < nch; ++c) {
        sum[c] = 0.0;
        lo[c] = std::numeric_limits<double>::infinity();
        hi[c] = -std::numeric_limits<double>::infinity();
    }
    for (int k = 0; k < 4; ++k) {
        for (int m = 0; m < 4; ++m) {
            fetch(g, cell, x0 - 1 + m, y0 - 1 + k, fast, jx, jy);
            const float* t = src.texel(jy, jx);
            bool central = (k == 1 || k == 2) && (m == 1 || m == 2);
            double ww = wx[m] * wy[k];
            for (int64_t c = 0; c < nch; ++c) {
                double v = double(t[c]);
                sum[c] += ww * v;
                if (central) {
                    lo[c] = std::min(lo[c], v);
                    hi[c] = std::max(hi[c], v);
                }
            }
        }
    }
    for (int64_t c = 0; c < nch; ++c) acc[c] += w * std::min(std::max(sum[c], lo[c]), hi[c]);
}

}  // namespace envconv
