// Exact integrals of a polygon over the unit texel grid (the area filter's rasteriser).
//
// For a closed polygon P with straight edges, in texel coordinates (texel (ix, iy) spans
// [ix, ix + 1) x [iy, iy + 1)), integrate returns, for every texel T that P overlaps, the area
// of P n T and its first moments about T's centre, Dx = int (x - ix - 1/2) and
// Dy = int (y - iy - 1/2) over P n T. It uses Green's theorem, area(P n T) = closed integral
// over the boundary of P of g_T(x) 1_T(y) dy with g_T(x) = clamp(x - ix, 0, 1): every edge
// adds to the texels it crosses (its part inside them) and, as a "cover", to every texel left
// of it in the same row, which a sweep from the right collects. Any closed polygon works
// (convex or not, one loop or several), and two polygons that share an edge traversed in
// opposite directions get exactly opposite contributions from it: pieces that share their
// edges partition the texels exactly.
//
// Values are signed: positive for a polygon whose shoelace area is positive (counter-clockwise
// with y up; with y down, as images store it, that is clockwise on screen).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace envconv {

// Per-row sums of the rasteriser: partial area, Dx and Dy of edge pieces inside a texel, and
// the covers (dy and dy times the mean y offset) that apply to every texel left of it.
struct GreenScratch {
    std::vector<double> pa, pdx, pdy, cdy, cv;
    void resize(int64_t width) {
        if (int64_t(pa.size()) >= width) return;
        size_t w = size_t(width);
        pa.resize(w);
        pdx.resize(w);
        pdy.resize(w);
        cdy.resize(w);
        cv.resize(w);
    }
};

// Shoelace area and first moments (about the origin) of a closed polygon.
inline void polygon_moments(const double* xs, const double* ys, int n, double& area,
                            double& mx, double& my) {
    area = mx = my = 0.0;
    for (int k = 0; k < n; ++k) {
        int l = k + 1 == n ? 0 : k + 1;
        double cross = xs[k] * ys[l] - xs[l] * ys[k];
        area += cross;
        mx += (xs[k] + xs[l]) * cross;
        my += (ys[k] + ys[l]) * cross;
    }
    area *= 0.5;
    mx *= 1.0 / 6.0;
    my *= 1.0 / 6.0;
}

// floor(x) as an index (x finite and well inside the int64 range).
inline int64_t floor_texel(double x) {
    int64_t i = int64_t(x);
    return i - int64_t(x < double(i));
}

namespace green_detail {

// Add the piece of an edge inside texel column c of a row (local coordinates: u = x - c in
// [0, 1], v = y - row - 1/2), from (up, vp) to (uq, vq).
inline void add_piece(GreenScratch& s, int64_t k, double up, double vp, double uq, double vq) {
    double dy = vq - vp;
    s.pa[k] += dy * 0.5 * (up + uq);
    s.pdx[k] += dy * 0.5 * ((up * up + up * uq + uq * uq) * (1.0 / 3.0) - 0.5 * (up + uq));
    s.pdy[k] += dy * (2.0 * up * vp + up * vq + uq * vp + 2.0 * uq * vq) * (1.0 / 6.0);
    s.cdy[k] += dy;
    s.cv[k] += dy * 0.5 * (vp + vq);
}

// Add the segment (xa, ya) -> (xb, yb), inside row `row`, split at every texel column it
// crosses; columns are relative to c0.
inline void add_row_segment(GreenScratch& s, int64_t c0, double row_mid, double xa, double ya,
                            double xb, double yb) {
    double va = ya - row_mid, vb = yb - row_mid;
    int64_t ca = int64_t(std::floor(xa)), cb = int64_t(std::floor(xb));
    if (ca == cb) {
        add_piece(s, ca - c0, xa - double(ca), va, xb - double(ca), vb);
        return;
    }
    // Walk the columns from a to b; t is the parameter along the segment.
    int64_t step = cb > ca ? 1 : -1;
    double inv = 1.0 / (xb - xa);
    double up = xa - double(ca), vp = va;
    for (int64_t c = ca; c != cb; c += step) {
        double edge = step > 0 ? double(c + 1) : double(c);
        double t = (edge - xa) * inv;
        double vq = va + t * (vb - va);
        add_piece(s, c - c0, up, vp, step > 0 ? 1.0 : 0.0, vq);
        up = step > 0 ? 0.0 : 1.0;
        vp = vq;
    }
    add_piece(s, cb - c0, up, vp, xb - double(cb), vb);
}

}  // namespace green_detail

