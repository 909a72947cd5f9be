// The source side of the area filter: points in a source cell's continued coordinates, the
// solid angle a texel's piece holds, and the texel a piece reads.
//
// A source point is (cell, x, y): level-0 image pixels of `cell`'s grid, continued past its
// edges (cells.h). A polygon is integrated in one cell's coordinates, so every vertex of it is
// first expressed there (continued_point): lat-long and tennisball columns unwrap to the
// vertex nearest a reference, octahedral squares unfold across their folds, cube faces extend
// their planes, paraboloid halves their formulas.
//
// Solid angle: texel t holds the density model rho_t(x, y) = m + gx (x - cx) + gy (y - cy)
// (sr per square level-0 pixel, cx, cy its centre), so a piece of t with area A and first
// moments Dx, Dy about the centre holds m A + gx Dx + gy Dy. The linear term integrates to 0
// over the whole texel, so the pieces of a texel always add up to m, the texel's mean density
// (exact for lat-long and tennisball rows, sphere and equal-area; within O(h^4) elsewhere),
// however the texel is cut: the area filter hands every texel's solid angle out exactly once.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "green.h"
#include "taps.h"

namespace envconv {

struct SourcePoint {
    double x, y;
    int64_t cell;
};

struct TexelDensity {
    double m, gx, gy;
};

// The slope gx of a texel whose density model is per part (SourceModel::weight).
constexpr double kKinked = std::numeric_limits<double>::infinity();

// Continued (a, b) of direction d on cube face `face` (GL, EXR or equi-angular family: the
// face plane's coordinates, which eac then takes to its angles, continued past the face as
// layouts.h continues it), false when d is not in front of the face's plane.
inline bool cube_face_coords(int family, int face, const Vec3& d, double& a, double& b) {
    const double tiny = 1e-9;
    double cx = family == kCubeGL ? -d.x : d.x, cy = d.y, cz = d.z;
    double s;
    if (family == kCubeGL) {
        switch (face) {
            case 0: s = cx; a = -cz; b = -cy; break;
            case 1: s = -cx; a = cz; b = -cy; break;
            case 2: s = cy; a = cx; b = cz; break;
            case 3: s = -cy; a = cx; b = -cz; break;
            case 4: s = cz; a = cx; b = -cy; break;
            default: s = -cz; a = -cx; b = -cy; break;
        }
    } else if (family == kEac) {  // the faces of views.h's eac table
        switch (face) {
            case 0: s = cx; a = cz; b = -cy; break;
            case 1: s = cz; a = -cx; b = -cy; break;
            case 2: s = -cx; a = -cz; b = -cy; break;
            case 3: s = -cy; a = -cz; b = cx; break;
            case 4: s = -cz; a = cy; b = cx; break;
            default: s = cy; a = cz; b = cx; break;
        }
    } else {
        switch (face) {
            case 0: s = cx; a = cz; b = -cy; break;
            case 1: s = -cx; a = -cz; b = -cy; break;
            case 2: s = cy; a = cx; b = -cz; break;
            case 3: s = -cy; a = cx; b = cz; break;
            case 4: s = cz; a = -cx; b = -cy; break;
            default: s = -cz; a = cx; b = -cy; break;
        }
    }
    if (!(s > tiny)) return false;
    a /= s;
    b /= s;
    if (family == kEac) {  // eac::plane inverted
        auto angle = [](double p) {
            return std::fabs(p) <= 1.0 ? (4.0 / kPi) * std::atan(p)
                                       : std::copysign(1.0 + (std::fabs(p) - 1.0) * (2.0 / kPi), p);
        };
        a = angle(a);
        b = angle(b);
    }
    return true;
}

// (a, b) of the unfolded octahedral square nearest (ref_a, ref_b) among the images of the
// square point (a, b): itself, its mirror across each edge and its translates across each
// corner (layouts.h, octa::fold, inverted).
inline void unfold_nearest(double& a, double& b, double ref_a, double ref_b) {
    const double cand[9][2] = {{a, b},           {2.0 - a, -b},     {-2.0 - a, -b},
                               {-a, 2.0 - b},    {-a, -2.0 - b},    {a + 2.0, b + 2.0},
                               {a - 2.0, b + 2.0}, {a + 2.0, b - 2.0}, {a - 2.0, b - 2.0}};
    double best = 1e300;
    int pick = 0;
    for (int k = 0; k < 9; ++k) {
        double da = cand[k][0] - ref_a, db = cand[k][1] - ref_b;
        double d2 = da * da + db * db;
        if (d2 < best) {
            best = d2;
            pick = k;
        }
    }
    a = cand[pick][0];
    b = cand[pick][1];
}

// Continued coordinates (x, y) in `cell` of direction d, the image nearest (ref_x, ref_y)
// where a layout repeats (lat-long and tennisball columns, octahedral folds); false when d has
// none (behind a cube face's plane, the far pole of a paraboloid half).
inline bool continued_point(const Geometry& g, int64_t cell, const Vec3& d, double ref_x,
                            double ref_y, double& x, double& y) {
    int face = g.cell_face[cell];
    double a, b;
    switch (g.family) {
        case kCubeGL:
        case kCubeExr:
        case kEac:
            if (!cube_face_coords(g.family, face, d, a, b)) return false;
            break;
        case kParaboloid: {
            double den = face == 0 ? 1.0 + d.z : 1.0 - d.z;
            if (!(den > 1e-9)) return false;
            a = d.x / den;
            b = -d.y / den;
            break;
        }
        case kTennisball: {
            double theta, phi;
            if (face == 0) {
                theta = std::asin(std::min(1.0, std::max(-1.0, d.y)));
                phi = std::atan2(d.x, d.z);
            } else {
                theta = std::asin(std::min(1.0, std::max(-1.0, d.x)));
                phi = std::atan2(d.y, -d.z);
            }
            a = -phi / tennisball::kPhiHalf;
            b = -theta / tennisball::kThetaHalf;
            break;
        }
        default: {
            FacePoint f = dir_to_face(g, d.x, d.y, d.z);
            a = f.a;
            b = f.b;
        }
    }
    if (g.family == kOctahedral || g.family == kEqualArea) {
        double ra, rb;
        cell_local(g, cell, ref_x, ref_y, ra, rb);
        unfold_nearest(a, b, ra, rb);
    }
    ImagePoint p = face_to_image(g, face, a, b);
    x = p.x;
    y = p.y;
    // Lat-long (period 2N) and tennisball (period 4N, 2 pi of phi) columns repeat.
    if (g.family == kLatlong || g.family == kTennisball) {
        double period = double(g.family == kLatlong ? 2 * g.n : 4 * g.n);
        x += period * std::nearbyint((ref_x - x) / period);
    }
    return true;
}

// The solid-angle density a source texel integrates (layouts.h's, continued without the
// absolute values past a rim, so that it stays smooth across it), sr per unit (a, b) area.
inline double area_density(const Chart& c, double a, double b) {
    switch (c.family) {
        case kSphere: return 4.0;
        case kAngular: {
            double r = std::sqrt(a * a + b * b);
            return r < 1e-9 ? kPi * kPi : kPi * std::sin(kPi * r) / r;
        }
        case kEqualArea: return kPi;
        case kFisheye: {
            double r = std::sqrt(a * a + b * b), h = c.param[kScaleX];
            return r < 1e-9 ? h * h : h * std::sin(h * r) / r;
        }
        default: return density(c, 0, a, b);
    }
}

// What the area filter needs of a source layout: its geometry, the exact per-row solid angles
// of lat-long and tennisball rows, and what a texel holds.
// A lat-long or tennisball row whose density changes by less than this share of itself across
// half a texel holds a flat density model: its pieces need no first moments, and a pixel's
// solid angle is off by at most about a tenth of it (the moments of a pixel's pieces about
// their texels' centres nearly cancel).
constexpr double kFlatRow = 2.5e-3;

struct SourceModel {
    const Image& image;
    const Geometry& g;
    std::vector<double> row_m, row_g;  // lat-long / tennisball: per image row
    double area;                       // (a, b) area of one texel

