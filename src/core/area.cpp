// The area filter: every output pixel is the solid-angle mean of the box-reconstructed source
// over the pixel's footprint, integrated exactly.
//
// The footprint of an output pixel is the region of the source that its directions come from.
// Its corners' source points are shared with the neighbouring pixels, so the footprints tile
// the source; each is integrated over the texel grid exactly (green.h), each texel's piece
// weighted by the solid angle it holds (area_source.h). Every texel's solid angle is thus
// handed out exactly once, to the pixels that cover it: a one-texel sun keeps its energy in
// any conversion, a constant map stays constant, and nothing aliases.
//
// Work is split into bands of kAreaTile output rows, each band into tiles (area_tiles.h).
#include <algorithm>
#include <mutex>
#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

#include "area.h"
#include "area_linear_walk.h"
#include "area_prefix.h"
#include "area_slow.h"
#include "area_tiles.h"
#include "parallel.h"
#include "tiles.h"

namespace envconv {
namespace {

std::atomic<bool> direct_allowed{true};

// Tiles are kAreaTile x kAreaTile pixels, in bands of kAreaTile rows (progress still counts
// bands of kTile rows, the unit the Python side expects).
constexpr int64_t kAreaTile = 32;
// Around a lat-long pole (split_tile): tiles split down to kPoleTile pixels a side, and those
// within kPoleReach output pixels of the pole take the general path.
constexpr int64_t kPoleTile = 4;
constexpr double kPoleReach = 1.5;
static_assert(kAreaTile % kTile == 0, "progress counts whole bands of kTile rows");

struct AreaJob {
    const Conversion& cv;
    const SourceModel& model;
    const Singular& sing;
    const ResampleOutput& out;
    int samples;  // sub-pixels per edge, each integrated exactly
    bool linear = false;     // the linear reconstruction (area_linear.h), else the box
    int valid_channel = -1;  // the source's V channel, or -1
};

// The exact coverage of pixel (i, j) when an alpha plane is wanted (else 0, unused).
double pixel_coverage(const Conversion& cv, const ResampleOutput& out, int64_t i, int64_t j) {
    if (!out.alpha) return 0.0;
    return rect_coverage(cv.dst, double(i) * cv.scale_x, double(j) * cv.scale_y,
                         double(i + 1) * cv.scale_x, double(j + 1) * cv.scale_y);
}

// Store pixel (i, j) from its signed sums: solid angle w and colour times solid angle acc.
void store_sums(const ResampleOutput& out, int64_t i, int64_t j, double w, const double* acc,
                double coverage) {
    const int64_t nch = out.channels;
    j -= out.row0;
    float* px = out.pixels + (j * out.width + i) * (out.stride ? out.stride : nch);
    const bool held = w != 0.0 && std::isfinite(w);
    const double inv = held ? 1.0 / w : 0.0;
    for (int64_t c = 0; c < nch; ++c) px[c] = held ? float(acc[c] * inv) : 0.0f;
    if (out.alpha) out.alpha[(j * out.width + i) * out.alpha_stride] = float(coverage);
    if (out.weights) out.weights[j * out.width + i] = float(std::fabs(w));
}

// Store pixel (i, j): its colour (the sums normalised), coverage and solid angle.
void store_pixel(const ResampleOutput& out, int64_t i, int64_t j, const PixelSums& s,
                 double coverage) {
    const int64_t nch = out.channels;
    j -= out.row0;
    float* px = out.pixels + (j * out.width + i) * (out.stride ? out.stride : nch);
    double inv = s.weight > 0.0 ? 1.0 / s.weight : 0.0;
    for (int64_t c = 0; c < nch; ++c) px[c] = s.weight > 0.0 ? float(s.acc[c] * inv) : 0.0f;
    if (out.alpha) out.alpha[(j * out.width + i) * out.alpha_stride] = float(coverage);
    if (out.weights) out.weights[j * out.width + i] = float(std::max(s.weight, 0.0));
}

// Every pixel of [i0, i1) x [j0, j1), one at a time through the general path.
void slow_block(const AreaJob& job, SlowPath& sp, PixelSums& sums, int64_t i0, int64_t j0,
                int64_t i1, int64_t j1) {
    const Conversion& cv = job.cv;
    for (int64_t j = j0; j < j1; ++j) {
        for (int64_t i = i0; i < i1; ++i) {
            std::fill(sums.acc, sums.acc + sums.nch, 0.0);
            sums.weight = 0.0;
            slow_rect(sp, double(i) * cv.scale_x, double(j) * cv.scale_y, double(i + 1) * cv.scale_x,
                      double(j + 1) * cv.scale_y, nullptr);
            store_pixel(job.out, i, j, sums, pixel_coverage(cv, job.out, i, j));
        }
    }
}

// The density models (SourceModel::texel) of a box of texels of one source cell, each
// computed on its first use: a tile's direct pixels share their texels (about four pieces
// each at 1:1), and a texel's model costs four maps and four densities.
struct DensityCache {
    int64_t cell = -1, c0 = 0, r0 = 0, w = 0, h = 0;
    std::vector<TexelDensity> t;  // m NaN: not computed yet
    void reset(int64_t cell_, int64_t c0_, int64_t r0_, int64_t c1, int64_t r1) {
        cell = cell_;
        c0 = c0_;
        r0 = r0_;
        w = c1 - c0 + 1;
        h = r1 - r0 + 1;
        t.assign(size_t(w * h), TexelDensity{std::nan(""), 0.0, 0.0});
    }
    TexelDensity get(const SourceModel& model, int64_t ix, int64_t iy) {
        const uint64_t dx = uint64_t(ix - c0), dy = uint64_t(iy - r0);
        if (dx >= uint64_t(w) || dy >= uint64_t(h)) return model.texel(cell, ix, iy);
        TexelDensity& e = t[size_t(dy * uint64_t(w) + dx)];
        if (std::isnan(e.m)) e = model.texel(cell, ix, iy);
        return e;
    }
};

// Sink of green.h for the direct path: texels read as they are (a lat-long's columns modulo its
// width), weighted by a lat-long or tennisball row's exact solid angle (kRows) or the density
// model (through the tile's cache); NCH channels (0: sums.nch).
template <bool kRows, int NCH>
struct DirectSink {
    static constexpr bool kMomentX = !kRows;
    const SourceModel& model;
    int64_t cell, row0, period;
    double sign;
    PixelSums& sums;
    DensityCache& cache;
    double m = 0.0, g = 0.0;
    // True when rows r0 ... r1 all hold a flat density model (no y moments needed).
    bool flat(int64_t r0, int64_t r1) const {
        if (!kRows) return false;
        for (int64_t r = r0; r <= r1; ++r)
            if (model.row_g[size_t(r - row0)] != 0.0) return false;
        return true;
    }
    void row(int64_t iy) {
        if (kRows) {
            m = sign * model.row_m[size_t(iy - row0)];
            g = sign * model.row_g[size_t(iy - row0)];
        }
    }
    void texel(int64_t ix, int64_t iy, double area, double dx, double dy) {
        double w;
        if (kRows) {
            w = m * area + g * dy;
        } else {
            TexelDensity t = cache.get(model, ix, iy);
            // An octahedral texel that a kink crosses holds a model per part (kKinked).
            w = sign * (t.gx == kKinked ? model.weight(cell, ix, iy, area, dx, dy)
                                        : t.m * area + t.gx * dx + t.gy * dy);
        }
        if (period) {
            while (ix < 0) ix += period;
            while (ix >= period) ix -= period;
        }
        const int64_t nch = NCH ? NCH : sums.nch;
        const float* v = model.image.data + (iy * model.image.width + ix) * nch;
        for (int64_t c = 0; c < nch; ++c) sums.acc[c] += w * double(v[c]);
        sums.weight += w;
    }
};

template <bool kRows, int NCH>
void direct_pixel(const SourceModel& model, int64_t cell, int64_t row0, int64_t period,
                  const double* xs, const double* ys, int n, PixelSums& sums, GreenScratch& green,
                  DensityCache& cache) {
    double area, mx, my;
    polygon_moments(xs, ys, n, area, mx, my);
    DirectSink<kRows, NCH> sink{model, cell, row0, period, area > 0.0 ? 1.0 : -1.0, sums, cache};
    if (kRows || model.g.family != kOctahedral) {
        integrate_any(xs, ys, n, sink, green);
        return;
    }
    thread_local std::vector<std::vector<double>> scratch;
    split_at_kinks(model.g, cell, xs, ys, n, scratch, [&](const double* px, const double* py, int m) {
        integrate_any(px, py, m, sink, green);
    });
}

using DirectPixel = void (*)(const SourceModel&, int64_t, int64_t, int64_t, const double*,
                             const double*, int, PixelSums&, GreenScratch&, DensityCache&);

DirectPixel direct_pixel_for(bool rows, int64_t nch) {
    if (rows) {
        return nch == 3 ? direct_pixel<true, 3> : nch == 4 ? direct_pixel<true, 4> : direct_pixel<true, 0>;
    }
    return nch == 3 ? direct_pixel<false, 3> : nch == 4 ? direct_pixel<false, 4> : direct_pixel<false, 0>;
}

// DirectSink for the linear reconstruction (area_linear.h): the same solid angles, and each
// piece's colour also takes the slope terms Dx c ax + Dy c ay of its texel (every texel of a
// direct footprint is its cell's own), so every piece needs both moments.
template <bool kRows, int NCH>
struct LinearDirectSink {
    static constexpr bool kMomentX = true;
    const SourceModel& model;
    SlopeCache& slopes;
    int64_t cell, row0, period;
    double sign;
    PixelSums& sums;
    DensityCache& cache;
    double m = 0.0, g = 0.0;
    bool flat(int64_t, int64_t) const { return false; }
    void row(int64_t iy) {
        if (kRows) {
            m = sign * model.row_m[size_t(iy - row0)];
            g = sign * model.row_g[size_t(iy - row0)];
        }
    }
    void texel(int64_t ix, int64_t iy, double area, double dx, double dy) {
        double w;
        if (kRows) {
            w = m * area + g * dy;
        } else {
            TexelDensity t = cache.get(model, ix, iy);
            w = sign * (t.gx == kKinked ? model.weight(cell, ix, iy, area, dx, dy)
                                        : t.m * area + t.gx * dx + t.gy * dy);
        }
        if (period) {
            while (ix < 0) ix += period;
            while (ix >= period) ix -= period;
        }
        const int64_t nch = NCH ? NCH : sums.nch, at = (iy * model.image.width + ix) * nch;
        const float* v = model.image.data + at;
        const float *sx = slopes.get(ix, iy), *sy = sx + nch, *sz = sy + nch;
        const double lx = sign * dx, ly = sign * dy, la = sign * area;
        for (int64_t c = 0; c < nch; ++c)
            sums.acc[c] += w * double(v[c]) + lx * double(sx[c]) + ly * double(sy[c]) + la * double(sz[c]);
        sums.weight += w;
    }
};

template <bool kRows, int NCH>
void direct_pixel_linear(const SourceModel& model, SlopeCache& slopes, int64_t cell,
                         int64_t row0, int64_t period, const double* xs, const double* ys, int n,
                         PixelSums& sums, GreenScratch& green, DensityCache& cache) {
    double area, mx, my;
    polygon_moments(xs, ys, n, area, mx, my);
    LinearDirectSink<kRows, NCH> sink{model, slopes, cell, row0, period, area > 0.0 ? 1.0 : -1.0,
                                      sums, cache};
    if (kRows || model.g.family != kOctahedral) {
        integrate_any(xs, ys, n, sink, green);
        return;
    }
    thread_local std::vector<std::vector<double>> scratch;
    split_at_kinks(model.g, cell, xs, ys, n, scratch, [&](const double* px, const double* py, int m) {
        integrate_any(px, py, m, sink, green);
    });
}

using LinearPixel = void (*)(const SourceModel&, SlopeCache&, int64_t, int64_t, int64_t,
                             const double*, const double*, int, PixelSums&, GreenScratch&,
                             DensityCache&);

LinearPixel direct_pixel_linear_for(bool rows, int64_t nch) {
    if (rows) {
        return nch == 3   ? direct_pixel_linear<true, 3>
               : nch == 4 ? direct_pixel_linear<true, 4>
                          : direct_pixel_linear<true, 0>;
    }
    return nch == 3   ? direct_pixel_linear<false, 3>
           : nch == 4 ? direct_pixel_linear<false, 4>
                      : direct_pixel_linear<false, 0>;
}

// True when the box [xmin, xmax] x [ymin, ymax] of tennisball band `cell` (its continued
// coordinates) holds only directions the band owns (layouts.h): the two bands overlap, and
// past |phi| = 90 deg a band owns only where |sin phi| cos theta >= sqrt(2)/2, least at the
// box's largest |phi| and |theta|. The general path reads the owner's texels; so must the
// direct path, or the overlap's texels would be read by both bands' pixels, or by neither.
bool tennisball_owned(const Geometry& g, int64_t cell, double xmin, double ymin, double xmax,
                      double ymax) {
    double a0, b0, a1, b1;
    cell_local(g, cell, xmin, ymin, a0, b0);
    cell_local(g, cell, xmax, ymax, a1, b1);
    const double phi = std::max(std::fabs(a0), std::fabs(a1)) * tennisball::kPhiHalf;
    const double theta = std::max(std::fabs(b0), std::fabs(b1)) * tennisball::kThetaHalf;
    return phi < 0.5 * kPi || std::sin(phi) * std::cos(theta) > tennisball::kHalfSqrt2 + 1e-9;
}

// True when the quad (xs, ys) of source cell `cell` can be integrated as it is: every texel it
// touches is one the cell holds (a lat-long's columns wrap, a tennisball band owns its
// directions), no singular point is inside or on it, and it does not wind around a lat-long
// pole.
bool direct_quad(const Geometry& g, int64_t cell, const double* xs, const double* ys) {
    double xmin = std::min({xs[0], xs[1], xs[2], xs[3]}), xmax = std::max({xs[0], xs[1], xs[2], xs[3]});
    double ymin = std::min({ys[0], ys[1], ys[2], ys[3]}), ymax = std::max({ys[0], ys[1], ys[2], ys[3]});
    const double margin = 1e-6;
    double x0 = double((cell % g.columns) * g.cell_width() + g.guard);
    double y0 = double((cell / g.columns) * g.cell_height() + g.guard);
    double w = double(g.nx), h = double(g.n);
    if (!(ymin > y0 + margin && ymax < y0 + h - margin)) return false;
    if (g.family == kLatlong && g.guard == 0) {
        // The corners share one unwrapping, so the outline winds around a pole only where a
        // side jumps by half a turn or more.
        for (int k = 0; k < 4; ++k)
            if (!(std::fabs(xs[(k + 1) % 4] - xs[k]) < 0.5 * w)) return false;
        return true;
    }
    if (!(xmin > x0 + margin && xmax < x0 + w - margin)) return false;
    if (g.family == kTennisball) return tennisball_owned(g, cell, xmin, ymin, xmax, ymax);
    if (!g.disk()) return true;
    double r = 0.5 * h, cx = x0 + r, cy = y0 + r;
    double turn = 0.0;
    for (int k = 0; k < 4; ++k) {
        if (std::hypot(xs[k] - cx, ys[k] - cy) > r * (1.0 - 1e-6)) return false;
        double d = std::atan2(ys[(k + 1) % 4] - cy, xs[(k + 1) % 4] - cx) - std::atan2(ys[k] - cy, xs[k] - cx);
        turn += d - 2.0 * kPi * std::nearbyint(d / (2.0 * kPi));
    }
    return std::fabs(turn) < kPi;  // not around the centre (-Z lies all around the rim)
}

// Per-band scratch of the direct path.
struct TileScratch {
    std::vector<char> direct;  // per pixel of the tile: integrate directly
    bool curved = false;       // the tile's edges are polylines (EdgeMemo::first, px, py)
    std::vector<SourcePoint> column;  // exact points of the last tile's right column
    SidePath sides[4];                // how the tile took a general-path pixel's sides