// The box [xmin, xmax] x [ymin, ymax] of the n >= 1 points (xs, ys).
inline void polygon_box(const double* xs, const double* ys, int n, double& xmin, double& xmax,
                        double& ymin, double& ymax) {
    xmin = xmax = xs[0];
    ymin = ymax = ys[0];
    for (int k = 1; k < n; ++k) {
        xmin = std::min(xmin, xs[k]);
        xmax = std::max(xmax, xs[k]);
        ymin = std::min(ymin, ys[k]);
        ymax = std::max(ymax, ys[k]);
    }
}

// Integrate the closed polygon (xs, ys) of n vertices over the texel grid, calling
// sink.texel(ix, iy, area, dx, dy) once for every texel it overlaps (signed values, see
// above); sink.row(iy) is called before the texels of each row.
template <class Sink>
void integrate(const double* xs, const double* ys, int n, Sink& sink, GreenScratch& s) {
    if (n < 3) return;
    double xmin, xmax, ymin, ymax;
    polygon_box(xs, ys, n, xmin, xmax, ymin, ymax);
    if (!(xmin <= xmax && ymin <= ymax)) return;  // NaN
    int64_t c0 = int64_t(std::floor(xmin)), c1 = int64_t(std::floor(xmax));
    int64_t r0 = int64_t(std::floor(ymin)), r1 = int64_t(std::floor(ymax));
    if (c1 > c0 && double(c1) == xmax) --c1;
    if (r1 > r0 && double(r1) == ymax) --r1;
    if (c0 == c1 && r0 == r1) {  // inside one texel: the shoelace moments
        double area, mx, my;
        polygon_moments(xs, ys, n, area, mx, my);
        sink.row(r0);
        sink.texel(c0, r0, area, mx - (double(c0) + 0.5) * area, my - (double(r0) + 0.5) * area);
        return;
    }
    int64_t width = c1 - c0 + 2;  // one spare column: an edge may end exactly on c1 + 1
    s.resize(width);
    for (int64_t r = r0; r <= r1; ++r) {
        std::fill(s.pa.begin(), s.pa.begin() + width, 0.0);
        std::fill(s.pdx.begin(), s.pdx.begin() + width, 0.0);
        std::fill(s.pdy.begin(), s.pdy.begin() + width, 0.0);
        std::fill(s.cdy.begin(), s.cdy.begin() + width, 0.0);
        std::fill(s.cv.begin(), s.cv.begin() + width, 0.0);
        const double lo = double(r), hi = double(r + 1), mid = double(r) + 0.5;
        double row_lo = xmax + 1.0, row_hi = xmin - 1.0;
        for (int k = 0; k < n; ++k) {
            int l = k + 1 == n ? 0 : k + 1;
            double x0 = xs[k], y0 = ys[k], x1 = xs[l], y1 = ys[l];
            if (y0 == y1) continue;  // horizontal: no dy
            double ylo = std::max(std::min(y0, y1), lo), yhi = std::min(std::max(y0, y1), hi);
            if (!(ylo < yhi)) continue;
            double slope = (x1 - x0) / (y1 - y0);
            double ya = y0 < y1 ? ylo : yhi, yb = y0 < y1 ? yhi : ylo;
            double xa = ya == y0 ? x0 : x0 + (ya - y0) * slope;
            double xb = yb == y1 ? x1 : x0 + (yb - y0) * slope;
            xa = std::min(std::max(xa, xmin), xmax);
            xb = std::min(std::max(xb, xmin), xmax);
            row_lo = std::min(row_lo, std::min(xa, xb));
            row_hi = std::max(row_hi, std::max(xa, xb));
            green_detail::add_row_segment(s, c0, mid, xa, ya, xb, yb);
        }
        if (row_lo > row_hi) continue;
        int64_t first = std::max(c0, int64_t(std::floor(row_lo)));
        int64_t last = std::min(c1, int64_t(std::floor(row_hi)));
        if (last > first && double(last) == row_hi) --last;
        sink.row(r);
        double cover = 0.0, cover_v = 0.0;
        for (int64_t c = c1 + 1; c > last; --c) {  // covers from edges right of the row's span
            cover += s.cdy[c - c0];
            cover_v += s.cv[c - c0];
        }
        for (int64_t c = last; c >= first; --c) {
            int64_t k = c - c0;
            double area = s.pa[k] + cover;
            if (area != 0.0 || s.pdx[k] != 0.0 || s.pdy[k] != 0.0)
                sink.texel(c, r, area, s.pdx[k], s.pdy[k] + cover_v);
            cover += s.cdy[k];
            cover_v += s.cv[k];
        }
    }
}

