// One row of sub-samples across an interpolated tile (resample.cpp's inner loops): the band's
// working memory (Scratch), the mapping of a row to source points, bilinear cells and texel
// weights (map_row, with an AVX loop chosen at run time where the CPU has it), and the blends
// of a sample's four texels (blend1, blend4). Every vector loop performs, lane by lane, the
// scalar formulas' operations in the same order (no fused multiply-add), so the bytes do not
// depend on the machine's instruction set.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ENVCONV_AVX_ROWS 1  // map_row's 4-wide loop for CPUs with AVX, chosen at run time
#endif

#include "tiles.h"

namespace envconv {

// The most sub-samples per pixel edge a tile may take (samples = 64 is the API's limit).
constexpr int kMaxRowSamples = 64;

// Per-band working memory.
struct Scratch {
    std::vector<double> acc, tmp;
    std::vector<double> fxs;                  // fx of every sub-sample column of a tile
    std::vector<double> tile_acc, tile_wsum;  // (kTile, C) and kTile
    // One row of sub-samples across a tile, mapped: source point, weight, the bilinear cell's
    // top-left texel (as whole numbers) and its four texel weights.
    std::vector<double> px, py, w, cx, cy, k00, k10, k01, k11;
    explicit Scratch(int64_t nch)
        : acc(nch),
          tmp(3 * nch, 0.0),
          fxs(size_t(kTile) * kMaxRowSamples),
          tile_acc(size_t(kTile) * nch),
          tile_wsum(kTile),
          px(fxs.size() + 1), py(px.size()), w(px.size()), cx(px.size()), cy(px.size()),
          k00(px.size()), k10(px.size()), k01(px.size()), k11(px.size()) {}
};

// Floor of positions clamped to +-2^30 (NaN to -2^30): far outside every image, so such a
// sample fails the fast path's bounds test and the slow path reads it from px, py.
constexpr double kFarTexel = 1073741824.0;

#if defined(ENVCONV_AVX_ROWS)
// map_row's loop four samples at a time with AVX (256-bit doubles), for the CPUs that have it
// (the build's baseline is SSE2): each lane is the same IEEE operations, in the same order, as
// the SSE2 loop's and the scalar formulas' (no fused multiply-add), so the bytes do not depend
// on the machine. Returns the columns it mapped (a multiple of 4); the caller does the rest.
template <bool kWeighted>
__attribute__((target("avx"))) inline int64_t map_row_avx(const double* q, const double* fxs,
                                                          int64_t columns, double x_scale,
                                                          double x_offset, Scratch& s) {
    const __m256d q0 = _mm256_set1_pd(q[0]), q1 = _mm256_set1_pd(q[1]), q2 = _mm256_set1_pd(q[2]);
    const __m256d q3 = _mm256_set1_pd(q[3]), q4 = _mm256_set1_pd(q[4]), q5 = _mm256_set1_pd(q[5]);
    const __m256d q6 = _mm256_set1_pd(q[6]), q7 = _mm256_set1_pd(q[7]), q8 = _mm256_set1_pd(q[8]);
    const __m256d xs = _mm256_set1_pd(x_scale), xo = _mm256_set1_pd(x_offset);
    const __m256d half = _mm256_set1_pd(0.5), one = _mm256_set1_pd(1.0);
    const __m256d lo = _mm256_set1_pd(-kFarTexel), hi = _mm256_set1_pd(kFarTexel);
    int64_t c = 0;
    for (; c + 4 <= columns; c += 4) {
        __m256d fx = _mm256_loadu_pd(fxs + c);
        __m256d x = _mm256_add_pd(q0, _mm256_mul_pd(fx, _mm256_add_pd(q1, _mm256_mul_pd(fx, q2))));
        __m256d y = _mm256_add_pd(q3, _mm256_mul_pd(fx, _mm256_add_pd(q4, _mm256_mul_pd(fx, q5))));
        __m256d w = _mm256_add_pd(q6, _mm256_mul_pd(fx, _mm256_add_pd(q7, _mm256_mul_pd(fx, q8))));
        _mm256_storeu_pd(&s.px[c], x);
        _mm256_storeu_pd(&s.py[c], y);
        _mm256_storeu_pd(&s.w[c], w);
        __m256d tx = _mm256_sub_pd(_mm256_add_pd(_mm256_mul_pd(x, xs), xo), half);
        __m256d ty = _mm256_sub_pd(y, half);
        __m256d ctx = _mm256_min_pd(_mm256_max_pd(tx, lo), hi);
        __m256d cty = _mm256_min_pd(_mm256_max_pd(ty, lo), hi);
        __m256d fx0 = _mm256_cvtepi32_pd(_mm256_cvttpd_epi32(ctx));
        __m256d fy0 = _mm256_cvtepi32_pd(_mm256_cvttpd_epi32(cty));
        fx0 = _mm256_sub_pd(fx0, _mm256_and_pd(_mm256_cmp_pd(ctx, fx0, _CMP_LT_OS), one));
        fy0 = _mm256_sub_pd(fy0, _mm256_and_pd(_mm256_cmp_pd(cty, fy0, _CMP_LT_OS), one));
        _mm256_storeu_pd(&s.cx[c], fx0);
        _mm256_storeu_pd(&s.cy[c], fy0);
        __m256d ux = _mm256_sub_pd(tx, fx0), uy = _mm256_sub_pd(ty, fy0);
        __m256d vx = _mm256_sub_pd(one, ux), vy = _mm256_sub_pd(one, uy);
        if (kWeighted) {
            vx = _mm256_mul_pd(w, vx);
            ux = _mm256_mul_pd(w, ux);
        }
        _mm256_storeu_pd(&s.k00[c], _mm256_mul_pd(vx, vy));
        _mm256_storeu_pd(&s.k10[c], _mm256_mul_pd(ux, vy));
        _mm256_storeu_pd(&s.k01[c], _mm256_mul_pd(vx, uy));
        _mm256_storeu_pd(&s.k11[c], _mm256_mul_pd(ux, uy));
    }
    return c;
}
#endif

// Whether map_row may take its AVX loop (set_wide_rows; the tests compare both loops).
inline std::atomic<bool> wide_rows_allowed{true};

#if defined(ENVCONV_AVX_ROWS)
// True when map_row takes its AVX loop: the CPU has AVX (and the OS keeps its registers), and
// it is allowed.
inline bool wide_rows() {
    static const bool have_avx = (__builtin_cpu_init(), __builtin_cpu_supports("avx"));
    return have_avx && wide_rows_allowed.load(std::memory_order_relaxed);
}
#endif

#if defined(__SSE2__)
// map_row's loop two samples at a time with SSE2, from column c; returns the columns mapped
// (all but an odd last one).
template <bool kWeighted>
inline int64_t map_row_sse2(const double* q, const double* fxs, int64_t c, int64_t columns,
                            double x_scale, double x_offset, Scratch& s) {
    const __m128d q0 = _mm_set1_pd(q[0]), q1 = _mm_set1_pd(q[1]), q2 = _mm_set1_pd(q[2]);
    const __m128d q3 = _mm_set1_pd(q[3]), q4 = _mm_set1_pd(q[4]), q5 = _mm_set1_pd(q[5]);
    const __m128d q6 = _mm_set1_pd(q[6]), q7 = _mm_set1_pd(q[7]), q8 = _mm_set1_pd(q[8]);
    const __m128d xs = _mm_set1_pd(x_scale), xo = _mm_set1_pd(x_offset);
    const __m128d half = _mm_set1_pd(0.5), one = _mm_set1_pd(1.0);
    const __m128d lo = _mm_set1_pd(-kFarTexel), hi = _mm_set1_pd(kFarTexel);
    for (; c + 2 <= columns; c += 2) {
        __m128d fx = _mm_loadu_pd(fxs + c);
        __m128d x = _mm_add_pd(q0, _mm_mul_pd(fx, _mm_add_pd(q1, _mm_mul_pd(fx, q2))));
        __m128d y = _mm_add_pd(q3, _mm_mul_pd(fx, _mm_add_pd(q4, _mm_mul_pd(fx, q5))));
        __m128d w = _mm_add_pd(q6, _mm_mul_pd(fx, _mm_add_pd(q7, _mm_mul_pd(fx, q8))));
        _mm_storeu_pd(&s.px[c], x);
        _mm_storeu_pd(&s.py[c], y);
        _mm_storeu_pd(&s.w[c], w);
        __m128d tx = _mm_sub_pd(_mm_add_pd(_mm_mul_pd(x, xs), xo), half);
        __m128d ty = _mm_sub_pd(y, half);
        // max(v, lo) gives lo for a NaN v (SSE returns the second operand).
        __m128d ctx = _mm_min_pd(_mm_max_pd(tx, lo), hi), cty = _mm_min_pd(_mm_max_pd(ty, lo), hi);
        __m128d fx0 = _mm_cvtepi32_pd(_mm_cvttpd_epi32(ctx));
        __m128d fy0 = _mm_cvtepi32_pd(_mm_cvttpd_epi32(cty));
        fx0 = _mm_sub_pd(fx0, _mm_and_pd(_mm_cmplt_pd(ctx, fx0), one));
        fy0 = _mm_sub_pd(fy0, _mm_and_pd(_mm_cmplt_pd(cty, fy0), one));
        _mm_storeu_pd(&s.cx[c], fx0);
        _mm_storeu_pd(&s.cy[c], fy0);
        __m128d ux = _mm_sub_pd(tx, fx0), uy = _mm_sub_pd(ty, fy0);
        __m128d vx = _mm_sub_pd(one, ux), vy = _mm_sub_pd(one, uy);
        if (kWeighted) {
            vx = _mm_mul_pd(w, vx);
            ux = _mm_mul_pd(w, ux);
        }
        _mm_storeu_pd(&s.k00[c], _mm_mul_pd(vx, vy));
        _mm_storeu_pd(&s.k10[c], _mm_mul_pd(ux, vy));
        _mm_storeu_pd(&s.k01[c], _mm_mul_pd(vx, uy));
        _mm_storeu_pd(&s.k11[c], _mm_mul_pd(ux, uy));
    }
    return c;
}
#endif

// map_row's scalar formulas, for columns [c, columns).
template <bool kWeighted>
inline void map_row_scalar(const double* q, const double* fxs, int64_t c, int64_t columns,
                           double x_scale, double x_offset, Scratch& s) {
    for (; c < columns; ++c) {
        double fx = fxs[c];
        double x = q[0] + fx * (q[1] + fx * q[2]);
        double y = q[3] + fx * (q[4] + fx * q[5]);
        double w = q[6] + fx * (q[7] + fx * q[8]);
        s.px[c] = x;
        s.py[c] = y;
        s.w[c] = w;
        double tx = x * x_scale + x_offset - 0.5, ty = y - 0.5;
        double ctx = std::min(std::max(tx, -kFarTexel), kFarTexel);
        double cty = std::min(std::max(ty, -kFarTexel), kFarTexel);
        if (!(ctx == ctx)) ctx = -kFarTexel;
        if (!(cty == cty)) cty = -kFarTexel;
        double fx0 = double(int32_t(ctx)), fy0 = double(int32_t(cty));
        fx0 -= ctx < fx0 ? 1.0 : 0.0;
        fy0 -= cty < fy0 ? 1.0 : 0.0;
        s.cx[c] = fx0;
        s.cy[c] = fy0;
        double ux = tx - fx0, uy = ty - fy0, vx = 1.0 - ux;
        if (kWeighted) {
            vx = w * vx;
            ux = w * ux;
        }
        s.k00[c] = vx * (1.0 - uy);
        s.k10[c] = ux * (1.0 - uy);
        s.k01[c] = vx * uy;
        s.k11[c] = ux * uy;
    }
}

// Map one row of sub-samples (fx = fxs[c], quadratics q) into scratch: source point, weight,
// bilinear cell and texel weights, by the scalar formulas of map_row_scalar, four samples at a
// time with AVX where the CPU has it (map_row_avx), then two at a time with SSE2 (each lane is
// the same IEEE operations in the same order, so the results are the scalar ones, bit for
// bit). kWeighted: the four texel weights carry the sample's weight w (k00 = w (1 - ux)
// (1 - uy)); else they are the plain bilinear fractions, for a pixel of one sample, where w
// cancels in the normalisation.
template <bool kWeighted>
inline void map_row(const double* q, const double* fxs, int64_t columns, double x_scale,
                    double x_offset, Scratch& s) {
    int64_t c = 0;
#if defined(ENVCONV_AVX_ROWS)
    if (columns >= 4 && wide_rows()) c = map_row_avx<kWeighted>(q, fxs, columns, x_scale, x_offset, s);
#endif
#if defined(__SSE2__)
    c = map_row_sse2<kWeighted>(q, fxs, c, columns, x_scale, x_offset, s);
#endif
    map_row_scalar<kWeighted>(q, fxs, c, columns, x_scale, x_offset, s);
}

// The bilinear blend of one channel of sample c of a mapped row: texels t0[ch], t0[nch + ch]
// (row y) and t1[ch], t1[nch + ch] (row y + 1) with its weights rounded to float, in float, in
// the order of blend4's SSE lanes (so either gives the same bits).
inline float blend1(const Scratch& r, int64_t c, const float* t0, const float* t1, int64_t nch,
                    int64_t ch) {
    float v = float(r.k00[c]) * t0[ch];
    v = v + float(r.k10[c]) * t0[nch + ch];
    v = v + float(r.k01[c]) * t1[ch];
    return v + float(r.k11[c]) * t1[nch + ch];
}

#if defined(__SSE2__)
// blend1 for four floats at once (the 3 or 4 channels of a texel, and what follows it).
inline __m128 blend4(const Scratch& r, int64_t c, const float* t0, const float* t1, int64_t nch) {
    __m128 v = _mm_mul_ps(_mm_set1_ps(float(r.k00[c])), _mm_loadu_ps(t0));
    v = _mm_add_ps(v, _mm_mul_ps(_mm_set1_ps(float(r.k10[c])), _mm_loadu_ps(t0 + nch)));
    v = _mm_add_ps(v, _mm_mul_ps(_mm_set1_ps(float(r.k01[c])), _mm_loadu_ps(t1)));
    return _mm_add_ps(v, _mm_mul_ps(_mm_set1_ps(float(r.k11[c])), _mm_loadu_ps(t1 + nch)));
}
#endif

}  // namespace envconv
