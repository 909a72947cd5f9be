// The direct path's edge walk (area_prefix.h) for the linear reconstruction of area_linear.h:
// lat-long and tennisball inputs of a magnifying conversion. The box's table and walk are not
// touched; these are their linear twins.
//
// By Green's theorem the colour a footprint P holds, the integral over P of
// rho s + c ax (x - cx) + c ay (y - cy) texel by texel, is the closed integral over P's
// boundary of Q dy - P dx. In texel t, with u = x - ix and w = y - iy in [0, 1]:
// Q = rho(y) (S + s u) + c ax (u^2 - u) / 2 and P = c ay (w^2 - w) / 2, S the table's sum of
// the row's values left of the texel. P and the slope part of Q vanish on the texel's sides,
// so they need no running sums, and they add nothing over a whole texel. Along a piece u and w
// are linear: the means of u, (u^2 - u) / 2, (w^2 - w) / 2 (and u (y - iy - 1/2) for the
// density's slope) are closed forms.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "area_linear.h"
#include "area_source.h"

namespace envconv {

// Running sums of a box of source rows with the slopes: entry (r, c) at
// p[(r * (cols + 1) + c) * 3 nch] is the sum of texels c0 ... c0 + c - 1 of row r0 + r (nch
// values; columns modulo `period` when it is not 0), then c ax and c ay of texel c0 + c (0 in
// the last entry).
struct LinearPrefixTable {
    int64_t r0 = 0, c0 = 0, rows = 0, cols = 0, nch = 0;
    std::vector<double> p;

    // As PrefixTable::build, the slopes from `slopes`; false when a texel is not finite.
    bool build(const Image& src, SlopeCache& slopes, int64_t period, int64_t r0_, int64_t r1,
               int64_t c0_, int64_t c1) {
        r0 = r0_;
        c0 = c0_;
        rows = r1 - r0 + 1;
        cols = c1 - c0 + 1;
        nch = src.channels;
        const int64_t e = 3 * nch;
        size_t need = size_t(rows * (cols + 1) * e);
        if (p.size() < need) p.resize(need);
        const int64_t start = period ? ((c0 % period) + period) % period : c0;
        for (int64_t r = 0; r < rows; ++r) {
            double* out = p.data() + r * (cols + 1) * e;
            for (int64_t ch = 0; ch < nch; ++ch) out[ch] = 0.0;
            int64_t x = start;
            for (int64_t k = 0; k < cols; ++k, out += e) {
                const float* v = src.texel(r0 + r, x);
                const float* s = slopes.get(x, r0 + r);
                for (int64_t ch = 0; ch < nch; ++ch) {
                    out[nch + ch] = double(s[ch]);
                    out[2 * nch + ch] = double(s[nch + ch]);
                    out[e + ch] = out[ch] + double(v[ch]);
                }
                if (++x == period) x = 0;
            }
            for (int64_t ch = 0; ch < nch; ++ch) {
                out[nch + ch] = out[2 * nch + ch] = 0.0;
                if (!std::isfinite(out[ch])) return false;
            }
        }
        return true;
    }
};

// Add the integral of Q dy - P dx along the edge (x0, y0) -> (x1, y1) (in texels (ix0, iy0)
// and (ix1, iy1)) to out[0] (solid angle) and out[1 ...] (colour), as edge_integral does for
// the box; the edge lies inside the table.
template <int NCH, bool kGrad>
void edge_integral_linear(const LinearPrefixTable& t, const SourceModel& model, int64_t row_base,
                          double x0, double y0, int64_t ix0, int64_t iy0, double x1, double y1,
                          int64_t ix1, int64_t iy1, double* out) {
    const double dx = x1 - x0, dy = y1 - y0;
    if (dy == 0.0 && dx == 0.0) return;
    const int64_t nch = NCH ? NCH : t.nch, e = 3 * nch, row_stride = (t.cols + 1) * e;
    int steps_x = int(std::llabs(ix1 - ix0)), steps_y = int(std::llabs(iy1 - iy0));
    const int sx = dx > 0.0 ? 1 : -1, sy = dy > 0.0 ? 1 : -1;
    const double off_x = sx > 0 ? 1.0 : 0.0, off_y = sy > 0 ? 1.0 : 0.0;
    double tx = steps_x ? (double(ix0) + off_x - x0) / dx : 2.0;
    double ty = steps_y ? (double(iy0) + off_y - y0) / dy : 2.0;
    const double step_tx = steps_x ? double(sx) / dx : 0.0, step_ty = steps_y ? double(sy) / dy : 0.0;
    int64_t at = ((iy0 - t.r0) * (t.cols + 1) + (ix0 - t.c0)) * e;
    const double* row_m = model.row_m.data() - row_base;
    const double* row_g = model.row_g.data() - row_base;
    int64_t r = iy0;
    double m = row_m[r], g = kGrad ? row_g[r] : 0.0, top = double(r);
    double base_x = double(ix0);
    const double first_col = double(t.c0);
    std::vector<double> heap;
    double local[1 + 8] = {};
    double* sum = local;
    if (nch > 8) {
        heap.assign(size_t(1 + nch), 0.0);
        sum = heap.data();
    }
    auto piece = [&](double px, double py, double qx, double qy) {
        const double* pr = t.p.data() + at;  // S, then c ax, c ay, then the next texel's S
        const double ex = qx - px, ey = qy - py;
        const double ubar = 0.5 * (px + qx) - base_x, wbar = 0.5 * (py + qy) - top;
        const double uu = 0.5 * (ubar * (ubar - 1.0) + ex * ex * (1.0 / 12.0));
        const double ww = 0.5 * (wbar * (wbar - 1.0) + ey * ey * (1.0 / 12.0));
        const double em = ey * m, emx = ey * uu, emy = -ex * ww;
        // The colour is cb S + cn S' + emx (c ax) + emy (c ay) per channel.
        double cn = em * ubar, cb = em - cn;
        const double col = base_x - first_col;
        if (kGrad) {
            const double vbar = wbar - 0.5, uv = ubar * vbar + ex * ey * (1.0 / 12.0);
            sum[0] += em * col + cn + ey * g * (col * vbar + uv);
            cb += ey * g * (vbar - uv);
            cn += ey * g * uv;
        } else {
            sum[0] += em * col + cn;
        }
        for (int64_t ch = 0; ch < nch; ++ch)
            sum[1 + ch] += cb * pr[ch] + cn * pr[e + ch] + emx * pr[nch + ch] + emy * pr[2 * nch + ch];
    };
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
        if (kGrad) g = row_g[r];
        steps_x -= across_x;
        steps_y -= !across_x;
        tx = across_x ? (steps_x ? tx + step_tx : 2.0) : tx;
        ty = across_x ? ty : (steps_y ? ty + step_ty : 2.0);
    }
    piece(px, py, x1, y1);
    for (int64_t c = 0; c <= nch; ++c) out[c] += sum[c];
}

}  // namespace envconv
