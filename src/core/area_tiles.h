// The area filter's corner grids: the source points of every pixel corner of a tile, each
// computed once, so that neighbouring pixels share them and their footprints tile the source.
//
// A tile is a block of at most kTile x kTile output pixels inside one output cell. The corners
// on its boundary are mapped exactly (the neighbouring tile maps the same points the same
// way); the corners inside are a Coons patch of the boundary, in the continued coordinates of
// one source cell (the cell of the tile's first corner), checked against exact maps at five
// inside corners. A tile whose check fails splits into quarters, whose new boundaries are
// mapped exactly, down to tiles without inside corners. The patch also bounds how far a pixel
// edge's image strays from its chord (second differences of the grid).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "area_slow.h"

namespace envconv {

struct CornerGrid {
    int64_t i0, j0;  // output pixel of corner (0, 0)
    int w, h;        // pixels; corners (w + 1) x (h + 1)
    int64_t ref_cell;
    std::vector<SourcePoint> exact;  // the canonical point of every mapped corner (cell: its own)
    std::vector<double> x, y;        // every corner in ref_cell's continued coordinates
    std::vector<int64_t> fx, fy;     // the texel of each (floor of x, y), for a usable grid
    std::vector<char> inside;        // corner interpolated (else mapped exactly)
    double bend;                     // how far pixel edges' images stray from chords (pixels)
    bool usable;                     // every corner has a point in ref_cell
    std::vector<double> coons_u;     // coons_fill's scratch: i / w of a patch's columns
    double xmin, xmax, ymin, ymax;   // the box of every corner (x, y), of a usable grid