    uint64_t id;                       // unique per model (cached_parts)

    SourceModel(const Image& image_, const Geometry& g_) : image(image_), g(g_) {
        static std::atomic<uint64_t> next_id{1};
        id = next_id.fetch_add(1, std::memory_order_relaxed);
        area = (2.0 / double(g.nx)) * (2.0 / double(g.n));
        if (g.family == kLatlong || g.family == kTennisball) fill_rows();
    }

    // Exact solid angle per texel of every row (its band's rows for tennisball, the same in
    // both bands), and the derivative of the density per pixel down the row's centre, or 0
    // where the density changes by less than kFlatRow of itself across half a texel (the model
    // is then flat: every piece of such a row, in every pixel, holds m times its area).
    void fill_rows() {
        int64_t ch = g.cell_height();
        row_m.resize(size_t(ch));
        row_g.resize(size_t(ch));
        bool band = g.family == kTennisball;
        double half = band ? tennisball::kThetaHalf : 0.5 * kPi;       // latitude of b = -1
        double dlon = band ? 1.5 * kPi / double(g.nx) : kPi / double(g.n);
        double dlat = 2.0 * half / double(g.n);                         // per pixel
        for (int64_t r = 0; r < ch; ++r) {
            double top = half - dlat * double(r - g.guard);
            double bottom = top - dlat, mid = top - 0.5 * dlat;
            row_m[size_t(r)] = std::fabs(dlon * (std::sin(top) - std::sin(bottom)));
            double g = dlon * std::sin(mid) * dlat * dlat * (std::cos(mid) < 0 ? -1 : 1);
            row_g[size_t(r)] = std::fabs(0.5 * g) < kFlatRow * row_m[size_t(r)] ? 0.0 : g;
        }
    }

