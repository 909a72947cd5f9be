// The area filter's linear reconstruction, for conversions that magnify (envconv/resample/
// convert.py decides; the box of area.cpp everywhere else, its code untouched).
//
// Inside texel t, centre (cx, cy) in level-0 image pixels, the source is
// f = s_t + ax (x - cx) + ay (y - cy), the slopes (colour per texel) the central differences of
// its four neighbours, scaled down so that f stays within the range of the texel and those
// neighbours (conservative: no overshoot, no ringing next to a sun). A piece of t with area A
// and first moments Dx, Dy about the centre (texels^2, texels^3; green.h) holds the solid
// angle w = m A + gx Dx + gy Dy (the density model of area_source.h) and the colour
// s w + c (ax Dx + ay Dy), c the model's least density over the texel (slope_weight, sr per
// texel^2; c <= the density keeps the weighted value within the range above). The slope terms
// integrate to 0 over a whole texel, so every texel still hands out exactly s_t times its
// solid angle: a one-texel sun keeps its energy, a constant map stays constant.
//
// A neighbour past a cell's edge is the texel across the seam (a cube face's neighbour face, a
// folded square's fold, a lat-long's row past the pole). A texel keeps the box (slopes 0)
// wherever its stencil is not wholly data: a texel or neighbour in a partial view's pad, whose
// valid channel V (holes, partial-view pads) is below 1 or whose value is not finite, a
// tennisball texel the band boundary cuts (the other band reads the rest of it), and a texel
// that a fold of an octahedral square's density crosses. No hole value therefore leaks into
// held texels. A disk's texel that the rim cuts, or whose neighbour lies past it, takes
// one-sided slopes about the centroid of its part inside the disk (rim_texel; a neighbour the
// rim cuts is read: its value is its part's mean). Where the general path reads a texel in
// another's place (a folded square's continued grid past its edge), the slopes are turned into
// that grid when the two grids map onto each other by a reflection or quarter turn (exact), else
// that read takes none: the general path cuts footprints at cube seams, so such reads are
// slivers within its chord tolerance of the seam.
//
// The slopes, premultiplied by c, are made per texel on first use (SlopeCache), not as planes.
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "area_source.h"

