// Interpolated tiles of the resampling kernel: map a tile's 3 x 3 grid, check it, and tell
// whether a block of output pixels lies in one cell.
//
// Tiles of kTile x kTile output pixels (kTile / 2 when a cell is too small; see
// kMinTilesPerCell) map a 3 x 3 grid of points exactly (corners, edge midpoints, centre); the
// source position and weight of every sub-sample inside is interpolated biquadratically from
// them. The map is then checked exactly at the four quarter points, where the cubic error of
// that interpolation is near its largest. If a check is more than kInterpTolerance source
// texels off (a seam, a pole, a wrap, strong curvature), or a grid point lands in another
// source cell, the tile splits into four quarters that try again, down to kMinSubtile pixels;
// a block that still fails maps every sub-sample exactly. At 0.01 texel a sub-sample's read is
// off by at most 1% of the difference between neighbouring texels. Weights (the output
// layout's solid-angle density) are checked to kWeightTolerance, relative.
#pragma once

#include <cmath>

#include "cells.h"

namespace envconv {

constexpr int kTile = 16;
constexpr int kMinSubtile = 2;
constexpr double kInterpTolerance = 0.01;
constexpr double kWeightTolerance = 1e-3;
constexpr int kMinTilesPerCell = 8;

// True when the level-0 box [x0, x1) x [y0, y1) lies in one cell that holds no face.
inline bool tile_in_empty_cell(const Geometry& d, double x0, double y0, double x1, double y1) {
    Located first = locate(d, x0, y0);
    if (first.face >= 0) return false;
    Located last = locate(d, std::nextafter(x1, x0), std::nextafter(y1, y0));
    return last.cell == first.cell;
}

// The face of the cell when the level-0 box [x0, x1] x [y0, y1] lies in that cell's valid
// region, else -1 (cell set either way). The valid region is convex (a rectangle or a disk),
// so checking the four corners suffices.
inline int tile_face(const Geometry& d, double x0, double y0, double x1, double y1,
                     int64_t& cell) {
    Located first = locate(d, x0, y0);
    cell = first.cell;
    if (first.face < 0 || !point_valid(d, first.face, first.a, first.b)) return -1;
    double xe = std::nextafter(x1, x0), ye = std::nextafter(y1, y0);
    for (int k = 0; k < 3; ++k) {
        double px = k != 1 ? xe : x0;
        double py = k != 0 ? ye : y0;
        Located corner = locate(d, px, py);
        if (corner.cell != first.cell || !point_valid(d, first.face, corner.a, corner.b)) return -1;
    }
    return first.face;
}

// Quadratic through (0, g0), (0.5, g1), (1, g2), at f.
inline double lagrange3(double g0, double g1, double g2, double f) {
    return g0 * (2.0 * f * f - 3.0 * f + 1.0) + g1 * (4.0 * f - 4.0 * f * f) +
           g2 * (2.0 * f * f - f);
}

// grid[r][c][k]: source x, source y and output density at grid point (r, c).
using TileGrid = double[3][3][3];

// Map the tile's 3 x 3 grid (a(fx, fy) = a00 + da_x fx + da_y fy, likewise b) and check the
// quarter points. Returns the source cell when interpolation is within tolerance and the whole
// grid lies in that cell, else -1.
inline int64_t map_tile(const Geometry& src, const Chart& dfam, int face, const Rotation& rot, double a00,
                        double b00, double da_x, double db_x, double da_y, double db_y,
                        TileGrid& grid) {
    int64_t cell0 = -1;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double a = a00 + da_x * (0.5 * c) + da_y * (0.5 * r);
            double b = b00 + db_x * (0.5 * c) + db_y * (0.5 * r);
            ImagePoint p = source_point(src, dfam, face, a, b, rot);
            if (r == 0 && c == 0) {
                cell0 = p.cell;
            } else if (p.cell != cell0) {
                return -1;
            }
            grid[r][c][0] = p.x;
            grid[r][c][1] = p.y;
            grid[r][c][2] = density(dfam, face, a, b);
        }
    }
    for (int q = 0; q < 4; ++q) {
        double fx = 0.25 + 0.5 * (q % 2), fy = 0.25 + 0.5 * (q / 2);
        double a = a00 + da_x * fx + da_y * fy;
        double b = b00 + db_x * fx + db_y * fy;
        ImagePoint p = source_point(src, dfam, face, a, b, rot);
        if (p.cell != cell0) return -1;
        double w = density(dfam, face, a, b);
        double exact[3] = {p.x, p.y, w};
        double tolerance[3] = {kInterpTolerance, kInterpTolerance, kWeightTolerance * w};
        for (int k = 0; k < 3; ++k) {
            double interpolated =
                lagrange3(lagrange3(grid[0][0][k], grid[0][1][k], grid[0][2][k], fx),
                          lagrange3(grid[1][0][k], grid[1][1][k], grid[1][2][k], fx),
                          lagrange3(grid[2][0][k], grid[2][1][k], grid[2][2][k], fx), fy);
            if (!(std::fabs(interpolated - exact[k]) <= tolerance[k])) return -1;
        }
    }
    return cell0;
}

}  // namespace envconv