    // The density model of texel (ix, iy) of `cell`'s continued grid (the texel's own cell
    // coordinates, before any wrap).
    TexelDensity texel(int64_t cell, int64_t ix, int64_t iy) const {
        int64_t ch = g.cell_height();
        if (!row_m.empty()) {
            int64_t r = iy - (cell / g.columns) * ch;
            if (r >= 0 && r < ch) return {row_m[size_t(r)], 0.0, row_g[size_t(r)]};
        }
        return generic(cell, ix, iy);
    }

    // 2 x 2 Gauss-Legendre points of the texel: their mean and the mean slope across them. A
    // texel of an octahedral square that a kink of its density crosses holds a model per part
    // (weight): this one is its mean and gx = kKinked, which tells a caller to ask weight().
    TexelDensity generic(int64_t cell, int64_t ix, int64_t iy) const {
        if (g.family == kOctahedral && octahedral_kink(cell, ix, iy))
            return {weight(cell, ix, iy, 1.0, 0.0, 0.0), kKinked, 0.0};
        const double off = 0.5 / std::sqrt(3.0);
        double v[2][2];
        for (int q = 0; q < 4; ++q) {
            double a, b;
            cell_local(g, cell, double(ix) + 0.5 + (q & 1 ? off : -off),
                       double(iy) + 0.5 + (q & 2 ? off : -off), a, b);
            v[q >> 1][q & 1] = area_density(g, a, b);
        }
        double m = 0.25 * (v[0][0] + v[0][1] + v[1][0] + v[1][1]);
        double gx = 0.5 * (v[0][1] + v[1][1] - v[0][0] - v[1][0]) / (2.0 * off);
        double gy = 0.5 * (v[1][0] + v[1][1] - v[0][0] - v[0][1]) / (2.0 * off);
        return {m * area, gx * area, gy * area};
    }