    PrefixTable table;
    ColumnTable column_table;        // a tile of meridians' (area_prefix.h)
    LinearPrefixTable linear_table;  // the linear reconstruction's (area_linear_walk.h)
    DensityCache density;  // the tile's texel densities (sources without exact rows)
    EdgeMemo edges;
};

// Largest prefix table (texels) a tile builds; a tile whose direct pixels span more takes its
// pixel rows one at a time, and a row that still does, its pixels one at a time.
constexpr int64_t kMaxTableTexels = int64_t(1) << 16;

// How a tile's edges are walked: through the box's prefix table (edge_integral, area_prefix.h)
// or the linear reconstruction's (edge_integral_linear, area_linear_walk.h). grid_edge and
// edge_pixels are the same for both.
template <int NCH_, bool kGrad>
struct BoxWalk {
    static constexpr int NCH = NCH_;
    using Table = PrefixTable;
    static const Table& table(const TileScratch& ts) { return ts.table; }
    static void edge(const Table& t, const SourceModel& model, int64_t row_base, double x0,
                     double y0, int64_t ix0, int64_t iy0, double x1, double y1, int64_t ix1,
                     int64_t iy1, double* out) {
        edge_integral<NCH, kGrad>(t, model, row_base, x0, y0, ix0, iy0, x1, y1, ix1, iy1, out);
    }
    static constexpr bool kMeridians = false;
    // A parabola edge in one walk: its chord and the sliver between them (edge_integral).
    static constexpr bool kBows = true;
    static void bowed(const Table& t, const SourceModel& model, int64_t row_base, double x0,
                      double y0, int64_t ix0, int64_t iy0, double x1, double y1, int64_t ix1,
                      int64_t iy1, double* out, double bow) {
        edge_integral<NCH, kGrad, true>(t, model, row_base, x0, y0, ix0, iy0, x1, y1, ix1, iy1,
                                        out, bow);
    }
};

template <int NCH_, bool kGrad>
struct LinearWalk {
    static constexpr int NCH = NCH_;
    using Table = LinearPrefixTable;
    static const Table& table(const TileScratch& ts) { return ts.linear_table; }
    static void edge(const Table& t, const SourceModel& model, int64_t row_base, double x0,
                     double y0, int64_t ix0, int64_t iy0, double x1, double y1, int64_t ix1,
                     int64_t iy1, double* out) {
        edge_integral_linear<NCH, kGrad>(t, model, row_base, x0, y0, ix0, iy0, x1, y1, ix1, iy1,
                                         out);
    }
    static constexpr bool kMeridians = false;
    // The linear reconstruction's value varies across a texel: its parabolas go as polylines.
    static constexpr bool kBows = false;
    static void bowed(const Table&, const SourceModel&, int64_t, double, double, int64_t, int64_t,
                      double, double, int64_t, int64_t, double*, double) {}
};

// A straight tile whose vertical sides all lie on meridians (tile_meridians), three channels,
// flat rows: minus P dx through the column table (edge_integral_columns), horizontal sides
// only.
struct ColumnWalk {
    static constexpr int NCH = 3;
    using Table = ColumnTable;
    static const Table& table(const TileScratch& ts) { return ts.column_table; }
    static void edge(const Table& t, const SourceModel&, int64_t, double x0, double y0,
                     int64_t ix0, int64_t iy0, double x1, double y1, int64_t ix1, int64_t iy1,
                     double* out) {
        edge_integral_columns(t, x0, y0, ix0, iy0, x1, y1, ix1, iy1, out);
    }
    static constexpr bool kMeridians = true;
    static constexpr bool kBows = false;
    static void bowed(const Table&, const SourceModel&, int64_t, double, double, int64_t, int64_t,
                      double, double, int64_t, int64_t, double*, double) {}
};

// How many points edge `index` of a curved tile runs through between its corners.
int edge_point_count(const EdgeMemo& e, size_t index) {
    const signed char r = e.refine[index];
    return r == 2 ? 1 : r == 3 ? 3 : r == 1 ? e.first[index + 1] - e.first[index] : 0;
}

// Point q of edge `index` (corners a to b), from a: refine_segment's, or the parabola's
// P(t) = Pa + t (Pb - Pa) + t (t - 1) D / 2 at t = (q + 1) / (count + 1).
void edge_point(const CornerGrid& g, const EdgeMemo& e, size_t index, size_t a, size_t b, int q,
                double& x, double& y) {
    const signed char r = e.refine[index];
    if (r == 1) {
        x = e.px[size_t(e.first[index] + q)];
        y = e.py[size_t(e.first[index] + q)];
        return;
    }
    const double t = r == 2 ? 0.5 : 0.25 * double(q + 1);
    x = g.x[a] + t * (g.x[b] - g.x[a]) + 0.5 * t * (t - 1.0) * e.dx[index];
    y = g.y[a] + t * (g.y[b] - g.y[a]) + 0.5 * t * (t - 1.0) * e.dy[index];
}

// Call f(x, y) for every point of every edge of a curved tile (refined and parabola edges).
template <class F>
void each_edge_point(const CornerGrid& g, const EdgeMemo& e, F&& f) {
    for (size_t k = 0; k < e.px.size(); ++k) f(e.px[k], e.py[k]);
    auto parabola = [&](size_t index, size_t a, size_t b) {
        if (e.refine[index] < 2) return;
        for (int q = 0, n = edge_point_count(e, index); q < n; ++q) {
            double x, y;
            edge_point(g, e, index, a, b, q, x, y);
            f(x, y);
        }
    };
    for (int j = 0; j <= g.h; ++j)
        for (int i = 0; i < g.w; ++i) parabola(e.horizontal(i, j), g.at(i, j), g.at(i + 1, j));
    for (int j = 0; j < g.h; ++j)
        for (int i = 0; i <= g.w; ++i) parabola(e.vertical(i, j), g.at(i, j), g.at(i, j + 1));
}

// Grow the box [xmin, xmax] x [ymin, ymax] to hold every point of every edge of a curved tile.
void extend_by_edge_points(const CornerGrid& g, const EdgeMemo& e, double& xmin, double& xmax,
                           double& ymin, double& ymax) {
    each_edge_point(g, e, [&](double x, double y) {
        xmin = std::min(xmin, x);
        xmax = std::max(xmax, x);
        ymin = std::min(ymin, y);
        ymax = std::max(ymax, y);
    });
}

// Integral of the grid's edge from corner a to corner b through the tile's table, along its
// polyline (count refinement points px, py) in a curved tile, or (bow not 0) the parabola
// about its chord that edge_integral's bow describes. Inlined into edge_pixels' loops (as a
// call it cost 2 % of the one shot's kernel).
template <class Walk>
__attribute__((always_inline)) inline void grid_edge(const AreaJob& job, const CornerGrid& g,
                                                     const typename Walk::Table& t,
               int64_t row_base, size_t a, size_t b, double* out, const double* px = nullptr,
               const double* py = nullptr, int count = 0, double bow = 0.0) {
    const int64_t nch = Walk::NCH ? Walk::NCH : t.nch;
    for (int64_t c = 0; c <= nch; ++c) out[c] = 0.0;
    if (bow != 0.0) {
        Walk::bowed(t, job.model, row_base, g.x[a], g.y[a], g.fx[a], g.fy[a], g.x[b], g.y[b],
                    g.fx[b], g.fy[b], out, bow);
        return;
    }
    if (count == 0) {
        Walk::edge(t, job.model, row_base, g.x[a], g.y[a], g.fx[a], g.fy[a], g.x[b], g.y[b],
                   g.fx[b], g.fy[b], out);
        return;
    }
    double x0 = g.x[a], y0 = g.y[a];
    int64_t fx0 = g.fx[a], fy0 = g.fy[a];
    for (int k = 0; k <= count; ++k) {
        double x1 = k < count ? px[k] : g.x[b], y1 = k < count ? py[k] : g.y[b];
        int64_t fx1 = k < count ? floor_texel(x1) : g.fx[b], fy1 = k < count ? floor_texel(y1) : g.fy[b];
        Walk::edge(t, job.model, row_base, x0, y0, fx0, fy0, x1, y1, fx1, fy1, out);
        x0 = x1;
        y0 = y1;
        fx0 = fx1;
        fy0 = fy1;
    }
}

// Integrate every edge of the direct pixels of rows [j0, j1) of the tile (independent loops,
// so that the walks of neighbouring edges overlap), then each direct pixel's sums from its
// four edges: the loop (i, j) -> (i + 1, j) -> (i + 1, j + 1) -> (i, j + 1), top and right
// edges as walked, bottom and left against their direction.
template <class Walk>
void edge_pixels(const AreaJob& job, const CornerGrid& g, TileScratch& ts, int64_t row_base,
                 int j0, int j1) {
    constexpr int NCH = Walk::NCH;
    const typename Walk::Table& table = Walk::table(ts);
    EdgeMemo& e = ts.edges;
    const int64_t st = e.stride, nch = st - 1;
    const int w = g.w;
    const size_t cs = size_t(w + 1);  // corners per grid row
    const char* dir = ts.direct.data();
    // A curved tile's edges run along their polylines, or as bowed chords where the grid gave
    // them a parabola and both pixels beside the edge are walked here (inside). An edge that
    // a pixel of another tile, of the general path or of the per-pixel path also takes runs
    // along the polyline as that pixel does, so that the two hand out the same piece of the
    // sphere (bowed against a polyline, they differed by a quarter of the sliver: the pixels'
    // solid angles of a 48-row lat-long into a 32 px equal-area square summed to 4π - 3.7e-4).
    double parabola_x[3], parabola_y[3];
    auto polyline = [&](size_t index, size_t a, size_t b, bool inside, const double*& px,
                        const double*& py, int& count, double& bow) {
        if (!ts.curved) return;
        if (e.refine[index] >= 2) {
            bow = Walk::kBows && inside ? e.bow[index] : 0.0;
            if (bow != 0.0) return;
            count = edge_point_count(e, index);
            for (int q = 0; q < count; ++q) edge_point(g, e, index, a, b, q, parabola_x[q], parabola_y[q]);
            px = parabola_x;
            py = parabola_y;
            return;
        }
        px = e.px.data() + e.first[index];
        py = e.py.data() + e.first[index];
        count = e.first[index + 1] - e.first[index];
    };
    for (int j = j0; j <= j1; ++j) {
        const char* above = j > j0 ? dir + (j - 1) * w : nullptr;
        const char* below = j < j1 ? dir + j * w : nullptr;
        for (int i = 0; i < w; ++i) {
            if (!((above && above[i]) || (below && below[i]))) continue;
            const double *px = nullptr, *py = nullptr;
            int count = 0;
            double bow = 0.0;
            const bool inside = above && above[i] && below && below[i];
            polyline(e.horizontal(i, j), j * cs + i, j * cs + i + 1, inside, px, py, count, bow);
            grid_edge<Walk>(job, g, table, row_base, j * cs + i, j * cs + i + 1,
                            &e.hv[size_t(j * w + i) * st], px, py, count, bow);
        }
    }
    for (int j = j0; j < j1 && !Walk::kMeridians; ++j) {  // a meridian holds no - P dx
        const char* row = dir + j * w;
        for (int i = 0; i <= w; ++i) {
            if (!((i > 0 && row[i - 1]) || (i < w && row[i]))) continue;
            const double *px = nullptr, *py = nullptr;
            int count = 0;
            double bow = 0.0;
            const bool inside = i > 0 && i < w && row[i - 1] && row[i];
            polyline(e.vertical(i, j), j * cs + i, (j + 1) * cs + i, inside, px, py, count, bow);
            grid_edge<Walk>(job, g, table, row_base, j * cs + i, (j + 1) * cs + i,
                            &e.vv[size_t(j * (w + 1) + i) * st], px, py, count, bow);
        }
    }
    for (int j = j0; j < j1; ++j) {
        const char* row = dir + j * w;
        for (int i = 0; i < w; ++i) {
            if (!row[i]) continue;
            const double* tp = &e.hv[size_t(j * w + i) * st];
            const double* bt = &e.hv[size_t((j + 1) * w + i) * st];
            double* sum = &e.pixel[size_t(j * w + i) * st];
            if constexpr (Walk::kMeridians) {
                for (int64_t c = 0; c <= NCH; ++c) sum[c] = tp[c] - bt[c];
                continue;
            }
            const double* lf = &e.vv[size_t(j * (w + 1) + i) * st];
            const double* rt = lf + st;
            for (int64_t c = 0; c <= (NCH ? NCH : nch); ++c) sum[c] = tp[c] + rt[c] - bt[c] - lf[c];
        }
    }
}

using EdgePixels = void (*)(const AreaJob&, const CornerGrid&, TileScratch&, int64_t, int, int);

// edge_pixels for the tile's walk (linear: the linear reconstruction's), its rows' density
// model (grad) and channel count.
template <template <int, bool> class Walk>
EdgePixels edge_pixels_of(bool grad, int64_t nch) {
    if (grad) {
        return nch == 3   ? edge_pixels<Walk<3, true>>
               : nch == 4 ? edge_pixels<Walk<4, true>>
                          : edge_pixels<Walk<0, true>>;
    }
    return nch == 3   ? edge_pixels<Walk<3, false>>
           : nch == 4 ? edge_pixels<Walk<4, false>>
                      : edge_pixels<Walk<0, false>>;
}

EdgePixels edge_pixels_for(bool grad, int64_t nch) { return edge_pixels_of<BoxWalk>(grad, nch); }

EdgePixels edge_pixels_linear_for(bool grad, int64_t nch) {
    return edge_pixels_of<LinearWalk>(grad, nch);
}

// True when every vertical line of corners of the grid lies at one x (a meridian of a
// lat-long: a cube's side faces, any tile of a lat-long → lat-long without rotation), to
// within kMeridianTol texels: the maps and the Coons interior round the same longitude a few
// units in the last place apart. A side that far off its meridian holds at most kMeridianTol
// times a column of the tile's rows (1e-7 of a texel's value for 100 rows), below float32
// output; the column walk takes it as nothing.
constexpr double kMeridianTol = 1e-9;
bool tile_meridians(const CornerGrid& g) {
    for (int i = 0; i <= g.w; ++i) {
        const double x = g.x[g.at(i, 0)];
        for (int j = 1; j <= g.h; ++j)
            if (!(std::fabs(g.x[g.at(i, j)] - x) <= kMeridianTol)) return false;
    }
    return true;
}

// The box of the corners of the direct pixels of rows [j0, j1) of the tile (empty, xmin >
// xmax, where there are none).
void direct_corner_box(const CornerGrid& g, const TileScratch& ts, int j0, int j1, double& xmin,
                       double& xmax, double& ymin, double& ymax) {
    xmin = ymin = 1e300;
    xmax = ymax = -1e300;
    for (int j = j0; j < j1; ++j) {
        for (int i = 0; i < g.w; ++i) {
            if (!ts.direct[size_t(j * g.w + i)]) continue;
            for (int q = 0; q < 4; ++q) {
                size_t k = g.at(i + (q & 1), j + (q >> 1));
                xmin = std::min(xmin, g.x[k]);
                xmax = std::max(xmax, g.x[k]);
                ymin = std::min(ymin, g.y[k]);
                ymax = std::max(ymax, g.y[k]);
            }
        }
    }
}

// Build the prefix table over the corners of the direct pixels of rows [j0, j1) of the tile;
// false when there are none, the box is too large or holds a texel that is not finite.
bool tile_table(const AreaJob& job, const CornerGrid& g, TileScratch& ts, int j0, int j1,
                bool& grad, SlopeCache* slopes = nullptr, bool* columns = nullptr) {
    const Geometry& s = job.cv.src;
    // The box of every corner of rows [j0, j1]; where that is too large (a pixel far off, as
    // near a pole), the box of the direct pixels' corners only.
    if (!g.usable) return false;  // no direct pixels
    double xmin = g.xmin, xmax = g.xmax, ymin = g.ymin, ymax = g.ymax;  // all rows: the grid's
    if (j0 > 0 || j1 < g.h) {
        xmin = ymin = 1e300;
        xmax = ymax = -1e300;
        for (size_t k = g.at(0, j0); k <= g.at(g.w, j1); ++k) {
            xmin = std::min(xmin, g.x[k]);
            xmax = std::max(xmax, g.x[k]);
            ymin = std::min(ymin, g.y[k]);
            ymax = std::max(ymax, g.y[k]);
        }
    }
    if ((xmax - xmin + 2.0) * (ymax - ymin + 2.0) > double(kMaxTableTexels) ||
        ymin < double((g.ref_cell / s.columns) * s.cell_height() + s.guard) ||
        ymax >= double((g.ref_cell / s.columns) * s.cell_height() + s.guard + s.n)) {
        direct_corner_box(g, ts, j0, j1, xmin, xmax, ymin, ymax);
    }
    if (xmin > xmax) return false;
    // A curved tile's polylines may bulge past their corners, its parabola edges too: a bowed
    // chord stays between its corners, but a side shared with a pixel that is not walked here
    // runs along the polyline through the parabola's points (edge_pixels).
    if (ts.curved) extend_by_edge_points(g, ts.edges, xmin, xmax, ymin, ymax);
    int64_t c0 = floor_texel(xmin), c1 = floor_texel(xmax), r0 = floor_texel(ymin), r1 = floor_texel(ymax);
    if ((c1 - c0 + 1) * (r1 - r0 + 1) > kMaxTableTexels) return false;
    const int64_t row_base = (g.ref_cell / s.columns) * s.cell_height();
    int64_t period = s.family == kLatlong && s.guard == 0 ? 2 * s.n : 0;
    // A curved tile's polylines may bulge past the cell: its rows (whose densities are known)
    // and, where columns do not wrap, its columns bound the table (else the per-pixel path).
    const int64_t col_base = (g.ref_cell % s.columns) * s.cell_width();
    if (r0 < row_base || r1 >= row_base + s.cell_height()) return false;
    if (!period && (c0 < col_base || c1 >= col_base + s.cell_width())) return false;
    grad = false;
    for (int64_t r = r0; r <= r1; ++r) grad = grad || job.model.row_g[size_t(r - row_base)] != 0.0;
    if (slopes) return ts.linear_table.build(job.model.image, *slopes, period, r0, r1, c0, c1);
    if (columns && *columns && !grad)  // the tile's meridians take the column table
        return ts.column_table.build(job.model.image, job.model.row_m, row_base, period, r0, r1, c0, c1);
    if (columns) *columns = false;
    return ts.table.build(job.model.image, period, r0, r1, c0, c1);
}

// True when every pixel of a lat-long or tennisball grid passes direct_quad: all corners
// between the first and last rows, the grid less than half a turn wide (no side can jump).
bool whole_tile_direct(const Geometry& g, const CornerGrid& grid) {
    if (g.family != kLatlong && g.family != kTennisball) return false;
    const double xmin = grid.xmin, xmax = grid.xmax, ymin = grid.ymin, ymax = grid.ymax;
    const int64_t cell = grid.ref_cell;
    const double margin = 1e-6;
    double x0 = double((cell % g.columns) * g.cell_width() + g.guard);
    double y0 = double((cell / g.columns) * g.cell_height() + g.guard);
    double w = double(g.nx), h = double(g.n);
    if (!(ymin > y0 + margin && ymax < y0 + h - margin)) return false;
    if (g.family == kLatlong && g.guard == 0) return xmax - xmin < 0.5 * w;
    return xmin > x0 + margin && xmax < x0 + w - margin &&
           tennisball_owned(g, cell, xmin, ymin, xmax, ymax);
}

// How the tile took the sides of pixel (i, j) (for the general path, in the order (i, j) ->
// (i + 1, j) -> (i + 1, j + 1) -> (i, j + 1)): chords in a straight tile, its polylines in a
// curved one, the general path's own rule where the tile has no usable grid.
void side_paths(const CornerGrid& g, TileScratch& ts, int i, int j, bool usable) {
    const EdgeMemo& e = ts.edges;
    const size_t index[4] = {e.horizontal(i, j), e.vertical(i + 1, j), e.horizontal(i, j + 1), e.vertical(i, j)};
    const size_t start[4] = {g.at(i, j), g.at(i + 1, j), g.at(i + 1, j + 1), g.at(i, j + 1)};
    for (int k = 0; k < 4; ++k) {
        SidePath& s = ts.sides[k];
        s.px.clear();
        s.py.clear();
        s.mode = usable ? 0 : 1;
        s.cell = g.ref_cell;  // where the tile decided the side (a chord is one there only)
        if (!usable || !ts.curved || e.refine[index[k]] == 0) continue;
        if (e.refine[index[k]] < 0) {
            s.mode = 1;
            continue;
        }
        s.mode = 2;
        s.x0 = g.x[start[k]];
        s.y0 = g.y[start[k]];
        // The bottom and left sides run against their edges (from corner b to a).
        const size_t a = k >= 2 ? start[(k + 1) % 4] : start[k], b = k >= 2 ? start[k] : start[k + 1];
        for (int m = 0, n = edge_point_count(e, index[k]); m < n; ++m) {
            double x, y;
            edge_point(g, e, index[k], a, b, k >= 2 ? n - 1 - m : m, x, y);
            s.px.push_back(x);
            s.py.push_back(y);
        }
    }
}

// The footprint of pixel (i, j) of the grid into xs, ys: its corners and, in a curved tile,
// the refinement points of its edges, around the pixel (i, j) -> (i + 1, j) -> (i + 1, j + 1)
// -> (i, j + 1).
void pixel_polygon(const CornerGrid& g, const TileScratch& ts, int i, int j,
                   std::vector<double>& xs, std::vector<double>& ys) {
    const EdgeMemo& e = ts.edges;
    xs.clear();
    ys.clear();
    // From `corner` along edge `index` (corners a to b, walked backwards when reverse).
    auto side = [&](size_t corner, size_t index, size_t a, size_t b, bool reverse) {
        xs.push_back(g.x[corner]);
        ys.push_back(g.y[corner]);
        if (!ts.curved) return;
        for (int k = 0, n = edge_point_count(e, index); k < n; ++k) {
            double x, y;
            edge_point(g, e, index, a, b, reverse ? n - 1 - k : k, x, y);
            xs.push_back(x);
            ys.push_back(y);
        }
    };
    const size_t c00 = g.at(i, j), c10 = g.at(i + 1, j), c11 = g.at(i + 1, j + 1), c01 = g.at(i, j + 1);
    side(c00, e.horizontal(i, j), c00, c10, false);
    side(c10, e.vertical(i + 1, j), c10, c11, false);
    side(c11, e.horizontal(i, j + 1), c01, c11, true);
    side(c01, e.vertical(i, j), c00, c01, true);
}

// True when a fold of an octahedral or equal-area output (its axes, its rim and the diamond
// |a| + |b| = 1 where the hemispheres meet) may touch the output box [x0, x1] x [y0, y1] of
// cell `cell` (image pixels, edges included).
bool box_on_output_fold(const Conversion& cv, int64_t cell, double x0, double y0, double x1,
                        double y1) {
    if (cv.dst.family != kOctahedral && cv.dst.family != kEqualArea) return false;
    double a0, b0, a1, b1;
    cell_local(cv.dst, cell, x0, y0, a0, b0);
    cell_local(cv.dst, cell, x1, y1, a1, b1);
    double alo = std::min(a0, a1), ahi = std::max(a0, a1), blo = std::min(b0, b1), bhi = std::max(b0, b1);
    for (double line : {-1.0, 0.0, 1.0})
        if ((alo <= line && line <= ahi) || (blo <= line && line <= bhi)) return true;
    double lo = 1e300, hi = -1e300;
    for (double a : {alo, ahi}) {
        for (double b : {blo, bhi}) {
            lo = std::min(lo, std::fabs(a) + std::fabs(b));
            hi = std::max(hi, std::fabs(a) + std::fabs(b));
        }
    }
    return lo <= 1.0 && 1.0 <= hi;
}

// True when a fold of the output or source map (area_map.h) may touch the tile.
bool tile_on_fold(const Conversion& cv, const CornerGrid& g, int64_t cell) {
    if (cv.src.family == kOctahedral || cv.src.family == kEqualArea) return true;
    return box_on_output_fold(cv, cell, double(g.i0) * cv.scale_x, double(g.j0) * cv.scale_y,
                              double(g.i0 + g.w) * cv.scale_x, double(g.j0 + g.h) * cv.scale_y);
}

// How far (output pixels across) the image of the grid's edge from corner (i, j) to
// (i + di, j + dj) strays from its chord, as the grid estimates it: the second differences
// along its line at its two ends (the one inside the line at its ends, doubled to stay on the
// safe side), across the line, over the spacing of the lines beside it, over eight; (dx, dy)
// their mean D, in texels. Where the second derivative changes linearly along the edge (a
// cubic, as near a pole), the parabola of D has the cubic's midpoint and the same area between
// it and the chord, so the estimate holds while the two ends' bends differ by up to
// kBendChange of their mean (or a quarter of kChordTol); beyond that, or where they bend to
// opposite sides by more than that, -1 (no estimate). The terms along the line use its own corners only, which the tile
// beyond a boundary line shares, so both tiles estimate a boundary edge alike (up to the
// spacing beside it, which decides only how an edge is taken, not where its points go).
constexpr double kBendChange = 0.5;
__attribute__((always_inline)) inline double edge_curve(const CornerGrid& g, int i, int j, int di,
                                                       int dj, double& dx, double& dy) {
    const double *x = g.x.data(), *y = g.y.data();
    const int n = di ? g.w : g.h, at = di ? i : j;        // position along the line
    const int m = di ? g.h : g.w, line = di ? j : i;      // which line across
    const int64_t step = di ? 1 : g.w + 1, across = di ? g.w + 1 : 1;
    const int64_t k0 = int64_t(g.at(i, j)), k1 = k0 + step;
    const int64_t lo = line > 0 ? k0 - across : k0, hi = line < m ? k0 + across : k0;
    // Over the number of spacings between lo and hi (1 or 2): a product, exactly the quotient.
    const double per_line = line > 0 && line < m ? 0.5 : 1.0;
    double tx = x[k1] - x[k0], ty = y[k1] - y[k0];
    double sx = (x[hi] - x[lo]) * per_line, sy = (y[hi] - y[lo]) * per_line;
    double spacing = std::fabs(tx * sy - ty * sx);
    dx = dy = 0.0;
    if (!(spacing > 0.0)) return -1.0;
    // The second differences at the two ends, in scalars (as arrays they were stored one by one
    // and read back in pairs, a stall on every edge).
    const bool first = at >= 1, second = at + 2 <= n;
    if (!first && !second) return -1.0;
    // One reciprocal for the edge's one or two bends (two quotients were a third of this
    // function's time).
    const double per_spacing = 1.0 / (8.0 * spacing);
    auto signed_bend = [&](double vx, double vy) { return (tx * vy - ty * vx) * per_spacing; };
    auto bend = [&](double vx, double vy) { return std::fabs(signed_bend(vx, vy)); };
    const double ax = first ? x[k0 - step] - 2.0 * x[k0] + x[k1] : 0.0;
    const double ay = first ? y[k0 - step] - 2.0 * y[k0] + y[k1] : 0.0;
    const double bx = second ? x[k0] - 2.0 * x[k1] + x[k1 + step] : 0.0;
    const double by = second ? y[k0] - 2.0 * y[k1] + y[k1 + step] : 0.0;
    if (!(first && second)) {
        dx = first ? ax : bx;
        dy = first ? ay : by;
        return 2.0 * bend(dx, dy);
    }
    dx = 0.5 * ax + 0.5 * bx;
    dy = 0.5 * ay + 0.5 * by;
    const double s0 = signed_bend(ax, ay), s1 = signed_bend(bx, by);
    const double mean = 0.5 * (std::fabs(s0) + std::fabs(s1));
    if (std::fabs(s0 - s1) > std::max(0.25 * kChordTol, kBendChange * mean)) return -1.0;
    return mean;
}

// An edge estimated to bend up to this many times kChordTol is taken as the parabola the grid
// implies: up to kMidpointBend times through its midpoint alone (two chords, four times
// straighter: within half of kChordTol, as a chord is held), beyond that through its points at
// a quarter, a half and three quarters (sixteen times straighter). Most curved edges of a 1:1
// lat-long → cube bend by one or two kChordTol: one midpoint saves two of their four walks.
constexpr double kParabolaBend = 16.0, kMidpointBend = 2.0;

// Decide every edge of a curved tile, once for the pixels on both sides: a chord where the
// grid's estimate of its bend is within half of kChordTol (away from folds), the estimated
// parabola (one or three points) where it is within kParabolaBend times kChordTol, else the
// polyline of refine_segment (in the reference cell). ts.edges.refine records what was done (0: chord,
// 1: refined, 2 and 3: parabola, -1: could not be refined in the reference cell, whose pixels
// are then not direct). The box's walk takes a parabola as its chord and the sliver beside it
// (edge_integral's bow: one walk, not the polyline's two or four); the general path and the
// linear reconstruction take the polylines (SidePath, edge_point).
void refine_tile_edges(const AreaJob& job, const CornerGrid& g, TileScratch& ts, int64_t cell) {
    const Conversion& cv = job.cv;
    EdgeMemo& e = ts.edges;
    const int w = g.w, h = g.h;
    const size_t edges = size_t((h + 1) * w + h * (w + 1));
    e.first.assign(edges + 1, 0);
    e.refine.assign(edges, 0);
    e.dx.resize(edges);  // these three are read for parabola edges only
    e.dy.resize(edges);
    e.bow.resize(edges);
    e.px.clear();
    e.py.clear();
    // Folds exist only in octahedral and equal-area squares (edge_on_fold).
    const bool folded = cv.dst.family == kOctahedral || cv.dst.family == kEqualArea ||
                        cv.src.family == kOctahedral || cv.src.family == kEqualArea;
    // Inlined, as edge_curve: a call an edge was 2 % of a view of a pole.
    auto edge = [&](size_t index, int i0, int j0, int di, int dj) __attribute__((always_inline)) {
        e.first[index] = int32_t(e.px.size());
        size_t a = g.at(i0, j0), b = g.at(i0 + di, j0 + dj);
        double ox0 = double(g.i0 + i0) * cv.scale_x, oy0 = double(g.j0 + j0) * cv.scale_y;
        double ox1 = double(g.i0 + i0 + di) * cv.scale_x, oy1 = double(g.j0 + j0 + dj) * cv.scale_y;
        bool fold = folded && edge_on_fold(cv, cell, ox0, oy0, ox1, oy1, g.corner_point(a), g.corner_point(b));
        if (!fold) {
            double dx, dy, bend = edge_curve(g, i0, j0, di, dj, dx, dy);
            if (bend >= 0.0 && bend <= kParabolaBend * kChordTol) {
                // A chord, or P(t) = P0 + t (P1 - P0) + t (t - 1) D / 2, D the second
                // difference: its points (edge_point) for the general path, its bow for the
                // box's walk. Chosen by selects: the three cases mix as good as randomly.
                const bool chord = bend <= 0.5 * kChordTol;
                e.refine[index] = chord ? 0 : bend <= kMidpointBend * kChordTol ? 2 : 3;
                e.dx[index] = dx;
                e.dy[index] = dy;
                // The bow holds the sliver of the polyline through the parabola's points (the
                // general path's side): 3/4 of the parabola's through its midpoint, 15/16
                // through its quarter points, so that both take the same area and the pixels
                // on either side of a side, or opposite sides of a pixel, agree as before.
                const double polyline = bend <= kMidpointBend * kChordTol ? 0.75 : 0.9375;
                e.bow[index] = chord ? 0.0 : polyline * 0.5 * (dx * (g.y[b] - g.y[a]) - dy * (g.x[b] - g.x[a]));
                return;
            }
        }
        e.refine[index] = 1;
        if (!refine_segment(cv, job.sing, cell, ox0, oy0, ox1, oy1, g.ref_cell, g.x[a], g.y[a], g.x[b],
                            g.y[b], fold ? 0.25 * kChordTol : kChordTol, e.px, e.py)) {
            e.px.resize(size_t(e.first[index]));
            e.py.resize(size_t(e.first[index]));
            e.refine[index] = -1;
        }
    };
    // A lat-long edge's points must stay in its corners' unwrapping: a step of a quarter turn
    // or more between neighbours means a point was wrapped apart (the pixel's columns would
    // not be its own), and its pixels go through the general path.
    const bool wraps = cv.src.family == kLatlong && cv.src.guard == 0;
    const double quarter = 0.25 * double(cv.src.nx);
    auto unwrapped = [&](size_t index, int i0, int j0, int di, int dj) {
        double x = g.x[g.at(i0, j0)];
        for (int32_t m = e.first[index]; m < int32_t(e.px.size()); ++m) {
            if (!(std::fabs(e.px[size_t(m)] - x) < quarter)) return false;
            x = e.px[size_t(m)];
        }
        return std::fabs(g.x[g.at(i0 + di, j0 + dj)] - x) < quarter;
    };
    auto checked_edge = [&](size_t index, int i0, int j0, int di,
                            int dj) __attribute__((always_inline)) {
        edge(index, i0, j0, di, dj);
        if (wraps && e.refine[index] > 0 && !unwrapped(index, i0, j0, di, dj)) {
            e.px.resize(size_t(e.first[index]));
            e.py.resize(size_t(e.first[index]));
            e.refine[index] = -1;
        }
    };
    for (int j = 0; j <= h; ++j)
        for (int i = 0; i < w; ++i) checked_edge(e.horizontal(i, j), i, j, 1, 0);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i <= w; ++i) checked_edge(e.vertical(i, j), i, j, 0, 1);
    e.first.back() = int32_t(e.px.size());
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            if (e.refine[e.horizontal(i, j)] < 0 || e.refine[e.horizontal(i, j + 1)] < 0 ||
                e.refine[e.vertical(i, j)] < 0 || e.refine[e.vertical(i + 1, j)] < 0)
                ts.direct[size_t(j * w + i)] = 0;
        }
    }
}

