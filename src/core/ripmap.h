// Horizontal rip-map of a lat-long source, for reading its polar rows cheaply.
//
// Level k (k >= 1) averages 2^k texels along x and none along y; texel i of level k is the mean
// of level-0 texels i 2^k ... (i+1) 2^k - 1 of the same row, so a level-0 image point x is
// point x / 2^k of level k (the pixel-centre rule holds at every level). Levels 1 ... K are
// packed side by side in one (H, W - W_K, C) float32 array; level k starts at column
// W - 2 W_k with W_k = W / 2^k. See envconv/resample/kernels.py for the level count rule.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "taps.h"

namespace envconv {

// First column of `level` (>= 1) in the packed array of a source `width` texels wide.
inline int64_t rip_offset(int64_t width, int level) { return width - 2 * (width >> level); }

// Rows beyond a footprint's reach that a rip-map read may touch: the bilinear tap's second row,
// the continuation over a pole, and the slack of interpolated tiles.
constexpr double kRipRowMargin = 3.0;

// Whether sub-samples within `extent` source rows of row position y stay in the rows next to
// each pole that the rip-map fill covered (`rows` at each pole of `height`).
inline bool rows_filled(double y, double extent, int64_t rows, int64_t height) {
    if (2 * rows >= height) return true;
    double reach = extent + kRipRowMargin;
    return y + reach <= double(rows) || y - reach >= double(height - rows);
}

// Add w x the bilinear read of one level at its point (x, y) to acc. Taps past the ends of a
// row wrap; taps past the first or last row continue over the pole: row -1 is row 0, row H is
// row H - 1, shifted by half a turn.
inline void level_tap(const Image& rip, int64_t start, int64_t level_width, double x, double y,
                      double w, double* acc) {
    const int64_t height = rip.height, nch = rip.channels;
    double fx = x - 0.5, fy = y - 0.5;
    int64_t x0 = floor_index(fx), y0 = floor_index(fy);
    double tx = fx - double(x0), ty = fy - double(y0);
    for (int k = 0; k < 4; ++k) {
        int64_t ix = x0 + (k & 1), iy = y0 + (k >> 1);
        double kw = w * ((k & 1) ? tx : 1.0 - tx) * ((k >> 1) ? ty : 1.0 - ty);
        if (iy < 0) {
            iy = -1 - iy;
            ix += level_width / 2;
        } else if (iy >= height) {
            iy = 2 * height - 1 - iy;
            ix += level_width / 2;
        }
        iy = std::min(std::max(iy, int64_t(0)), height - 1);
        ix = ((ix % level_width) + level_width) % level_width;
        const float* t = rip.texel(iy, start + ix);
        for (int64_t c = 0; c < nch; ++c) acc[c] += kw * double(t[c]);
    }
}

}  // namespace envconv
