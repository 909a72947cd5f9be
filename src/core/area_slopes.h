// Slopes of the area filter's piecewise-linear reconstruction of the source.
//
// Inside texel t (centre (cx, cy), level-0 image pixels, y down as stored) the source is
// f(x, y) = s_t + ax_t (x - cx) + ay_t (y - cy): ax, ay in colour per texel, per channel. They
// are central differences of the texel's four neighbours, scaled down together (per channel)
// until the texel's corners, s +- (|ax| + |ay|) / 2, stay within the minimum and maximum of
// the texel and its neighbours (a Barth-Jespersen limiter): the reconstruction never leaves
// that range, so no negative value and no overshoot next to an HDR sun, and a linear ramp is
// kept as it is. Past a cell's edge the neighbour is the texel across the seam (remap_tap). The
// slope along an axis is 0 (the box) where it has no neighbour (past a disk's rim, a lat-long's
// poles); both are 0 in a lat-long's pole rows, in texels a disk's rim cuts, and wherever a
// texel or neighbour is not finite (or the slopes overflow).
//
// The planes x, y hold ax and ay at the same offsets as the image holds s. A piece of texel t
// adds c (ax Dx + ay Dy) to the colour (Dx, Dy its first moments about the centre, green.h;
// c = slope_weight, area_source.h), which adds up to 0 over the whole texel: every texel still
// hands out exactly s_t times its solid angle. Where the general path reads a texel in another's
// place (a continued grid past a cell's edge), it turns that texel's slopes into its frame if
// the grids map onto each other by a reflection or turn (the octahedral and equal-area folds),
// else takes none (the box).
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "area_source.h"
#include "parallel.h"