// A folded source's pixels stay direct only where their whole footprint lies inside the
// square: every point of their outline (corners and refinement points) more than a margin
// inside it (past an edge the texels fold, which the direct path does not read). Tiles that
// hold a cone point take the general path whole (cone_in_box).
void fold_guard(const AreaJob& job, const CornerGrid& g, TileScratch& ts, int64_t cell) {
    const Conversion& cv = job.cv;
    const Geometry& s = cv.src;
    const double margin = 1e-6;
    const double x0 = double((g.ref_cell % s.columns) * s.cell_width() + s.guard);
    const double y0 = double((g.ref_cell / s.columns) * s.cell_height() + s.guard);
    const double w = double(s.nx), h = double(s.n);
    auto inside = [&](double x, double y) {
        return x > x0 + margin && x < x0 + w - margin && y > y0 + margin && y < y0 + h - margin;
    };
    // Most tiles lie inside the square whole: every corner and polyline point at once.
    bool all = true;
    for (size_t k = 0; all && k < g.x.size(); ++k) all = inside(g.x[k], g.y[k]);
    if (all && ts.curved) each_edge_point(g, ts.edges, [&](double x, double y) { all = all && inside(x, y); });
    if (all) return;
    std::vector<double> xs, ys;
    for (int j = 0; j < g.h; ++j) {
        for (int i = 0; i < g.w; ++i) {
            char& direct = ts.direct[size_t(j * g.w + i)];
            if (!direct) continue;
            pixel_polygon(g, ts, i, j, xs, ys);
            for (size_t k = 0; k < xs.size(); ++k) {
                if (!inside(xs[k], ys[k])) {
                    direct = 0;
                    break;
                }
            }
        }
    }
}

