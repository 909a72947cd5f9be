// Output-side geometry of the area filter: a pixel's pieces and their exact coverage.
//
// A piece is a convex region of one output cell in level-0 output pixels (x right, y down):
// the pixel square cut by the cell's square and, for a disk layout, by its readable circle,
// later cut by seams and splits. Its boundary is a polygon whose edges are straight or arcs of
// the piece's circle; vertices run so that the shoelace area is positive (the order of
// (x0, y0), (x1, y0), (x1, y1), (x0, y1)), and an arc runs from its start to its end vertex by
// increasing angle atan2(y - cy, x - cx). Each vertex may carry its source point.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "area_source.h"

namespace envconv {

constexpr int kPieceVertices = 24;

struct PieceVertex {
    double x, y;
    bool arc;       // the edge from this vertex to the next is an arc of the piece's circle
    bool mapped;    // src holds the vertex's source point
    bool seam;      // the edge from this vertex to the next is a cut along a source seam
    bool fold;      // the edge from this vertex to the next touches a fold (area_map.h)
    bool chord;     // the edge from this vertex to the next stays a chord (its tile decided)
    int side;       // the pixel side (0 ... 3) the edge from this vertex runs along, or -1
    bool boundary;  // the vertex lies on a source seam: it belongs to either side's cell
    int snapped;    // a source singular point (area_map.h) moved onto this vertex, or -1
    int cone;       // the folded source's cone point (area_map.h) this vertex stands on, or -1
    SourcePoint src;
};

struct Piece {
    int64_t cell;   // output cell
    int n;
    PieceVertex v[kPieceVertices];
    double cx, cy, r;  // the circle of the arc edges
    bool valid;        // the piece lies in the cell's valid region (else in a guard ring)
};

inline PieceVertex plain_vertex(double x, double y) {
    return {x, y, false, false, false, false, false, -1, false, -1, -1, {0.0, 0.0, -1}};
}

// The disk of a disk cell in level-0 pixels: centre and the radius of unit (a, b) radius.
inline void cell_disk(const Geometry& d, int64_t cell, double& cx, double& cy, double& unit) {
    unit = 0.5 * double(d.n);
    cx = double((cell % d.columns) * d.cell_width() + d.guard) + unit;
    cy = double((cell / d.columns) * d.cell_height() + d.guard) + unit;
}

// Point at parameter t in [0, 1] of edge k of the piece (along the chord, or the arc's angle).
inline void edge_point(const Piece& p, int k, double t, double& x, double& y) {
    const PieceVertex &s = p.v[k], &e = p.v[k + 1 == p.n ? 0 : k + 1];
    if (!s.arc) {
        x = s.x + t * (e.x - s.x);
        y = s.y + t * (e.y - s.y);
        return;
    }
    double a0 = std::atan2(s.y - p.cy, s.x - p.cx), a1 = std::atan2(e.y - p.cy, e.x - p.cx);
    if (a1 <= a0) a1 += 2.0 * kPi;
    double a = a0 + t * (a1 - a0);
    x = p.cx + p.r * std::cos(a);
    y = p.cy + p.r * std::sin(a);
}

// The piece of the square [x0, x1] x [y0, y1] inside the circle (cx, cy, r) (out.n = 0 when
// they do not meet): the square's corners inside the circle and the points where its boundary
// crosses the circle, in order along the boundary; a stretch of the boundary outside the
// circle becomes an arc between the points where it leaves and re-enters.
inline void clip_square_to_circle(double x0, double y0, double x1, double y1, double cx,
                                  double cy, double r, Piece& out) {
    const double sx[5] = {x0, x1, x1, x0, x0}, sy[5] = {y0, y0, y1, y1, y0};
    const double r2 = r * r;
    auto inside = [&](double x, double y) {
        return (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r2;
    };
    double where[kPieceVertices];  // position along the perimeter, side k at [k, k + 1)
    int n = 0;
    for (int k = 0; k < 4; ++k) {
        double ax = sx[k], ay = sy[k], dx = sx[k + 1] - ax, dy = sy[k + 1] - ay;
        if (inside(ax, ay)) {
            where[n] = double(k);
            out.v[n++] = plain_vertex(ax, ay);
        }
        double fx = ax - cx, fy = ay - cy;
        double qa = dx * dx + dy * dy, qb = 2.0 * (fx * dx + fy * dy), qc = fx * fx + fy * fy - r2;
        double disc = qb * qb - 4.0 * qa * qc;
        if (!(disc > 0.0)) continue;
        double root = std::sqrt(disc);
        for (double t : {(-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)}) {
            if (t <= 1e-12 || t >= 1.0 - 1e-12) continue;
            where[n] = double(k) + t;
            out.v[n++] = plain_vertex(ax + t * dx, ay + t * dy);
        }
    }
    out.n = n;
    if (n == 0) {
        // Neither a corner inside nor a crossing: the circle lies inside the square, or apart.
        out.n = 0;
        if (cx - r >= x0 && cx + r <= x1 && cy - r >= y0 && cy + r <= y1) {
            const double ang[4] = {-0.5 * kPi, 0.0, 0.5 * kPi, kPi};
            for (int k = 0; k < 4; ++k) {
                out.v[k] = plain_vertex(cx + r * std::cos(ang[k]), cy + r * std::sin(ang[k]));
                out.v[k].arc = true;
            }
            out.n = 4;
        }
        return;
    }
    // The boundary between two consecutive points: along the square where its middle is inside
    // the circle, else along the circle.
    for (int k = 0; k < n; ++k) {
        double s0 = where[k], s1 = k + 1 < n ? where[k + 1] : where[0] + 4.0;
        double mid = 0.5 * (s0 + s1);
        if (mid >= 4.0) mid -= 4.0;
        int side = std::min(3, int(mid));
        double t = mid - double(side);
        double mx = sx[side] + t * (sx[side + 1] - sx[side]);
        double my = sy[side] + t * (sy[side + 1] - sy[side]);
        out.v[k].arc = !inside(mx, my);
    }
}

// The crossings of edge k of the piece with the line nx x + ny y = c, as parameters t in
// (0, 1) along it in increasing order; returns their count (at most 2, for an arc).
inline int edge_crossings(const Piece& p, int k, double nx, double ny, double c, double* ts) {
    const PieceVertex &s = p.v[k], &e = p.v[k + 1 == p.n ? 0 : k + 1];
    const double lo = 1e-12, hi = 1.0 - 1e-12;
    int count = 0;
    if (!s.arc) {
        double fs = nx * s.x + ny * s.y - c, fe = nx * e.x + ny * e.y - c;
        if ((fs < 0.0 && fe > 0.0) || (fs > 0.0 && fe < 0.0)) {
            double t = fs / (fs - fe);
            if (t > lo && t < hi) ts[count++] = t;
        }
        return count;
    }
    double a0 = std::atan2(s.y - p.cy, s.x - p.cx), a1 = std::atan2(e.y - p.cy, e.x - p.cx);
    if (a1 <= a0) a1 += 2.0 * kPi;
    // n . (centre + r (cos a, sin a)) = c  <=>  cos(a - phi) = (c - n . centre) / (r |n|)
    double len = std::hypot(nx, ny), phi = std::atan2(ny, nx);
    double q = (c - nx * p.cx - ny * p.cy) / (p.r * len);
    if (!(q > -1.0 && q < 1.0)) return 0;
    double base = std::acos(q), cand[2] = {phi - base, phi + base};
    for (double& a : cand) {
        while (a < a0) a += 2.0 * kPi;
        while (a >= a0 + 2.0 * kPi) a -= 2.0 * kPi;
    }
    if (cand[0] > cand[1]) std::swap(cand[0], cand[1]);
    for (double a : cand) {
        double t = (a - a0) / (a1 - a0);
        if (t > lo && t < hi) ts[count++] = t;
    }
    return count;
}

// Cut the piece by the line nx x + ny y = c and keep the side where nx x + ny y <= c
// (keep_below) or >= c. The kept parts of edges keep their kind; the stretches along the line
// become straight edges. out.n = 0 when nothing is left.
inline void clip_piece(const Piece& in, double nx, double ny, double c, bool keep_below,
                       Piece& out) {
    out = in;
    out.n = 0;
    const double sgn = keep_below ? 1.0 : -1.0;
    const double tol = 1e-12 * (std::fabs(c) + 1.0);
    for (int k = 0; k < in.n; ++k) {
        const PieceVertex& s = in.v[k];
        double ts[2];
        int count = edge_crossings(in, k, nx, ny, c, ts);
        // Which side the edge runs on just after s (s itself may lie on the line).
        double px, py;
        edge_point(in, k, count ? 0.5 * ts[0] : 0.5, px, py);
        bool inside = sgn * (nx * px + ny * py - c) <= 0.0;
        if (sgn * (nx * s.x + ny * s.y - c) <= tol && out.n < kPieceVertices) {
            PieceVertex v = s;
            if (!inside) {  // on the line, leaving: a cut
                v.arc = v.seam = v.fold = v.chord = false;
                v.side = -1;
            }
            out.v[out.n++] = v;
        }
        for (int m = 0; m < count && out.n < kPieceVertices; ++m) {
            PieceVertex v = s;
            v.mapped = false;
            v.cone = -1;
            edge_point(in, k, ts[m], v.x, v.y);
            inside = !inside;  // every crossing changes sides
            if (!inside) {  // leaving: along the cut
                v.arc = v.seam = v.fold = v.chord = false;
                v.side = -1;
            }
            out.v[out.n++] = v;
        }
    }
    if (out.n < 3 && !(out.n == 2 && (out.v[0].arc || out.v[1].arc))) out.n = 0;
}

// Area of {(x, y) in [x0, x1] x [y0, y1] : (x - cx)^2 + (y - cy)^2 <= r^2}, exactly.
inline double disk_rect_area(double x0, double y0, double x1, double y1, double cx, double cy,
                             double r) {
    x0 -= cx;
    x1 -= cx;
    y0 -= cy;
    y1 -= cy;
    // int_{x0}^{x1} clamp(s(x), lo, hi) dx with s(x) = sqrt(r^2 - x^2) (0 past |x| = r).
    auto part = [r](double xa, double xb, double lo, double hi) {
        auto s = [r](double x) { return std::sqrt(std::max(r * r - x * x, 0.0)); };
        auto prim = [r, &s](double x) {  // antiderivative of s
            double xc = std::min(std::max(x, -r), r);
            return 0.5 * (xc * s(xc) + r * r * std::asin(xc / r));
        };
        double cuts[8] = {xa, xb};
        int nc = 2;
        for (double level : {lo, hi}) {
            if (std::fabs(level) < r) {
                double w = std::sqrt(r * r - level * level);
                cuts[nc++] = -w;
                cuts[nc++] = w;
            }
        }
        cuts[nc++] = -r;
        cuts[nc++] = r;
        std::sort(cuts, cuts + nc);
        double total = 0.0;
        for (int k = 0; k + 1 < nc; ++k) {
            double a = std::max(cuts[k], xa), b = std::min(cuts[k + 1], xb);
            if (!(b > a)) continue;
            double mid = s(0.5 * (a + b));
            if (mid >= hi) total += hi * (b - a);
            else if (mid <= lo) total += lo * (b - a);
            else total += prim(b) - prim(a);
        }
        return total;
    };
    // Height of the disk's column at x inside [y0, y1]: clamp(s) - clamp(-s).
    return std::max(0.0, part(x0, x1, y0, y1) + part(x0, x1, -y1, -y0));
}

// Fraction of the level-0 rectangle [x0, x1] x [y0, y1] that lies in the valid region of the
// output layout (faces of occupied cells without their guard rings, or the unit disks).
inline double rect_coverage(const Geometry& d, double x0, double y0, double x1, double y1) {
    double cw = double(d.cell_width()), ch = double(d.cell_height());
    int64_t col0 = std::max<int64_t>(0, int64_t(std::floor(x0 / cw)));
    int64_t col1 = std::min<int64_t>(d.columns - 1, int64_t(std::floor(x1 / cw)));
    int64_t row0 = std::max<int64_t>(0, int64_t(std::floor(y0 / ch)));
    int64_t row1 = std::min<int64_t>(d.rows - 1, int64_t(std::floor(y1 / ch)));
    double covered = 0.0;
    for (int64_t row = row0; row <= row1; ++row) {
        for (int64_t col = col0; col <= col1; ++col) {
            int64_t cell = row * d.columns + col;
            if (d.cell_face[cell] < 0) continue;
            double fx0 = double(col) * cw + double(d.guard), fy0 = double(row) * ch + double(d.guard);
            double fx1 = fx0 + double(d.nx), fy1 = fy0 + double(d.n);
            double ax = std::max(x0, fx0), bx = std::min(x1, fx1);
            double ay = std::max(y0, fy0), by = std::min(y1, fy1);
            if (!(bx > ax && by > ay)) continue;
            if (!d.disk()) {
                covered += (bx - ax) * (by - ay);
                continue;
            }
            double cx, cy, unit;
            cell_disk(d, cell, cx, cy, unit);
            covered += disk_rect_area(ax, ay, bx, by, cx, cy, unit);
        }
    }
    return covered / ((x1 - x0) * (y1 - y0));
}

}  // namespace envconv
