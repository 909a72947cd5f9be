// The area filter's general path: one piece of an output pixel at a time, its footprint in
// the source built exactly and integrated (area_pieces.h, green.h).
//
// A piece's footprint is the polygon of its vertices' source points in one source cell's
// coordinates, each edge refined where the image of its midpoint strays more than kChordTol
// texels from the chord (recursively). Where the piece's vertices fall in several source cells
// (cube faces, paraboloid halves, tennisball bands), its edges are bisected to the seam and the
// piece is cut along the chord between the two crossings, each side integrated in its own cell:
// the cut's two ends lie on the seam, so a cube face's side of the footprint ends exactly on
// the face's edge. A source singular point (a lat-long pole, a mirror ball's -Z) on the piece's
// boundary becomes a run of its edge (the pole's row edge, the rim arc) between the limits of
// the adjacent edges; one inside the piece closes the footprint around it. Anything else that
// does not resolve (three cells at a cube corner, a seam that bulges between two vertices)
// splits the piece in four, down to kMaxPieceDepth; the last leftover piece, or one too small
// to matter (kTinyPiece), is read at its centre with its own solid angle.
#pragma once

#include <cmath>
#include <vector>

#include "area_linear.h"
#include "area_map.h"
#include "green.h"

namespace envconv {

// A pixel edge whose image strays more than kChordTol from its chord (at its midpoint, in
// output pixels across the edge: the share of the pixel's solid angle the chord would
// misplace) is refined: its midpoint's image is inserted and both halves are tested again. An
// edge that touches a fold of the octahedral and equal-area squares is held to a quarter of
// that (a fold through a pixel's corners leaves two edges on each side, bending in mirrored
// ways, whose chords' errors add up rather than cancel). The test depends on the edge alone,
// so the two pixels that share an edge agree on it. Interpolated corners may be kCornerTol
// from their exact images (area_tiles.h), in output pixels too. Measured over 64 one-texel
// suns into every layout at 1:1 to 16:1 (tests/test_area.py): 5e-4 keeps the worst within
// 0.07 %, 1e-3 within 0.10 % and a fifth faster (most 1:1 edges of a lat-long to a cube are
// then chords), 2e-3 lets one reach 0.78 % (an octahedral square at 4:1).
constexpr double kChordTol = 1e-3;
constexpr double kCornerTol = 1e-3;
constexpr int kMaxRefine = 16;       // halvings of an edge
constexpr int kMaxPieceDepth = 8;    // splits of a piece
// A piece that does not resolve and covers at most this share of an output pixel is read at
// its centre without splitting (it moves at most this share of the pixel's weight).
constexpr double kTinyPiece = 1e-9;
constexpr double kSnap = 1e-5;       // output pixels: a singular point this near the boundary is on it
constexpr double kRimStep = 2e-3;    // rad: steps of a rim arc in a disk source
constexpr double kConeAngle = 1e-6;  // rad: a vertex this near a cone point stands on it

// A pixel's running sums: colour times solid angle, and solid angle (sr).
struct PixelSums {
    double* acc;
    int64_t nch;
    double weight;
};

// A side of a pixel as the tile that holds the pixel took it: a chord (mode 0), refined by
// the general path's own rule (1), or the tile's polyline (2): points in `cell`'s
// coordinates, from the side's start (whose point there is (x0, y0)) to its end, exclusive.
struct SidePath {
    int mode = 1;
    int64_t cell = -1;
    double x0 = 0.0, y0 = 0.0;
    std::vector<double> px, py;
};

// Everything the general path needs; one per band (scratch inside).
struct SlowPath {
    const Conversion& cv;
    const SourceModel& model;
    const Singular& sing;
    GreenScratch green;
    std::vector<double> xs, ys;
    std::vector<std::vector<double>> kink_scratch;
    PixelSums* sums = nullptr;
    const SidePath* sides = nullptr;  // the pixel's four sides, when its tile took them
    double side_x[4][2], side_y[4][2];  // their ends (output pixels)
    // A partial source: the output solid angle of the pixel's pieces (piece_solid_angle), and
    // whether one lay beyond the source's reach; such a pixel's weight is that solid angle
    // (the covered pieces' footprints stop at the reach, not at the chord that splits them
    // from the uncovered ones: a sun on a fisheye's rim got up to 2 % too much at 4:1).
    double out_weight = 0.0;
    bool uncovered = false;
    // The linear reconstruction's slopes (area_linear.h) when the conversion magnifies, else
    // none (the box).
    SlopeCache* linear = nullptr;