// Set the tile's density cache to the texel box of its direct pixels (their corners and, in a
// curved tile, their polylines), or to no box where there are none or it is too large.
void density_box(const CornerGrid& g, TileScratch& ts) {
    double xmin, xmax, ymin, ymax;
    direct_corner_box(g, ts, 0, g.h, xmin, xmax, ymin, ymax);
    if (ts.curved) extend_by_edge_points(g, ts.edges, xmin, xmax, ymin, ymax);
    if (!(xmin <= xmax && ymin <= ymax) ||
        (xmax - xmin + 2.0) * (ymax - ymin + 2.0) > double(kMaxTableTexels)) {
        ts.density.reset(g.ref_cell, 0, 0, -1, -1);
        return;
    }
    ts.density.reset(g.ref_cell, floor_texel(xmin), floor_texel(ymin), floor_texel(xmax),
                     floor_texel(ymax));
}

// The pixels of one tile inside output cell `cell` (grid: its corners): direct where the
// corner grid allows (through edge integrals for lat-long and tennisball sources, else pixel
// by pixel), the general path with the grid's corners elsewhere.
void tile_pixels(const AreaJob& job, SlowPath& sp, PixelSums& sums, CornerGrid& grid,
                 TileScratch& ts, int64_t cell, bool regular) {
    const Conversion& cv = job.cv;
    const Geometry& s = cv.src;
    const bool usable = regular && grid.usable;
    // Straight: every pixel edge's image within kChordTol of its chord (half of it as the
    // grid estimates it) and no fold in reach; else each edge is refined (refine_tile_edges).
    const bool folds = usable && tile_on_fold(cv, grid, cell);
    const bool straight = usable && grid.bend <= 0.5 * kChordTol && !folds;
    const int64_t period = s.family == kLatlong && s.guard == 0 ? 2 * s.n : 0;
    const int64_t row0 = (grid.ref_cell / s.columns) * s.cell_height();
    const bool rows = !job.model.row_m.empty();
    const DirectPixel direct = direct_pixel_for(rows, sums.nch);
    // The linear reconstruction: its own sinks and, for lat-long and tennisball inputs, its own
    // tables and walks (area_linear_walk.h).
    const LinearPixel linear = job.linear ? direct_pixel_linear_for(rows, sums.nch) : nullptr;
    const bool tables = rows;
    ts.direct.assign(size_t(grid.w * grid.h), 0);
    const int64_t st = grid.w + 1;
    // Every pixel passes direct_quad where the whole grid does (a lat-long or tennisball
    // source), curved or not, unless an output fold may cut one.
    const bool all_direct = usable && !folds && whole_tile_direct(s, grid);
    if (all_direct) std::fill(ts.direct.begin(), ts.direct.end(), 1);
    // Straight sides on meridians, three channels, the box: - P dx down the columns, the
    // horizontal sides alone (ColumnTable; its rows must be flat, tile_table's to decide).
    const bool meridians = tables && straight && !linear && sums.nch == 3 && tile_meridians(grid);
    // A disk source's -Z (its whole rim) in or on a pixel: the side through it leaves the
    // rim at one point and comes back at the opposite one, and its image is that half of the
    // rim, not the chord the grid would take (a sun on the rim texels of a 32-px mirror ball
    // lost 6 % into a 50 x 25 lat-long): the general path runs along the rim.
    double rim_x = 0.0, rim_y = 0.0;
    const bool rim = usable && !all_direct && job.sing.kind == 2 &&
                     continued_point(cv.dst, cell, job.sing.out[0],
                                     (double(grid.i0) + 0.5 * grid.w) * cv.scale_x,
                                     (double(grid.j0) + 0.5 * grid.h) * cv.scale_y, rim_x, rim_y);
    const double slack = 1e-3 * std::max(cv.scale_x, cv.scale_y);
    for (int j = 0; j < grid.h && usable && !all_direct; ++j) {
        const double* x = grid.x.data() + j * st;
        const double* y = grid.y.data() + j * st;
        char* direct_row = ts.direct.data() + j * grid.w;
        for (int i = 0; i < grid.w; ++i) {
            const double xs[4] = {x[i], x[i + 1], x[i + 1 + st], x[i + st]};
            const double ys[4] = {y[i], y[i + 1], y[i + 1 + st], y[i + st]};
            // A pixel cut by an output fold has kinked sides, which no grid estimate holds:
            // the general path finds the kinks.
            const double px0 = double(grid.i0 + i) * cv.scale_x, py0 = double(grid.j0 + j) * cv.scale_y;
            direct_row[i] = direct_quad(s, grid.ref_cell, xs, ys) &&
                            !box_on_output_fold(cv, cell, px0, py0, px0 + cv.scale_x, py0 + cv.scale_y) &&
                            !(rim && rim_x >= px0 - slack && rim_x <= px0 + cv.scale_x + slack &&
                              rim_y >= py0 - slack && rim_y <= py0 + cv.scale_y + slack);
        }
    }
    ts.curved = usable && !straight;
    ts.edges.reset(grid.w, grid.h, sums.nch);
    if (ts.curved) refine_tile_edges(job, grid, ts, cell);
    if (usable && (s.family == kOctahedral || s.family == kEqualArea)) fold_guard(job, grid, ts, cell);
    if (!rows) density_box(grid, ts);
    // Rows of pixels share one table where it fits, else each pixel row has its own.
    int band_j0 = 0;
    while (band_j0 < grid.h) {
        bool by_columns = meridians;
        bool grad = false, whole = tables && tile_table(job, grid, ts, band_j0, grid.h, grad,
                                                        sp.linear, &by_columns);
        int band_j1 = grid.h;
        if (!whole && tables) {
            band_j1 = band_j0 + 1;
            by_columns = meridians;
            whole = tile_table(job, grid, ts, band_j0, band_j1, grad, sp.linear, &by_columns);
        } else if (!tables) {
            band_j1 = grid.h;
        }
        if (whole) {
            ts.edges.reset(grid.w, grid.h, sums.nch);
            const EdgePixels walk = by_columns ? edge_pixels<ColumnWalk>
                                    : linear   ? edge_pixels_linear_for(grad, sums.nch)
                                               : edge_pixels_for(grad, sums.nch);
            walk(job, grid, ts, row0, band_j0, band_j1);
        }
        for (int j = band_j0; j < band_j1; ++j) {
            for (int i = 0; i < grid.w; ++i) {
                const size_t k[4] = {grid.at(i, j), grid.at(i + 1, j), grid.at(i + 1, j + 1), grid.at(i, j + 1)};
                int64_t pi = grid.i0 + i, pj = grid.j0 + j;
                if (ts.direct[size_t(j * grid.w + i)]) {
                    if (whole) {
                        // The loop's sums, signed as the footprint runs (the ratio is not).
                        const double* e = &ts.edges.pixel[size_t(j * grid.w + i) * ts.edges.stride];
                        store_sums(job.out, pi, pj, e[0], e + 1, pixel_coverage(cv, job.out, pi, pj));
                        continue;
                    } else {
                        std::fill(sums.acc, sums.acc + sums.nch, 0.0);
                        sums.weight = 0.0;
                        pixel_polygon(grid, ts, i, j, sp.xs, sp.ys);
                        if (linear) {
                            linear(job.model, *sp.linear, grid.ref_cell, row0, period, sp.xs.data(),
                                   sp.ys.data(), int(sp.xs.size()), sums, sp.green, ts.density);
                        } else {
                            direct(job.model, grid.ref_cell, row0, period, sp.xs.data(),
                                   sp.ys.data(), int(sp.xs.size()), sums, sp.green, ts.density);
                        }
                    }
                } else {
                    std::fill(sums.acc, sums.acc + sums.nch, 0.0);
                    sums.weight = 0.0;
                    SourcePoint corners[4] = {grid.corner_point(k[0]), grid.corner_point(k[1]),
                                              grid.corner_point(k[2]), grid.corner_point(k[3])};
                    side_paths(grid, ts, i, j, usable);
                    slow_rect(sp, double(pi) * cv.scale_x, double(pj) * cv.scale_y,
                              double(pi + 1) * cv.scale_x, double(pj + 1) * cv.scale_y, corners,
                              ts.sides);
                }
                store_pixel(job.out, pi, pj, sums, pixel_coverage(cv, job.out, pi, pj));
            }
        }
        band_j0 = band_j1;
    }
}

