// The area filter's general path (see area_slow.h for what it does and why).
#include "area_slow.h"

#include <algorithm>
#include <cmath>

namespace envconv {
namespace {

void process_piece(SlowPath& sp, Piece& p, int depth);

// Centroid of a piece's vertices.
void piece_centre(const Piece& p, double& x, double& y) {
    x = y = 0.0;
    for (int k = 0; k < p.n; ++k) {
        x += p.v[k].x;
        y += p.v[k].y;
    }
    x /= p.n;
    y /= p.n;
}

// Distance from (x, y) to edge k and the parameter of the nearest point on it.
double edge_distance(const Piece& p, int k, double x, double y, double& t) {
    const PieceVertex &s = p.v[k], &e = p.v[k + 1 == p.n ? 0 : k + 1];
    if (!s.arc) {
        double dx = e.x - s.x, dy = e.y - s.y, len2 = dx * dx + dy * dy;
        t = len2 > 0.0 ? std::min(1.0, std::max(0.0, ((x - s.x) * dx + (y - s.y) * dy) / len2)) : 0.0;
        return std::hypot(s.x + t * dx - x, s.y + t * dy - y);
    }
    double a0 = std::atan2(s.y - p.cy, s.x - p.cx), a1 = std::atan2(e.y - p.cy, e.x - p.cx);
    if (a1 <= a0) a1 += 2.0 * kPi;
    double a = std::atan2(y - p.cy, x - p.cx);
    while (a < a0) a += 2.0 * kPi;
    if (a <= a1) {
        t = (a - a0) / (a1 - a0);
        return std::fabs(std::hypot(x - p.cx, y - p.cy) - p.r);
    }
    double ds = std::hypot(x - s.x, y - s.y), de = std::hypot(x - e.x, y - e.y);
    t = ds < de ? 0.0 : 1.0;
    return std::min(ds, de);
}

// True when (x, y) lies inside the convex piece.
bool inside_piece(const Piece& p, double x, double y) {
    for (int k = 0; k < p.n; ++k) {
        const PieceVertex &s = p.v[k], &e = p.v[k + 1 == p.n ? 0 : k + 1];
        if (s.arc) {
            if (std::hypot(x - p.cx, y - p.cy) > p.r) return false;
        } else if ((e.x - s.x) * (y - s.y) - (e.y - s.y) * (x - s.x) < 0.0) {
            return false;
        }
    }
    return true;
}

// The edge of the piece nearest (x, y): its index (-1 for a piece without edges), distance
// and the parameter t of the nearest point along it.
int nearest_edge(const Piece& p, double x, double y, double& best_d, double& best_t) {
    int best = -1;
    best_d = 1e300;
    best_t = 0.0;
    for (int k = 0; k < p.n; ++k) {
        double t, dist = edge_distance(p, k, x, y, t);
        if (dist < best_d) {
            best_d = dist;
            best = k;
            best_t = t;
        }
    }
    return best;
}

// The vertex of the piece at the point t along edge `best` (which lies within snap of it): an
// end of the edge within snap, else a new vertex inserted there (a copy of the edge's first
// vertex, not mapped, on no boundary, holding no singular or cone point); -1 when the piece
// has no room for one.
int vertex_on_edge(Piece& p, int best, double t, double snap) {
    int next = best + 1 == p.n ? 0 : best + 1;
    double px, py;
    edge_point(p, best, t, px, py);
    if (std::hypot(px - p.v[best].x, py - p.v[best].y) <= snap) return best;
    if (std::hypot(px - p.v[next].x, py - p.v[next].y) <= snap) return next;
    if (p.n >= kPieceVertices) return -1;
    PieceVertex v = p.v[best];
    v.x = px;
    v.y = py;
    v.mapped = false;
    v.snapped = -1;
    v.boundary = false;
    v.cone = -1;
    for (int k = p.n; k > best + 1; --k) p.v[k] = p.v[k - 1];
    p.v[best + 1] = v;
    ++p.n;
    return best + 1;
}

// Put each source singular point that lands in the piece on it: onto the vertex or edge it
// lies on (within kSnap), else mark it for closure.
void place_singular(const SlowPath& sp, Piece& p, bool closure[2]) {
    const double snap = kSnap * std::max({1.0, sp.cv.scale_x, sp.cv.scale_y});
    for (int s = 0; s < sp.sing.count; ++s) {
        double cx, cy, x, y;
        piece_centre(p, cx, cy);
        if (!continued_point(sp.cv.dst, p.cell, sp.sing.out[s], cx, cy, x, y)) continue;
        double best_d, best_t;
        int best = nearest_edge(p, x, y, best_d, best_t);
        if (best < 0) continue;
        if (best_d > snap) {
            if (inside_piece(p, x, y)) closure[s] = true;
            continue;
        }
        int at = vertex_on_edge(p, best, best_t, snap);
        if (at >= 0) p.v[at].snapped = s;
    }
}

// Put each cone point of a folded source (area_map.h) that lands in the piece on the piece's
// boundary, where its image is exact: onto the vertex (within kSnap) or as a new vertex of the
// edge it lies on; a piece that holds one inside is cut in two by the vertical line through
// it, each half taken on its own (the point then lies on the cut). True when the piece was cut
// (and its halves integrated).
bool split_at_cone(SlowPath& sp, Piece& p, int depth) {
    const double snap = kSnap * std::max({1.0, sp.cv.scale_x, sp.cv.scale_y});
    for (int c = 0; c < sp.sing.cones; ++c) {
        double cx, cy, x, y;
        piece_centre(p, cx, cy);
        if (!continued_point(sp.cv.dst, p.cell, sp.sing.cone_out[c], cx, cy, x, y)) continue;
        double best_d, best_t;
        int best = nearest_edge(p, x, y, best_d, best_t);
        if (best < 0) continue;
        if (best_d > snap) {
            if (!inside_piece(p, x, y)) continue;
            for (int side = 0; side < 2; ++side) {
                Piece half;
                clip_piece(p, 1.0, 0.0, x, side == 0, half);
                if (half.n > 0) process_piece(sp, half, depth + 1);
            }
            return true;
        }
        const int n = p.n;
        int at = vertex_on_edge(p, best, best_t, snap);
        if (at < 0) continue;
        p.v[at].cone = c;
        if (p.n > n) {
            // A new vertex: the edge's image bends at the point (a half turn there is a quarter
            // turn in the square), so both halves are refined as fold edges, neither kept as
            // the tile's chord.
            p.v[best].chord = p.v[at].chord = false;
            p.v[best].fold = p.v[at].fold = true;
        }
    }
    return false;
}

// Whether the image of an output segment is straight: its midpoint's image (mx, my) strays
// from the chord (x0, y0) -> (x1, y1) by at most tol output pixels across it (through
// (qx, qy), the image of a step of h output pixels across the segment at its midpoint), and
// is neither a loop nor a bulge (a chord of no length, or a midpoint further off than a
// quarter of the chord: both ends at -Z, say).
bool image_straight(double x0, double y0, double x1, double y1, double mx, double my, double qx,
                    double qy, double h, double tol) {
    double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    double chx = x1 - x0, chy = y1 - y0;
    double off = std::fabs(chx * (my - cy) - chy * (mx - cx));  // |c x (M - C)|
    double scale = std::fabs(chx * (qy - my) - chy * (qx - mx)) / h;  // |c x J n|
    double chord2 = chx * chx + chy * chy;
    bool near = chord2 > 0.0 ? off <= 0.25 * chord2 : (mx == cx && my == cy);
    return near && off <= tol * scale;
}

// refine_segment, for the edges of pieces: straight edges through it (so that a pixel side
// refines as it does in the direct path), arcs by their angle the same way.
bool refine_edge(SlowPath& sp, const Piece& p, int k, int64_t cell, double t0, double x0,
                 double y0, double t1, double x1, double y1, int depth) {
    // The tile's chord holds in the tile's source cell only: in another cell's chart the same
    // side may bend (a tennisball tile whose reference band folds near its pole gave pixels of
    // the other band up to 180 times their solid angle through chords kept there).
    if (p.v[k].chord && p.v[k].side >= 0 && sp.sides && sp.sides[p.v[k].side].cell == cell)
        return true;
    const double tol = p.v[k].fold ? 0.25 * kChordTol : kChordTol;
    if (!p.v[k].arc) {
        double ox0, oy0, ox1, oy1;
        edge_point(p, k, t0, ox0, oy0);
        edge_point(p, k, t1, ox1, oy1);
        return refine_segment(sp.cv, sp.sing, p.cell, ox0, oy0, ox1, oy1, cell, x0, y0, x1, y1, tol,
                              sp.xs, sp.ys, depth);
    }
    if (depth >= kMaxRefine) return true;
    double tm = 0.5 * (t0 + t1), ox, oy;
    edge_point(p, k, tm, ox, oy);
    Vec3 d = output_direction(sp.cv, p.cell, ox, oy);
    if (on_singular(sp.sing, d) >= 0) return true;
    if (source_cell(sp.cv.src, d) != cell) return false;
    double mx, my;
    if (!continued_point(sp.cv.src, cell, d, 0.5 * (x0 + x1), 0.5 * (y0 + y1), mx, my)) return false;
    const double h = 1e-3;
    double r = std::hypot(ox - p.cx, oy - p.cy), qx, qy;  // across an arc: along its radius
    double nx = r > 0.0 ? (ox - p.cx) / r : 1.0, ny = r > 0.0 ? (oy - p.cy) / r : 0.0;
    Vec3 dq = output_direction(sp.cv, p.cell, ox - h * nx, oy - h * ny);
    if (!continued_point(sp.cv.src, cell, dq, mx, my, qx, qy)) return false;
    if (image_straight(x0, y0, x1, y1, mx, my, qx, qy, h, tol)) return true;
    if (!refine_edge(sp, p, k, cell, t0, x0, y0, tm, mx, my, depth + 1)) return false;
    sp.xs.push_back(mx);
    sp.ys.push_back(my);
    return refine_edge(sp, p, k, cell, tm, mx, my, t1, x1, y1, depth + 1);
}

// The source point where edge k leaves (at_end false) or reaches (at_end true) singular point
// s: the limit of its points' positions along the pole's row edge, or around the rim,
// extrapolated from two points near the end.
bool singular_limit(const SlowPath& sp, const Piece& p, int k, bool at_end, int64_t cell, int s,
                    double ref_x, double ref_y, double& x, double& y) {
    double tau = 1e-3;
    for (int it = 0; it < 4; ++it) {
        double ox, oy;
        edge_point(p, k, at_end ? 1.0 - tau : tau, ox, oy);
        double dist = singular_distance(sp.sing, s, output_direction(sp.cv, p.cell, ox, oy));
        if (dist > 0.0) tau = std::min(0.25, std::max(1e-12, tau * 1e-5 / dist));
    }
    double px[2], py[2];
    for (int m = 0; m < 2; ++m) {
        double t = m == 0 ? tau : 0.5 * tau, ox, oy;
        edge_point(p, k, at_end ? 1.0 - t : t, ox, oy);
        Vec3 d = output_direction(sp.cv, p.cell, ox, oy);
        if (!continued_point(sp.cv.src, cell, d, m == 0 ? ref_x : px[0], m == 0 ? ref_y : py[0],
                             px[m], py[m]))
            return false;
    }
    if (sp.sing.kind == 1) {
        SourcePoint q = singular_image(sp.cv.src, sp.sing, cell, s, 2.0 * px[1] - px[0], 0.0);
        x = q.x;
        y = q.y;
        return true;
    }
    double cx, cy, unit;
    cell_disk(sp.cv.src, cell, cx, cy, unit);
    double a0 = std::atan2(py[0] - cy, px[0] - cx), a1 = std::atan2(py[1] - cy, px[1] - cx);
    a0 += 2.0 * kPi * std::nearbyint((a1 - a0) / (2.0 * kPi));
    double a = 2.0 * a1 - a0;
    x = cx + unit * std::cos(a);
    y = cy + unit * std::sin(a);
    return true;
}

// Append the rim arc of a disk source from (x0, y0) through the direction of (xp, yp) to
// (x1, y1) (all on the rim or near it), without its ends.
void append_rim_arc(SlowPath& sp, int64_t cell, double x0, double y0, double xp, double yp,
                    double x1, double y1) {
    double cx, cy, unit;
    cell_disk(sp.cv.src, cell, cx, cy, unit);
    auto near = [](double a, double ref) {
        return a + 2.0 * kPi * std::nearbyint((ref - a) / (2.0 * kPi));
    };
    double a0 = std::atan2(y0 - cy, x0 - cx);
    double ap = near(std::atan2(yp - cy, xp - cx), a0);
    double a1 = near(std::atan2(y1 - cy, x1 - cx), ap);
    int steps = int(std::ceil(std::fabs(a1 - a0) / kRimStep));
    for (int m = 1; m < steps; ++m) {
        double a = a0 + (a1 - a0) * double(m) / double(steps);
        sp.xs.push_back(cx + unit * std::cos(a));
        sp.ys.push_back(cy + unit * std::sin(a));
    }
}

// A source point just inside the piece next to the run of singular vertices first ... last:
// which way the footprint turns around the singular point s (a half turn at a vertex on a
// straight edge cannot tell by itself).
bool singular_probe(const SlowPath& sp, const Piece& p, int first, int last, int64_t cell, int s,
                    double ref_x, double ref_y, double& x, double& y) {
    double mx = 0.5 * (p.v[first].x + p.v[last].x), my = 0.5 * (p.v[first].y + p.v[last].y);
    if (first != last && p.v[first].arc) edge_point(p, first, 0.5, mx, my);
    double cx, cy;
    piece_centre(p, cx, cy);
    double tau = 1e-3, ox = mx, oy = my;
    for (int it = 0; it < 5; ++it) {
        ox = mx + tau * (cx - mx);
        oy = my + tau * (cy - my);
        double dist = singular_distance(sp.sing, s, output_direction(sp.cv, p.cell, ox, oy));
        if (dist > 0.0) tau = std::min(0.5, std::max(1e-12, tau * 1e-5 / dist));
    }
    Vec3 d = output_direction(sp.cv, p.cell, mx + tau * (cx - mx), my + tau * (cy - my));
    return continued_point(sp.cv.src, cell, d, ref_x, ref_y, x, y);
}

// Append the footprint's stretch from the point (x, y) of vertex k over edge k and the run of
// singular vertices after it (k + 1 ... m) to the point of vertex m + 1, exclusive: the edge
// up to the singular point's limit, the singular point's own edge (the pole's row edge, the
// rim arc) and the edge after the run from its limit on. Returns the vertex after the run (or
// -1 on failure).
int append_singular_run(SlowPath& sp, const Piece& p, const VertexFacts& f, int k, int64_t cell,
                        double x, double y) {
    const int n = p.n;
    int first = (k + 1) % n, m = first, len = 1;
    while (f.singular[(m + 1) % n] >= 0 && len < n) {
        m = (m + 1) % n;
        ++len;
    }
    double ix, iy, ox, oy;
    if (!singular_limit(sp, p, k, true, cell, f.singular[first], x, y, ix, iy)) return -1;
    if (!p.v[k].seam && !refine_edge(sp, p, k, cell, 0.0, x, y, 1.0, ix, iy, 0)) return -1;
    sp.xs.push_back(ix);
    sp.ys.push_back(iy);
    double qx, qy;
    if (!singular_probe(sp, p, first, m, cell, f.singular[first], ix, iy, qx, qy)) return -1;
    if (!singular_limit(sp, p, m, false, cell, f.singular[m], qx, qy, ox, oy)) return -1;
    if (sp.sing.kind == 2) append_rim_arc(sp, cell, ix, iy, qx, qy, ox, oy);
    sp.xs.push_back(ox);
    sp.ys.push_back(oy);
    int after = (m + 1) % n;
    double nx, ny;
    if (!vertex_image(sp, p, f, after, cell, ox, oy, nx, ny)) return -1;
    if (!p.v[m].seam && !refine_edge(sp, p, m, cell, 0.0, ox, oy, 1.0, nx, ny, 0)) return -1;
    return after;
}

// Append the points of the tile's polyline for edge k of the piece when the edge is a whole
// side of the pixel that its tile took as a polyline (SidePath mode 2), in `cell`'s
// coordinates (the image of the side's start there is (x, y)); false otherwise.
bool side_path(SlowPath& sp, const Piece& p, int k, int64_t cell, double x, double y) {
    const int side = p.v[k].side;
    if (side < 0 || !sp.sides || sp.sides[side].mode != 2) return false;
    if (p.v[k].cone >= 0 || p.v[(k + 1) % p.n].cone >= 0) return false;  // (cone_reference)
    const PieceVertex &s = p.v[k], &e = p.v[(k + 1) % p.n];
    if (s.x != sp.side_x[side][0] || s.y != sp.side_y[side][0] || e.x != sp.side_x[side][1] ||
        e.y != sp.side_y[side][1])
        return false;  // a part of the side only
    const SidePath& path = sp.sides[side];
    const Geometry& g = sp.cv.src;
    const bool shift = path.cell == cell && g.family != kOctahedral && g.family != kEqualArea;
    double rx = x, ry = y;
    for (size_t m = 0; m < path.px.size(); ++m) {
        double px = path.px[m] + (shift ? x - path.x0 : 0.0), py = path.py[m] + (shift ? y - path.y0 : 0.0);
        if (!shift) {
            Vec3 d = source_direction(g, SourcePoint{path.px[m], path.py[m], path.cell});
            if (!continued_point(g, cell, d, rx, ry, px, py)) return false;
        }
        sp.xs.push_back(px);
        sp.ys.push_back(py);
        rx = px;
        ry = py;
    }
    return true;
}

// Refine the cut from output point (ox0, oy0) to (ox1, oy1) of output cell `ocell`, whose ends
// lie on a source seam (their images in source cell `cell`: (x0, y0) and (x1, y1)), along the
// seam: the point where the seam crosses the cut's perpendicular bisector (by bisection on the
// source cell, within half the cut's length either side) is inserted wherever its image strays
// from the chord by more than kChordTol output pixels, and both halves are refined again.
// Where the bisector meets no change of cell, the chord stays. False when a point has no image
// in `cell`.
bool refine_seam(SlowPath& sp, int64_t ocell, double ox0, double oy0, double ox1, double oy1,
                 int64_t cell, double x0, double y0, double x1, double y1, int depth) {
    if (depth >= kMaxRefine) return true;
    const Conversion& cv = sp.cv;
    const double len = std::hypot(ox1 - ox0, oy1 - oy0);
    if (!(len > 0.0)) return true;
    const double nx = -(oy1 - oy0) / len, ny = (ox1 - ox0) / len, reach = 0.5 * len;
    const double cx = 0.5 * (ox0 + ox1), cy = 0.5 * (oy0 + oy1);
    auto cell_at = [&](double t) {
        return source_cell(cv.src, output_direction(cv, ocell, cx + t * nx, cy + t * ny));
    };
    double lo = -reach, hi = reach;
    const int64_t c_lo = cell_at(lo);
    if (cell_at(hi) == c_lo) return true;
    for (int it = 0; it < 52; ++it) {
        const double t = 0.5 * (lo + hi);
        (cell_at(t) == c_lo ? lo : hi) = t;
    }
    const double t = 0.5 * (lo + hi), ox = cx + t * nx, oy = cy + t * ny, h = 1e-3;
    double mx, my, qx, qy;
    if (!continued_point(cv.src, cell, output_direction(cv, ocell, ox, oy), 0.5 * (x0 + x1),
                         0.5 * (y0 + y1), mx, my))
        return false;
    if (!continued_point(cv.src, cell, output_direction(cv, ocell, ox + h * nx, oy + h * ny), mx,
                         my, qx, qy))
        return false;
    if (image_straight(x0, y0, x1, y1, mx, my, qx, qy, h, kChordTol)) return true;
    if (!refine_seam(sp, ocell, ox0, oy0, ox, oy, cell, x0, y0, mx, my, depth + 1)) return false;
    sp.xs.push_back(mx);
    sp.ys.push_back(my);
    return refine_seam(sp, ocell, ox, oy, ox1, oy1, cell, mx, my, x1, y1, depth + 1);
}

// True when edge k of the piece runs along the rim of a paraboloid source's half `cell`: its
// ends' images (x0, y0) and (x1, y1) there and the image of its midpoint all lie on the rim
// (within 1e-9 of its radius). The rim is the seam between the halves.
bool on_paraboloid_rim(const SlowPath& sp, const Piece& p, int k, int64_t cell, double x0,
                       double y0, double x1, double y1) {
    const Geometry& g = sp.cv.src;
    if (g.family != kParaboloid) return false;
    double cx, cy, unit;
    cell_disk(g, cell, cx, cy, unit);
    auto on_rim = [&](double x, double y) {
        return std::fabs(std::hypot(x - cx, y - cy) - unit) <= 1e-9 * unit;
    };
    if (!on_rim(x0, y0) || !on_rim(x1, y1)) return false;
    double ox, oy, mx, my;
    edge_point(p, k, 0.5, ox, oy);
    Vec3 d = output_direction(sp.cv, p.cell, ox, oy);
    return continued_point(g, cell, d, 0.5 * (x0 + x1), 0.5 * (y0 + y1), mx, my) && on_rim(mx, my);
}

// The reference for the vertex after cone vertex k: every point and its copy turned by half
// a turn about the cone point lie equally far from it, so the next vertex cannot be placed
// near the cone's image. Probes inside the piece close to the cone, swept in eight steps from
// its edge before to its edge after, each placed near the one before (from (prev_x, prev_y),
// the footprint's point before the cone), carry the side across: a step turns by an eighth of
// the piece's corner at most (a quarter turn in the source, where the output's own map is
// folded there too), and the last lies beside the edge after.
bool cone_reference(const SlowPath& sp, const Piece& p, int k, int64_t cell, double prev_x,
                    double prev_y, double& x, double& y) {
    const int before = (k + p.n - 1) % p.n;
    const double px = p.v[k].x, py = p.v[k].y;
    double ax, ay, bx, by;
    edge_point(p, before, 1.0 - 1e-3, ax, ay);
    edge_point(p, k, 1e-3, bx, by);
    const double r = 0.5 * std::min(std::hypot(ax - px, ay - py), std::hypot(bx - px, by - py));
    if (!(r > 0.0)) return false;
    const double a0 = std::atan2(ay - py, ax - px), a1 = std::atan2(by - py, bx - px);
    // The piece runs with a positive shoelace area: its inside turns from the edge after to
    // the edge before by increasing angle.
    double turn = a0 - a1;
    turn -= 2.0 * kPi * std::floor(turn / (2.0 * kPi));
    x = prev_x;
    y = prev_y;
    const int steps = 8;
    for (int m = 1; m < steps; ++m) {
        const double ang = a0 - turn * double(m) / double(steps);
        Vec3 d = output_direction(sp.cv, p.cell, px + r * std::cos(ang), py + r * std::sin(ang));
        double qx, qy;
        if (!continued_point(sp.cv.src, cell, d, x, y, qx, qy)) return false;
        x = qx;
        y = qy;
    }
    return true;
}

// The footprint of the piece in source cell `cell`, into sp.xs, sp.ys; false when it cannot
// be built there (a vertex without a point in the cell, an edge that leaves it).
bool build_footprint(SlowPath& sp, const Piece& p, const VertexFacts& f, int64_t cell) {
    sp.xs.clear();
    sp.ys.clear();
    const int n = p.n;
    int k0 = 0;
    while (k0 < n && (f.singular[k0] >= 0 || p.v[k0].cone >= 0)) ++k0;
    if (k0 == n) return false;
    double rx = p.v[k0].mapped ? p.v[k0].src.x : 0.0, ry = p.v[k0].mapped ? p.v[k0].src.y : 0.0;
    if (!p.v[k0].mapped) {
        SourcePoint s = source_of(sp.cv.src, f.dir[k0]);
        rx = s.x;
        ry = s.y;
    }
    int k = k0;
    bool placed = false;  // (hx, hy): vertex k's point, as the edge before it placed it
    double hx = 0.0, hy = 0.0;
    do {
        double x = hx, y = hy;
        if (!placed && !vertex_image(sp, p, f, k, cell, rx, ry, x, y)) return false;
        placed = false;
        sp.xs.push_back(x);
        sp.ys.push_back(y);
        int next = (k + 1) % n;
        if (f.singular[next] >= 0) {
            k = append_singular_run(sp, p, f, k, cell, x, y);
            if (k < 0) return false;
        } else {
            double nx, ny, ref_x = x, ref_y = y;
            if (p.v[k].cone >= 0) {
                // The last point of the footprint off the cone's image.
                size_t m = sp.xs.size() - 1;
                while (m > 0 && std::hypot(sp.xs[m] - x, sp.ys[m] - y) <= 1e-9 * (1.0 + std::fabs(x))) --m;
                if (!cone_reference(sp, p, k, cell, sp.xs[m], sp.ys[m], ref_x, ref_y)) return false;
            }
            if (!vertex_image(sp, p, f, next, cell, ref_x, ref_y, nx, ny)) return false;
            // An edge between two vertices on one cone point (a rim arc over it) is that point.
            const bool collapsed = p.v[k].cone >= 0 && p.v[next].cone == p.v[k].cone;
            if ((p.v[k].seam && sp.cv.src.family == kParaboloid) ||
                on_paraboloid_rim(sp, p, k, cell, x, y, nx, ny)) {
                // A cut between a paraboloid's halves, or a side of the pixel along it, runs
                // along their shared rim, a circle in either half, not along a chord or the
                // tile's parabola: the chord left a circular segment of the other half inside
                // the footprint (a pixel whose side lay on the rim took up to 15 % of its
                // colour from the other half; the parabola, 0.25 %).
                append_rim_arc(sp, cell, x, y, 0.5 * (x + nx), 0.5 * (y + ny), nx, ny);
            } else if (p.v[k].seam && sp.cv.src.family == kTennisball) {
                // Where a tennisball's bands meet, the seam is curved in either band: the cut
                // follows it (a pixel across it took up to 1.2 % of its solid angle from the
                // wrong band along the chord).
                if (!refine_seam(sp, p.cell, p.v[k].x, p.v[k].y, p.v[next].x, p.v[next].y, cell, x,
                                 y, nx, ny, 0))
                    return false;
            } else if (!p.v[k].seam && !collapsed && !side_path(sp, p, k, cell, x, y) &&
                       !refine_edge(sp, p, k, cell, 0.0, x, y, 1.0, nx, ny, 0)) {
                return false;
            }
            // After a cone the next vertex keeps the point placed here (near the probe); the
            // points after it are not ambiguous.
            placed = p.v[k].cone >= 0;
            hx = nx;
            hy = ny;
            k = next;
        }
        rx = sp.xs.back();
        ry = sp.ys.back();
    } while (k != k0);
    return true;
}

// Close a footprint around singular point s inside its piece: around a lat-long pole, the
// outline's columns have drifted by a whole turn, and the pole's row edge closes it; around
// -Z of a disk, the outline circles the rim, and the footprint is what lies between the two
// (the rim traversed against the outline). False when the outline does not wind as it should.
bool close_around_singular(SlowPath& sp, int64_t cell, int s) {
    const Geometry& g = sp.cv.src;
    size_t n = sp.xs.size();
    if (sp.sing.kind == 1) {
        double period = double(2 * g.n), jump = sp.xs[0] - sp.xs[n - 1];
        double drift = -period * std::nearbyint(jump / period);
        if (drift == 0.0) return false;
        double pole = singular_image(g, sp.sing, cell, s, 0.0, 0.0).y;
        double x0 = sp.xs[0], y0 = sp.ys[0];
        sp.xs.insert(sp.xs.end(), {x0 + drift, x0 + drift, x0});
        sp.ys.insert(sp.ys.end(), {y0, pole, pole});
        return true;
    }
    double cx, cy, unit;
    cell_disk(g, cell, cx, cy, unit);
    double turn = 0.0;
    for (size_t k = 0; k < n; ++k) {
        size_t l = (k + 1) % n;
        double da = std::atan2(sp.ys[l] - cy, sp.xs[l] - cx) - std::atan2(sp.ys[k] - cy, sp.xs[k] - cx);
        turn += da - 2.0 * kPi * std::nearbyint(da / (2.0 * kPi));
    }
    if (std::fabs(turn) < kPi) return false;
    double a0 = std::atan2(sp.ys[0] - cy, sp.xs[0] - cx), step = turn > 0.0 ? -1.0 : 1.0;
    int steps = int(std::ceil(2.0 * kPi / kRimStep));
    sp.xs.push_back(sp.xs[0]);
    sp.ys.push_back(sp.ys[0]);
    for (int m = 0; m <= steps; ++m) {
        double a = a0 + step * 2.0 * kPi * double(m) / double(steps);
        sp.xs.push_back(cx + unit * std::cos(a));
        sp.ys.push_back(cy + unit * std::sin(a));
    }
    return true;
}

// Cut the piece where its edges cross from one source cell to another (bisection), along the
// chord between the two crossings; false unless there are exactly two.
bool split_at_seam(SlowPath& sp, const Piece& p, const VertexFacts& f, int depth) {
    Piece q = p;
    q.n = 0;
    int cross[2], count = 0;
    for (int k = 0; k < p.n; ++k) {
        if (q.n >= kPieceVertices - 1) return false;
        q.v[q.n++] = p.v[k];
        int next = (k + 1) % p.n;
        if (f.singular[k] >= 0 || f.singular[next] >= 0 || p.v[k].boundary ||
            p.v[next].boundary || f.cell[k] == f.cell[next])
            continue;
        double lo = 0.0, hi = 1.0;
        for (int it = 0; it < 52; ++it) {
            double t = 0.5 * (lo + hi), ox, oy;
            edge_point(p, k, t, ox, oy);
            int64_t c = source_cell(sp.cv.src, output_direction(sp.cv, p.cell, ox, oy));
            (c == f.cell[k] ? lo : hi) = t;
        }
        PieceVertex v = p.v[k];
        edge_point(p, k, 0.5 * (lo + hi), v.x, v.y);
        v.mapped = false;
        v.boundary = true;
        v.snapped = -1;
        v.cone = -1;
        if (count == 2) return false;
        cross[count++] = q.n;
        q.v[q.n++] = v;
    }
    if (count != 2) return false;
    for (int side = 0; side < 2; ++side) {
        Piece part = q;
        part.n = 0;
        int from = cross[side], to = cross[1 - side];
        for (int k = from;; k = (k + 1) % q.n) {
            part.v[part.n++] = q.v[k];
            if (k == to) break;
        }
        part.v[part.n - 1].arc = false;
        part.v[part.n - 1].seam = true;
        process_piece(sp, part, depth + 1);
    }
    return true;
}

// Split the piece in four at the middle of its bounding box.
void split_in_four(SlowPath& sp, const Piece& p, int depth) {
    double x0 = p.v[0].x, x1 = x0, y0 = p.v[0].y, y1 = y0;
    for (int k = 1; k < p.n; ++k) {
        x0 = std::min(x0, p.v[k].x);
        x1 = std::max(x1, p.v[k].x);
        y0 = std::min(y0, p.v[k].y);
        y1 = std::max(y1, p.v[k].y);
    }
    double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
    for (int q = 0; q < 4; ++q) {
        Piece half, quarter;
        clip_piece(p, 1.0, 0.0, xm, q % 2 == 0, half);
        if (half.n == 0) continue;
        clip_piece(half, 0.0, 1.0, ym, q / 2 == 0, quarter);
        if (quarter.n == 0) continue;
        process_piece(sp, quarter, depth + 1);
    }
}

// True when the piece (straight edges only) covers at most kTinyPiece of an output pixel.
bool tiny_piece(const SlowPath& sp, const Piece& p) {
    double area = 0.0;
    for (int k = 0; k < p.n; ++k) {
        const PieceVertex &s = p.v[k], &e = p.v[(k + 1) % p.n];
        if (s.arc) return false;
        area += s.x * e.y - e.x * s.y;
    }
    return 0.5 * std::fabs(area) <= kTinyPiece * sp.cv.scale_x * sp.cv.scale_y;
}

// A piece that did not resolve: split in four, or read at its centre at once where it is tiny
// (its quarters would hold no more, and a sliver along a seam, which no cell's footprint
// holds, would otherwise split down to kMaxPieceDepth: 4^8 leftovers).
void split_or_leftover(SlowPath& sp, const Piece& p, int depth) {
    if (tiny_piece(sp, p)) add_leftover(sp, p);
    else split_in_four(sp, p, depth);
}

// Integrate one piece of an output pixel into the pixel's sums.
void process_piece(SlowPath& sp, Piece& p, int depth) {
    if (p.n < 2) return;
    if (depth > kMaxPieceDepth) {
        add_leftover(sp, p);
        return;
    }
    if (split_at_cone(sp, p, depth)) return;
    bool closure[2] = {false, false};
    place_singular(sp, p, closure);
    VertexFacts f;
    vertex_facts(sp, p, f);
    int64_t cell = -1;
    bool several = false, seen = false;  // not cell < 0: kUncovered (-2) is a cell here
    for (int k = 0; k < p.n; ++k) {
        if (f.singular[k] >= 0 || p.v[k].boundary) continue;
        if (!seen) cell = f.cell[k];
        else if (f.cell[k] != cell) several = true;
        seen = true;
    }
    if (several) {
        if (!split_at_seam(sp, p, f, depth)) split_or_leftover(sp, p, depth);
        return;
    }
    if (cell < 0) {
        double cx, cy;
        piece_centre(p, cx, cy);
        cell = source_cell(sp.cv.src, output_direction(sp.cv, p.cell, cx, cy));
    }
    if (cell == kUncovered) {
        add_leftover(sp, p, false);
        return;
    }
    bool built = build_footprint(sp, p, f, cell);
    for (int s = 0; built && s < 2; ++s)
        if (closure[s]) built = close_around_singular(sp, cell, s);
    if (!built) {
        split_or_leftover(sp, p, depth);
        return;
    }
    if (partial_source(sp.cv.src)) sp.out_weight += piece_solid_angle(sp, p);
    add_footprint(sp, cell);
}

// The rectangle [x0, x1] x [y0, y1] of output cell `cell` as a piece, its corners carrying
// `corners` (the pixel's own corners, in the order (x0, y0), (x1, y0), (x1, y1), (x0, y1))
// where they are the pixel's.
// Whether each side of the output rectangle [x0, x1] x [y0, y1] of `cell` (from corner k, in
// the order (x0, y0), (x1, y0), (x1, y1), (x0, y1), to corner k + 1) touches a fold:
// edge_on_fold of its corners' points (`corners` when given, else mapped exactly).
void fold_sides(const SlowPath& sp, int64_t cell, double x0, double y0, double x1, double y1,
                const SourcePoint* corners, bool fold[4]) {
    const Geometry &d = sp.cv.dst, &g = sp.cv.src;
    const bool folds = d.family == kOctahedral || d.family == kEqualArea ||
                       g.family == kOctahedral || g.family == kEqualArea;
    const double xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
    SourcePoint p[4];
    for (int k = 0; k < 4; ++k) {
        fold[k] = false;
        if (folds) p[k] = corners ? corners[k] : exact_source(sp.cv, cell, xs[k], ys[k]);
    }
    for (int k = 0; folds && k < 4; ++k) {
        int l = (k + 1) % 4;
        fold[k] = edge_on_fold(sp.cv, cell, xs[k], ys[k], xs[l], ys[l], p[k], p[l]);
    }
}

// Mark each straight edge of the piece that runs along a side of the rectangle [x0, x1] x
// [y0, y1] with that side's fold flag, and as a chord where its tile decided so (`sides`);
// other edges (arcs, cuts) are left as they are.
void mark_sides(Piece& p, double x0, double y0, double x1, double y1, const bool fold[4],
                const SidePath* sides = nullptr) {
    for (int k = 0; k < p.n; ++k) {
        PieceVertex &s = p.v[k], &e = p.v[(k + 1) % p.n];
        if (s.arc) continue;
        int side = -1;
        if (s.y == y0 && e.y == y0) side = 0;
        else if (s.x == x1 && e.x == x1) side = 1;
        else if (s.y == y1 && e.y == y1) side = 2;
        else if (s.x == x0 && e.x == x0) side = 3;
        if (side < 0) continue;
        s.fold = fold[side];
        s.chord = sides && sides[side].mode == 0;
        s.side = sides ? side : -1;
    }
}

Piece rect_piece(int64_t cell, double x0, double y0, double x1, double y1,
                 const SourcePoint* corners, const double* pixel) {
    Piece p;
    p.cell = cell;
    p.cx = p.cy = p.r = 0.0;
    p.n = 4;
    const double xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
    for (int k = 0; k < 4; ++k) {
        p.v[k] = plain_vertex(xs[k], ys[k]);
        if (corners && corners[k].cell >= 0 && xs[k] == pixel[k == 1 || k == 2 ? 2 : 0] &&
            ys[k] == pixel[k >= 2 ? 3 : 1]) {
            p.v[k].mapped = true;
            p.v[k].src = corners[k];
        }
    }
    return p;
}

// The readable part of a disk cell's rectangle: inside the readable circle (everything with
// --guard fill), as one piece for a paraboloid; for a mirror ball or an angular map, whose
// rim circle maps to the single direction -Z, the valid disk as one piece and the guard ring
// around it as 4 x 4 centre samples.
void disk_pieces(SlowPath& sp, int64_t cell, double x0, double y0, double x1, double y1) {
    const Geometry& d = sp.cv.dst;
    double cx, cy, unit;
    cell_disk(d, cell, cx, cy, unit);
    double readable = unit + double(d.guard);
    bool singular_rim = rim_singular(d);
    Piece p;
    p.cell = cell;
    p.cx = cx;
    p.cy = cy;
    p.r = singular_rim ? unit : readable;
    if (sp.cv.fill && !singular_rim) {
        p = rect_piece(cell, x0, y0, x1, y1, nullptr, nullptr);
    } else {
        clip_square_to_circle(x0, y0, x1, y1, cx, cy, p.r, p);
    }
    if (p.n > 0) {
        bool fold[4];
        fold_sides(sp, cell, x0, y0, x1, y1, nullptr, fold);
        mark_sides(p, x0, y0, x1, y1, fold);
        process_piece(sp, p, 0);
    }
    if (!singular_rim || (d.guard == 0 && !sp.cv.fill)) return;
    const int sub = 4;
    for (int q = 0; q < sub * sub; ++q) {
        double qx0 = x0 + (x1 - x0) * double(q % sub) / sub, qx1 = qx0 + (x1 - x0) / sub;
        double qy0 = y0 + (y1 - y0) * double(q / sub) / sub, qy1 = qy0 + (y1 - y0) / sub;
        double r = std::hypot(0.5 * (qx0 + qx1) - cx, 0.5 * (qy0 + qy1) - cy);
        if (r <= unit || (!sp.cv.fill && r > readable)) continue;
        add_leftover(sp, rect_piece(cell, qx0, qy0, qx1, qy1, nullptr, nullptr));
    }
}

}  // namespace

bool refine_segment(const Conversion& cv, const Singular& sing, int64_t ocell, double ox0,
                    double oy0, double ox1, double oy1, int64_t cell, double x0, double y0,
                    double x1, double y1, double tol, std::vector<double>& xs,
                    std::vector<double>& ys, int depth) {
    if (depth >= kMaxRefine) return true;
    const double ox = 0.5 * (ox0 + ox1), oy = 0.5 * (oy0 + oy1), h = 1e-3;
    Vec3 d = output_direction(cv, ocell, ox, oy);
    if (on_singular(sing, d) >= 0) return true;
    if (source_cell(cv.src, d) != cell) return false;
    double mx, my, qx, qy;
    if (!continued_point(cv.src, cell, d, 0.5 * (x0 + x1), 0.5 * (y0 + y1), mx, my)) return false;
    double len = std::hypot(ox1 - ox0, oy1 - oy0);
    double nx = len > 0.0 ? -(oy1 - oy0) / len : 0.0, ny = len > 0.0 ? (ox1 - ox0) / len : 1.0;
    Vec3 dq = output_direction(cv, ocell, ox + h * nx, oy + h * ny);
    if (!continued_point(cv.src, cell, dq, mx, my, qx, qy)) return false;
    if (image_straight(x0, y0, x1, y1, mx, my, qx, qy, h, tol)) return true;
    if (!refine_segment(cv, sing, ocell, ox0, oy0, ox, oy, cell, x0, y0, mx, my, tol, xs, ys, depth + 1))
        return false;
    xs.push_back(mx);
    ys.push_back(my);
    return refine_segment(cv, sing, ocell, ox, oy, ox1, oy1, cell, mx, my, x1, y1, tol, xs, ys, depth + 1);
}

void slow_rect_pieces(SlowPath& sp, double x0, double y0, double x1, double y1,
                      const SourcePoint* corners, const SidePath* sides);

// Every output cell that the rectangle [x0, x1] x [y0, y1] (level-0 output pixels) meets,
// with the rectangle's part in it: visit(cell, ax, ay, bx, by).
template <class Visit>
void rect_cells(const Geometry& d, double x0, double y0, double x1, double y1, Visit&& visit) {
    const double cw = double(d.cell_width()), ch = double(d.cell_height());
    int64_t col0 = std::max<int64_t>(0, floor_index(x0 / cw));
    int64_t col1 = std::min<int64_t>(d.columns - 1, floor_index(std::nextafter(x1, x0) / cw));
    int64_t row0 = std::max<int64_t>(0, floor_index(y0 / ch));
    int64_t row1 = std::min<int64_t>(d.rows - 1, floor_index(std::nextafter(y1, y0) / ch));
    for (int64_t row = row0; row <= row1; ++row) {
        for (int64_t col = col0; col <= col1; ++col) {
            double ax = std::max(x0, double(col) * cw), bx = std::min(x1, double(col + 1) * cw);
            double ay = std::max(y0, double(row) * ch), by = std::min(y1, double(row + 1) * ch);
            if (bx > ax && by > ay) visit(row * d.columns + col, ax, ay, bx, by);
        }
    }
}

// The output pieces of the rectangle [x0, x1] x [y0, y1] in every output cell it meets, as
// slow_rect_pieces takes them (a disk cell's clipped to its readable circle unless `whole`),
// passed to visit(piece).
template <class Visit>
void output_pieces(const SlowPath& sp, double x0, double y0, double x1, double y1, bool whole,
                   Visit&& visit) {
    const Geometry& d = sp.cv.dst;
    rect_cells(d, x0, y0, x1, y1, [&](int64_t cell, double ax, double ay, double bx, double by) {
        if (d.cell_face[cell] < 0) {
            if (sp.cv.fill)
                visit(rect_piece(nearest_cell(d, 0.5 * (ax + bx), 0.5 * (ay + by)), ax, ay, bx, by, nullptr, nullptr));
        } else if (d.disk() && !sp.cv.fill && !whole) {
            double cx, cy, unit;
            cell_disk(d, cell, cx, cy, unit);
            Piece p;
            p.cell = cell;
            clip_square_to_circle(ax, ay, bx, by, cx, cy, unit + double(d.guard), p);
            if (p.n > 0) visit(p);
        } else {
            visit(rect_piece(cell, ax, ay, bx, by, nullptr, nullptr));
        }
    });
}

// A last check of the general path: the footprints it built for the rectangle must hold the
// rectangle's own output solid angle. Where they are off by more than kFootprintCheck of the
// rectangle's solid angle, a construction failed where singular features meet (measured: a
// mirror ball's -Z on an odd octahedral square's edge midpoint, whose pixel took the whole
// sphere; a cube edge across an odd equal-area square's axis, 24 % too much; a lat-long pole
// on an odd paraboloid's rim pixel, 2.7 times; a tennisball seam's kinks in a 20 px angular
// map, 6.5 %), and the rectangle is read instead as 32 x 32 sub-rectangles, each at its
// centre with its own solid angle: a supersampled mean, not exact, but of the right region
// (0.6 % off the box's mean where the texels under it vary by a factor of three, against
// 126 % before). A handful of pixels an image at most: a sweep of every whole-sphere input
// into eight outputs at 20 and 33 px fell back 23 times, each at one of these, and correct
// pixels stay within 1.1 % (an octahedral input's linear density model at 24 px). Not near a
// sphere or angular output's singular rim, which has its own ring logic, nor for partial
// sources (whose weight is the output's already).
constexpr double kFootprintCheck = 0.03;

void check_rect(SlowPath& sp, double x0, double y0, double x1, double y1) {
    const Geometry& d = sp.cv.dst;
    if (partial_source(sp.cv.src)) return;
    if (rim_singular(d)) {  // only well inside a mirror ball's or angular map's disk
        const Located at = locate(d, 0.5 * (x0 + x1), 0.5 * (y0 + y1));
        if (at.cell < 0 || d.cell_face[at.cell] < 0) return;
        double cx, cy, unit;
        cell_disk(d, at.cell, cx, cy, unit);
        const double fx = std::max(std::fabs(x0 - cx), std::fabs(x1 - cx));
        const double fy = std::max(std::fabs(y0 - cy), std::fabs(y1 - cy));
        if (fx * fx + fy * fy > 0.9 * 0.9 * unit * unit) return;
    }
    double expected = 0.0, scale = 0.0;
    output_pieces(sp, x0, y0, x1, y1, false, [&](const Piece& p) { expected += piece_solid_angle(sp, p); });
    output_pieces(sp, x0, y0, x1, y1, true, [&](const Piece& p) { scale += piece_solid_angle(sp, p); });
    const double got = sp.sums->weight;
    if (!(expected > 0.0) || std::fabs(got - expected) <= kFootprintCheck * std::max(expected, scale)) return;
    std::fill(sp.sums->acc, sp.sums->acc + sp.sums->nch, 0.0);
    sp.sums->weight = 0.0;
    const int sub = 32;
    for (int q = 0; q < sub * sub; ++q) {
        const double qx0 = x0 + (x1 - x0) * double(q % sub) / sub, qx1 = x0 + (x1 - x0) * double(q % sub + 1) / sub;
        const double qy0 = y0 + (y1 - y0) * double(q / sub) / sub, qy1 = y0 + (y1 - y0) * double(q / sub + 1) / sub;
        output_pieces(sp, qx0, qy0, qx1, qy1, false, [&](const Piece& p) { add_leftover(sp, p); });
    }
}

void slow_rect(SlowPath& sp, double x0, double y0, double x1, double y1,
               const SourcePoint* corners, const SidePath* sides) {
    sp.out_weight = 0.0;
    sp.uncovered = false;
    slow_rect_pieces(sp, x0, y0, x1, y1, corners, sides);
    if (sp.uncovered && sp.out_weight > 0.0) sp.sums->weight = sp.out_weight;
    check_rect(sp, x0, y0, x1, y1);
}

void slow_rect_pieces(SlowPath& sp, double x0, double y0, double x1, double y1,
                      const SourcePoint* corners, const SidePath* sides) {
    sp.sides = sides;
    const double cx[4] = {x0, x1, x1, x0}, cy[4] = {y0, y0, y1, y1};
    for (int k = 0; k < 4; ++k) {
        sp.side_x[k][0] = cx[k];
        sp.side_y[k][0] = cy[k];
        sp.side_x[k][1] = cx[(k + 1) % 4];
        sp.side_y[k][1] = cy[(k + 1) % 4];
    }
    const Geometry& d = sp.cv.dst;
    const double pixel[4] = {x0, y0, x1, y1};
    rect_cells(d, x0, y0, x1, y1, [&](int64_t cell, double ax, double ay, double bx, double by) {
        if (d.cell_face[cell] < 0) {
            if (!sp.cv.fill) return;
            // An empty cell under --guard fill: its nearest face's continued mapping.
            int64_t near = nearest_cell(d, 0.5 * (ax + bx), 0.5 * (ay + by));
            Piece p = rect_piece(near, ax, ay, bx, by, nullptr, nullptr);
            process_piece(sp, p, 0);
        } else if (d.disk()) {
            disk_pieces(sp, cell, ax, ay, bx, by);
        } else {
            Piece p = rect_piece(cell, ax, ay, bx, by, corners, pixel);
            bool fold[4];
            const bool whole = ax == x0 && ay == y0 && bx == x1 && by == y1;
            fold_sides(sp, cell, ax, ay, bx, by, whole ? corners : nullptr, fold);
            mark_sides(p, ax, ay, bx, by, fold, whole ? sides : nullptr);
            process_piece(sp, p, 0);
        }
    });
}

}  // namespace envconv
