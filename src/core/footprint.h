// How many sub-samples a pixel takes under samples="auto", and which rip-map level it reads.
//
// The footprint of an output pixel is the number of source texels its edges span there, along
// each axis: from a tile's grid (tiles.h) or, for exactly mapped pixels, from the Jacobian at
// the pixel's centre (pixel_footprint). The rules and their reasons are stated in
// envconv/resample/convert.py and docs/conventions.md; the constants are exported to Python.
#pragma once

#include <algorithm>
#include <cmath>

#include "cells.h"

namespace envconv {

// nx = clamp(ceil(footprint / kAutoSpacing - kAutoSlack), 1, kAutoMaxSamples): sub-samples
// about half a texel apart in a reduction, one sample up to a footprint of 2 texels.
constexpr double kAutoSpacing = 0.5;
constexpr double kAutoSlack = 3.0;
constexpr int kAutoMaxSamples = 32;
// A pixel not wholly inside one cell's valid region takes at least this many per edge, so that
// its coverage (alpha) is exact to 1/64.
constexpr int kAutoEdgeSamples = 8;
// A pixel spanning X level-0 texels along a lat-long's x reads level k, the largest with
// 2^k kRipMinSpan <= X.
constexpr double kRipMinSpan = 8.0;

inline int rip_level(double x_extent, int levels) {
    int level = 0;
    while (level < levels && kRipMinSpan * double(2 << level) <= x_extent) ++level;
    return level;
}

// Length in level-k texels of an edge `span` level-0 texels long whose x component is x_part.
inline double level_span(double span, double x_part, int level) {
    if (level == 0) return span;
    double shrink = 1.0 / double(1 << level);
    return std::sqrt(std::max(span * span - x_part * x_part * (1.0 - shrink * shrink), 0.0));
}

// Source-y component of an edge `span` texels long whose x component is x_part.
inline double edge_y_part(double span, double x_part) {
    return std::sqrt(std::max(span * span - x_part * x_part, 0.0));
}

// A footprint within kAutoTie of a step (an exact ratio, as 48 -> 32 texels gives exactly 3)
// takes the lower count, whatever the last bits of rounding say.
constexpr double kAutoTie = 1e-9;

inline int auto_count(double footprint) {
    int n = int(std::ceil(footprint / kAutoSpacing - kAutoSlack - kAutoTie));
    return std::min(std::max(n, 1), kAutoMaxSamples);
}

// Everything the kernel knows about one conversion's two layouts.
struct Conversion {
    Geometry src, dst;
    Rotation rot;
    double scale_x, scale_y;  // level-0 output pixels per pixel of the level being made
    bool fill;
};

// Source row position of output pixel (i, j)'s centre (the middle row if it has none).
inline double centre_source_y(const Conversion& cv, int64_t i, int64_t j) {
    OutputSample s =
        output_sample(cv.dst, (double(i) + 0.5) * cv.scale_x, (double(j) + 0.5) * cv.scale_y,
                      cv.fill);
    if (!s.readable) return 0.5 * double(cv.src.n);
    return source_point(cv.src, cv.dst, s.face, s.a, s.b, cv.rot).y;
}

// Source pixels per output pixel along (step_x, step_y), by a forward or backward difference of
// a hundredth of a pixel, whichever stays in one output face and one source cell and moves less
// (the other may jump across a seam); -1 when neither does. Sets x_part to |x component|.
inline double one_sided_span(const Conversion& cv, int face, double px, double py, double step_x,
                             double step_y, const ImagePoint& s0, double& x_part) {
    const double delta = 0.01;
    double best = -1.0;
    x_part = -1.0;
    for (double side : {1.0, -1.0}) {
        OutputSample q =
            output_sample(cv.dst, px + side * delta * step_x, py + side * delta * step_y, cv.fill);
        if (!q.readable || q.face != face) continue;
        ImagePoint s = source_point(cv.src, cv.dst, face, q.a, q.b, cv.rot);
        if (s.cell != s0.cell) continue;
        double span = std::hypot(s.x - s0.x, s.y - s0.y) / delta;
        if (best < 0.0 || span < best) {
            best = span;
            x_part = std::fabs(s.x - s0.x) / delta;
        }
    }
    return best;
}

struct Footprint {
    double span_x, span_y, x_of_x, x_of_y;
};

// Source pixels spanned by the x and y edges of output pixel (i, j), at its centre, from the
// Jacobian of output point -> source point (anisotropic). Where both differences cross a seam,
// the isotropic sqrt(omega_out / omega_in) of the pixel solid angles is used, with the x parts
// -1; all -1 when the centre holds no direction.
inline Footprint pixel_footprint(const Conversion& cv, int64_t i, int64_t j) {
    double px = (double(i) + 0.5) * cv.scale_x, py = (double(j) + 0.5) * cv.scale_y;
    OutputSample s = output_sample(cv.dst, px, py, cv.fill);
    if (!s.readable) return {-1.0, -1.0, -1.0, -1.0};
    const Chart& dfam = cv.dst;
    ImagePoint s0 = source_point(cv.src, dfam, s.face, s.a, s.b, cv.rot);
    Footprint f;
    f.span_x = one_sided_span(cv, s.face, px, py, cv.scale_x, 0.0, s0, f.x_of_x);
    f.span_y = one_sided_span(cv, s.face, px, py, 0.0, cv.scale_y, s0, f.x_of_y);
    if (f.span_x >= 0.0 && f.span_y >= 0.0) return f;
    const Geometry &d = cv.dst, &src = cv.src;
    double d_area = (2.0 * cv.scale_x / double(d.nx)) * (2.0 * cv.scale_y / double(d.n));
    double s_area = (2.0 / double(src.nx)) * (2.0 / double(src.n));
    Vec3 v = cv.rot.apply(face_to_dir(dfam, s.face, s.a, s.b));
    FacePoint sf = dir_to_face(src, v.x, v.y, v.z);
    double omega_in = density(src, sf.face, sf.a, sf.b) * s_area;
    double omega_out = density(dfam, s.face, s.a, s.b) * d_area;
    if (omega_in <= omega_out * 1e-6) return {1e3, 1e3, -1.0, -1.0};  // angular's rim
    double ratio = std::sqrt(omega_out / omega_in);
    return {ratio, ratio, -1.0, -1.0};
}

}  // namespace envconv