// The output cell that holds the whole level-0 rectangle, or -1.
int64_t rect_cell(const Geometry& d, double x0, double y0, double x1, double y1) {
    Located a = locate(d, x0, y0), b = locate(d, std::nextafter(x1, x0), std::nextafter(y1, y0));
    return a.cell == b.cell ? a.cell : -1;
}

// True when the rectangle lies in its disk cell's valid disk (every pixel wholly valid).
bool inside_disk(const Geometry& d, int64_t cell, double x0, double y0, double x1, double y1) {
    double cx, cy, unit;
    cell_disk(d, cell, cx, cy, unit);
    double fx = std::max(std::fabs(x0 - cx), std::fabs(x1 - cx));
    double fy = std::max(std::fabs(y0 - cy), std::fabs(y1 - cy));
    return fx * fx + fy * fy <= unit * unit;
}

// True when a cone point of a folded source (area_map.h) lands inside the output box
// [x0, x1] x [y0, y1] of `cell` (more than a thousandth of a pixel from its edges). A tile
// with one on its outline does not wind around it; should its corners be placed in two copies
// about it, the grid's far-corner check fails and the tile goes pixel by pixel anyway.
bool cone_in_box(const AreaJob& job, int64_t cell, double x0, double y0, double x1, double y1) {
    const Conversion& cv = job.cv;
    const double slack = 1e-3 * std::max(cv.scale_x, cv.scale_y);
    for (int c = 0; c < job.sing.cones; ++c) {
        double x, y;
        if (!continued_point(cv.dst, cell, job.sing.cone_out[c], 0.5 * (x0 + x1), 0.5 * (y0 + y1), x, y))
            continue;
        if (x > x0 + slack && x < x1 - slack && y > y0 + slack && y < y1 - slack) return true;
    }
    return false;
}

