// The fused resampling kernel.
//
// For every output pixel the kernel takes S x S stratified sub-samples at (i + (sx + 0.5)/S,
// j + (sy + 0.5)/S) output pixels, scales them to level-0 image points, maps each to a
// direction through the output layout (continued into guard rings), rotates it into the source
// frame, maps it to a source image point and reads the source through the reconstruction
// filter. Samples are weighted by the output layout's solid-angle density, so a pixel is the
// solid-angle mean of the environment over the part of it that holds directions. Alpha is the
// fraction of sub-samples in the valid region.
//
// Work is split into bands of kTile output rows, one band per task, so the working set stays
// a few rows whatever the image size. Within a band, tiles (tiles.h) interpolate the map; tiles
// that fail their checks split, and blocks that still fail map every sub-sample exactly.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "kernels.h"
#include "parallel.h"
#include "ripmap.h"
#include "rows.h"
#include "tiles.h"

namespace envconv {
namespace {

struct Job {
    const Image& src;
    const RipMap& rip;
    const Conversion& cv;
    const ResampleOutput& out;
    int samples, filter;
    bool adaptive, fast_taps, may_tile;
    int rip_levels, largest_tile, min_subtile;
    int64_t s_width;
};

// Write the normalised accumulator and the coverage of output pixel (i, j). NCH is the channel
// count when known at compile time (3 or 4, the common cases), else 0.
template <int NCH = 0>
void store(const ResampleOutput& out, int64_t j, int64_t i, const double* acc, double wsum,
           double coverage) {
    const int64_t nch = NCH ? NCH : out.channels;
    float* px = out.pixels + (j * out.width + i) * (out.stride ? out.stride : nch);
    double inv = wsum > 0.0 ? 1.0 / wsum : 0.0;
    for (int64_t c = 0; c < nch; ++c) px[c] = wsum > 0.0 ? float(acc[c] * inv) : 0.0f;
    if (out.alpha) out.alpha[(j * out.width + i) * out.alpha_stride] = float(coverage);
    if (out.weights) out.weights[j * out.width + i] = float(wsum);
}

// Accumulate output pixel (i, j) mapping its nx x ny sub-samples exactly. With level >= 1
// (a lat-long source) the taps read that level of the rip-map. Returns the summed weights and
// sets nvalid to the number of sub-samples in the valid region.
double exact_pixel(const Job& job, int64_t i, int64_t j, int nx, int ny, int level,
                   Scratch& scratch, int& nvalid) {
    const Conversion& cv = job.cv;
    const Chart& dfam = cv.dst;
    int64_t start = rip_offset(job.s_width, level);
    int64_t level_width = job.s_width >> level;
    double x_scale = 1.0 / double(1 << level);
    double wsum = 0.0;
    nvalid = 0;
    for (int sy = 0; sy < ny; ++sy) {
        double py = (double(j) + (sy + 0.5) / ny) * cv.scale_y;
        for (int sx = 0; sx < nx; ++sx) {
            double px = (double(i) + (sx + 0.5) / nx) * cv.scale_x;
            OutputSample s = output_sample(cv.dst, px, py, cv.fill);
            if (!s.readable) continue;
            if (s.valid) ++nvalid;
            double w = density(dfam, s.face, s.a, s.b);
            ImagePoint p = source_point(cv.src, dfam, s.face, s.a, s.b, cv.rot);
            if (level > 0) {
                level_tap(job.rip.image, start, level_width, p.x * x_scale, p.y, w,
                          scratch.acc.data());
            } else {
                accumulate_sample(job.src, cv.src, p.cell, p.x, p.y, job.filter, w,
                                  scratch.acc.data(), scratch.tmp.data());
            }
            wsum += w;
        }
    }
    return wsum;
}

// Sub-samples per edge and rip-map level of an exactly mapped pixel under adaptive sampling.
void adaptive_counts(const Job& job, int64_t i, int64_t j, int& nx, int& ny, int& level) {
    const Conversion& cv = job.cv;
    Footprint f = pixel_footprint(cv, i, j);
    level = 0;
    if (job.rip_levels > 0 && f.x_of_x >= 0.0) {
        level = rip_level(f.x_of_x + f.x_of_y, job.rip_levels);
        if (level > 0 &&
            !rows_filled(centre_source_y(cv, i, j),
                         edge_y_part(f.span_x, f.x_of_x) + edge_y_part(f.span_y, f.x_of_y),
                         job.rip.rows, job.src.height)) {
            level = 0;
        }
    }
    nx = auto_count(level_span(f.span_x, f.x_of_x, level));
    ny = auto_count(level_span(f.span_y, f.x_of_y, level));
    // A pixel not wholly in one cell's valid region (a rim, a cell edge) needs enough
    // sub-samples for its coverage (alpha).
    int64_t cell;
    int whole = tile_face(cv.dst, double(i) * cv.scale_x, double(j) * cv.scale_y,
                          double(i + 1) * cv.scale_x, double(j + 1) * cv.scale_y, cell);
    if (whole < 0) {
        nx = std::max(nx, kAutoEdgeSamples);
        ny = std::max(ny, kAutoEdgeSamples);
    }
}

// Every pixel of block [i0, i1) x [j0, j1), mapped exactly.
void exact_block(const Job& job, int64_t i0, int64_t j0, int64_t i1, int64_t j1,
                 Scratch& scratch) {
    for (int64_t j = j0; j < j1; ++j) {
        for (int64_t i = i0; i < i1; ++i) {
            std::fill(scratch.acc.begin(), scratch.acc.end(), 0.0);
            int nx = job.samples, ny = job.samples, level = 0;
            if (job.adaptive) adaptive_counts(job, i, j, nx, ny, level);
            int nvalid;
            double wsum = exact_pixel(job, i, j, nx, ny, level, scratch, nvalid);
            store(job.out, j, i, scratch.acc.data(), wsum, double(nvalid) / double(nx * ny));
        }
    }
}

// Rip-map level and sub-samples per edge of an interpolated tile under adaptive sampling.
void tile_counts(const Job& job, const TileGrid& grid, double inv_tw, double inv_th, int& nx,
                 int& ny, int& level) {
    level = 0;
    if (job.rip_levels > 0) {
        double x_extent = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
            x_extent = std::min(x_extent, std::fabs(grid[k][2][0] - grid[k][0][0]) * inv_tw +
                                              std::fabs(grid[2][k][0] - grid[0][k][0]) * inv_th);
        }
        level = rip_level(x_extent, job.rip_levels);
        if (level > 0) {
            double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
            for (int k = 0; k < 3; ++k) {
                for (int m = 0; m < 3; ++m) {
                    y_lo = std::min(y_lo, grid[k][m][1]);
                    y_hi = std::max(y_hi, grid[k][m][1]);
                }
            }
            if (!rows_filled(0.5 * (y_lo + y_hi), y_hi - y_lo, job.rip.rows, job.src.height)) {
                level = 0;
            }
        }
    }
    double shrink = 1.0 / double(1 << level);
    double edge_x = 0.0, edge_y = 0.0;
    for (int k = 0; k < 3; ++k) {
        edge_x = std::max(edge_x, std::hypot((grid[k][2][0] - grid[k][0][0]) * shrink,
                                             grid[k][2][1] - grid[k][0][1]));
        edge_y = std::max(edge_y, std::hypot((grid[2][k][0] - grid[0][k][0]) * shrink,
                                             grid[2][k][1] - grid[0][k][1]));
    }
    nx = auto_count(edge_x * inv_tw);
    ny = auto_count(edge_y * inv_th);
}

// Where the taps of an interpolated tile read: level 0 (src) or a rip-map level, at
// x_scale x + x_offset, with the fast (direct bilinear) path inside [bx0, bx1) x [by0, by1).
struct TapWindow {
    const Image* image;
    double x_scale, x_offset;
    int64_t level, level_start, level_width;
    int64_t bx0, by0, bx1, by1;
};

// Add w x the bilinear read of a tap that is not on the fast path: a rip-map level's wrapped
// read, or the seam-aware read of level 0.
void slow_tap(const Job& job, const TapWindow& win, int64_t c00, double px, double py, double w,
              double* acc, Scratch& scratch) {
    if (win.level > 0) {
        level_tap(job.rip.image, win.level_start, win.level_width, px * win.x_scale, py, w, acc);
    } else {
        accumulate_sample(job.src, job.cv.src, c00, px, py, job.filter, w, acc,
                          scratch.tmp.data());
    }
}

// Add one row of sub-samples (q: the row's quadratics in fx) across a tile to the pixels'
// accumulators acc (pixels, C) and weight sums. Fast taps of 3 or 4 channels blend 4 floats at
// once and sum a pixel's row in float (at most 64 samples: within 4e-6 relative) before it
// joins the double accumulator; other taps go through slow_tap.
template <int NCH>
void add_sample_row(const Job& job, const TapWindow& win, int64_t c00, const double* q,
                    const double* fxs, int64_t pixels, int nx, double* acc, double* wsum,
                    Scratch& scratch) {
    const int64_t nch = NCH ? NCH : job.out.channels;
    const Image& image = *win.image;
    const int64_t iw = image.width;
    // The fast path takes cells whose top-left texel is in [bx0, bx1) x [by0, by1) (none
    // without fast taps); unsigned differences test both ends at once.
    const int64_t bx0 = win.bx0, by0 = win.by0;
    const uint64_t span_x = job.fast_taps ? uint64_t(win.bx1 - win.bx0) : 0;
    const uint64_t span_y = job.fast_taps ? uint64_t(win.by1 - win.by0) : 0;
    // A 4-float load at the last tap (texel flat + W + 1) must stay inside the array.
    [[maybe_unused]] const int64_t last_safe = image.height * iw - iw - 1 - (nch == 3 ? 1 : 0);
    map_row<true>(q, fxs, pixels * nx, win.x_scale, win.x_offset, scratch);
    const Scratch& r = scratch;
    for (int64_t i = 0; i < pixels; ++i) {
        double* a = acc + i * nch;
        double ws = 0.0;
#if defined(__SSE2__)
        __m128 sum = _mm_setzero_ps();
#endif
        for (int64_t c = i * nx; c < (i + 1) * nx; ++c) {
            ws += r.w[c];
            int64_t ix = int64_t(r.cx[c]), iy = int64_t(r.cy[c]);
            if (!(uint64_t(ix - bx0) < span_x && uint64_t(iy - by0) < span_y)) {
                slow_tap(job, win, c00, r.px[c], r.py[c], r.w[c], a, scratch);
                continue;
            }
            int64_t flat = iy * iw + ix;
            const float* t0 = image.data + flat * nch;
            const float* t1 = t0 + iw * nch;
#if defined(__SSE2__)
            if ((NCH == 3 || NCH == 4) && flat < last_safe) {
                sum = _mm_add_ps(sum, blend4(r, c, t0, t1, nch));
                continue;
            }
#endif
            for (int64_t ch = 0; ch < nch; ++ch) {
                a[ch] += r.k00[c] * t0[ch] + r.k10[c] * t0[nch + ch] + r.k01[c] * t1[ch] +
                         r.k11[c] * t1[nch + ch];
            }
        }
#if defined(__SSE2__)
        if (NCH == 3 || NCH == 4) {
            float part[4];
            _mm_storeu_ps(part, sum);
            for (int64_t ch = 0; ch < nch; ++ch) a[ch] += double(part[ch]);
        }
#endif
        wsum[i] += ws;
    }
}

// The row quadratics q (source x, y and weight in fx) of the sub-sample row at fy of a tile.
inline void row_quadratics(const TileGrid& grid, double fy, double* q) {
    for (int k = 0; k < 3; ++k) {
        double q0 = lagrange3(grid[0][0][k], grid[1][0][k], grid[2][0][k], fy);
        double q1 = lagrange3(grid[0][1][k], grid[1][1][k], grid[2][1][k], fy);
        double q2 = lagrange3(grid[0][2][k], grid[1][2][k], grid[2][2][k], fy);
        q[3 * k] = q0;
        q[3 * k + 1] = -3.0 * q0 + 4.0 * q1 - q2;
        q[3 * k + 2] = 2.0 * q0 - 4.0 * q1 + 2.0 * q2;
    }
}

// tiled_block_n at one sample a pixel (S = 1, 3 or 4 channels): each pixel's single tap goes
// straight to the output, with no per-tile accumulators. A lone sample's weight w cancels in
// the normalisation (sum w v / sum w = v), so the taps blend with the plain bilinear fractions
// and the float result is stored as it is; w only decides, as in store, that a pixel of no
// weight (w <= 0, or NaN) is 0, and is what out.weights records.
template <int NCH>
void single_tap_rows(const Job& job, const TapWindow& win, int64_t c00, const TileGrid& grid,
                     const double* fxs, int64_t i0, int64_t j0, int64_t i1, int64_t j1,
                     double inv_th, Scratch& scratch) {
    const Image& image = *win.image;
    const ResampleOutput& out = job.out;
    const int64_t iw = image.width, pixels = i1 - i0;
    const int64_t bx0 = win.bx0, by0 = win.by0;
    const uint64_t span_x = job.fast_taps ? uint64_t(win.bx1 - win.bx0) : 0;
    const uint64_t span_y = job.fast_taps ? uint64_t(win.by1 - win.by0) : 0;
    [[maybe_unused]] const int64_t last_safe = image.height * iw - iw - 1 - (NCH == 3 ? 1 : 0);
    const int64_t step = out.stride ? out.stride : NCH;
    const Scratch& r = scratch;
    for (int64_t j = j0; j < j1; ++j) {
        double q[9];
        row_quadratics(grid, (double(j - j0) + 0.5) * inv_th, q);
        map_row<false>(q, fxs, pixels, win.x_scale, win.x_offset, scratch);
        float* row = out.pixels + (j * out.width + i0) * step;
        for (int64_t c = 0; c < pixels; ++c) {
            const double ws = r.w[c];
            const int64_t ix = int64_t(r.cx[c]), iy = int64_t(r.cy[c]);
            const int64_t flat = iy * iw + ix;
            const bool in_window = uint64_t(ix - bx0) < span_x && uint64_t(iy - by0) < span_y;
            float* px = row + c * step;
#if defined(__SSE2__)
            if (in_window && flat < last_safe && ws > 0.0) {
                const float* t0 = image.data + flat * NCH;
                __m128 v = blend4(r, c, t0, t0 + iw * NCH, NCH);
                if (NCH == 4 && step == 4) {
                    _mm_storeu_ps(px, v);
                } else {
                    float part[4];
                    _mm_storeu_ps(part, v);
                    for (int64_t ch = 0; ch < NCH; ++ch) px[ch] = part[ch];
                }
            } else
#endif
            if (!(ws > 0.0)) {
                for (int64_t ch = 0; ch < NCH; ++ch) px[ch] = 0.0f;
            } else if (in_window) {
                const float* t0 = image.data + flat * NCH;
                for (int64_t ch = 0; ch < NCH; ++ch)
                    px[ch] = blend1(r, c, t0, t0 + iw * NCH, NCH, ch);
            } else {
                double a[4] = {0.0, 0.0, 0.0, 0.0};
                slow_tap(job, win, c00, r.px[c], r.py[c], 1.0, a, scratch);
                for (int64_t ch = 0; ch < NCH; ++ch) px[ch] = float(a[ch]);
            }
            if (out.alpha) out.alpha[(j * out.width + i0 + c) * out.alpha_stride] = 1.0f;
            if (out.weights) out.weights[j * out.width + i0 + c] = float(ws);
        }
    }
}

// Every pixel of an interpolated tile [i0, i1) x [j0, j1) whose grid maps into source cell c00.
template <int NCH>
void tiled_block_n(const Job& job, int64_t i0, int64_t j0, int64_t i1, int64_t j1,
                   const TileGrid& grid, int64_t c00, Scratch& scratch) {
    const Geometry& s = job.cv.src;
    const int64_t nch = NCH ? NCH : job.out.channels;
    double inv_tw = 1.0 / double(i1 - i0), inv_th = 1.0 / double(j1 - j0);
    int nx = job.samples, ny = job.samples, level = 0;
    if (job.adaptive) tile_counts(job, grid, inv_tw, inv_th, nx, ny, level);
    TapWindow win{&job.src, 1.0, 0.0, level, 0, job.s_width, 0, 0, 0, 0};
    win.bx0 = (c00 % s.columns) * s.cell_width();
    win.by0 = (c00 / s.columns) * s.cell_height();
    win.bx1 = win.bx0 + s.cell_width() - 1;
    win.by1 = win.by0 + s.cell_height() - 1;
    if (level > 0) {
        win.image = &job.rip.image;
        win.x_scale = 1.0 / double(1 << level);
        win.level_start = rip_offset(job.s_width, level);
        win.level_width = job.s_width >> level;
        win.x_offset = double(win.level_start);
        win.bx0 = win.level_start;
        win.bx1 = win.level_start + win.level_width - 1;
    }
    double inv_nx = 1.0 / nx, inv_ny = 1.0 / ny;
    const int64_t columns = (i1 - i0) * nx;
    // Each row of sub-samples (j, sy) has source x, source y and weight as quadratics in fx,
    // q0 + fx (c1 + fx c2): 9 numbers per row, shared by the tile's pixels along it.
    double* fxs = scratch.fxs.data();
    for (int64_t c = 0; c < columns; ++c)
        fxs[c] = (double(c / nx) + (double(c % nx) + 0.5) * inv_nx) * inv_tw;
    if (nx == 1 && ny == 1 && (NCH == 3 || NCH == 4)) {
        single_tap_rows<NCH>(job, win, c00, grid, fxs, i0, j0, i1, j1, inv_th, scratch);
        return;
    }
    double* acc = scratch.tile_acc.data();  // (i1 - i0, C)
    double* wsum = scratch.tile_wsum.data();
    for (int64_t j = j0; j < j1; ++j) {
        std::fill(acc, acc + (i1 - i0) * nch, 0.0);
        std::fill(wsum, wsum + (i1 - i0), 0.0);
        for (int sy = 0; sy < ny; ++sy) {
            double fy = (double(j - j0) + (sy + 0.5) * inv_ny) * inv_th;
            double q[9];
            row_quadratics(grid, fy, q);
            add_sample_row<NCH>(job, win, c00, q, fxs, i1 - i0, nx, acc, wsum, scratch);
        }
        for (int64_t i = i0; i < i1; ++i)
            store<NCH>(job.out, j, i, acc + (i - i0) * nch, wsum[i - i0], 1.0);
    }
}

void tiled_block(const Job& job, int64_t i0, int64_t j0, int64_t i1, int64_t j1,
                 const TileGrid& grid, int64_t c00, Scratch& scratch) {
    switch (job.out.channels) {
        case 3: return tiled_block_n<3>(job, i0, j0, i1, j1, grid, c00, scratch);
        case 4: return tiled_block_n<4>(job, i0, j0, i1, j1, grid, c00, scratch);
        default: return tiled_block_n<0>(job, i0, j0, i1, j1, grid, c00, scratch);
    }
}

// One band of kTile output rows, tile by tile.
void resample_band(const Job& job, int64_t band, Scratch& scratch) {
    const Conversion& cv = job.cv;
    const Geometry& d = cv.dst;
    const ResampleOutput& out = job.out;
    int64_t stack[16][3];
    for (int64_t tile_i0 = 0; tile_i0 < out.width; tile_i0 += kTile) {
        stack[0][0] = tile_i0;
        stack[0][1] = band * kTile;
        stack[0][2] = kTile;
        int depth = 1;
        while (depth > 0) {
            --depth;
            int64_t i0 = stack[depth][0], j0 = stack[depth][1], size = stack[depth][2];
            if (i0 >= out.width || j0 >= out.height) continue;
            int64_t i1 = std::min(i0 + size, out.width), j1 = std::min(j0 + size, out.height);
            double x0 = double(i0) * cv.scale_x, y0 = double(j0) * cv.scale_y;
            double x1 = double(i1) * cv.scale_x, y1 = double(j1) * cv.scale_y;
            if (!cv.fill && tile_in_empty_cell(d, x0, y0, x1, y1)) {
                if (out.zeroed) continue;  // zeros already, and their pages never touched
                std::fill(scratch.acc.begin(), scratch.acc.end(), 0.0);
                for (int64_t j = j0; j < j1; ++j) {
                    for (int64_t i = i0; i < i1; ++i) store(out, j, i, scratch.acc.data(), 0.0, 0.0);
                }
                continue;
            }
            int face = -1;
            int64_t cell = -1, c00 = -1;
            if (job.may_tile && size <= job.largest_tile) face = tile_face(d, x0, y0, x1, y1, cell);
            TileGrid grid;
            if (face >= 0) {
                double a00, b00, a10, b10, a01, b01;
                cell_local(d, cell, x0, y0, a00, b00);
                cell_local(d, cell, x1, y0, a10, b10);
                cell_local(d, cell, x0, y1, a01, b01);
                c00 = map_tile(cv.src, d, face, cv.rot, a00, b00, a10 - a00, b10 - b00,
                               a01 - a00, b01 - b00, grid);
            }
            if (c00 >= 0) {
                tiled_block(job, i0, j0, i1, j1, grid, c00, scratch);
            } else if (job.may_tile && size > job.min_subtile) {
                int64_t half = size / 2;
                for (int q = 0; q < 4; ++q) {
                    stack[depth][0] = i0 + half * (q % 2);
                    stack[depth][1] = j0 + half * (q / 2);
                    stack[depth][2] = half;
                    ++depth;
                }
            } else {
                exact_block(job, i0, j0, i1, j1, scratch);
            }
        }
    }
}

}  // namespace