// integrate() for a polygon whose bounding box spans at most kSmallCells texels each way (a
// pixel near 1:1): the same sums, kept on the stack, every edge walked once.
constexpr int kSmallCells = 4;

struct SmallCell {
    double pa, pdx, pdy, cdy, cv;
};

namespace green_detail {

// add_piece and add_row_segment on one row of SmallCells (columns relative to c0).
inline void small_piece(SmallCell* row, int64_t k, double up, double vp, double uq, double vq) {
    double dy = vq - vp;
    SmallCell& c = row[k];
    c.pa += dy * 0.5 * (up + uq);
    c.pdx += dy * 0.5 * ((up * up + up * uq + uq * uq) * (1.0 / 3.0) - 0.5 * (up + uq));
    c.pdy += dy * (2.0 * up * vp + up * vq + uq * vp + 2.0 * uq * vq) * (1.0 / 6.0);
    c.cdy += dy;
    c.cv += dy * 0.5 * (vp + vq);
}

inline void small_segment(SmallCell* row, int64_t c0, double row_mid, double xa, double ya,
                          double xb, double yb) {
    double va = ya - row_mid, vb = yb - row_mid;
    int64_t ca = floor_texel(xa), cb = floor_texel(xb);
    if (ca == cb) {
        small_piece(row, ca - c0, xa - double(ca), va, xb - double(ca), vb);
        return;
    }
    int64_t step = cb > ca ? 1 : -1;
    double inv = 1.0 / (xb - xa), up = xa - double(ca), vp = va;
    for (int64_t c = ca; c != cb; c += step) {
        double edge = step > 0 ? double(c + 1) : double(c);
        double vq = va + (edge - xa) * inv * (vb - va);
        small_piece(row, c - c0, up, vp, step > 0 ? 1.0 : 0.0, vq);
        up = step > 0 ? 0.0 : 1.0;
        vp = vq;
    }
    small_piece(row, cb - c0, up, vp, xb - double(cb), vb);
}

}  // namespace green_detail