// True when a lat-long source's pole lies within `reach` output pixels of the level-0
// rectangle of output cell `cell` (inside it, on it, or that near outside).
bool pole_near_box(const AreaJob& job, int64_t cell, double x0, double y0, double x1, double y1,
                   double reach) {
    const Conversion& cv = job.cv;
    if (job.sing.kind != 1) return false;
    const double slack = reach * std::max(cv.scale_x, cv.scale_y);
    for (int c = 0; c < job.sing.count; ++c) {
        double x, y;
        if (!continued_point(cv.dst, cell, job.sing.out[c], 0.5 * (x0 + x1), 0.5 * (y0 + y1), x, y))
            continue;
        if (x >= x0 - slack && x <= x1 + slack && y >= y0 - slack && y <= y1 + slack) return true;
    }
    return false;
}

// The end (exclusive) of the run of output pixels from pixel i (scale level-0 pixels each)
// that lie in the same row or column of cells (cell level-0 pixels each), at least i + 1.
int64_t cell_run_end(int64_t i, double scale, int64_t cell) {
    int64_t c = floor_index(double(i) * scale / double(cell));
    return std::max(i + 1, int64_t(std::floor(double(c + 1) * double(cell) / scale)));
}

// True when a tile's grid has no one chart because a lat-long pole lies inside or on it (its
// border winds around the pole), and the tile is large enough to split (split_tile).
bool split_at_pole(const AreaJob& job, const CornerGrid& grid, int64_t cell) {
    const Conversion& cv = job.cv;
    return !grid.usable && grid.ref_cell >= 0 && grid.w >= kPoleTile && grid.h >= kPoleTile &&
           pole_near_box(job, cell, double(grid.i0) * cv.scale_x, double(grid.j0) * cv.scale_y,
                         double(grid.i0 + grid.w) * cv.scale_x,
                         double(grid.j0 + grid.h) * cv.scale_y, 1e-3);
}