    // The octahedral density is smooth on each octant's face and kinks where the faces meet:
    // along the square's axes and edges, the diamond |a| + |b| = 1, and their images past the
    // edges (the fold maps lines a, b = integer and a +- b = odd integer onto themselves). A 2 x
    // 2 Gauss model across a kink misses the texel's solid angle by up to 0.7 % (N = 24).
    // Lines that cross texel (ix, iy) strictly inside: (family, value) pairs, family 0: a,
    // 1: b, 2: a + b, 3: a - b; returns their count (at most 8).
    int kink_lines(int64_t cell, int64_t ix, int64_t iy, int* family, double* value) const {
        double lo[4] = {1e300, 1e300, 1e300, 1e300}, hi[4] = {-1e300, -1e300, -1e300, -1e300};
        for (int q = 0; q < 4; ++q) {
            double a, b;
            cell_local(g, cell, double(ix + (q & 1)), double(iy + (q >> 1)), a, b);
            const double v[4] = {a, b, a + b, a - b};
            for (int f = 0; f < 4; ++f) {
                lo[f] = std::min(lo[f], v[f]);
                hi[f] = std::max(hi[f], v[f]);
            }
        }
        int count = 0;
        for (int f = 0; f < 4; ++f) {
            const double eps = 1e-12 * (1.0 + std::fabs(hi[f]));
            for (double k = std::floor(lo[f]) ; k <= hi[f] && count < 8; k += 1.0) {
                const bool odd = std::fmod(std::fabs(k), 2.0) == 1.0;
                if (k > lo[f] + eps && k < hi[f] - eps && (f < 2 || odd)) {
                    family[count] = f;
                    value[count++] = k;
                }
            }
        }
        return count;
    }


    // One convex part of a kinked texel (pixel coordinates) and its density model: mean m
    // over the part, slopes gx, gy about its centroid (cx, cy) (the least-squares plane).
    struct KinkPart {
        int n;
        double x[12], y[12];
        double m, gx, gy, cx, cy;
    };

    // kink_lines(...) > 0, cheaply. In pixels (u, v) from the square's corner, the lines are
    // u, v in (N/2) Z and u +- v in (N/2) (2Z + 1): texel (i, j) is crossed by u = L inside iff
    // 2L = 2i + 1 (so N odd), by u + v = L iff 2L is one of 2(i + j) + 1 ... 3, by u - v = L
    // iff 2L is one of 2(i - j) - 1 ... 1 (integers, so no rounding).
    bool octahedral_kink(int64_t cell, int64_t ix, int64_t iy) const {
        if (g.cell_turns[cell] == 0 && g.nx == g.n) {
            const int64_t n = g.n;
            const int64_t i = ix - (cell % g.columns) * g.cell_width() - g.guard;
            const int64_t j = iy - (cell / g.columns) * g.cell_height() - g.guard;
            auto line = [n](int64_t twice) { return twice % n == 0; };  // 2L = m N
            auto odd_line = [n](int64_t twice) { return twice % n == 0 && (twice / n) % 2 != 0; };
            if (line(2 * i + 1) || line(2 * j + 1)) return true;
            const int64_t s2 = 2 * (i + j), d2 = 2 * (i - j);
            for (int64_t t = 1; t <= 3; ++t)
                if (odd_line(s2 + t)) return true;
            for (int64_t t = -1; t <= 1; ++t)
                if (odd_line(d2 + t)) return true;
            return false;
        }
        return float_kink(cell, ix, iy);
    }