bool set_wide_rows(bool allowed) { return wide_rows_allowed.exchange(allowed); }

void resample(const Image& src, const RipMap& rip, const Conversion& cv, int samples, int filter,
              const ResampleOutput& out, int threads, int64_t* progress) {
    const Geometry& d = cv.dst;
    bool adaptive = samples <= 0;
    bool fast_taps = filter == kBilinear && !cv.src.disk();
    // Tiles small enough against an output cell (level-0 pixels) for the checks to hold.
    double dn = double(d.n), dan = double(d.nx);
    bool may_tile = (kTile / 2) * cv.scale_x * kMinTilesPerCell <= dan &&
                    (kTile / 2) * cv.scale_y * kMinTilesPerCell <= dn && samples <= kMaxRowSamples;
    int largest_tile = kTile / 2;
    if (kTile * cv.scale_x * kMinTilesPerCell <= dan && kTile * cv.scale_y * kMinTilesPerCell <= dn)
        largest_tile = kTile;
    // A failing tile splits down to kMinSubtile (4 at S = 1, where mapping a 2 x 2 block's grid
    // costs more than its 4 samples).
    int min_subtile = samples == 1 ? 4 : kMinSubtile;
    Job job{src, rip, cv, out, samples, filter, adaptive, fast_taps, may_tile,
            (adaptive && fast_taps) ? rip.levels : 0, largest_tile, min_subtile,
            cv.src.nx};
    int64_t bands = (out.height + kTile - 1) / kTile;
    parallel_for(bands, threads, [&](int64_t band) {
        Scratch scratch(out.channels);
        resample_band(job, band, scratch);
        if (progress) __atomic_add_fetch(progress, 1, __ATOMIC_RELAXED);
    });
}

}  // namespace envconv
