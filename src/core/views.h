// Layout maps of the equi-angular cubemap and of the aimed views (fisheye, perspective), the
// families envconv takes from ffmpeg v360 and py360convert; the conventions are those of
// src/core/layouts.h, which dispatches on their codes. docs/geometry.md states each map.
#pragma once

#include <algorithm>
#include <cmath>

#include "chart.h"

namespace envconv {

// A view frame: world direction = C * view direction, C row-major in param[kFrame..kFrame+8].
// The view direction frame: +Z_v forward, +Y_v up, +X_v to the viewer's left, so that image
// right (+a) is -X_v: an unmirrored picture, as the lat-long's centre is seen from inside.
namespace view {
inline Vec3 to_world(const Chart& c, double x, double y, double z) {
    const double* m = c.param + kFrame;
    return {m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z};
}
inline Vec3 to_view(const Chart& c, double x, double y, double z) {
    const double* m = c.param + kFrame;
    return {m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z};
}
}  // namespace view

// Equi-angular cubemap, ffmpeg v360 `eac` (YouTube's EAC), six N x N cells in a 3 x 2 grid:
// face k in column k % 3, row k / 3. A cell's (a', b') are equal in angle: the cube face's plane
// coordinate is a = tan(pi/4 a'), inverse a' = (4/pi) atan(a). Faces as stored, world direction
// before normalising (the top row is OpenEXR's +X, +Z, -X faces; the bottom row turns -Y and
// +Y by a quarter turn and -Z by a quarter turn the other way, ffmpeg's ROT_270 / ROT_90):
//   0 +X (1, -b, a)   1 +Z (-a, -b, 1)   2 -X (-1, -b, -a)
//   3 -Y (b, -1, -a)  4 -Z (b, a, -1)    5 +Y (b, 1, a)
// Each row is continuous across its two inner edges. Continued map (guard rings, taps): past
// |a'| = 1 the face plane goes on at the edge's rate, a = +-(1 + pi/2 (|a'| - 1)), so the map
// stays C1 across the edge and reaches any distance (the tangent would end at |a'| = 2).
namespace eac {
inline double plane(double e) {
    if (std::fabs(e) <= 1.0) return std::tan(0.25 * kPi * e);
    return std::copysign(1.0 + 0.5 * kPi * (std::fabs(e) - 1.0), e);
}
// d(plane)/d(e): (pi/4)(1 + a^2) on the face, pi/2 past its edge.
inline double plane_rate(double e, double a) {
    return std::fabs(e) <= 1.0 ? 0.25 * kPi * (1.0 + a * a) : 0.5 * kPi;
}
inline Vec3 face_to_dir(int face, double ea, double eb) {
    double a = plane(ea), b = plane(eb);
    switch (face) {
        case 0: return normalized(1.0, -b, a);
        case 1: return normalized(-a, -b, 1.0);
        case 2: return normalized(-1.0, -b, -a);
        case 3: return normalized(b, -1.0, -a);
        case 4: return normalized(b, a, -1.0);
        default: return normalized(b, 1.0, a);
    }
}
// Major axis, ties to x, then y, then z, zero counting as positive (as the cube families).
inline FacePoint dir_to_face(double x, double y, double z) {
    double ax = std::fabs(x), ay = std::fabs(y), az = std::fabs(z);
    int face;
    double a, b;
    if (ax >= ay && ax >= az) {
        face = x >= 0.0 ? 0 : 2;
        a = (x >= 0.0 ? z : -z) / ax;
        b = -y / ax;
    } else if (ay >= az) {
        face = y >= 0.0 ? 5 : 3;
        a = (y >= 0.0 ? z : -z) / ay;
        b = x / ay;
    } else {
        face = z >= 0.0 ? 1 : 4;
        a = (z >= 0.0 ? -x : y) / az;
        b = (z >= 0.0 ? -y : x) / az;
    }
    constexpr double k = 4.0 / kPi;
    return {face, k * std::atan(a), k * std::atan(b)};
}
// The cube's (1 + a^2 + b^2)^(-3/2) times both plane rates.
inline double density(int, double ea, double eb) {
    double a = plane(ea), b = plane(eb);
    double r2 = 1.0 + a * a + b * b;
    return plane_rate(ea, a) * plane_rate(eb, b) / (r2 * std::sqrt(r2));
}
}  // namespace eac

// Fisheye, ffmpeg v360 `fisheye` (equidistant): one N x N cell, the disk R <= 1 valid. With
// X = a, Y = -b, R = |(X, Y)| and the half field of view h = param[kScaleX] (radians), the angle
// from the view axis is theta = h R; view direction (-sin theta X/R, sin theta Y/R, cos theta)
// (unmirrored: image right is -X_v), then the view frame. Continued: the same formula past
// R = 1. dir_to_face returns R up to param[kReach] (directions the view does not cover, which
// a partial source's guard ring holds).
namespace fisheye {
inline Vec3 face_to_dir(const Chart& c, double a, double b) {
    double X = a, Y = -b;
    double r = std::hypot(X, Y);
    double theta = c.param[kScaleX] * r;
    double s = r < 1e-12 ? c.param[kScaleX] : std::sin(theta) / r;
    return view::to_world(c, -s * X, s * Y, std::cos(theta));
}
inline FacePoint dir_to_face(const Chart& c, double x, double y, double z) {
    Vec3 v = view::to_view(c, x, y, z);
    double h = std::hypot(v.x, v.y);
    double r = std::min(std::atan2(h, v.z) / c.param[kScaleX], c.param[kReach]);
    if (h == 0.0) return v.z >= 0.0 ? FacePoint{0, 0.0, 0.0} : FacePoint{0, r, 0.0};
    if (h < 1e-150) {
        // Subnormal components: scale by an exact power of two before dividing (as angular).
        v.x = std::ldexp(v.x, 600);
        v.y = std::ldexp(v.y, 600);
        h = std::hypot(v.x, v.y);
    }
    return {0, -r * v.x / h, -r * v.y / h};
}
// h |sin(h R)| / R sr per unit area; h^2 at the centre.
inline double density(const Chart& c, double a, double b) {
    double r = std::hypot(a, b), h = c.param[kScaleX];
    if (r < 1e-9) return h * h;
    return h * std::fabs(std::sin(h * r)) / r;
}
}  // namespace fisheye

// Perspective (rectilinear; py360convert's e2p): one W x H cell, all of it valid. With
// t_x = param[kScaleX] = tan(horizontal fov / 2) and t_y = param[kScaleY] = tan(vertical
// fov / 2) the view direction is normalise(-a t_x, -b t_y, 1), then the view frame. Continued:
// the image plane past its edges. A direction behind the camera, or past param[kReach] on the
// plane, lands on the square |a|, |b| <= reach along its own bearing.
namespace perspective {
inline Vec3 face_to_dir(const Chart& c, double a, double b) {
    Vec3 v = normalized(-a * c.param[kScaleX], -b * c.param[kScaleY], 1.0);
    return view::to_world(c, v.x, v.y, v.z);
}
inline FacePoint dir_to_face(const Chart& c, double x, double y, double z) {
    Vec3 v = view::to_view(c, x, y, z);
    double a = -v.x / c.param[kScaleX], b = -v.y / c.param[kScaleY];
    double reach = c.param[kReach];
    double far = std::max(std::fabs(a), std::fabs(b));
    if (v.z > 0.0 && far <= reach * v.z) return {0, a / v.z, b / v.z};
    if (far == 0.0) return {0, reach, 0.0};  // straight behind
    return {0, a * reach / far, b * reach / far};
}
// t_x t_y / |(a t_x, b t_y, 1)|^3 sr per unit area: the plane patch seen from the centre.
inline double density(const Chart& c, double a, double b) {
    double px = a * c.param[kScaleX], py = b * c.param[kScaleY];
    double r2 = 1.0 + px * px + py * py;
    return c.param[kScaleX] * c.param[kScaleY] / (r2 * std::sqrt(r2));
}
}  // namespace perspective

}  // namespace envconv