    bool float_kink(int64_t cell, int64_t ix, int64_t iy) const {
        double a0, b0, a1, b1;
        cell_local(g, cell, double(ix), double(iy), a0, b0);
        cell_local(g, cell, double(ix + 1), double(iy + 1), a1, b1);
        if (a1 < a0) std::swap(a0, a1);
        if (b1 < b0) std::swap(b0, b1);
        auto crosses = [](double lo, double hi) {  // an integer strictly inside (lo, hi)
            double k = std::floor(lo) + 1.0;
            return k < hi;
        };
        auto crosses_odd = [](double lo, double hi) {  // an odd integer strictly inside
            double k = 2.0 * std::floor(0.5 * (lo + 1.0)) + 1.0;  // the first odd >= lo
            if (!(k > lo)) k += 2.0;
            return k < hi;
        };
        return crosses(a0, a1) || crosses(b0, b1) || crosses_odd(a0 + b0, a1 + b1) ||
               crosses_odd(a0 - b1, a1 - b0);
    }

    // The parts of a kinked texel, cached per thread for the last few texels (the pieces of
    // a texel come together).
    int cached_parts(int64_t cell, int64_t ix, int64_t iy, const KinkPart*& parts) const {
        struct Entry {
            uint64_t model;
            int64_t cell, ix, iy;
            int count;
            KinkPart parts[8];
        };
        thread_local Entry cache[16];
        Entry& e = cache[size_t((ix * 7 + iy * 13) & 15)];
        if (e.model != id || e.cell != cell || e.ix != ix || e.iy != iy || e.count == 0) {
            e.model = id;
            e.cell = cell;
            e.ix = ix;
            e.iy = iy;
            e.count = kink_parts(cell, ix, iy, e.parts, 8);
        }
        parts = e.parts;
        return e.count;
    }