// Returns false (and does nothing) when the bounding box is too large; integrate() then.
template <class Sink>
bool integrate_small(const double* xs, const double* ys, int n, Sink& sink) {
    double xmin, xmax, ymin, ymax;
    polygon_box(xs, ys, n, xmin, xmax, ymin, ymax);
    if (!(xmin <= xmax && ymin <= ymax)) return true;  // NaN: nothing
    int64_t c0 = floor_texel(xmin), c1 = floor_texel(xmax);
    int64_t r0 = floor_texel(ymin), r1 = floor_texel(ymax);
    if (c1 > c0 && double(c1) == xmax) --c1;
    if (r1 > r0 && double(r1) == ymax) --r1;
    if (c1 - c0 >= kSmallCells || r1 - r0 >= kSmallCells) return false;
    if (c0 == c1 && r0 == r1) {
        double area, mx, my;
        polygon_moments(xs, ys, n, area, mx, my);
        sink.row(r0);
        sink.texel(c0, r0, area, mx - (double(c0) + 0.5) * area, my - (double(r0) + 0.5) * area);
        return true;
    }
    const int rows = int(r1 - r0) + 1, width = int(c1 - c0) + 2;
    SmallCell cells[kSmallCells][kSmallCells + 1];
    double lo[kSmallCells], hi[kSmallCells];
    for (int r = 0; r < rows; ++r) {
        for (int c = 0; c < width; ++c) cells[r][c] = {0.0, 0.0, 0.0, 0.0, 0.0};
        lo[r] = xmax + 1.0;
        hi[r] = xmin - 1.0;
    }
    for (int k = 0; k < n; ++k) {
        int l = k + 1 == n ? 0 : k + 1;
        double x0 = xs[k], y0 = ys[k], x1 = xs[l], y1 = ys[l];
        if (y0 == y1) continue;
        double slope = (x1 - x0) / (y1 - y0);
        int64_t ra = std::max(r0, floor_texel(std::min(y0, y1)));
        int64_t rb = std::min(r1, floor_texel(std::max(y0, y1)));
        for (int64_t r = ra; r <= rb; ++r) {
            double ylo = std::max(std::min(y0, y1), double(r));
            double yhi = std::min(std::max(y0, y1), double(r + 1));
            if (!(ylo < yhi)) continue;
            double ya = y0 < y1 ? ylo : yhi, yb = y0 < y1 ? yhi : ylo;
            double xa = ya == y0 ? x0 : x0 + (ya - y0) * slope;
            double xb = yb == y1 ? x1 : x0 + (yb - y0) * slope;
            xa = std::min(std::max(xa, xmin), xmax);
            xb = std::min(std::max(xb, xmin), xmax);
            int q = int(r - r0);
            lo[q] = std::min(lo[q], std::min(xa, xb));
            hi[q] = std::max(hi[q], std::max(xa, xb));
            green_detail::small_segment(cells[q], c0, double(r) + 0.5, xa, ya, xb, yb);
        }
    }
    for (int q = 0; q < rows; ++q) {
        if (lo[q] > hi[q]) continue;
        int64_t first = std::max(c0, floor_texel(lo[q])), last = std::min(c1, floor_texel(hi[q]));
        if (last > first && double(last) == hi[q]) --last;
        sink.row(r0 + q);
        double cover = 0.0, cover_v = 0.0;
        for (int64_t c = c1 + 1; c > last; --c) {
            cover += cells[q][c - c0].cdy;
            cover_v += cells[q][c - c0].cv;
        }
        for (int64_t c = last; c >= first; --c) {
            const SmallCell& cell = cells[q][c - c0];
            double area = cell.pa + cover;
            if (area != 0.0 || cell.pdx != 0.0 || cell.pdy != 0.0)
                sink.texel(c, r0 + q, area, cell.pdx, cell.pdy + cover_v);
            cover += cell.cdy;
            cover_v += cell.cv;
        }
    }
    return true;
}