// A tile with a lat-long pole inside or on it (split_at_pole) as four quarters, each mapped
// afresh. A quarter within kPoleReach pixels of the pole splits again while it is at least
// kPoleTile pixels on each side, and then takes the general path whole; the others take the
// direct path as any tile does. So the general path (about fifty times a direct pixel's cost)
// takes the few pixels around a pole, not the whole tile's 1024: 4 % of the one shot
// (2048 x 1024 lat-long → cube-vcross 512). A smaller quarter would not do: a grid without
// inside corners cannot estimate how its edges bend, and passes as straight (measured: a 1-px
// tile beside a pole pixel lost three quarters of a sun's energy).
void split_tile(const AreaJob& job, SlowPath& sp, PixelSums& sums, CornerGrid& grid,
                TileScratch& ts, int64_t cell, int64_t i0, int64_t j0, int64_t i1, int64_t j1) {
    const Conversion& cv = job.cv;
    const int64_t im = (i0 + i1) / 2, jm = (j0 + j1) / 2;
    const int64_t is[3] = {i0, im, i1}, js[3] = {j0, jm, j1};
    for (int b = 0; b < 2; ++b) {
        for (int a = 0; a < 2; ++a) {
            const int64_t x0 = is[a], x1 = is[a + 1], y0 = js[b], y1 = js[b + 1];
            if (x1 <= x0 || y1 <= y0) continue;
            const bool near = pole_near_box(job, cell, double(x0) * cv.scale_x, double(y0) * cv.scale_y,
                                            double(x1) * cv.scale_x, double(y1) * cv.scale_y,
                                            kPoleReach);
            map_grid(cv, cell, x0, y0, int(x1 - x0), int(y1 - y0), grid);
            if (near && x1 - x0 >= 2 * kPoleTile && y1 - y0 >= 2 * kPoleTile) {
                split_tile(job, sp, sums, grid, ts, cell, x0, y0, x1, y1);
            } else {
                tile_pixels(job, sp, sums, grid, ts, cell, !near);
            }
        }
    }
}

