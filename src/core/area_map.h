// Mapping the area filter's output points into the source, and the source's singular points.
//
// Singular points are the source directions where a source layout's map is not one to one:
// a lat-long's poles (the top and bottom rows' outer edges) and the -Z of a mirror ball or an
// angular map (their rim circle). A footprint that holds one is not a plain polygon: near a
// pole it runs along the pole's row edge, near -Z along the rim. The area filter finds where
// each singular direction lands in an output cell and closes the footprints around it
// (area_slow.h).
//
// Cone points are the source directions where a folded square (octahedral, equal-area) folds
// an edge onto itself: the midpoints (+-1, 0), (0, +-1) of its edges, where (1, b) and (1, -b)
// are one direction. The square's neighbourhood of such a point is a half disk, and the fold
// continues it by a half turn about the point, so a full turn around the direction is half a
// turn around the point in the square (or its continuation): a footprint that holds one does
// not close in any continued coordinates. The general path splits such a piece through the
// cone point (area_slow.h) and gives the point, on the pieces' boundary, its exact image.
#pragma once

#include <cmath>

#include "area_pieces.h"
#include "footprint.h"

namespace envconv {

// The source directions where the source map is singular.
struct Singular {
    int count = 0;
    int kind = 0;  // 1: lat-long poles (+Y, -Y); 2: a disk's -Z (sphere, angular)
    Vec3 src[2];   // in the source frame
    Vec3 out[2];   // in the output frame: rot^T src
    int cones = 0;        // a folded square's cone points: +X, -X, +Z, -Z (its edge midpoints)
    Vec3 cone_src[4];     // in the source frame
    Vec3 cone_out[4];     // in the output frame
};

// True when a disk family's rim circle maps to one direction (the view axis's opposite): a
// mirror ball, an angular map, a fisheye of 360 degrees.
inline bool rim_singular(const Chart& c) {
    return c.family == kSphere || c.family == kAngular ||
           (c.family == kFisheye && c.param[kScaleX] >= kPi * (1.0 - 1e-12));
}

inline Singular source_singular(const Conversion& cv) {
    Singular s;
    const Rotation& r = cv.rot;
    auto back = [&r](const Vec3& d) {  // rot^T d
        return Vec3{r.m[0] * d.x + r.m[3] * d.y + r.m[6] * d.z,
                    r.m[1] * d.x + r.m[4] * d.y + r.m[7] * d.z,
                    r.m[2] * d.x + r.m[5] * d.y + r.m[8] * d.z};
    };
    if (cv.src.family == kLatlong) {
        s.kind = 1;
        s.count = 2;
        s.src[0] = {0.0, 1.0, 0.0};
        s.src[1] = {0.0, -1.0, 0.0};
    } else if (rim_singular(cv.src)) {
        s.kind = 2;
        s.count = 1;
        s.src[0] = cv.src.family == kFisheye ? view::to_world(cv.src, 0.0, 0.0, -1.0)
                                             : Vec3{0.0, 0.0, -1.0};
    }
    for (int k = 0; k < s.count; ++k) s.out[k] = back(s.src[k]);
    if (cv.src.family == kOctahedral || cv.src.family == kEqualArea) {
        // face_to_dir of (1, 0), (-1, 0), (0, -1), (0, 1): the same in both squares.
        const Vec3 cones[4] = {{1.0, 0.0, 0.0}, {-1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, -1.0}};
        s.cones = 4;
        for (int k = 0; k < 4; ++k) {
            s.cone_src[k] = cones[k];
            s.cone_out[k] = back(cones[k]);
        }
    }
    return s;
}

// True when the line (a0, b0) -> (a1, b1) crosses or touches a fold of the octahedral and
// equal-area squares (their axes, their edges, the diamond |a| + |b| = 1), where their maps
// have a kink. Touching counts: a pixel that a fold cuts through two of its corners has two
// edges on each side, whose images bend in mirrored ways, so their chords' errors add up.
inline bool crosses_fold(double a0, double b0, double a1, double b1) {
    for (double line : {-1.0, 0.0, 1.0})
        if ((a0 - line) * (a1 - line) <= 0.0 || (b0 - line) * (b1 - line) <= 0.0) return true;
    return (std::fabs(a0) + std::fabs(b0) - 1.0) * (std::fabs(a1) + std::fabs(b1) - 1.0) <= 0.0;
}

// True when a pixel edge touches a fold of the output map (output points (ox0, oy0),
// (ox1, oy1) of cell `cell`) or of the source map (source points s0, s1 in their own cells):
// such edges are refined to a tighter tolerance (area_slow.h). Depends on the edge alone.
inline bool edge_on_fold(const Conversion& cv, int64_t cell, double ox0, double oy0, double ox1,
                         double oy1, const SourcePoint& s0, const SourcePoint& s1) {
    const Geometry &d = cv.dst, &g = cv.src;
    if (d.family == kOctahedral || d.family == kEqualArea) {
        double a0, b0, a1, b1;
        cell_local(d, cell, ox0, oy0, a0, b0);
        cell_local(d, cell, ox1, oy1, a1, b1);
        if (crosses_fold(a0, b0, a1, b1)) return true;
    }
    if (g.family == kOctahedral || g.family == kEqualArea) {
        double a0, b0, a1, b1;
        cell_local(g, s0.cell, s0.x, s0.y, a0, b0);
        cell_local(g, s1.cell, s1.x, s1.y, a1, b1);
        // Folded into the square, points across one of its edges land far apart.
        if (crosses_fold(a0, b0, a1, b1) || std::fabs(a1 - a0) + std::fabs(b1 - b0) > 1.0) return true;
    }
    return false;
}

// Angular distance of a unit direction from singular direction k (cheap, small angles).
inline double singular_distance(const Singular& s, int k, const Vec3& d) {
    double dx = d.x - s.src[k].x, dy = d.y - s.src[k].y, dz = d.z - s.src[k].z;
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Within this angle (rad) of a singular direction a point counts as on it.
constexpr double kSingularAngle = 1e-9;

// Index of the singular direction d lies on, or -1.
inline int on_singular(const Singular& s, const Vec3& d) {
    for (int k = 0; k < s.count; ++k)
        if (singular_distance(s, k, d) <= kSingularAngle) return k;
    return -1;
}

// Source-frame direction of output point (x, y) through output cell `cell`'s (continued) map.
inline Vec3 output_direction(const Conversion& cv, int64_t cell, double x, double y) {
    double a, b;
    cell_local(cv.dst, cell, x, y, a, b);
    return cv.rot.apply(face_to_dir(cv.dst, cv.dst.cell_face[cell], a, b));
}

// A partial source (a fisheye of less than 360 degrees, a perspective view, padded by
// resample/partial.py) has no point for a direction it does not cover: its dir_to_face puts
// such directions on the circle or square of its reach, in the middle of its padding. The
// area filter gives the part of a footprint beyond the reach its output solid angle and no
// colour, in a cell of its own (kUncovered), so that the coverage it leaves is exact.
constexpr int64_t kUncovered = -2;

// True for a partial source (padded, with a reach).
inline bool partial_source(const Geometry& src) {
    return src.param[kReach] > 0.0 && (src.family == kFisheye || src.family == kPerspective);
}

// False when direction d lies beyond a partial source's reach.
inline bool source_covers(const Geometry& src, const Vec3& d) {
    const double reach = src.param[kReach];
    if (!partial_source(src)) return true;
    Vec3 v = view::to_view(src, d.x, d.y, d.z);
    if (src.family == kFisheye)
        return std::atan2(std::hypot(v.x, v.y), v.z) <= src.param[kScaleX] * reach;
    double a = std::fabs(v.x / src.param[kScaleX]), b = std::fabs(v.y / src.param[kScaleY]);
    return v.z > 0.0 && std::max(a, b) <= reach * v.z;
}

// The source point of direction d in the cell that holds it (its own cell's coordinates).
inline SourcePoint source_of(const Geometry& src, const Vec3& d) {
    FacePoint f = dir_to_face(src, d.x, d.y, d.z);
    ImagePoint p = face_to_image(src, f.face, f.a, f.b);
    return {p.x, p.y, p.cell};
}

// The cell of direction d's source point, kUncovered beyond a partial source's reach.
inline int64_t source_cell(const Geometry& src, const Vec3& d) {
    return source_covers(src, d) ? source_of(src, d).cell : kUncovered;
}

// Direction of source point p (its cell's continued map).
inline Vec3 source_direction(const Geometry& src, const SourcePoint& p) {
    double a, b;
    cell_local(src, p.cell, p.x, p.y, a, b);
    return face_to_dir(src, src.cell_face[p.cell], a, b);
}

// The exact source point of output point (x, y) through output cell `cell`; its cell is
// kUncovered beyond a partial source's reach.
inline SourcePoint exact_source(const Conversion& cv, int64_t cell, double x, double y) {
    Vec3 d = output_direction(cv, cell, x, y);
    SourcePoint p = source_of(cv.src, d);
    if (!source_covers(cv.src, d)) p.cell = kUncovered;
    return p;
}

// Where the singular source point of singular direction k lies in `cell`'s coordinates, seen
// from (ref_x, ref_y): for a lat-long pole the point of its row edge below ref_x... the caller
// replaces the x; for -Z, the rim point in the direction of (ref_x, ref_y).
inline SourcePoint singular_image(const Geometry& src, const Singular& s, int64_t cell, int k,
                                  double ref_x, double ref_y) {
    if (s.kind == 1) {
        double top = double((cell / src.columns) * src.cell_height() + src.guard);
        return {ref_x, k == 0 ? top : top + double(src.n), cell};
    }
    double cx, cy, unit;
    cell_disk(src, cell, cx, cy, unit);
    double ang = std::atan2(ref_y - cy, ref_x - cx);
    return {cx + unit * std::cos(ang), cy + unit * std::sin(ang), cell};
}

}  // namespace envconv