    // Texel (ix, iy) cut along every kink line that crosses it into convex parts, each with its
    // own density model: mass, centroid and the least-squares plane of the density over the
    // part, integrated by the degree-4 six-point rule on the triangles of its fan. A piece of
    // the texel that lies in one part (split_at_kinks cuts footprints along the same lines)
    // holds its part's model; the pieces of a part add up to its mass, and the parts to the
    // texel's solid angle.
    int kink_parts(int64_t cell, int64_t ix, int64_t iy, KinkPart* parts, int max_parts) const {
        int family[8];
        double value[8];
        const int lines = kink_lines(cell, ix, iy, family, value);
        auto line_value = [&](int f, double x, double y) {
            double a, b;
            cell_local(g, cell, x, y, a, b);
            return f == 0 ? a : f == 1 ? b : f == 2 ? a + b : a - b;
        };
        const double x0 = double(ix), y0 = double(iy);
        int count = 1;
        parts[0].n = 4;
        const double sx[4] = {x0, x0 + 1.0, x0 + 1.0, x0}, sy[4] = {y0, y0, y0 + 1.0, y0 + 1.0};
        for (int k = 0; k < 4; ++k) {
            parts[0].x[k] = sx[k];
            parts[0].y[k] = sy[k];
        }
        for (int l = 0; l < lines; ++l) {
            const int before = count;
            for (int i = 0; i < before; ++i) {
                KinkPart p = parts[i];
                for (int side = 0; side < 2; ++side) {
                    KinkPart q;
                    q.n = 0;
                    const double sg = side == 0 ? 1.0 : -1.0;
                    for (int k = 0; k < p.n; ++k) {
                        int m = (k + 1) % p.n;
                        double fk = sg * (line_value(family[l], p.x[k], p.y[k]) - value[l]);
                        double fm = sg * (line_value(family[l], p.x[m], p.y[m]) - value[l]);
                        if (fk >= 0.0 && q.n < 12) {
                            q.x[q.n] = p.x[k];
                            q.y[q.n++] = p.y[k];
                        }
                        if (((fk > 0.0 && fm < 0.0) || (fk < 0.0 && fm > 0.0)) && q.n < 12) {
                            double t = fk / (fk - fm);
                            q.x[q.n] = p.x[k] + t * (p.x[m] - p.x[k]);
                            q.y[q.n++] = p.y[k] + t * (p.y[m] - p.y[k]);
                        }
                    }
                    if (q.n < 3) continue;
                    if (side == 0) parts[i] = q;
                    else if (count < max_parts) parts[count++] = q;
                }
            }
        }
        // Dunavant's degree-4 rule: barycentric points and weights.
        const double pa = 0.445948490915965, pb = 0.108103018168070, qa = 0.091576213509771,
                     qb = 0.816847572980459, wa = 0.223381589678011, wb = 0.109951743655322;
        const double pts[6][3] = {{pb, pa, pa}, {pa, pb, pa}, {pa, pa, pb},
                                  {qb, qa, qa}, {qa, qb, qa}, {qa, qa, qb}};
        const double wts[6] = {wa, wa, wa, wb, wb, wb};
        for (int i = 0; i < count; ++i) {
            KinkPart& p = parts[i];
            // Area and centroid (exact), then the density's mass, first moments about the
            // centroid and the part's second moments.
            double area_p = 0.0, mx = 0.0, my = 0.0;
            for (int k = 1; k + 1 < p.n; ++k) {
                double t = 0.5 * ((p.x[k] - p.x[0]) * (p.y[k + 1] - p.y[0]) -
                                  (p.x[k + 1] - p.x[0]) * (p.y[k] - p.y[0]));
                area_p += t;
                mx += t * (p.x[0] + p.x[k] + p.x[k + 1]) / 3.0;
                my += t * (p.y[0] + p.y[k] + p.y[k + 1]) / 3.0;
            }
            p.cx = mx / area_p;
            p.cy = my / area_p;
            double mass = 0.0, fx = 0.0, fy = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0;
            for (int k = 1; k + 1 < p.n; ++k) {
                const double tx[3] = {p.x[0], p.x[k], p.x[k + 1]}, ty[3] = {p.y[0], p.y[k], p.y[k + 1]};
                double tri = 0.5 * std::fabs((tx[1] - tx[0]) * (ty[2] - ty[0]) - (tx[2] - tx[0]) * (ty[1] - ty[0]));
                for (int q = 0; q < 6; ++q) {
                    double x = pts[q][0] * tx[0] + pts[q][1] * tx[1] + pts[q][2] * tx[2];
                    double y = pts[q][0] * ty[0] + pts[q][1] * ty[1] + pts[q][2] * ty[2];
                    double a, b;
                    cell_local(g, cell, x, y, a, b);
                    double w = wts[q] * tri, rho = area_density(g, a, b);
                    double ux = x - p.cx, uy = y - p.cy;
                    mass += w * rho;
                    fx += w * rho * ux;
                    fy += w * rho * uy;
                    sxx += w * ux * ux;
                    sxy += w * ux * uy;
                    syy += w * uy * uy;
                }
            }
            double det = sxx * syy - sxy * sxy;
            p.m = mass / std::fabs(area_p);
            p.gx = det > 0.0 ? (syy * fx - sxy * fy) / det : 0.0;
            p.gy = det > 0.0 ? (sxx * fy - sxy * fx) / det : 0.0;
        }
        return count;
    }