namespace envconv {

// The density the slope terms are weighted by: the model's least value over the texel (0 if
// it goes negative). Any constant integrates the slopes to 0 over the whole texel.
inline double slope_weight(double m, double gx, double gy) {
    return std::max(0.0, m - 0.5 * (std::fabs(gx) + std::fabs(gy)));
}

namespace linear_detail {

// A limited slope is scaled a few float roundings short of its bound, so that the corners stay
// within range as they are computed, not only in exact arithmetic.
constexpr float kShrink = 1.0f - 8.0f * FLT_EPSILON;

// The limited slopes of one channel: s the texel, (l, r) its neighbours along x, (t, b) along y.
inline void limit(float s, float l, float r, float t, float b, float& ax, float& ay) {
    ax = 0.5f * (r - l);
    ay = 0.5f * (b - t);
    float hi = std::max(std::max(std::max(l, r), std::max(t, b)), s);
    float lo = std::min(std::min(std::min(l, r), std::min(t, b)), s);
    float room = std::min(hi - s, s - lo), d = 0.5f * (std::fabs(ax) + std::fabs(ay));
    float k = room < d ? room / d * kShrink : 1.0f;
    ax *= k;
    ay *= k;
}

// The limited slopes of one channel of a disk texel whose stencil lacks neighbours (null: past
// the rim) or that the rim cuts, its value held at the centroid (ox, oy) of its part inside the
// disk (texels from its centre): central differences where both neighbours are there, one-sided
// where one is, else 0, scaled so that the reconstruction stays within the range of the texel
// and its neighbours over the whole texel (|x - ox| <= 1/2 + |ox|).
inline void limit_rim(float s, const float* l, const float* r, const float* t, const float* b,
                      int64_t k, double ox, double oy, float& ax, float& ay) {
    ax = l && r ? 0.5f * (r[k] - l[k]) : r ? r[k] - s : l ? s - l[k] : 0.0f;
    ay = t && b ? 0.5f * (b[k] - t[k]) : b ? b[k] - s : t ? s - t[k] : 0.0f;
    float hi = s, lo = s;
    for (const float* n : {l, r, t, b}) {
        if (!n) continue;
        hi = std::max(hi, n[k]);
        lo = std::min(lo, n[k]);
    }
    const float room = std::min(hi - s, s - lo);
    const float d = std::fabs(ax) * float(0.5 + std::fabs(ox)) + std::fabs(ay) * float(0.5 + std::fabs(oy));
    const float q = room < d ? room / d * kShrink : 1.0f;
    ax *= q;
    ay *= q;
}

// The share of texel (ix, iy) inside the disk of the cell whose valid region starts at
// (x0, y0) (n texels across), and that part's centroid from the texel's centre (texels): the
// disk's chord clipped to the texel, integrated over 64 columns (centroid within 1e-4).
inline double disk_part(double n, int64_t x0, int64_t y0, int64_t ix, int64_t iy, double& ox,
                        double& oy) {
    const double c = 0.5 * n, top = double(iy - y0) - c, bottom = top + 1.0;
    double area = 0.0, mx = 0.0, my = 0.0;
    constexpr int kColumns = 64;
    for (int k = 0; k < kColumns; ++k) {
        const double u = (double(k) + 0.5) / kColumns, x = double(ix - x0) + u - c;
        const double half = std::sqrt(std::max(c * c - x * x, 0.0));
        const double y0c = std::max(-half, top), y1c = std::min(half, bottom);
        if (!(y1c > y0c)) continue;
        const double h = y1c - y0c;
        area += h;
        mx += h * (u - 0.5);
        my += h * (0.5 * (y0c + y1c) - top - 0.5);
    }
    if (!(area > 0.0)) return 0.0;
    ox = mx / area;
    oy = my / area;
    return area / kColumns;
}

// True when texel (ix, iy) of `cell` is wholly data for a stencil: in the cell's valid region
// (its columns modulo the width for a lat-long), for a disk wholly inside the disk, finite in
// every channel and, with a valid channel, V = 1. ix is wrapped in place.
inline bool whole_texel(const Image& img, const Geometry& g, int64_t cell, int64_t& ix,
                        int64_t iy, int valid_channel, bool cut = false) {
    const int64_t cw = g.cell_width(), ch = g.cell_height();
    const int64_t x0 = (cell % g.columns) * cw + g.guard, y0 = (cell / g.columns) * ch + g.guard;
    if (iy < y0 || iy >= y0 + g.n) return false;
    if (g.family == kLatlong && g.guard == 0) {
        const int64_t w = 2 * g.n;
        ix = ((ix % w) + w) % w;
    } else if (ix < x0 || ix >= x0 + g.nx) {
        return false;
    }
    if (g.disk() && !(cut && area_readable(g, cell, ix, iy))) {
        const double c = 0.5 * double(g.n);
        const double dx = std::max(std::fabs(double(ix - x0) - c), std::fabs(double(ix + 1 - x0) - c));
        const double dy = std::max(std::fabs(double(iy - y0) - c), std::fabs(double(iy + 1 - y0) - c));
        if (dx * dx + dy * dy > c * c) return false;
    }
    const float* v = img.texel(iy, ix);
    for (int64_t k = 0; k < img.channels; ++k)
        if (!std::isfinite(v[k])) return false;
    return valid_channel < 0 || v[valid_channel] >= 1.0f;
}

// True when every direction of texel (ix, iy) of tennisball band `cell` is the band's own
// (layouts.h: past |phi| = 90 deg a band owns only where |sin phi| cos theta >= sqrt(2)/2,
// least at the texel's largest |phi| and |theta|). The other band reads the rest of a texel
// the boundary cuts, so that its slope terms would not add up to 0 over the part read here.
inline bool tennisball_texel_owned(const Geometry& g, int64_t cell, int64_t ix, int64_t iy) {
    double a0, b0, a1, b1;
    cell_local(g, cell, double(ix), double(iy), a0, b0);
    cell_local(g, cell, double(ix + 1), double(iy + 1), a1, b1);
    const double phi = std::max(std::fabs(a0), std::fabs(a1)) * tennisball::kPhiHalf;
    const double theta = std::max(std::fabs(b0), std::fabs(b1)) * tennisball::kThetaHalf;
    return phi <= 0.5 * kPi || std::sin(phi) * std::cos(theta) > tennisball::kHalfSqrt2 + 1e-9;
}

// Neighbour (jx, jy) of a texel of `cell`, or null where the stencil may not read it: the
// texel itself where it is wholly data; past a cell's edge (a cube face's, a folded square's, a
// tennisball band's, a lat-long's pole rows) the texel across the seam (remap_tap: the one that
// holds its continued centre's direction) if that is wholly data; none inside the cell (a hole,
// V < 1, a value not finite), past a disk's rim or around a partial view.
inline const float* neighbour(const Image& img, const Geometry& g, int64_t cell, int64_t jx,
                              int64_t jy, int valid_channel) {
    int64_t x = jx;
    if (whole_texel(img, g, cell, x, jy, valid_channel, true)) return img.texel(jy, x);
    if (g.disk() || g.param[kReach] > 0.0) return nullptr;
    const int64_t x0 = (cell % g.columns) * g.cell_width() + g.guard;
    const int64_t y0 = (cell / g.columns) * g.cell_height() + g.guard;
    const bool wraps = g.family == kLatlong && g.guard == 0;
    if (jy >= y0 && jy < y0 + g.n && (wraps || (jx >= x0 && jx < x0 + g.nx))) return nullptr;
    int64_t kx, ky;
    remap_tap(g, cell, jx, jy, kx, ky);
    const int64_t other = (ky / g.cell_height()) * g.columns + kx / g.cell_width();
    if (g.cell_face[other] < 0 || !whole_texel(img, g, other, kx, ky, valid_channel)) return nullptr;
    return img.texel(ky, kx);
}

// The slopes of a disk's texel (ix, iy) of `cell` that the rim cuts or whose stencil reaches
// past it: its value held at the centroid of its part inside the disk, so that the slope terms
// add up to 0 over that part (the part the cell's footprints read: the rest of the texel lies
// in the other cell's or past the rim), the centroid's term k = -(c ax ox + c ay oy) per unit
// area into z.
inline void rim_texel(const SourceModel& model, int64_t cell, int64_t ix, int64_t iy,
                      int valid_channel, float* x, float* y, float* z) {
    const Image& img = model.image;
    const Geometry& g = model.g;
    int64_t sx = ix;
    if (!whole_texel(img, g, cell, sx, iy, valid_channel, true)) return;
    const int64_t x0 = (cell % g.columns) * g.cell_width() + g.guard;
    const int64_t y0 = (cell / g.columns) * g.cell_height() + g.guard;
    double ox = 0.0, oy = 0.0;
    // A sliver (under a tenth of the texel) keeps the box: its centroid is far off-centre.
    if (disk_part(double(g.n), x0, y0, ix, iy, ox, oy) < 0.1) return;
    const float* nb[4];
    const int64_t dx[4] = {-1, 1, 0, 0}, dy[4] = {0, 0, -1, 1};
    for (int k = 0; k < 4; ++k) nb[k] = neighbour(img, g, cell, ix + dx[k], iy + dy[k], valid_channel);
    TexelDensity t = model.texel(cell, ix, iy);
    const double c = slope_weight(t.m, t.gx, t.gy);
    const float* s = img.texel(iy, ix);
    for (int64_t k = 0; k < img.channels; ++k) {
        float ax, ay;
        limit_rim(s[k], nb[0], nb[1], nb[2], nb[3], k, ox, oy, ax, ay);
        const double cx = c * double(ax), cy = c * double(ay), cz = -(cx * ox + cy * oy);
        const bool ok = std::isfinite(cx) && std::isfinite(cy) && std::isfinite(cz);
        x[k] = ok ? float(cx) : 0.0f;
        y[k] = ok ? float(cy) : 0.0f;
        z[k] = ok ? float(cz) : 0.0f;
    }
}

// The slopes of texel (ix, iy) of `cell`, times c, into x, y (nch each; left as they are, 0,
// where it keeps the box); a disk's texel at its rim through rim_texel, which also sets z.
inline void texel(const SourceModel& model, int64_t cell, int64_t ix, int64_t iy,
                  int valid_channel, float* x, float* y, float* z) {
    const Image& img = model.image;
    const Geometry& g = model.g;
    const int64_t dx[4] = {-1, 1, 0, 0}, dy[4] = {0, 0, -1, 1};
    const float* nb[4];
    int64_t sx = ix;
    if (g.disk()) {
        bool whole = whole_texel(img, g, cell, sx, iy, valid_channel);
        for (int k = 0; k < 4 && whole; ++k) {
            int64_t jx = ix + dx[k];
            whole = whole_texel(img, g, cell, jx, iy + dy[k], valid_channel);
        }
        if (!whole) {
            rim_texel(model, cell, ix, iy, valid_channel, x, y, z);
            return;
        }
    }
    if (!whole_texel(img, g, cell, sx, iy, valid_channel)) return;
    for (int k = 0; k < 4; ++k) {
        nb[k] = neighbour(img, g, cell, ix + dx[k], iy + dy[k], valid_channel);
        if (!nb[k]) return;
    }
    if (g.family == kTennisball && !tennisball_texel_owned(g, cell, ix, iy)) return;
    TexelDensity t = model.texel(cell, ix, iy);
    if (t.gx == kKinked) return;
    const double c = slope_weight(t.m, t.gx, t.gy);
    const float* s = img.texel(iy, ix);
    for (int64_t k = 0; k < img.channels; ++k) {
        float ax, ay;
        limit(s[k], nb[0][k], nb[1][k], nb[2][k], nb[3][k], ax, ay);
        const float cx = float(c * double(ax)), cy = float(c * double(ay));
        const bool ok = std::isfinite(cx) && std::isfinite(cy);
        x[k] = ok ? cx : 0.0f;
        y[k] = ok ? cy : 0.0f;
    }
}

}  // namespace linear_detail

// The slopes of the texels a band of output rows reads, each computed on its first use and
// kept in a direct-mapped table (one per thread: a magnified band reads a few hundred texels,
// each many times). No slope plane as large as the image is ever made: the peak memory of a
// magnifying conversion stays that of the box (docs/memory.md's bound, 1.25 x the arrays).
class SlopeCache {
  public:
    SlopeCache(const SourceModel& model, int valid_channel)
        : model_(model), valid_(valid_channel), nch_(model.image.channels) {
        // At most 2 MB a thread, at most 4096 texels (a magnified 32 x 32 tile reads a few hundred).
        const size_t bytes = size_t(8 + 12 * nch_);
        size_t entries = 64;
        while (entries < 4096 && 2 * entries * bytes <= (size_t(2) << 20)) entries *= 2;
        bits_ = 0;
        while ((size_t(1) << bits_) < entries) ++bits_;
        key_.assign(entries, -1);
        val_.resize(entries * size_t(3 * nch_));
        partial_ = model.g.param[kReach] > 0.0 && valid_channel < 0;
    }

