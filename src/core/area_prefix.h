// The area filter's direct path for lat-long and tennisball sources: footprints integrated
// through their edges, each edge once for the two pixels that share it.
//
// By Green's theorem, the colour a footprint P holds, sum over texels t of s_t times the solid
// angle of P n t, is the closed integral over P's boundary of Q dy, with
// Q(x, y) = rho(y) S_r(x): rho the row's density model (area_source.h) and S_r(x) the running
// sum of row r's values from the tile's first column to x (a prefix sum plus the part of the
// texel under x). Its solid angle is the same with S_r(x) = x - c0. The integral along an edge
// walks the texels it crosses (green.h's grid traversal) and needs nothing else, so a pixel's
// colour is the sum of its four edges' integrals, and a pixel 16 texels wide costs its
// perimeter, not its area. The prefix sums are made per tile over its source box.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "area_source.h"
#include "green.h"

namespace envconv {

// Two doubles as one SSE2 register (GCC and Clang vector extensions): edge_integral keeps a
// three-channel walk's four sums in two of them.
typedef double v2d __attribute__((vector_size(16)));
inline v2d load2(const double* p) {
    v2d v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

// Running sums of a box of source rows: p[(r * (cols + 1) + c) * nch + ch] is the sum of
// texels c0 ... c0 + c - 1 of row r0 + r (columns modulo `period` when it is not 0).
struct PrefixTable {
    int64_t r0 = 0, c0 = 0, rows = 0, cols = 0, nch = 0;
    std::vector<double> p;

    // Fill the table for rows [r0, r1] and columns [c0, c1]; false when a texel is not finite
    // (inf and NaN stay in the pixels that cover them: the per-texel path then). A row's last
    // sums are finite only if all its texels are (or it overflowed: the other path too).
    bool build(const Image& src, int64_t period, int64_t r0_, int64_t r1, int64_t c0_, int64_t c1) {
        r0 = r0_;
        c0 = c0_;
        rows = r1 - r0 + 1;
        cols = c1 - c0 + 1;
        nch = src.channels;
        size_t need = size_t(rows * (cols + 1) * nch);
        if (p.size() < need) p.resize(need);  // grows to the largest table only: no refills
        int64_t start = period ? ((c0 % period) + period) % period : c0;
        int64_t r = 0;
        if (nch == 3) {  // two rows at once: six running sums, twice the additions in flight
            for (; r + 1 < rows; r += 2) {
                double* row = p.data() + r * (cols + 1) * 3;
                double* next = row + (cols + 1) * 3;
                for (int64_t ch = 0; ch < 3; ++ch) row[ch] = next[ch] = 0.0;
                int64_t done = 0, x = start;
                while (done < cols) {
                    int64_t run = period ? std::min(cols - done, period - x) : cols - done;
                    const float* v = src.texel(r0 + r, x);
                    const float* w = src.texel(r0 + r + 1, x);
                    double* out = row + (done + 1) * 3;
                    double* out2 = next + (done + 1) * 3;
                    double a = out[-3], b = out[-2], c = out[-1];
                    double d = out2[-3], e = out2[-2], f = out2[-1];
                    for (int64_t k = 0; k < run; ++k, v += 3, w += 3, out += 3, out2 += 3) {
                        out[0] = a += double(v[0]);
                        out[1] = b += double(v[1]);
                        out[2] = c += double(v[2]);
                        out2[0] = d += double(w[0]);
                        out2[1] = e += double(w[1]);
                        out2[2] = f += double(w[2]);
                    }
                    done += run;
                    x = 0;
                }
                for (int64_t ch = 0; ch < 3; ++ch)
                    if (!std::isfinite(row[cols * 3 + ch]) || !std::isfinite(next[cols * 3 + ch])) return false;
            }
        }
        for (; r < rows; ++r) {
            double* row = p.data() + r * (cols + 1) * nch;
            for (int64_t ch = 0; ch < nch; ++ch) row[ch] = 0.0;
            // At most two runs of source columns: up to the wrap, then from column 0.
            int64_t done = 0, x = start;
            while (done < cols) {
                int64_t run = period ? std::min(cols - done, period - x) : cols - done;
                const float* v = src.texel(r0 + r, x);
                double* out = row + (done + 1) * nch;
                if (nch == 3) {  // running sums in registers, not through the stored row
                    double a = out[-3], b = out[-2], c = out[-1];
                    for (int64_t k = 0; k < run; ++k, v += 3, out += 3) {
                        out[0] = a += double(v[0]);
                        out[1] = b += double(v[1]);
                        out[2] = c += double(v[2]);
                    }
                } else {
                    for (int64_t k = 0; k < run * nch; ++k) out[k] = out[k - nch] + double(v[k]);
                }
                done += run;
                x = 0;
            }
            for (int64_t ch = 0; ch < nch; ++ch)
                if (!std::isfinite(row[cols * nch + ch])) return false;
        }
        return true;
    }
};

// Add the integral of Q dy along the edge (x0, y0) -> (x1, y1) (in texels (ix0, iy0) and
// (ix1, iy1)) to out[0] (solid angle) and out[1 ...] (colour): the density of row r is
// m_r + g_r (y - r - 1/2), from model.row_m, row_g (rows relative to row_base). The edge lies
// inside the table. The walk keeps the texel's place in the table and its row's density as it
// steps, so that a piece costs a few multiplications per channel.
//
// kBow: the edge is the parabola P(t) = C(t) + t (t - 1) D / 2 about its chord C(t) =
// P0 + t (P1 - P0), with bow = cross(D, P1 - P0) / 2 (texels squared). To first order in its
// offset from the chord, the integral of Q dy along it is the chord's plus the integral of
// dQ/dx = f (density times value) over the sliver between them: f(C(t)) cross(d(t), P1 - P0)
// dt, that is bow times the sum over the chord's pieces of f there times G(t_q) - G(t_p),
// G(t) = t^3 / 3 - t^2 / 2 (the parabola's sliver, measured along the chord). Exact for the
// sliver's area (its solid angle where the density is constant); f is taken on the chord, so
// a sliver that reaches past a texel line the chord does not cross counts that part as the
// chord's texel. One walk instead of a polyline's two or four. (area.cpp scales the bow to
// the sliver of the polyline through the parabola's points, which the general path takes.)
template <int NCH, bool kGrad, bool kBow = false>
void edge_integral(const PrefixTable& t, const SourceModel& model, int64_t row_base, double x0,
                   double y0, int64_t ix0, int64_t iy0, double x1, double y1, int64_t ix1,
                   int64_t iy1, double* out, double bow = 0.0) {
    const double dx = x1 - x0, dy = y1 - y0;
    if (dy == 0.0 && !kBow) return;  // a level chord holds nothing; its sliver may
    const int64_t nch = NCH ? NCH : t.nch, row_stride = (t.cols + 1) * nch;
    if constexpr (NCH == 3 && !kGrad && !kBow) {
        // A vertical edge (a meridian of a lat-long, as every vertical pixel side of a cube's
        // side faces is) crosses rows only: S_r(x) = b_r + s_r u at one u, no reciprocals.
        if (dx == 0.0) {
            const double* pr = t.p.data() + ((iy0 - t.r0) * (t.cols + 1) + (ix0 - t.c0)) * 3;
            const double* row_m = model.row_m.data() - row_base;
            const double u = x0 - double(ix0), col = double(ix0 - t.c0);
            const int sy = dy > 0.0 ? 1 : -1;
            const int64_t step = sy * row_stride;
            v2d sum01 = {0.0, 0.0}, sum23 = {0.0, 0.0};
            const v2d su = {1.0, 0.0};
            double py = y0, line_y = double(sy > 0 ? iy0 + 1 : iy0);
            int64_t r = iy0;
            auto piece = [&](double qy) {
                const double em = (qy - py) * row_m[r];
                const v2d b01 = {col, pr[0]}, s01 = su * u + v2d{0.0, (pr[3] - pr[0]) * u};
                const v2d b23 = load2(pr + 1), s23 = (load2(pr + 4) - b23) * u;
                sum01 += em * (b01 + s01);
                sum23 += em * (b23 + s23);
            };
            for (int64_t left = std::llabs(iy1 - iy0); left > 0; --left) {
                piece(line_y);
                py = line_y;
                line_y += double(sy);
                r += sy;
                pr += step;
            }
            piece(y1);
            out[0] += sum01[0];
            out[1] += sum01[1];
            out[2] += sum23[0];
            out[3] += sum23[1];
            return;
        }
    }
    int steps_x = int(std::llabs(ix1 - ix0)), steps_y = int(std::llabs(iy1 - iy0));
    const int sx = dx > 0.0 ? 1 : -1, sy = dy > 0.0 ? 1 : -1;
    double line_x = double(sx > 0 ? ix0 + 1 : ix0), line_y = double(sy > 0 ? iy0 + 1 : iy0);
    // Two reciprocals, not four quotients: the divisions were a walk's largest fixed cost (most
    // walks take one or two pieces).
    // (A bowed level chord's 1 / dy is infinite and never used: it crosses no row.)
    const double inv_dx = steps_x ? 1.0 / dx : 0.0, inv_dy = 1.0 / dy;
    double tx = steps_x ? (line_x - x0) * inv_dx : 2.0, ty = steps_y ? (line_y - y0) * inv_dy : 2.0;
    const double step_tx = double(sx) * inv_dx, step_ty = double(sy) * inv_dy;
    const double* pr = t.p.data() + ((iy0 - t.r0) * (t.cols + 1) + (ix0 - t.c0)) * nch;
    const double* row_m = model.row_m.data() - row_base;
    const double* row_g = model.row_g.data() - row_base;
    int64_t r = iy0;
    double m = row_m[r], g = kGrad ? row_g[r] : 0.0, mid = double(r) + 0.5;
    double base_x = double(ix0), col = double(ix0 - t.c0);
    double local[1 + (NCH ? NCH : 8)] = {};
    double* sum = NCH || nch <= 8 ? local : out;
    // Three channels: the sums (solid angle, colour) as the pairs (sum[0], sum[1]) and
    // (sum[2], sum[3]), held in registers for the whole walk. (Summed through the array, they
    // went through memory, and reading them back as pairs at the end stalled on the separate
    // scalar stores: a third of this function's time.) The solid angle is the colour of a row
    // whose running sums are the columns: base col, step 1. Same operations, same results.
    v2d sum01 = {0.0, 0.0}, sum23 = {0.0, 0.0};
    // kBow: the sliver's G at the piece's start; its part of the piece, bow (G(tq) - G(tp)),
    // times the density there is added to the weight of the texel's value s (the solid
    // angle's s is 1).
    double g_p = 0.0;
    auto sliver = [&](double tq) {
        const double g_q = tq * tq * (tq * (1.0 / 3.0) - 0.5), part = bow * (g_q - g_p);
        g_p = g_q;
        return part;
    };
    auto piece = [&](double px, double py, double qx, double qy, double tq) {
        double ey = qy - py, up = px - base_x, uq = qx - base_x, ubar = 0.5 * (up + uq);
        if constexpr (NCH == 3) {
            const v2d b01 = {col, pr[0]}, s01 = {1.0, pr[3] - pr[0]};
            const v2d b23 = load2(pr + 1), s23 = load2(pr + 4) - b23;
            if (!kGrad) {
                const double em = ey * m;
                if constexpr (kBow) {
                    const double ws = em * ubar + m * sliver(tq);
                    sum01 += em * b01 + s01 * ws;
                    sum23 += em * b23 + s23 * ws;
                    return;
                }
                sum01 += em * (b01 + s01 * ubar);
                sum23 += em * (b23 + s23 * ubar);
                return;
            }
            double vp = py - mid, vq = qy - mid, vbar = 0.5 * (vp + vq);
            double uv = (up * (2.0 * vp + vq) + uq * (vp + 2.0 * vq)) * (1.0 / 6.0);
            // ey (m (b + s ubar) + g (b vbar + s uv)) = b (em + eg vbar) + s (em ubar + eg uv):
            // two scalar weights, then two products a pair.
            const double em = ey * m, eg = ey * g;
            const double wb = em + eg * vbar;
            double ws = em * ubar + eg * uv;
            if constexpr (kBow) ws += (m + g * vbar) * sliver(tq);
            sum01 += b01 * wb + s01 * ws;
            sum23 += b23 * wb + s23 * ws;
            return;
        }
        const double density = kGrad ? m + g * 0.5 * ((py - mid) + (qy - mid)) : m;
        const double bowed = kBow ? density * sliver(tq) : 0.0;
        if (!kGrad) {
            double em = ey * m;
            sum[0] += em * (col + ubar) + bowed;
            for (int64_t ch = 0; ch < nch; ++ch)
                sum[1 + ch] += em * (pr[ch] + (pr[nch + ch] - pr[ch]) * ubar) + bowed * (pr[nch + ch] - pr[ch]);
            return;
        }
        double vp = py - mid, vq = qy - mid, vbar = 0.5 * (vp + vq);
        double uv = (up * (2.0 * vp + vq) + uq * (vp + 2.0 * vq)) * (1.0 / 6.0);
        sum[0] += ey * (m * (col + ubar) + g * (col * vbar + uv)) + bowed;
        for (int64_t ch = 0; ch < nch; ++ch) {
            double b = pr[ch], s = pr[nch + ch] - b;
            sum[1 + ch] += ey * (m * (b + s * ubar) + g * (b * vbar + s * uv)) + bowed * s;
        }
    };
    // Which line comes next is as good as random: the steps are selects, not branches.
    double px = x0, py = y0;
    const int64_t step_cx = sx * nch, step_cy = sy * row_stride;
    for (int left = steps_x + steps_y; left > 0; --left) {
        const bool across_x = tx < ty;
        const double qx = across_x ? line_x : x0 + ty * dx;
        const double qy = across_x ? y0 + tx * dy : line_y;
        piece(px, py, qx, qy, across_x ? tx : ty);
        px = qx;
        py = qy;
        pr += across_x ? step_cx : step_cy;
        const double shift_x = across_x ? double(sx) : 0.0, shift_y = across_x ? 0.0 : double(sy);
        base_x += shift_x;
        col += shift_x;
        line_x += shift_x;
        r += across_x ? 0 : sy;
        mid += shift_y;
        line_y += shift_y;
        m = row_m[r];
        if (kGrad) g = row_g[r];
        steps_x -= across_x;
        steps_y -= !across_x;
        tx = across_x ? (steps_x ? tx + step_tx : 2.0) : tx;
        ty = across_x ? ty : (steps_y ? ty + step_ty : 2.0);
    }
    piece(px, py, x1, y1, 1.0);
    if constexpr (NCH == 3) {
        out[0] += sum01[0];
        out[1] += sum01[1];
        out[2] += sum23[0];
        out[3] += sum23[1];
        return;
    }
    if (sum != out) {
        for (int64_t c = 0; c <= nch; ++c) out[c] += sum[c];
    }
}

// Running sums down the columns of a box of source rows whose density is flat (every row's
// g_r is 0), the density inside: p[(k * cols + c) * 3 + ch] is the sum of m_r times texel
// (r, c0 + c) over rows r0 ... r0 + k - 1 (columns modulo `period` when it is not 0), and
// m[k] the sum of m_r alone (the solid angle's). Three channels. Row k + 1 is row k plus a
// source row: built in the source's order, a running sum a column.
//
// With P(x, y) = the integral of density times value down column floor(x) from row r0 to y,
// the colour a footprint holds is also minus the closed integral of P dx (Green's theorem, as
// area_prefix.h's Q dy): a vertical side contributes nothing. Where every vertical side of a
// tile lies on one source column's meridian (a cube's side faces from a lat-long: x depends
// on the longitude alone), only its horizontal sides are walked, half of the walks.
struct ColumnTable {
    int64_t r0 = 0, c0 = 0, rows = 0, cols = 0, nch = 3;
    std::vector<double> p, m;

    // Fill the table for rows [r0, r1] and columns [c0, c1] (row densities row_m, relative to
    // row_base); false when a sum is not finite (the per-texel path then).
    bool build(const Image& src, const std::vector<double>& row_m, int64_t row_base,
               int64_t period, int64_t r0_, int64_t r1, int64_t c0_, int64_t c1) {
        r0 = r0_;
        c0 = c0_;
        rows = r1 - r0 + 1;
        cols = c1 - c0 + 1;
        const int64_t line = cols * 3;
        size_t need = size_t((rows + 1) * line);
        if (p.size() < need) p.resize(need);  // grows to the largest table only: no refills
        m.resize(size_t(rows + 1));
        m[0] = 0.0;
        std::fill(p.begin(), p.begin() + line, 0.0);
        const int64_t start = period ? ((c0 % period) + period) % period : c0;
        for (int64_t k = 0; k < rows; ++k) {
            const double mk = row_m[size_t(r0 + k - row_base)];
            m[size_t(k + 1)] = m[size_t(k)] + mk;
            const double* above = p.data() + k * line;
            double* out = p.data() + (k + 1) * line;
            int64_t done = 0, x = start;
            while (done < cols) {  // at most two runs of source columns: up to the wrap, then from 0
                int64_t run = period ? std::min(cols - done, period - x) : cols - done;
                const float* v = src.texel(r0 + k, x);
                for (int64_t q = done * 3, end = (done + run) * 3; q < end; ++q, ++v)
                    out[q] = above[q] + mk * double(*v);
                done += run;
                x = 0;
            }
        }
        const double* last = p.data() + rows * line;
        for (int64_t q = 0; q < line; ++q)
            if (!std::isfinite(last[q])) return false;
        return true;
    }
};

// Add minus the integral of P dx along the edge (x0, y0) -> (x1, y1) (in texels (ix0, iy0)
// and (ix1, iy1)) to out[0] (solid angle) and out[1 ...] (colour), P from the column table
// (ColumnTable). The edge lies inside the table. In texel (c, r), P is linear in y, and y in x
// along a piece, so the piece holds its length in x times P at its mean y: one product a
// channel, as edge_integral's flat pieces. A vertical edge holds nothing.
inline void edge_integral_columns(const ColumnTable& t, double x0, double y0, int64_t ix0,
                                  int64_t iy0, double x1, double y1, int64_t ix1, int64_t iy1,
                                  double* out) {
    const double dx = x1 - x0, dy = y1 - y0;
    if (dx == 0.0) return;
    const int64_t line = t.cols * 3;  // the table's next row
    int steps_x = int(std::llabs(ix1 - ix0)), steps_y = int(std::llabs(iy1 - iy0));
    const int sx = dx > 0.0 ? 1 : -1, sy = dy > 0.0 ? 1 : -1;
    double line_x = double(sx > 0 ? ix0 + 1 : ix0), line_y = double(sy > 0 ? iy0 + 1 : iy0);
    const double inv_dx = 1.0 / dx, inv_dy = steps_y ? 1.0 / dy : 0.0;
    double tx = steps_x ? (line_x - x0) * inv_dx : 2.0, ty = steps_y ? (line_y - y0) * inv_dy : 2.0;
    const double step_tx = double(sx) * inv_dx, step_ty = double(sy) * inv_dy;
    const double* pc = t.p.data() + (iy0 - t.r0) * line + (ix0 - t.c0) * 3;
    const double* pm = t.m.data() + (iy0 - t.r0);
    double base_y = double(iy0);
    // (solid angle, colour 0) and (colour 1, colour 2) as pairs, as edge_integral's.
    v2d sum01 = {0.0, 0.0}, sum23 = {0.0, 0.0};
    auto piece = [&](double px, double py, double qx, double qy) {
        const double ex = px - qx, vbar = 0.5 * (py + qy) - base_y;  // minus: -P dx
        const v2d b01 = {pm[0], pc[0]}, s01 = v2d{pm[1], pc[line]} - b01;
        const v2d b23 = load2(pc + 1), s23 = load2(pc + line + 1) - b23;
        sum01 += ex * (b01 + s01 * vbar);
        sum23 += ex * (b23 + s23 * vbar);
    };
    double px = x0, py = y0;
    const int64_t step_cx = sx * 3, step_cy = sy * line;
    for (int left = steps_x + steps_y; left > 0; --left) {
        const bool across_x = tx < ty;
        const double qx = across_x ? line_x : x0 + ty * dx;
        const double qy = across_x ? y0 + tx * dy : line_y;
        piece(px, py, qx, qy);
        px = qx;
        py = qy;
        pc += across_x ? step_cx : step_cy;
        pm += across_x ? 0 : sy;
        const double shift_x = across_x ? double(sx) : 0.0, shift_y = across_x ? 0.0 : double(sy);
        line_x += shift_x;
        base_y += shift_y;
        line_y += shift_y;
        steps_x -= across_x;
        steps_y -= !across_x;
        tx = across_x ? (steps_x ? tx + step_tx : 2.0) : tx;
        ty = across_x ? ty : (steps_y ? ty + step_ty : 2.0);
    }
    piece(px, py, x1, y1);
    out[0] += sum01[0];
    out[1] += sum01[1];
    out[2] += sum23[0];
    out[3] += sum23[1];
}

// Edge integrals of a tile, each computed once: horizontal edge (i, j) runs from corner (i, j)
// to (i + 1, j), vertical edge (i, j) from (i, j) to (i, j + 1); and each pixel's sums.
struct EdgeMemo {
    int w = 0, h = 0;
    int64_t stride = 0;  // doubles per edge: 1 + channels (solid angle, colour)
    std::vector<double> hv, vv, pixel;
    // A curved tile's edges (horizontal edges first, then vertical ones). refine: 0 chord,
    // 1 refined (its points px, py [first[e], first[e + 1])), 2 and 3 the parabola the grid
    // implies through its midpoint or its quarter points (computed from its corners and D =
    // (dx, dy), area.cpp's edge_point), -1 not in the reference cell.
    std::vector<int32_t> first;
    std::vector<double> px, py;
    std::vector<signed char> refine;
    std::vector<double> dx, dy, bow;  // per parabola edge: D (texels) and edge_integral's bow
    void reset(int w_, int h_, int64_t nch) {
        w = w_;
        h = h_;
        stride = 1 + nch;
        hv.resize(size_t((h + 1) * w * stride));
        vv.resize(size_t(h * (w + 1) * stride));
        pixel.resize(size_t(h * w * stride));
    }
    size_t horizontal(int i, int j) const { return size_t(j * w + i); }
    size_t vertical(int i, int j) const { return size_t((h + 1) * w + j * (w + 1) + i); }
};

}  // namespace envconv
