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

#include <cmath>
#include <cstdint>
#include <vector>

#include "taps.h"

namespace envconv {

struct SourcePoint {
    double x, y;
    int64_t cell;
};

struct TexelDensity {
    double m, gx, gy;
};

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

    SourceModel(const Image& image_, const Geometry& g_) : image(image_), g(g_) {
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

    // 2 x 2 Gauss-Legendre points of the texel: their mean and the mean slope across them.
    TexelDensity generic(int64_t cell, int64_t ix, int64_t iy) const {
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
};

// True when texel (ix, iy) of `cell`'s grid holds data the area filter reads as it is: inside
// the cell's valid region (the face, not its guard ring), or for a disk, a texel whose square
// meets the disk.
inline bool area_readable(const Geometry& g, int64_t cell, int64_t ix, int64_t iy) {
    int64_t cw = g.cell_width(), ch = g.cell_height();
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