namespace envconv {

namespace slope_detail {

// A limited slope is scaled a few float roundings short of its bound, so that the corners
// stay within range as they are computed, not only in exact arithmetic.
constexpr float kShrink = 1.0f - 8.0f * FLT_EPSILON;

// The limited slopes of one channel: s the texel, (l, r) its neighbours along x, (t, b) along
// y (with hx, hy false: none, that axis' slope is 0 and its neighbours bound nothing).
inline void limit(float s, float l, float r, float t, float b, bool hx, bool hy, float& ax,
                  float& ay) {
    ax = hx ? 0.5f * (r - l) : 0.0f;
    ay = hy ? 0.5f * (b - t) : 0.0f;
    float hi = s, lo = s;
    if (hx) {
        hi = std::max(hi, std::max(l, r));
        lo = std::min(lo, std::min(l, r));
    }
    if (hy) {
        hi = std::max(hi, std::max(t, b));
        lo = std::min(lo, std::min(t, b));
    }
    float room = std::min(hi - s, s - lo), d = 0.5f * (std::fabs(ax) + std::fabs(ay));
    float k = room < d ? room / d * kShrink : 1.0f;
    ax *= k;
    ay *= k;
    bool ok = std::fabs(s) <= FLT_MAX && std::fabs(ax) <= FLT_MAX && std::fabs(ay) <= FLT_MAX;
    ax = ok ? ax : 0.0f;
    ay = ok ? ay : 0.0f;
}

// limit() over n consecutive floats whose neighbours are all there: v[k -+ xs] along x,
// v[k -+ ys] along y (branch-free, so that it vectorises).
inline void run(const float* v, int64_t n, int64_t xs, int64_t ys, float* __restrict ox,
                float* __restrict oy) {
    const float *vl = v - xs, *vr = v + xs, *vt = v - ys, *vb = v + ys;
    for (int64_t k = 0; k < n; ++k) {
        float s = v[k], l = vl[k], r = vr[k], t = vt[k], b = vb[k];
        float ax = 0.5f * (r - l), ay = 0.5f * (b - t);
        float hi = std::max(std::max(std::max(l, r), std::max(t, b)), s);
        float lo = std::min(std::min(std::min(l, r), std::min(t, b)), s);
        float room = std::min(hi - s, s - lo), d = 0.5f * (std::fabs(ax) + std::fabs(ay));
        float q = room < d ? room / std::max(d, FLT_MIN) * kShrink : 1.0f;
        ax *= q;
        ay *= q;
        bool ok = (s + ax + ay) * 0.0f == 0.0f;  // all finite (an overflowing sum: 0 too)
        ox[k] = ok ? ax : 0.0f;
        oy[k] = ok ? ay : 0.0f;
    }
}

// True when texel (ix, iy) is a neighbour the slopes of `cell`'s texels may use; ix wraps
// in a lat-long.
inline bool usable(const Geometry& g, int64_t cell, int64_t& ix, int64_t iy) {
    if (g.family == kLatlong && g.guard == 0) {
        if (iy < 0 || iy >= g.n) return false;
        int64_t w = 2 * g.n;
        ix = ((ix % w) + w) % w;
        return true;
    }
    return area_readable(g, cell, ix, iy);
}

// Neighbour (jx, jy) of a texel of `cell`: itself where the cell holds it; past a cell's edge
// the texel across the seam (remap_tap: the one that holds its continued centre's direction),
// but none past a disk's rim or a lat-long's poles.
inline const float* neighbour(const Image& img, const Geometry& g, int64_t cell, int64_t jx,
                              int64_t jy) {
    if (usable(g, cell, jx, jy)) return img.texel(jy, jx);
    if (g.disk() || g.family == kLatlong) return nullptr;
    int64_t kx, ky;
    remap_tap(g, cell, jx, jy, kx, ky);
    return img.texel(ky, kx);
}

// The slopes of texel (ix, iy) of `cell` (readable), each neighbour found by neighbour().
inline void texel(const Image& img, const Geometry& g, int64_t cell, int64_t ix, int64_t iy,
                  float* sx, float* sy) {
    const int64_t nch = img.channels, at = (iy * img.width + ix) * nch;
    const float *l = neighbour(img, g, cell, ix - 1, iy), *r = neighbour(img, g, cell, ix + 1, iy);
    const float *t = neighbour(img, g, cell, ix, iy - 1), *b = neighbour(img, g, cell, ix, iy + 1);
    const bool hx = l && r, hy = t && b;
    const float* s = img.data + at;
    for (int64_t c = 0; c < nch; ++c) {
        limit(s[c], hx ? l[c] : 0.0f, hx ? r[c] : 0.0f, hy ? t[c] : 0.0f, hy ? b[c] : 0.0f, hx, hy,
              sx[at + c], sy[at + c]);
    }
}

// True when texel (ix, iy) of the cell whose valid region starts at (x0, y0) lies wholly in
// its disk (or the layout has none): a texel the rim cuts keeps the box, whose pieces on this
// side of the rim then still hand out exactly its value.
inline bool in_disk(const Geometry& g, int64_t x0, int64_t y0, int64_t ix, int64_t iy) {
    if (!g.disk()) return true;
    double c = 0.5 * double(g.n);
    double dx = std::max(std::fabs(double(ix) - double(x0) - c), std::fabs(double(ix + 1) - double(x0) - c));
    double dy = std::max(std::fabs(double(iy) - double(y0) - c), std::fabs(double(iy + 1) - double(y0) - c));
    return dx * dx + dy * dy <= c * c;
}

// The slopes of image row iy (sx, sy already zero outside the valid regions).
inline void row(const Image& img, const Geometry& g, int64_t iy, float* sx, float* sy) {
    const int64_t cw = g.cell_width(), ch = g.cell_height(), nch = img.channels;
    const int64_t band = iy / ch, y0 = band * ch + g.guard;
    if (iy < y0 || iy >= y0 + g.n) return;
    const bool pole = g.family == kLatlong && (iy == y0 || iy == y0 + g.n - 1);
    if (pole) return;  // a lat-long's pole rows: the box
    const bool inner_rows = iy > y0 && iy < y0 + g.n - 1 && !g.disk();
    for (int64_t col = 0; col < g.columns; ++col) {
        const int64_t cell = band * g.columns + col;
        if (g.cell_face[cell] < 0) continue;
        const int64_t x0 = col * cw + g.guard, x1 = x0 + g.nx;
        if (inner_rows && g.nx > 2) {  // the inner columns at once, the two edges checked
            const int64_t at = (iy * img.width + x0 + 1) * nch;
            run(img.data + at, (g.nx - 2) * nch, nch, img.width * nch, sx + at, sy + at);
            texel(img, g, cell, x0, iy, sx, sy);
            texel(img, g, cell, x1 - 1, iy, sx, sy);
            continue;
        }
        for (int64_t x = x0; x < x1; ++x)
            if (in_disk(g, x0, y0, x, iy)) texel(img, g, cell, x, iy, sx, sy);
    }
}

}  // namespace slope_detail

// Fill sx, sy (as large as the image) with the slopes of every texel (0 outside the valid
// regions), rows in parallel.
inline void build_slopes(const Image& img, const Geometry& g, int threads, std::vector<float>& sx,
                         std::vector<float>& sy) {
    const size_t size = size_t(img.height * img.width * img.channels);
    sx.assign(size, 0.0f);
    sy.assign(size, 0.0f);
    constexpr int64_t kRows = 16;
    parallel_for((img.height + kRows - 1) / kRows, threads, [&](int64_t task) {
        int64_t end = std::min(img.height, (task + 1) * kRows);
        for (int64_t iy = task * kRows; iy < end; ++iy)
            slope_detail::row(img, g, iy, sx.data(), sy.data());
    });
}

}  // namespace envconv