    SlowPath(const Conversion& cv_, const SourceModel& model_, const Singular& sing_)
        : cv(cv_), model(model_), sing(sing_) {}
};

// Sink of green.h: solid angle of each texel's piece (the texel's density model) and its
// colour, read through area_texel.
struct TexelSink {
    static constexpr bool kMomentX = true;
    const SourceModel& model;
    int64_t cell;
    double sign;
    PixelSums& sums;
    bool flat(int64_t, int64_t) const { return false; }
    void row(int64_t) {}
    void texel(int64_t ix, int64_t iy, double area, double dx, double dy) {
        double w = sign * model.weight(cell, ix, iy, area, dx, dy);
        if (w == 0.0) return;
        const float* v = area_texel(model.image, model.g, cell, ix, iy);
        for (int64_t c = 0; c < sums.nch; ++c) sums.acc[c] += w * double(v[c]);
        sums.weight += w;
    }
};

// TexelSink for the linear reconstruction (area_linear.h): each piece's colour also takes the
// slope terms Dx c ax + Dy c ay of the texel read (turned into its grid where it is read in
// another's place; none where the grids do not map by a reflection or quarter turn).
struct LinearTexelSink {
    static constexpr bool kMomentX = true;
    const SourceModel& model;
    SlopeCache& slopes;
    int64_t cell;
    double sign;
    PixelSums& sums;
    bool flat(int64_t, int64_t) const { return false; }
    void row(int64_t) {}
    // True when area_texel reads texel (ix, iy) of the cell's continued grid as itself.
    bool own(int64_t ix, int64_t iy) const {
        const Geometry& g = model.g;
        if (g.family == kLatlong && g.guard == 0 && iy >= 0 && iy < g.n) return true;
        return area_readable(g, cell, ix, iy);
    }
    void texel(int64_t ix, int64_t iy, double area, double dx, double dy) {
        double w = sign * model.weight(cell, ix, iy, area, dx, dy);
        if (w == 0.0 && dx == 0.0 && dy == 0.0) return;
        const float* v = area_texel(model.image, model.g, cell, ix, iy);
        const int64_t at = v - model.image.data;
        sums.weight += w;
        int turn[4] = {1, 0, 0, 1};  // this grid's x and y steps in the read texel's grid
        if (!own(ix, iy) &&
            !grid_turn(model.g, model.image.width, cell, ix, iy, at / model.image.channels, turn)) {
            for (int64_t c = 0; c < sums.nch; ++c) sums.acc[c] += w * double(v[c]);
            return;
        }
        const int64_t texel = at / model.image.channels;
        const float* sx = slopes.get(texel % model.image.width, texel / model.image.width);
        const float *sy = sx + sums.nch, *sz = sy + sums.nch;
        const double lx = sign * dx, ly = sign * dy, la = sign * area;
        for (int64_t c = 0; c < sums.nch; ++c) {
            const double ax = double(sx[c]), ay = double(sy[c]);
            sums.acc[c] += w * double(v[c]) + lx * (turn[0] * ax + turn[1] * ay) +
                           ly * (turn[2] * ax + turn[3] * ay) + la * double(sz[c]);
        }
    }
};

// Integrate the closed polygon (sp.xs, sp.ys) of source cell `cell` into the pixel's sums.
inline void add_footprint(SlowPath& sp, int64_t cell) {
    int n = int(sp.xs.size());
    if (n < 3) return;
    double area, mx, my;
    polygon_moments(sp.xs.data(), sp.ys.data(), n, area, mx, my);
    if (!(std::fabs(area) > 0.0)) return;
    if (sp.linear) {
        LinearTexelSink sink{sp.model, *sp.linear, cell, area > 0.0 ? 1.0 : -1.0, *sp.sums};
        split_at_kinks(sp.model.g, cell, sp.xs.data(), sp.ys.data(), n, sp.kink_scratch,
                       [&](const double* xs, const double* ys, int m) {
                           integrate_any(xs, ys, m, sink, sp.green);
                       });
        return;
    }
    TexelSink sink{sp.model, cell, area > 0.0 ? 1.0 : -1.0, *sp.sums};
    split_at_kinks(sp.model.g, cell, sp.xs.data(), sp.ys.data(), n, sp.kink_scratch,
                   [&](const double* xs, const double* ys, int m) {
                       integrate_any(xs, ys, m, sink, sp.green);
                   });
}

// The output solid angle of a piece: its triangles from vertex 0, each by the 3-point Gauss
// rule of degree 2 (the density at one point of a lat-long pixel 4 source texels of a fisheye
// wide left its rim suns up to 2 % over).
inline double piece_solid_angle(const SlowPath& sp, const Piece& p) {
    const Geometry& d = sp.cv.dst;
    const int face = d.cell_face[p.cell];
    const double unit = (2.0 / double(d.nx)) * (2.0 / double(d.n));
    double total = 0.0;
    for (int k = 1; k + 1 < p.n; ++k) {
        const PieceVertex &A = p.v[0], &B = p.v[k], &C = p.v[k + 1];
        double area = 0.5 * std::fabs((B.x - A.x) * (C.y - A.y) - (C.x - A.x) * (B.y - A.y));
        if (!(area > 0.0)) continue;
        double sum = 0.0;
        for (int q = 0; q < 3; ++q) {
            double la = q == 0 ? 2.0 / 3.0 : 1.0 / 6.0, lb = q == 1 ? 2.0 / 3.0 : 1.0 / 6.0;
            double lc = 1.0 - la - lb, a, b;
            cell_local(d, p.cell, la * A.x + lb * B.x + lc * C.x, la * A.y + lb * B.y + lc * C.y, a, b);
            sum += density(d, face, a, b);
        }
        total += area * sum / 3.0;
    }
    return total * unit;
}

// A piece that did not resolve: the texel at its centre (no colour with `colour` false: a
// piece beyond a partial source's reach, whose solid angle is piece_solid_angle's), with the
// piece's own solid angle.
inline void add_leftover(SlowPath& sp, const Piece& p, bool colour = true) {
    if (!colour) {
        double w = piece_solid_angle(sp, p);
        if (w > 0.0) sp.sums->weight += w;
        sp.out_weight += w;
        sp.uncovered = true;
        return;
    }
    if (partial_source(sp.cv.src)) sp.out_weight += piece_solid_angle(sp, p);
    double cx = 0.0, cy = 0.0, area = 0.0;
    for (int k = 0; k < p.n; ++k) {
        const PieceVertex &s = p.v[k], &e = p.v[(k + 1) % p.n];
        cx += s.x;
        cy += s.y;
        area += s.x * e.y - e.x * s.y;
    }
    cx /= p.n;
    cy /= p.n;
    const Geometry& d = sp.cv.dst;
    double a, b;
    cell_local(d, p.cell, cx, cy, a, b);
    double w = 0.5 * std::fabs(area) * density(d, d.cell_face[p.cell], a, b) *
               (2.0 / double(d.nx)) * (2.0 / double(d.n));
    if (!(w > 0.0)) return;
    sp.sums->weight += w;
    if (!colour) return;
    const Vec3 centre = output_direction(sp.cv, p.cell, cx, cy);
    if (!source_covers(sp.cv.src, centre)) {  // its solid angle, no colour
        sp.uncovered = true;
        return;
    }
    SourcePoint s = source_of(sp.cv.src, centre);
    const float* v = area_texel(sp.model.image, sp.cv.src, s.cell, floor_index(s.x),
                                floor_index(s.y));
    for (int64_t c = 0; c < sp.sums->nch; ++c) sp.sums->acc[c] += w * double(v[c]);
}

// Per-vertex facts of a piece: source direction, true cell, singular index (-1 if none).
struct VertexFacts {
    Vec3 dir[kPieceVertices];
    int64_t cell[kPieceVertices];
    int singular[kPieceVertices];
};

inline void vertex_facts(const SlowPath& sp, Piece& p, VertexFacts& f) {
    for (int k = 0; k < p.n; ++k) {
        PieceVertex& v = p.v[k];
        f.dir[k] = v.cone >= 0 ? sp.sing.cone_src[v.cone]
                   : v.mapped ? source_direction(sp.cv.src, v.src)
                              : output_direction(sp.cv, p.cell, v.x, v.y);
        // A vertex whose direction is a cone point (a mirror ball's rim over a folded
        // square's -Z, say) stands on it: within kConeAngle, as a rim point r = 1 - 1e-16 of a
        // mirror ball lies 1.4e-8 from -Z.
        for (int c = 0; c < sp.sing.cones && v.cone < 0; ++c) {
            const Vec3& q = sp.sing.cone_src[c];
            const Vec3& d = f.dir[k];
            if (std::sqrt((d.x - q.x) * (d.x - q.x) + (d.y - q.y) * (d.y - q.y) + (d.z - q.z) * (d.z - q.z)) <=
                kConeAngle) {
                v.cone = c;
                f.dir[k] = q;
            }
        }
        int s = on_singular(sp.sing, f.dir[k]);
        if (s < 0 && v.snapped >= 0) s = v.snapped;
        f.singular[k] = s;
        f.cell[k] = source_cell(sp.cv.src, f.dir[k]);
    }
}

// The source point of piece vertex k in cell C, near (ref_x, ref_y): its own point where it
// has one in C (the copy nearest ref where columns repeat), else its direction's.
inline bool vertex_image(const SlowPath& sp, const Piece& p, const VertexFacts& f, int k,
                         int64_t cell, double ref_x, double ref_y, double& x, double& y) {
    const PieceVertex& v = p.v[k];
    const Geometry& g = sp.cv.src;
    if (v.mapped && v.src.cell == cell && g.family != kOctahedral && g.family != kEqualArea) {
        x = v.src.x;
        y = v.src.y;
        if (g.family == kLatlong || g.family == kTennisball) {
            double period = double(g.family == kLatlong ? 2 * g.n : 4 * g.n);
            x += period * std::nearbyint((ref_x - x) / period);
        }
        return true;
    }
    return continued_point(g, cell, f.dir[k], ref_x, ref_y, x, y);
}

// Append to xs, ys the refinement points of the straight output segment (ox0, oy0) ->
// (ox1, oy1) of output cell `ocell`, whose images in source cell `cell` are (x0, y0) and
// (x1, y1): the image of its midpoint where it strays more than tol (output pixels) from the
// chord, and recursively. False when the segment leaves the cell in between.
bool refine_segment(const Conversion& cv, const Singular& sing, int64_t ocell, double ox0,
                    double oy0, double ox1, double oy1, int64_t cell, double x0, double y0,
                    double x1, double y1, double tol, std::vector<double>& xs,
                    std::vector<double>& ys, int depth = 0);

// Integrate the output rectangle [x0, x1] x [y0, y1] (level-0 output pixels: a pixel, or a
// sub-pixel) into *sp.sums: its piece in every output cell it meets, through that cell's map.
// `corners`, when not null, are the source points of the rectangle's corners (x0, y0),
// (x1, y0), (x1, y1), (x0, y1), as the pixels around it use them; `sides`, when not null, how
// its tile took each side (from corner k to k + 1; SidePath).
void slow_rect(SlowPath& sp, double x0, double y0, double x1, double y1,
               const SourcePoint* corners, const SidePath* sides = nullptr);

}  // namespace envconv