    void resize(int w_, int h_) {
        w = w_;
        h = h_;
        size_t count = size_t(w + 1) * size_t(h + 1);
        exact.resize(count);
        x.resize(count);
        y.resize(count);
        fx.resize(count);
        fy.resize(count);
        inside.assign(count, 0);
    }
    size_t at(int i, int j) const { return size_t(j) * size_t(w + 1) + size_t(i); }
    // Corner k's source point: mapped (exact), or interpolated in the reference cell.
    SourcePoint corner_point(size_t k) const { return inside[k] ? SourcePoint{x[k], y[k], ref_cell} : exact[k]; }
};

// Exact source point of output corner (x, y) through output cell `cell`.
inline SourcePoint exact_corner(const Conversion& cv, int64_t cell, double x, double y) {
    return exact_source(cv, cell, x, y);
}

// Express corner k of the grid (an exact point) in the reference cell's coordinates, near
// (ref_x, ref_y); false when it has none there.
inline bool to_reference(const Conversion& cv, CornerGrid& g, size_t k, double ref_x,
                         double ref_y) {
    const SourcePoint& p = g.exact[k];
    const Geometry& s = cv.src;
    if (p.cell < 0) return false;  // beyond a partial source's reach
    if (p.cell == g.ref_cell && s.family != kLatlong && s.family != kTennisball &&
        s.family != kOctahedral && s.family != kEqualArea) {
        g.x[k] = p.x;
        g.y[k] = p.y;
        return true;
    }
    if (p.cell == g.ref_cell && (s.family == kLatlong || s.family == kTennisball)) {
        double period = double(s.family == kLatlong ? 2 * s.n : 4 * s.n);
        g.x[k] = p.x + period * std::nearbyint((ref_x - p.x) / period);
        g.y[k] = p.y;
        return true;
    }
    return continued_point(s, g.ref_cell, source_direction(s, p), ref_x, ref_y, g.x[k], g.y[k]);
}

// Map corner (i, j) of the grid exactly (an output point of cell `cell`).
inline void map_exact(const Conversion& cv, int64_t cell, CornerGrid& g, int i, int j) {
    size_t k = g.at(i, j);
    g.exact[k] = exact_corner(cv, cell, double(g.i0 + i) * cv.scale_x, double(g.j0 + j) * cv.scale_y);
    g.inside[k] = 0;
}

// Express corners (i, j) ... along a line of the grid in the reference cell, each near the one
// before it (from (i, j) toward (i + n di, j + n dj)); false if one has no point there.
inline bool line_to_reference(const Conversion& cv, CornerGrid& g, int i, int j, int di, int dj,
                              int n) {
    for (int m = 1; m <= n; ++m) {
        size_t prev = g.at(i + (m - 1) * di, j + (m - 1) * dj), k = g.at(i + m * di, j + m * dj);
        if (!to_reference(cv, g, k, g.x[prev], g.y[prev])) return false;
    }
    return true;
}


// The source offset (dx, dy) at inside corner (i, j) of the grid in output pixels, through
// the grid's local Jacobian (central differences).
inline double pixels_off(const CornerGrid& g, int i, int j, double dx, double dy) {
    size_t l = g.at(i - 1, j), r = g.at(i + 1, j), u = g.at(i, j - 1), d = g.at(i, j + 1);
    double ax = 0.5 * (g.x[r] - g.x[l]), ay = 0.5 * (g.y[r] - g.y[l]);
    double bx = 0.5 * (g.x[d] - g.x[u]), by = 0.5 * (g.y[d] - g.y[u]);
    double det = ax * by - ay * bx;
    if (!(std::fabs(det) > 0.0)) return 1e300;
    return std::hypot(by * dx - bx * dy, ax * dy - ay * dx) / std::fabs(det);
}

// True when the output map is smooth over the level-0 rectangle [x0, x1] x [y0, y1] of
// `cell`: the octahedral and equal-area squares fold along their axes, their diamond
// |a| + |b| = 1 and (past them, in guard rings) their edges, where no interpolation holds.
inline bool output_smooth(const Geometry& d, int64_t cell, double x0, double y0, double x1,
                          double y1) {
    if (d.family != kOctahedral && d.family != kEqualArea) return true;
    double a0, b0, a1, b1;
    cell_local(d, cell, x0, y0, a0, b0);
    cell_local(d, cell, x1, y1, a1, b1);
    double alo = std::min(a0, a1), ahi = std::max(a0, a1), blo = std::min(b0, b1), bhi = std::max(b0, b1);
    for (double line : {-1.0, 0.0, 1.0}) {
        if (alo < line && line < ahi) return false;
        if (blo < line && line < bhi) return false;
    }
    // Off the axes |a| + |b| is linear on the box: its extremes are at corners.
    double lo = 1e300, hi = -1e300;
    for (double a : {alo, ahi}) {
        for (double b : {blo, bhi}) {
            lo = std::min(lo, std::fabs(a) + std::fabs(b));
            hi = std::max(hi, std::fabs(a) + std::fabs(b));
        }
    }
    return !(lo < 1.0 && 1.0 < hi);
}

// Coons patch of the sub-grid [a0, a1] x [b0, b1] from its boundary (in reference
// coordinates), then its check at up to five inside corners against their exact images:
// within tol output pixels.
inline bool coons_fill(const Conversion& cv, int64_t cell, CornerGrid& g, int a0, int b0, int a1,
                       int b1, double tol) {
    const int w = a1 - a0, h = b1 - b0;
    // u = i / w, one quotient a column rather than one a corner (the same values).
    g.coons_u.resize(size_t(w));
    double* us = g.coons_u.data();
    for (int i = 1; i < w; ++i) us[i] = double(i) / w;
    for (int q = 0; q < 2; ++q) {
        double* c = (q == 0 ? g.x : g.y).data();
        const double* top = c + g.at(a0, b0);
        const double* bot = c + g.at(a0, b1);
        const double c00 = top[0], c10 = top[w], c01 = bot[0], c11 = bot[w];
        for (int j = 1; j < h; ++j) {
            const double v = double(j) / h;
            double* row = c + g.at(a0, b0 + j);
            const double left = row[0], right = row[w];
            // (1 - v) top + v bottom + (1 - u) left + u right - bilinear(corners), with u = i / w.
            const double base = left - ((1.0 - v) * c00 + v * c01);
            const double slope = (right - ((1.0 - v) * c10 + v * c11)) - base;
            for (int i = 1; i < w; ++i) row[i] = (1.0 - v) * top[i] + v * bot[i] + base + us[i] * slope;
        }
    }
    // Interpolated corners: their points are (x, y) in the reference cell (corner_point).
    for (int j = b0 + 1; j < b1; ++j) std::fill_n(g.inside.begin() + g.at(a0 + 1, j), a1 - a0 - 1, char(1));
    const int checks[5][2] = {{2, 2}, {1, 1}, {3, 1}, {1, 3}, {3, 3}};  // quarters of the grid
    for (int c = 0; c < ((w >= 4 && h >= 4) ? 5 : 1); ++c) {
        int i = a0 + (w * checks[c][0]) / 4, j = b0 + (h * checks[c][1]) / 4;
        if (i <= a0 || i >= a1 || j <= b0 || j >= b1) continue;
        size_t k = g.at(i, j);
        SourcePoint e = exact_corner(cv, cell, double(g.i0 + i) * cv.scale_x,
                                     double(g.j0 + j) * cv.scale_y);
        if (e.cell < 0) return false;
        double ex, ey;
        if (!continued_point(cv.src, g.ref_cell, source_direction(cv.src, e), g.x[k], g.y[k], ex, ey))
            return false;
        if (!(pixels_off(g, i, j, ex - g.x[k], ey - g.y[k]) <= tol)) return false;
    }
    return true;
}

// Fill the inside of sub-grid [a0, a1] x [b0, b1] (whose boundary is mapped and expressed in
// the reference cell): a Coons patch where it passes its check, else quarters with exactly
// mapped new boundaries. False when a corner has no point in the reference cell.
inline bool fill_grid(const Conversion& cv, int64_t cell, CornerGrid& g, int a0, int b0, int a1,
                      int b1, double tol) {
    if (a1 - a0 < 2 || b1 - b0 < 2) return true;
    const bool smooth = output_smooth(cv.dst, cell, double(g.i0 + a0) * cv.scale_x,
                                      double(g.j0 + b0) * cv.scale_y, double(g.i0 + a1) * cv.scale_x,
                                      double(g.j0 + b1) * cv.scale_y);
    if (smooth && coons_fill(cv, cell, g, a0, b0, a1, b1, tol)) return true;
    int am = (a0 + a1) / 2, bm = (b0 + b1) / 2;
    for (int i = a0 + 1; i < a1; ++i) map_exact(cv, cell, g, i, bm);
    for (int j = b0 + 1; j < b1; ++j)
        if (j != bm) map_exact(cv, cell, g, am, j);
    if (!line_to_reference(cv, g, a0, bm, 1, 0, a1 - a0 - 1)) return false;
    if (!line_to_reference(cv, g, am, b0, 0, 1, bm - b0 - 1)) return false;
    if (!line_to_reference(cv, g, am, bm, 0, 1, b1 - bm - 1)) return false;
    return fill_grid(cv, cell, g, a0, b0, am, bm, tol) && fill_grid(cv, cell, g, am, b0, a1, bm, tol) &&
           fill_grid(cv, cell, g, a0, bm, am, b1, tol) && fill_grid(cv, cell, g, am, bm, a1, b1, tol);
}

// How far (output pixels) the images of the grid's pixel edges stray from their chords: the
// largest second difference along its rows and columns, across the line it runs along,
// divided by the spacing of the lines there, over eight (the sagitta of a parabola).
// Sampled (see below); the general path refines any edge that strays further.
inline double grid_bend(const CornerGrid& g) {
    const double* x = g.x.data();
    const double* y = g.y.data();
    const int64_t st = g.w + 1;
    double worst = 0.0;
    // Bend at k along step d (1: a row, st: a column), against the neighbouring lines at k - e
    // and k + e (scaled by `lines`, the number of spacings between them).
    auto bend = [&](int64_t k, int64_t d, int64_t lo, int64_t hi, double lines) {
        double tx = x[k + d] - x[k - d], ty = y[k + d] - y[k - d];
        double dx = x[k - d] - 2.0 * x[k] + x[k + d], dy = y[k - d] - 2.0 * y[k] + y[k + d];
        double sx = x[hi] - x[lo], sy = y[hi] - y[lo];
        double across = std::fabs(tx * sy - ty * sx), off = std::fabs(tx * dy - ty * dx);
        double b = across > 0.0 ? lines * off / across : 1e300;
        if (!(b <= worst)) worst = b;
    };
    // The grid is smooth (a Coons patch of a checked map), so its bend varies slowly: sampled
    // on a 5 x 5 lattice of corners, ends and quarters of each side included.
    for (int qj = 0; qj <= 4; ++qj) {
        const int j = (qj * g.h) / 4;
        const int64_t up = j > 0 ? -st : 0, down = j < g.h ? st : 0;
        const double rows = double((j > 0) + (j < g.h));
        for (int qi = 0; qi <= 4; ++qi) {
            const int i = (qi * g.w) / 4;
            const int64_t k = j * st + i;
            if (i > 0 && i < g.w) bend(k, 1, k + up, k + down, rows);
            if (j > 0 && j < g.h) {
                const int64_t l = i > 0 ? -1 : 0, r = i < g.w ? 1 : 0;
                bend(k, st, k + l, k + r, double((i > 0) + (i < g.w)));
            }
        }
    }
    return worst / 8.0;
}

// True when a tennisball grid's boundary reaches within 22.5 deg of a pole of its reference
// band's chart (|theta| > 67.5 deg, far past what the band owns): around that pole the band's
// continued coordinates no longer follow the sphere, and a tile of a small output can hold one
// (measured: a 32 px tennisball into a 42 x 21 lat-long, whose first tile spans the image's
// left 265 deg, gave pixels up to 180 times their solid angle through its Coons interior and
// polylines). Such a grid is not usable: its pixels take the general path, each in its owner's
// chart. (Only the boundary is mapped when this is asked; a pole inside it would break the
// check of its far corner.)
inline bool near_band_pole(const Geometry& s, const CornerGrid& g) {
    if (s.family != kTennisball) return false;
    const int64_t st = g.w + 1;
    double worst = 0.0;
    auto check = [&](size_t k) {
        double a, b;
        cell_local(s, g.ref_cell, g.x[k], g.y[k], a, b);
        worst = std::max(worst, std::fabs(b));  // b: theta over 45 deg
    };
    for (int i = 0; i <= g.w; ++i) {
        check(size_t(i));
        check(size_t(g.h * st + i));
    }
    for (int j = 1; j < g.h; ++j) {
        check(size_t(j * st));
        check(size_t(j * st + g.w));
    }
    return worst > 1.5;
}

// The corner grid of the w x h pixels from (i0, j0) of output cell `cell`. Every corner gets
// its canonical point (exact, or interpolated inside); usable tells whether all of them could
// be expressed in one source cell for the direct path. `left`, when not null, holds the exact
// points of the grid's left column (the right column of the tile before it, mapped already).
inline void map_grid(const Conversion& cv, int64_t cell, int64_t i0, int64_t j0, int w, int h,
                     CornerGrid& g, const SourcePoint* left = nullptr) {
    const double tol = kCornerTol;
    g.i0 = i0;
    g.j0 = j0;
    g.resize(w, h);
    for (int j = 0; j <= h; ++j) {
        if (left) {
            g.exact[g.at(0, j)] = left[j];
            g.inside[g.at(0, j)] = 0;
        } else {
            map_exact(cv, cell, g, 0, j);
        }
    }
    for (int i = 1; i <= w; ++i) {
        map_exact(cv, cell, g, i, 0);
        map_exact(cv, cell, g, i, h);
    }
    for (int j = 1; j < h; ++j) map_exact(cv, cell, g, w, j);
    const SourcePoint& first = g.exact[0];
    g.ref_cell = first.cell;
    if (first.cell < 0) {  // beyond a partial source's reach: every corner for the general path
        for (int j = 1; j < h; ++j)
            for (int i = 1; i < w; ++i) map_exact(cv, cell, g, i, j);
        g.usable = false;
        g.bend = 1e300;
        return;
    }
    g.x[0] = first.x;
    g.y[0] = first.y;
    // The boundary is expressed along its four sides; the far corner, reached both ways, must
    // come out the same, or the boundary winds around a singular point (a lat-long pole): no
    // direct path for such a tile.
    g.usable = line_to_reference(cv, g, 0, 0, 1, 0, w) && line_to_reference(cv, g, w, 0, 0, 1, h);
    const double far_x = g.x[g.at(w, h)], far_y = g.y[g.at(w, h)];
    g.usable = g.usable && line_to_reference(cv, g, 0, 0, 0, 1, h) &&
               line_to_reference(cv, g, 0, h, 1, 0, w) &&
               std::hypot(g.x[g.at(w, h)] - far_x, g.y[g.at(w, h)] - far_y) < 1e-6 * (1.0 + std::fabs(far_x)) &&
               !near_band_pole(cv.src, g) && fill_grid(cv, cell, g, 0, 0, w, h, tol);
    if (!g.usable) {  // every corner exact, for the general path
        for (int j = 1; j < h; ++j)
            for (int i = 1; i < w; ++i) map_exact(cv, cell, g, i, j);
        g.bend = 1e300;
        return;
    }
    g.bend = grid_bend(g);
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (size_t k = 0; k < g.x.size(); ++k) {
        g.fx[k] = floor_texel(g.x[k]);
        g.fy[k] = floor_texel(g.y[k]);
        xmin = std::min(xmin, g.x[k]);
        xmax = std::max(xmax, g.x[k]);
        ymin = std::min(ymin, g.y[k]);
        ymax = std::max(ymax, g.y[k]);
    }
    g.xmin = xmin;
    g.xmax = xmax;
    g.ymin = ymin;
    g.ymax = ymax;
}


}  // namespace envconv
