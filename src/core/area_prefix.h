// The area filter's direct path for lat-long and tennisball sources: footprints integrated
// through their edges, each edge once for the two pixels that share it.
//
// By Green's theorem, the colour a footprint P holds, the integral over P of rho f (f the
// linear reconstruction of area_slopes.h, rho the row's density model, area_source.h), is the
// closed integral over P's boundary of Q dy - P dx. Q(x, y) = rho(y) S_r(x) + c ax (u^2 - u) / 2
// carries the values: S_r(x) the running sum of row r's values from the tile's first column to
// x (a prefix sum plus the part of the texel under x, u = x - ix); the x slope's term and
// P = c ay (w^2 - w) / 2 (w = y - iy) carry the slopes, c the row's slope weight (sr per
// texel^2). Both slope terms vanish on the texel's sides, so they need no running sums and add
// nothing over a whole texel. Its solid angle is the same with S_r(x) = x - c0 and no slopes.
// The integral along an edge walks the texels it crosses (green.h's grid traversal) and needs
// nothing else, so a pixel's colour is the sum of its four edges' integrals, and a pixel 16
// texels wide costs its perimeter, not its area. The prefix sums are made per tile over its
// source box.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "area_source.h"
#include "green.h"

namespace envconv {

// Two doubles as one SSE2 register (GCC and Clang vector extensions).
typedef double v2d __attribute__((vector_size(16)));
inline v2d load2(const double* p) {
    v2d v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

// Running sums of a box of source rows, entry (r, c) at p[(r * (cols + 1) + c) * 3 nch]: the
// sum of texels c0 ... c0 + c - 1 of row r0 + r (nch values; columns modulo `period` when it is
// not 0), then the slopes ax and ay of texel c0 + c (area_slopes.h; 0 in the last entry).
struct PrefixTable {
    int64_t r0 = 0, c0 = 0, rows = 0, cols = 0, nch = 0;
    std::vector<double> p;

    // Fill the table for rows [r0, r1] and columns [c0, c1] from the image and its slope planes
    // sx, sy; false when a texel is not finite (inf and NaN stay in the pixels that cover them:
    // the per-texel path then). A row's last sums are finite only if all its texels are (or it
    // overflowed: the other path too).
    bool build(const Image& src, const float* sx, const float* sy, int64_t period, int64_t r0_,
               int64_t r1, int64_t c0_, int64_t c1) {
        r0 = r0_;
        c0 = c0_;
        rows = r1 - r0 + 1;
        cols = c1 - c0 + 1;
        nch = src.channels;
        const int64_t e = 3 * nch;
        size_t need = size_t(rows * (cols + 1) * e);
        if (p.size() < need) p.resize(need);  // grows to the largest table only: no refills
        int64_t start = period ? ((c0 % period) + period) % period : c0;
        for (int64_t r = 0; r < rows; ++r) {
            double* row = p.data() + r * (cols + 1) * e;
            for (int64_t ch = 0; ch < nch; ++ch) row[ch] = 0.0;
            // At most two runs of source columns: up to the wrap, then from column 0.
            int64_t done = 0, x = start;
            while (done < cols) {
                int64_t run = period ? std::min(cols - done, period - x) : cols - done;
                const int64_t at = ((r0 + r) * src.width + x) * nch;
                const float *v = src.data + at, *ax = sx + at, *ay = sy + at;
                double* out = row + done * e;
                if (nch == 3) {  // running sums in registers, not through the stored row
                    double a = out[0], b = out[1], c = out[2];
                    for (int64_t k = 0; k < run; ++k, v += 3, ax += 3, ay += 3, out += 9) {
                        out[3] = double(ax[0]);
                        out[4] = double(ax[1]);
                        out[5] = double(ax[2]);
                        out[6] = double(ay[0]);
                        out[7] = double(ay[1]);
                        out[8] = double(ay[2]);
                        out[9] = a += double(v[0]);
                        out[10] = b += double(v[1]);
                        out[11] = c += double(v[2]);
                    }
                } else {
                    for (int64_t k = 0; k < run; ++k, v += nch, ax += nch, ay += nch, out += e) {
                        for (int64_t ch = 0; ch < nch; ++ch) {
                            out[nch + ch] = double(ax[ch]);
                            out[2 * nch + ch] = double(ay[ch]);
                            out[e + ch] = out[ch] + double(v[ch]);
                        }
                    }
                }
                done += run;
                x = 0;
            }
            double* last = row + cols * e;
            for (int64_t ch = 0; ch < nch; ++ch) {
                last[nch + ch] = last[2 * nch + ch] = 0.0;
                if (!std::isfinite(last[ch])) return false;
            }
        }
        return true;
    }
};

// Add the integral of Q dy - P dx along the edge (x0, y0) -> (x1, y1) (in texels (ix0, iy0)
// and (ix1, iy1)) to out[0] (solid angle) and out[1 ...] (colour): the density of row r is
// m_r + g_r (y - r - 1/2), from model.row_m, row_g (rows relative to row_base). The edge lies
// inside the table. The walk keeps the texel's place in the table and its row's density as it
// steps, so that a piece costs a few multiplications per channel.
//
// In texel t, with u = x - ix and w = y - iy in [0, 1]: Q = rho(y) (S + s u) + c ax (u^2 - u) / 2
// and P = c ay (w^2 - w) / 2, S the table's sum of s left of the texel. Their divergence is
// the reconstruction times the density, its slope terms weighted by the row's least density c
// (slope_weight: over a whole texel they add nothing); P and the slope part of Q vanish on the
// texel's sides, so that they need no running sums. Along a piece, u and w are linear: the means of
// u, (u^2 - u) / 2, (w^2 - w) / 2 (and u (y - iy - 1/2) for the density's slope) are closed.
template <int NCH, bool kGrad>
void edge_integral(const PrefixTable& t, const SourceModel& model, int64_t row_base, double x0,
                   double y0, int64_t ix0, int64_t iy0, double x1, double y1, int64_t ix1,
                   int64_t iy1, double* out) {
    const double dx = x1 - x0, dy = y1 - y0;
    if (dy == 0.0 && dx == 0.0) return;
    const int64_t nch = NCH ? NCH : t.nch, e = 3 * nch, row_stride = (t.cols + 1) * e;
    int steps_x = int(std::llabs(ix1 - ix0)), steps_y = int(std::llabs(iy1 - iy0));
    const int sx = dx > 0.0 ? 1 : -1, sy = dy > 0.0 ? 1 : -1;
    const double off_x = sx > 0 ? 1.0 : 0.0, off_y = sy > 0 ? 1.0 : 0.0;  // the next lines, from the texel's corner
    double tx = steps_x ? (double(ix0) + off_x - x0) / dx : 2.0;
    double ty = steps_y ? (double(iy0) + off_y - y0) / dy : 2.0;
    const double step_tx = steps_x ? double(sx) / dx : 0.0, step_ty = steps_y ? double(sy) / dy : 0.0;
    int64_t at = ((iy0 - t.r0) * (t.cols + 1) + (ix0 - t.c0)) * e;
    const double* row_m = model.row_m.data() - row_base;
    const double* row_g = model.row_g.data() - row_base;
    int64_t r = iy0;
    double m = row_m[r], g = kGrad ? row_g[r] : 0.0, top = double(r);
    double c = kGrad ? slope_weight(m, 0.0, g) : m;
    double base_x = double(ix0);
    const double first_col = double(t.c0);
    double local[1 + (NCH ? NCH : 8)] = {};
    double* sum = NCH || nch <= 8 ? local : out;
    v2d sum01 = {0.0, 0.0};  // three channels: the first two as a pair
    auto piece = [&](double px, double py, double qx, double qy) {
        const double* pr = t.p.data() + at;  // S, then ax, ay, then the next texel's S
        // Means along the piece of u, (u^2 - u) / 2 and (w^2 - w) / 2 (u, w linear along it).
        double ex = qx - px, ey = qy - py;
        double ubar = 0.5 * (px + qx) - base_x, wbar = 0.5 * (py + qy) - top;
        double uu = 0.5 * (ubar * (ubar - 1.0) + ex * ex * (1.0 / 12.0));
        double ww = 0.5 * (wbar * (wbar - 1.0) + ey * ey * (1.0 / 12.0));
        double em = ey * m, emx = ey * c * uu, emy = -ex * c * ww;
        // The colour is cb S + cn S' + emx ax + emy ay per channel (S' the next texel's sum).
        double cn = em * ubar, cb = em - cn, col = base_x - first_col;
        if (kGrad) {
            double vbar = wbar - 0.5, uv = ubar * vbar + ex * ey * (1.0 / 12.0);  // mean of u v
            sum[0] += em * col + cn + ey * g * (col * vbar + uv);
            cb += ey * g * (vbar - uv);
            cn += ey * g * uv;
        } else {
            sum[0] += em * col + cn;
        }
        if (NCH == 3) {
            sum01 += cb * load2(pr) + cn * load2(pr + 9) + emx * load2(pr + 3) + emy * load2(pr + 6);
            sum[3] += cb * pr[2] + cn * pr[11] + emx * pr[5] + emy * pr[8];
            return;
        }
        for (int64_t ch = 0; ch < nch; ++ch)
            sum[1 + ch] += cb * pr[ch] + cn * pr[e + ch] + emx * pr[nch + ch] + emy * pr[2 * nch + ch];
    };
    // Which line comes next is as good as random: the steps are selects, not branches.
    double px = x0, py = y0;
    const int64_t step_cx = sx * e, step_cy = sy * row_stride;
    for (int left = steps_x + steps_y; left > 0; --left) {
        const bool across_x = tx < ty;
        const double qx = across_x ? base_x + off_x : x0 + ty * dx;
        const double qy = across_x ? y0 + tx * dy : top + off_y;
        piece(px, py, qx, qy);
        px = qx;
        py = qy;
        at += across_x ? step_cx : step_cy;
        const double shift_x = across_x ? double(sx) : 0.0, shift_y = across_x ? 0.0 : double(sy);
        base_x += shift_x;
        r += across_x ? 0 : sy;
        top += shift_y;
        m = row_m[r];
        if (kGrad) {
            g = row_g[r];
            c = slope_weight(m, 0.0, g);
        } else {
            c = m;
        }
        steps_x -= across_x;
        steps_y -= !across_x;
        tx = across_x ? (steps_x ? tx + step_tx : 2.0) : tx;
        ty = across_x ? ty : (steps_y ? ty + step_ty : 2.0);
    }
    piece(px, py, x1, y1);
    sum[1] += sum01[0];
    sum[2] += sum01[1];
    if (sum != out) {
        for (int64_t c = 0; c <= nch; ++c) out[c] += sum[c];
    }
}

// Edge integrals of a tile, each computed once: horizontal edge (i, j) runs from corner (i, j)
// to (i + 1, j), vertical edge (i, j) from (i, j) to (i, j + 1); and each pixel's sums.
struct EdgeMemo {
    int w = 0, h = 0;
    int64_t stride = 0;  // doubles per edge: 1 + channels (solid angle, colour)
    std::vector<double> hv, vv, pixel;
    // A curved tile's edges as polylines: the refinement points of edge e (horizontal edges
    // first, then vertical ones) are px, py [first[e], first[e + 1]).
    std::vector<int32_t> first;
    std::vector<double> px, py;
    std::vector<signed char> refine;  // per edge: 1 refined, 0 chord, -1 not in the cell
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