    // c ax (nch values), then c ay, then k (nch values each) of the image's texel (ix, iy), all
    // 0 where it keeps the box (sr x colour per texel^3; k per texel^2: a disk's rim texel's
    // centroid term, 0 elsewhere).
    const float* get(int64_t ix, int64_t iy) {
        const Image& img = model_.image;
        const int64_t index = iy * img.width + ix;
        const size_t slot = size_t((uint64_t(index) * 0x9E3779B97F4A7C15ull) >> (64 - bits_));
        float* v = val_.data() + slot * size_t(3 * nch_);
        if (key_[slot] == index) return v;
        key_[slot] = index;
        std::fill(v, v + 3 * nch_, 0.0f);
        // A partial view's pad holds colour x V: without V no texel can be told wholly data.
        if (partial_) return v;
        const Geometry& g = model_.g;
        const int64_t cell = (iy / g.cell_height()) * g.columns + ix / g.cell_width();
        if (g.cell_face[cell] >= 0)
            linear_detail::texel(model_, cell, ix, iy, valid_, v, v + nch_, v + 2 * nch_);
        return v;
    }

  private:
    const SourceModel& model_;
    int valid_;
    int64_t nch_;
    int bits_ = 0;
    bool partial_ = false;
    std::vector<int64_t> key_;
    std::vector<float> val_;
};

// For texel (ix, iy) of `cell`'s continued grid, read in another's place (the texel at
// `offset` texels into the image): true when the two grids map onto each other by a
// reflection or a quarter turn around it (the folds of the octahedral and equal-area squares),
// turn then the read texel's grid steps of a step in x and in y; false elsewhere.
inline bool grid_turn(const Geometry& g, int64_t width, int64_t cell, int64_t ix, int64_t iy,
                      int64_t offset, int* turn) {
    // The centre and a quarter texel along x and y: inside the texel, clear of the fold.
    const double px[3] = {double(ix) + 0.5, double(ix) + 0.75, double(ix) + 0.5};
    const double py[3] = {double(iy) + 0.5, double(iy) + 0.5, double(iy) + 0.75};
    ImagePoint q[3];
    for (int k = 0; k < 3; ++k) {
        double a, b;
        cell_local(g, cell, px[k], py[k], a, b);
        Vec3 d = face_to_dir(g, g.cell_face[cell], a, b);
        FacePoint f = dir_to_face(g, d.x, d.y, d.z);
        q[k] = face_to_image(g, f.face, f.a, f.b);
        if (q[k].cell != q[0].cell) return false;
    }
    if (floor_index(q[0].x) != offset % width || floor_index(q[0].y) != offset / width) return false;
    const double j[4] = {4.0 * (q[1].x - q[0].x), 4.0 * (q[1].y - q[0].y), 4.0 * (q[2].x - q[0].x),
                         4.0 * (q[2].y - q[0].y)};
    for (int k = 0; k < 4; ++k) {
        turn[k] = int(std::lround(j[k]));
        if (std::fabs(j[k] - turn[k]) > 1e-6 || std::abs(turn[k]) > 1) return false;
    }
    return std::abs(turn[0]) + std::abs(turn[1]) == 1 && std::abs(turn[2]) + std::abs(turn[3]) == 1;
}

}  // namespace envconv