// Output rows [j0, j1), all in one row of cells: tiles of up to kAreaTile x kAreaTile pixels,
// ending where a column of cells does, each inside one output cell through tile_pixels; a tile
// across cell edges (a pixel that straddles one) pixel by pixel.
void area_tiles(const AreaJob& job, int64_t j0, int64_t j1, SlowPath& sp, PixelSums& sums,
                CornerGrid& grid, TileScratch& ts) {
    const Conversion& cv = job.cv;
    const Geometry& d = cv.dst;
    const ResampleOutput& out = job.out;
    // The right column of the last tile mapped, for the next tile of the same cell.
    std::vector<SourcePoint>& shared = ts.column;
    int64_t shared_cell = -1, shared_i = -1;
    for (int64_t i0 = 0, i1; i0 < out.width; i0 = i1) {
        i1 = std::min({i0 + kAreaTile, out.width, cell_run_end(i0, cv.scale_x, d.cell_width())});
        double x0 = double(i0) * cv.scale_x, y0 = double(j0) * cv.scale_y;
        double x1 = double(i1) * cv.scale_x, y1 = double(j1) * cv.scale_y;
        if (!cv.fill && out.zeroed && tile_in_empty_cell(d, x0, y0, x1, y1)) continue;
        bool direct = direct_allowed.load(std::memory_order_relaxed);
        int64_t cell = direct ? rect_cell(d, x0, y0, x1, y1) : -1;
        bool regular = cell >= 0 && d.cell_face[cell] >= 0 && (!d.disk() || inside_disk(d, cell, x0, y0, x1, y1));
        // A tile around a folded source's cone point has no one chart: going around the
        // point flips the source's copy (four of them can add up to none, so the grid's own
        // check may pass). Every pixel of it takes the general path.
        regular = regular && !cone_in_box(job, cell, x0, y0, x1, y1);
        if (!regular) {
            slow_block(job, sp, sums, i0, j0, i1, j1);
            continue;
        }
        const bool after = shared_cell == cell && shared_i == i0;
        map_grid(cv, cell, i0, j0, int(i1 - i0), int(j1 - j0), grid, after ? shared.data() : nullptr);
        shared.resize(size_t(j1 - j0 + 1));
        for (int j = 0; j <= grid.h; ++j) shared[size_t(j)] = grid.exact[grid.at(grid.w, j)];
        shared_cell = cell;
        shared_i = i1;
        if (split_at_pole(job, grid, cell)) {
            split_tile(job, sp, sums, grid, ts, cell, i0, j0, i1, j1);
        } else {
            tile_pixels(job, sp, sums, grid, ts, cell, regular);
        }
    }
}

// Output rows [j0, j1): split where a row of cells ends (so that a band across a cell edge
// still has direct tiles), each part through area_tiles.
void area_rows(const AreaJob& job, int64_t j0, int64_t j1, SlowPath& sp, PixelSums& sums,
               CornerGrid& grid, TileScratch& ts) {
    const Conversion& cv = job.cv;
    for (int64_t a = j0, b; a < j1; a = b) {
        b = std::min(j1, cell_run_end(a, cv.scale_y, cv.dst.cell_height()));
        area_tiles(job, a, b, sp, sums, grid, ts);
    }
}

// Rows [j0, j1) of `out` with samples x samples sub-pixels each: the rows of sub-pixels
// integrated into a band buffer (a grid `samples` times finer, every sub-pixel exactly), then
// each pixel the solid-angle-weighted mean of its sub-pixels.
void sub_pixel_rows(const AreaJob& job, int64_t j0, int64_t j1, SlowPath& sp, PixelSums& sums,
                    CornerGrid& grid, TileScratch& ts, std::vector<float>& buffer,
                    std::vector<float>& weights) {
    const int64_t n = job.samples, nch = job.out.channels, width = job.out.width * n;
    Conversion fine = job.cv;
    fine.scale_x /= double(n);
    fine.scale_y /= double(n);
    buffer.assign(size_t((j1 - j0) * n * width * nch), 0.0f);
    weights.assign(size_t((j1 - j0) * n * width), 0.0f);
    ResampleOutput sub{buffer.data(), job.out.height * n, width, nch, nullptr, weights.data(), true};
    sub.row0 = j0 * n;
    SlowPath fine_sp(fine, sp.model, sp.sing);
    fine_sp.sums = &sums;
    fine_sp.linear = sp.linear;
    AreaJob fine_job{fine, job.model, job.sing, sub, 1, job.linear, job.valid_channel};
    area_rows(fine_job, j0 * n, j1 * n, fine_sp, sums, grid, ts);
    std::vector<double> acc(static_cast<size_t>(nch));  // any number of channels (a fixed 64 overran)
    for (int64_t j = j0; j < j1; ++j) {
        for (int64_t i = 0; i < job.out.width; ++i) {
            double w = 0.0;
            std::fill(acc.begin(), acc.end(), 0.0);
            for (int64_t b = 0; b < n; ++b) {
                for (int64_t a = 0; a < n; ++a) {
                    int64_t k = ((j - j0) * n + b) * width + i * n + a;
                    double wk = weights[size_t(k)];
                    w += wk;
                    for (int64_t c = 0; c < nch; ++c) acc[size_t(c)] += wk * double(buffer[size_t(k * nch + c)]);
                }
            }
            store_sums(job.out, i, j, w, acc.data(), pixel_coverage(job.cv, job.out, i, j));
        }
    }
}

}  // namespace

bool set_area_direct(bool allowed) { return direct_allowed.exchange(allowed); }

void resample_area(const Image& src, const Conversion& cv, int samples, const ResampleOutput& out,
                   int threads, int64_t* progress, bool linear, int valid_channel) {
    SourceModel model(src, cv.src);
    Singular sing = source_singular(cv);
    AreaJob job{cv, model, sing, out, samples, linear, valid_channel};
    int64_t bands = (out.height + kAreaTile - 1) / kAreaTile;
    // A band's corner grid, tile scratch (prefix table, edge memo, density cache) and slope
    // cache (2 MB) go back to a pool for the next band a thread takes, rather than being made
    // afresh for each of a conversion's bands: a fresh process faulted their pages in again and
    // again (the one shot's first call). The slopes cached stay valid: one model, one call.
    struct Scratch {
        CornerGrid grid;
        TileScratch ts;
        std::unique_ptr<SlopeCache> slopes;
    };
    std::vector<std::unique_ptr<Scratch>> idle;
    std::mutex idle_lock;
    parallel_for(bands, threads, [&](int64_t band) {
        std::unique_ptr<Scratch> scratch;
        {
            std::lock_guard<std::mutex> hold(idle_lock);
            if (!idle.empty()) {
                scratch = std::move(idle.back());
                idle.pop_back();
            }
        }
        if (!scratch) {
            scratch = std::make_unique<Scratch>();
            if (linear) scratch->slopes = std::make_unique<SlopeCache>(model, valid_channel);
        }
        SlowPath sp(cv, model, sing);
        sp.linear = scratch->slopes.get();
        std::vector<double> acc(size_t(out.channels));
        PixelSums sums{acc.data(), out.channels, 0.0};
        sp.sums = &sums;
        CornerGrid& grid = scratch->grid;
        TileScratch& ts = scratch->ts;
        int64_t j0 = band * kAreaTile, j1 = std::min(j0 + kAreaTile, out.height);
        if (samples > 1) {
            std::vector<float> buffer, weights;
            sub_pixel_rows(job, j0, j1, sp, sums, grid, ts, buffer, weights);
        } else {
            area_rows(job, j0, j1, sp, sums, grid, ts);
        }
        int64_t rows = std::min(kAreaTile, out.height - band * kAreaTile);
        if (progress) __atomic_add_fetch(progress, (rows + kTile - 1) / kTile, __ATOMIC_RELAXED);
        std::lock_guard<std::mutex> hold(idle_lock);
        idle.push_back(std::move(scratch));
    });
}

}  // namespace envconv
