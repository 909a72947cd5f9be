// Cell bookkeeping: image point <-> (face, a, b).
//
// A layout is a grid of columns x rows equal cells; each occupied cell holds one face, stored
// unturned or turned by 180 degrees. With characteristic size N, a cell N_x = A N pixels wide
// (A the cell aspect; a perspective view's own width) and guard G a cell is (N_x + 2G) x
// (N + 2G) pixels. Image points are level-0 pixels: x right, y down, pixel (i, j) spans
// [i, i+1) x [j, j+1). Inside a cell whose top-left pixel is (x0, y0):
//   a = 2 (x - x0 - G) / N_x - 1,   b = 2 (y - y0 - G) / N - 1.
#pragma once

#include <cmath>
#include <cstdint>

#include "layouts.h"

namespace envconv {

// Tolerance of the validity test: rim directions land at R^2 = 1 + O(1e-16).
constexpr double kOnEdge = 1e-9;

// One layout instance: the Python side's geo = [family, N, G, N_x, columns, rows, parameters]
// (the chart: family and parameters) plus the tables cell -> face (-1: empty), cell -> half
// turns (0 or 2), face -> cell.
struct Geometry : Chart {
    int64_t n, guard, nx, columns, rows;
    const int32_t* cell_face;
    const int32_t* cell_turns;
    const int32_t* face_cell;

    int64_t cell_width() const { return nx + 2 * guard; }
    int64_t cell_height() const { return n + 2 * guard; }
    bool disk() const { return is_disk(family); }
};

struct Located {
    int face;
    double a, b;
    int64_t cell;
};

struct ImagePoint {
    double x, y;
    int64_t cell;
};

// Local (a, b) of image point (px, py) in the frame of `cell`, continued past it.
inline void cell_local(const Geometry& g, int64_t cell, double px, double py, double& a,
                       double& b) {
    int64_t col = cell % g.columns, row = cell / g.columns;
    a = 2.0 * (px - double(col * g.cell_width() + g.guard)) / double(g.nx) - 1.0;
    b = 2.0 * (py - double(row * g.cell_height() + g.guard)) / double(g.n) - 1.0;
    if (g.cell_turns[cell] == 2) {
        a = -a;
        b = -b;
    }
}

// (face, a, b, cell) of image point (px, py); face is -1 in an empty cell.
inline Located locate(const Geometry& g, double px, double py) {
    int64_t col = floor_index(px / double(g.cell_width()));
    int64_t row = floor_index(py / double(g.cell_height()));
    col = col < 0 ? 0 : (col > g.columns - 1 ? g.columns - 1 : col);
    row = row < 0 ? 0 : (row > g.rows - 1 ? g.rows - 1 : row);
    Located out;
    out.cell = row * g.columns + col;
    cell_local(g, out.cell, px, py, out.a, out.b);
    out.face = g.cell_face[out.cell];
    return out;
}

// Image point and cell of local point (a, b) of `face`.
inline ImagePoint face_to_image(const Geometry& g, int face, double a, double b) {
    int64_t cell = g.face_cell[face];
    if (g.cell_turns[cell] == 2) {
        a = -a;
        b = -b;
    }
    int64_t col = cell % g.columns, row = cell / g.columns;
    double px = double(col * g.cell_width() + g.guard) + 0.5 * (a + 1.0) * double(g.nx);
    double py = double(row * g.cell_height() + g.guard) + 0.5 * (b + 1.0) * double(g.n);
    return {px, py, cell};
}

// True when (a, b) of `face` lies in the valid region (not guard).
inline bool point_valid(const Geometry& g, int face, double a, double b) {
    if (face < 0) return false;
    if (g.disk()) return a * a + b * b <= 1.0 + kOnEdge;
    return std::fabs(a) <= 1.0 + kOnEdge && std::fabs(b) <= 1.0 + kOnEdge;
}

// True when (a, b) holds data: the valid region or the guard ring around it.
inline bool point_readable(const Geometry& g, int face, double a, double b) {
    if (face < 0) return false;
    if (g.disk()) {
        double r = 1.0 + 2.0 * double(g.guard) / double(g.n);
        return a * a + b * b <= r * r + kOnEdge;
    }
    return true;
}

// Cell whose valid region is nearest to (px, py) in pixels; ties go to the lower face.
inline int64_t nearest_cell(const Geometry& g, double px, double py) {
    double cw = double(g.cell_width()), ch = double(g.cell_height());
    double n = double(g.n), an = double(g.nx);
    int64_t best_cell = -1;
    int best_face = 1 << 30;
    double best_d = 1e300;
    for (int64_t cell = 0; cell < g.columns * g.rows; ++cell) {
        int face = g.cell_face[cell];
        if (face < 0) continue;
        double x0 = double(cell % g.columns) * cw + double(g.guard);
        double y0 = double(cell / g.columns) * ch + double(g.guard);
        double d;
        if (g.disk()) {
            double dx = px - (x0 + 0.5 * n), dy = py - (y0 + 0.5 * n);
            d = std::max(std::sqrt(dx * dx + dy * dy) - 0.5 * n, 0.0);
        } else {
            double dx = std::max({x0 - px, 0.0, px - (x0 + an)});
            double dy = std::max({y0 - py, 0.0, py - (y0 + n)});
            d = std::sqrt(dx * dx + dy * dy);
        }
        if (d < best_d || (d == best_d && face < best_face)) {
            best_cell = cell;
            best_face = face;
            best_d = d;
        }
    }
    return best_cell;
}

// An output sample: where it lands, whether it holds data, whether it is in the valid region.
struct OutputSample {
    int face;
    double a, b;
    bool readable, valid;
};

// (face, a, b, readable, valid) of output image point (px, py); `fill` extends readability to
// every pixel, through the continued mapping of its nearest cell.
inline OutputSample output_sample(const Geometry& g, double px, double py, bool fill) {
    Located at = locate(g, px, py);
    bool valid = point_valid(g, at.face, at.a, at.b);
    if (valid || point_readable(g, at.face, at.a, at.b)) return {at.face, at.a, at.b, true, valid};
    if (!fill) return {at.face, at.a, at.b, false, false};
    int64_t cell = nearest_cell(g, px, py);
    OutputSample s{g.cell_face[cell], 0.0, 0.0, true, false};
    cell_local(g, cell, px, py, s.a, s.b);
    return s;
}

// A 3 x 3 rotation, row-major: output direction -> source direction.
struct Rotation {
    double m[9];
    Vec3 apply(const Vec3& d) const {
        return {m[0] * d.x + m[1] * d.y + m[2] * d.z, m[3] * d.x + m[4] * d.y + m[5] * d.z,
                m[6] * d.x + m[7] * d.y + m[8] * d.z};
    }
};

// Source image point and cell of output point (a, b) of `face` (output chart `dfam`).
inline ImagePoint source_point(const Geometry& src, const Chart& dfam, int face, double a,
                               double b, const Rotation& rot) {
    Vec3 d = rot.apply(face_to_dir(dfam, face, a, b));
    FacePoint s = dir_to_face(src, d.x, d.y, d.z);
    return face_to_image(src, s.face, s.a, s.b);
}

}  // namespace envconv