    // The solid angle a piece of texel (ix, iy) holds: its area A and first moments Dx, Dy
    // about the texel's centre (signed alike), through the texel's density model (a kinked
    // texel's: the model of the part that holds the piece's centroid).
    double weight(int64_t cell, int64_t ix, int64_t iy, double a, double dx, double dy) const {
        if (g.family == kOctahedral && octahedral_kink(cell, ix, iy)) {
            const KinkPart* parts;
            const int count = cached_parts(cell, ix, iy, parts);
            if (a == 0.0) return 0.0;
            if (a == 1.0 && dx == 0.0 && dy == 0.0) {  // the whole texel (generic)
                double total = 0.0;
                for (int i = 0; i < count; ++i) {
                    const KinkPart& p = parts[i];
                    double part_area = 0.0;
                    for (int k = 0; k < p.n; ++k) {
                        int m = (k + 1) % p.n;
                        part_area += 0.5 * (p.x[k] * p.y[m] - p.x[m] * p.y[k]);
                    }
                    total += p.m * std::fabs(part_area);
                }
                return area * total;
            }
            const double px = double(ix) + 0.5 + dx / a, py = double(iy) + 0.5 + dy / a;
            int pick = 0;
            double best = 1e300;
            for (int i = 0; i < count; ++i) {
                // Outside distance to the convex part (0 inside).
                double out = 0.0;
                const KinkPart& p = parts[i];
                for (int k = 0; k < p.n; ++k) {
                    int m = (k + 1) % p.n;
                    double ex = p.x[m] - p.x[k], ey = p.y[m] - p.y[k];
                    double len = std::hypot(ex, ey);
                    if (len > 0.0) out = std::max(out, ((px - p.x[k]) * ey - (py - p.y[k]) * ex) / len);
                }
                if (out < best) {
                    best = out;
                    pick = i;
                }
            }
            const KinkPart& p = parts[pick];
            const double ox = double(ix) + 0.5 - p.cx, oy = double(iy) + 0.5 - p.cy;
            return area * (p.m * a + p.gx * (dx + ox * a) + p.gy * (dy + oy * a));
        }
        TexelDensity t = texel(cell, ix, iy);
        return t.m * a + t.gx * dx + t.gy * dy;
    }
};

// Integrate the closed polygon (xs, ys) of source cell `cell` through part(xs, ys, n): for an
// octahedral source, cut first along every kink line of its density that crosses the
// polygon's box (SourceModel::kink_lines), so that each piece of a kinked texel lies in one of
// its parts; `scratch` holds the cut polygons. Cutting a polygon along lines keeps its union:
// the footprints still tile the source.
template <class Part>
void split_at_kinks(const Geometry& g, int64_t cell, const double* xs, const double* ys, int n,
                    std::vector<std::vector<double>>& scratch, Part&& part) {
    if (g.family != kOctahedral) {
        part(xs, ys, n);
        return;
    }
    // The lines that cross the polygon's box (a superset: a line that misses the polygon
    // leaves one side empty).
    double xmin, xmax, ymin, ymax;
    polygon_box(xs, ys, n, xmin, xmax, ymin, ymax);
    double lo[4] = {1e300, 1e300, 1e300, 1e300}, hi[4] = {-1e300, -1e300, -1e300, -1e300};
    for (int q = 0; q < 4; ++q) {
        double a, b;
        cell_local(g, cell, q & 1 ? xmax : xmin, q & 2 ? ymax : ymin, a, b);
        const double v[4] = {a, b, a + b, a - b};
        for (int f = 0; f < 4; ++f) {
            lo[f] = std::min(lo[f], v[f]);
            hi[f] = std::max(hi[f], v[f]);
        }
    }
    int family[16];
    double value[16];
    int lines = 0;
    for (int f = 0; f < 4; ++f) {
        for (double k = std::ceil(lo[f]); k < hi[f] && lines < 16; k += 1.0) {
            if (k > lo[f] && (f < 2 || std::fmod(std::fabs(k), 2.0) == 1.0)) {
                family[lines] = f;
                value[lines++] = k;
            }
        }
    }
    if (lines == 0) {
        part(xs, ys, n);
        return;
    }
    // scratch holds polygons as interleaved x, y.
    std::vector<std::vector<double>> polys(1), next;
    polys[0].resize(size_t(2 * n));
    for (int k = 0; k < n; ++k) {
        polys[0][size_t(2 * k)] = xs[k];
        polys[0][size_t(2 * k + 1)] = ys[k];
    }
    auto line_value = [&](int f, double x, double y) {
        double a, b;
        cell_local(g, cell, x, y, a, b);
        return f == 0 ? a : f == 1 ? b : f == 2 ? a + b : a - b;
    };
    for (int l = 0; l < lines; ++l) {
        next.clear();
        for (const std::vector<double>& p : polys) {
            const size_t m = p.size() / 2;
            for (double sg : {1.0, -1.0}) {
                std::vector<double> q;
                for (size_t k = 0; k < m; ++k) {
                    size_t j = k + 1 == m ? 0 : k + 1;
                    double fk = sg * (line_value(family[l], p[2 * k], p[2 * k + 1]) - value[l]);
                    double fj = sg * (line_value(family[l], p[2 * j], p[2 * j + 1]) - value[l]);
                    if (fk >= 0.0) {
                        q.push_back(p[2 * k]);
                        q.push_back(p[2 * k + 1]);
                    }
                    if ((fk > 0.0 && fj < 0.0) || (fk < 0.0 && fj > 0.0)) {
                        double t = fk / (fk - fj);
                        q.push_back(p[2 * k] + t * (p[2 * j] - p[2 * k]));
                        q.push_back(p[2 * k + 1] + t * (p[2 * j + 1] - p[2 * k + 1]));
                    }
                }
                if (q.size() >= 6) next.push_back(std::move(q));
            }
        }
        polys.swap(next);
    }
    scratch.resize(2);
    for (const std::vector<double>& p : polys) {
        const size_t m = p.size() / 2;
        scratch[0].resize(m);
        scratch[1].resize(m);
        for (size_t k = 0; k < m; ++k) {
            scratch[0][k] = p[2 * k];
            scratch[1][k] = p[2 * k + 1];
        }
        part(scratch[0].data(), scratch[1].data(), int(m));
    }
}

// True when texel (ix, iy) of `cell`'s grid holds data the area filter reads as it is: inside
// the cell's valid region (the face, not its guard ring), or for a disk, a texel whose square
// meets the disk. A partial source (padded by resample/partial.py, param[kReach] > 0) reads
// its whole cell, guard ring included: every texel there is its own colour x V (0 off the
// view), and a footprint past the view's edge, up to the reach, lies on those texels (read
// through remap_tap, the ring's texels gave the edge texel's colour: a sun on a perspective
// view's edge texel got 3.7 times its energy).
inline bool area_readable(const Geometry& g, int64_t cell, int64_t ix, int64_t iy) {
    int64_t cw = g.cell_width(), ch = g.cell_height();
    if (g.param[kReach] > 0.0 && (g.family == kFisheye || g.family == kPerspective)) {
        int64_t cx0 = (cell % g.columns) * cw, cy0 = (cell / g.columns) * ch;
        return ix >= cx0 && ix < cx0 + cw && iy >= cy0 && iy < cy0 + ch;
    }
    int64_t x0 = (cell % g.columns) * cw + g.guard, y0 = (cell / g.columns) * ch + g.guard;
    int64_t w = g.nx, h = g.n;
    if (ix < x0 || ix >= x0 + w || iy < y0 || iy >= y0 + h) return false;
    if (!g.disk()) return true;
    double c = 0.5 * double(g.n);  // the disk's centre and radius, in pixels from (x0, y0)
    double dx = std::max({double(x0) + c - double(ix + 1), 0.0, double(ix) - double(x0) - c});
    double dy = std::max({double(y0) + c - double(iy + 1), 0.0, double(iy) - double(y0) - c});
    return dx * dx + dy * dy <= c * c;
}

// The texel the area filter reads for texel (ix, iy) of `cell`'s continued grid: itself where
// readable; a lat-long column past the wrap, modulo the width; anything else, the texel that
// holds the continued direction of its centre (remap_tap).
inline const float* area_texel(const Image& src, const Geometry& g, int64_t cell, int64_t ix,
                               int64_t iy) {
    if (g.family == kLatlong && g.guard == 0 && iy >= 0 && iy < g.n) {
        int64_t w = 2 * g.n;
        ix %= w;
        if (ix < 0) ix += w;
        return src.texel(iy, ix);
    }
    if (area_readable(g, cell, ix, iy)) return src.texel(iy, ix);
    int64_t jx, jy;
    remap_tap(g, cell, ix, iy, jx, jy);
    return src.texel(jy, jx);
}

}  // namespace envconv