// integrate() for a polygon within kSmallCells x kSmallCells texels (footprints near 1:1),
// with the sums on the stack: each edge is walked through the texels it crosses in order
// (a grid traversal, stepping to whichever grid line comes next), each piece adding to its
// texel and covering the texels left of it in its row. kMomentY false: the sink needs no y
// moments (Dy passed as 0).
template <bool kMomentY, class Sink>
void integrate_walk(const double* xs, const double* ys, int n, int64_t c0, int64_t r0, int cols,
                    int rows, Sink& sink) {
    constexpr int W = kSmallCells + 1;  // a spare row and column: an edge may end on the far line
    double pa[W][W], cdy[W][W], pdx[W][W], pdy[W][W], cv[W][W];
    for (int q = 0; q <= rows; ++q) {
        for (int c = 0; c <= cols; ++c) {
            pa[q][c] = cdy[q][c] = 0.0;
            if (Sink::kMomentX) pdx[q][c] = 0.0;
            if (kMomentY) pdy[q][c] = cv[q][c] = 0.0;
        }
    }
    auto piece = [&](int c, int q, double px, double py, double qx, double qy) {
        double ey = qy - py, base = double(c0 + c);
        double up = px - base, uq = qx - base;
        pa[q][c] += ey * 0.5 * (up + uq);
        cdy[q][c] += ey;
        if (Sink::kMomentX)
            pdx[q][c] += ey * 0.5 * ((up * up + up * uq + uq * uq) * (1.0 / 3.0) - 0.5 * (up + uq));
        if (kMomentY) {
            double mid = double(r0 + q) + 0.5, vp = py - mid, vq = qy - mid;
            pdy[q][c] += ey * (up * (2.0 * vp + vq) + uq * (vp + 2.0 * vq)) * (1.0 / 6.0);
            cv[q][c] += ey * 0.5 * (vp + vq);
        }
    };
    for (int k = 0; k < n; ++k) {
        int l = k + 1 == n ? 0 : k + 1;
        const double x0 = xs[k], y0 = ys[k], x1 = xs[l], y1 = ys[l];
        const double dx = x1 - x0, dy = y1 - y0;
        if (dy == 0.0) continue;
        int64_t ix0 = floor_texel(x0), iy0 = floor_texel(y0);
        int steps_x = int(std::llabs(floor_texel(x1) - ix0)), steps_y = int(std::llabs(floor_texel(y1) - iy0));
        const int sx = dx > 0.0 ? 1 : -1, sy = dy > 0.0 ? 1 : -1;
        double line_x = double(sx > 0 ? ix0 + 1 : ix0), line_y = double(sy > 0 ? iy0 + 1 : iy0);
        double tx = steps_x ? (line_x - x0) / dx : 2.0, ty = steps_y ? (line_y - y0) / dy : 2.0;
        const double step_tx = steps_x ? double(sx) / dx : 0.0, step_ty = double(sy) / dy;
        int c = int(ix0 - c0), q = int(iy0 - r0);
        double px = x0, py = y0;
        for (int left = steps_x + steps_y; left > 0; --left) {
            double qx, qy;
            if (tx < ty) {
                qx = line_x;
                qy = y0 + tx * dy;
                piece(c, q, px, py, qx, qy);
                c += sx;
                line_x += sx;
                tx = --steps_x ? tx + step_tx : 2.0;
            } else {
                qy = line_y;
                qx = x0 + ty * dx;
                piece(c, q, px, py, qx, qy);
                q += sy;
                line_y += sy;
                ty = --steps_y ? ty + step_ty : 2.0;
            }
            px = qx;
            py = qy;
        }
        piece(c, q, px, py, x1, y1);
    }
    for (int q = 0; q < rows; ++q) {
        sink.row(r0 + q);
        double cover = cdy[q][cols], cover_v = kMomentY ? cv[q][cols] : 0.0;
        for (int c = cols - 1; c >= 0; --c) {
            double area = pa[q][c] + cover;
            double ddx = Sink::kMomentX ? pdx[q][c] : 0.0, ddy = kMomentY ? pdy[q][c] + cover_v : 0.0;
            if (area != 0.0 || ddx != 0.0 || ddy != 0.0) sink.texel(c0 + c, r0 + q, area, ddx, ddy);
            cover += cdy[q][c];
            if (kMomentY) cover_v += cv[q][c];
        }
    }
}

// integrate() choosing the cheapest exact way: one texel, 2 x 2 texels, kSmallCells, or rows.
template <class Sink>
void integrate_any(const double* xs, const double* ys, int n, Sink& sink, GreenScratch& s) {
    double xmin, xmax, ymin, ymax;
    polygon_box(xs, ys, n, xmin, xmax, ymin, ymax);
    if (!(xmin <= xmax && ymin <= ymax) || !(xmax - xmin < 1e9 && ymax - ymin < 1e9)) return;
    int64_t c0 = floor_texel(xmin), c1 = floor_texel(xmax);
    int64_t r0 = floor_texel(ymin), r1 = floor_texel(ymax);
    if (c1 > c0 && double(c1) == xmax) --c1;
    if (r1 > r0 && double(r1) == ymax) --r1;
    if (c1 - c0 < kSmallCells && r1 - r0 < kSmallCells) {
        int cols = int(c1 - c0) + 1, rows = int(r1 - r0) + 1;
        if (sink.flat(r0, r1)) integrate_walk<false>(xs, ys, n, c0, r0, cols, rows, sink);
        else integrate_walk<true>(xs, ys, n, c0, r0, cols, rows, sink);
        return;
    }
    if (!integrate_small(xs, ys, n, sink)) integrate(xs, ys, n, sink, s);
}

}  // namespace envconv
