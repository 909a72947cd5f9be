// Layout maps of every geometry family: (face, a, b) <-> unit direction, and the solid-angle
// density of (a, b).
//
// Frame (docs/geometry.md): world +Y up, +Z the lat-long centre, +X at u = 0.25 of a lat-long.
// A face is a chart with local coordinates (a, b) in [-1, 1]^2, a to the right and b downward;
// the Python layout modules (envconv/layouts/) place faces in cells and carry the diagrams.
// Every face_to_dir is continued past its valid region (guard rings and filter taps read it),
// and density is the solid angle per unit (a, b) area, in steradians.
//
// The family codes (src/core/chart.h) reach Python through module.cpp (envconv/layouts/base.py
// FAMILY_* reads them). Kernels dispatch on the code, never on a Python callback. A Chart is a
// family with its parameters: the aimed families (fisheye, perspective, src/core/views.h) read
// their field of view and view frame there; the others ignore them.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "chart.h"
#include "views.h"

namespace envconv {

// latlong (OpenEXR envmap=latlong): lon = -pi a, lat = -pi/2 b,
// d = (sin lon cos lat, sin lat, cos lon cos lat). Past |a| > 1 columns wrap; past |b| > 1 rows
// continue over the pole on the opposite meridian (the same formulas).
namespace latlong {
inline Vec3 face_to_dir(int, double a, double b) {
    double lon = -kPi * a, lat = -0.5 * kPi * b;
    double cl = std::cos(lat);
    return {std::sin(lon) * cl, std::sin(lat), std::cos(lon) * cl};
}
inline FacePoint dir_to_face(double x, double y, double z) {
    double lon = std::atan2(x, z);
    double lat = std::asin(std::min(1.0, std::max(-1.0, y)));
    return {0, -lon / kPi, -2.0 * lat / kPi};
}
inline double density(int, double, double b) {
    return std::fabs(std::cos(0.5 * kPi * b)) * (0.5 * kPi * kPi);
}
}  // namespace latlong

// Cube faces in the GL/D3D/KTX order, in the left-handed cube frame c = (-x, y, z): faces
// +Xc -Xc +Yc -Yc +Zc -Zc, each an unmirrored view from inside. Face texel (a, b) -> c:
//   +Xc (1, -b, -a)  -Xc (-1, -b, a)  +Yc (a, 1, b)  -Yc (a, -1, -b)  +Zc (a, -b, 1)  -Zc (-a, -b, -1)
// World d = normalise(-c_x, c_y, c_z). Major axis picks the face; exact ties go to x, then y,
// then z, and zero counts as positive. The continued map is the face plane past +-1.
namespace cube_gl {
inline Vec3 face_to_dir(int face, double a, double b) {
    switch (face) {
        case 0: return normalized(-1.0, -b, -a);
        case 1: return normalized(1.0, -b, a);
        case 2: return normalized(-a, 1.0, b);
        case 3: return normalized(-a, -1.0, -b);
        case 4: return normalized(-a, -b, 1.0);
        default: return normalized(a, -b, -1.0);
    }
}
inline FacePoint dir_to_face(double x, double y, double z) {
    double cx = -x;
    double ax = std::fabs(cx), ay = std::fabs(y), az = std::fabs(z);
    if (ax >= ay && ax >= az) {
        if (cx >= 0.0) return {0, -z / ax, -y / ax};
        return {1, z / ax, -y / ax};
    }
    if (ay >= az) {
        if (y >= 0.0) return {2, cx / ay, z / ay};
        return {3, cx / ay, -z / ay};
    }
    if (z >= 0.0) return {4, cx / az, -y / az};
    return {5, -cx / az, -y / az};
}
// (1 + a^2 + b^2)^(-3/2) sr per unit area, for both cube families.
inline double density(int, double a, double b) {
    double r2 = 1.0 + a * a + b * b;
    return 1.0 / (r2 * std::sqrt(r2));
}
}  // namespace cube_gl

// OpenEXR envcube (envmap=cube): world faces +X -X +Y -Y +Z -Z. Face texel (a, b) -> d:
//   +X (1, -b, a)  -X (-1, -b, -a)  +Y (a, 1, -b)  -Y (a, -1, b)  +Z (-a, -b, 1)  -Z (a, -b, -1)
namespace cube_exr {
inline Vec3 face_to_dir(int face, double a, double b) {
    switch (face) {
        case 0: return normalized(1.0, -b, a);
        case 1: return normalized(-1.0, -b, -a);
        case 2: return normalized(a, 1.0, -b);
        case 3: return normalized(a, -1.0, b);
        case 4: return normalized(-a, -b, 1.0);
        default: return normalized(a, -b, -1.0);
    }
}
inline FacePoint dir_to_face(double x, double y, double z) {
    double ax = std::fabs(x), ay = std::fabs(y), az = std::fabs(z);
    if (ax >= ay && ax >= az) {
        if (x >= 0.0) return {0, z / ax, -y / ax};
        return {1, -z / ax, -y / ax};
    }
    if (ay >= az) {
        if (y >= 0.0) return {2, x / ay, -z / ay};
        return {3, x / ay, z / ay};
    }
    if (z >= 0.0) return {4, -x / az, -y / az};
    return {5, x / az, -y / az};
}
}  // namespace cube_exr

// Mirror ball (GL_SPHERE_MAP): X = a, Y = -b, R^2 = X^2 + Y^2 <= 1, n_z = sqrt(1 - R^2),
// d = (2 n_z X, 2 n_z Y, 2 n_z^2 - 1). Past the rim (1 < R <= 2) the great circle continues
// through -Z: alpha = 2 pi - 2 asin(2 - R), d = (sin alpha X/R, sin alpha Y/R, cos alpha).
namespace sphere {
inline Vec3 face_to_dir(int, double a, double b) {
    double X = a, Y = -b;
    double r2 = X * X + Y * Y;
    if (r2 <= 1.0) {
        double nz = std::sqrt(1.0 - r2);
        return {2.0 * nz * X, 2.0 * nz * Y, 2.0 * nz * nz - 1.0};
    }
    double r = std::sqrt(r2);
    double rc = std::min(r, 2.0);
    double alpha = 2.0 * kPi - 2.0 * std::asin(2.0 - rc);
    double s = std::sin(alpha) / r;
    return {s * X, s * Y, std::cos(alpha)};
}
// (a, b) = (x, -y) / |d + Z|; -Z itself lands on the rim at a = 1. hypot keeps precision when
// the components' squares are subnormal.
inline FacePoint dir_to_face(double x, double y, double z) {
    double zp = z + 1.0;
    double m = std::hypot(std::hypot(x, y), zp);
    if (m == 0.0) return {0, 1.0, 0.0};
    if (m < 1e-150) {
        // Subnormal components carry too few bits for x / m: scale by an exact power of two.
        x = std::ldexp(x, 600);
        y = std::ldexp(y, 600);
        m = std::hypot(std::hypot(x, y), std::ldexp(zp, 600));
    }
    return {0, x / m, -y / m};
}
// 4 sr per unit area inside the disk, 4 (2 - R) / R past the rim.
inline double density(int, double a, double b) {
    double r = std::sqrt(a * a + b * b);
    if (r <= 1.0) return 4.0;
    return 4.0 * std::max(2.0 - r, 1e-6) / r;
}
}  // namespace sphere

// Angular light probe (Debevec): alpha = pi R from +Z, d = (sin alpha X/R, sin alpha Y/R,
// cos alpha), X = a, Y = -b; R = 1 is -Z. Continued: the same formula past R = 1.
namespace angular {
inline Vec3 face_to_dir(int, double a, double b) {
    double X = a, Y = -b;
    double r = std::sqrt(X * X + Y * Y);
    if (r < 1e-12) return {0.0, 0.0, 1.0};
    double alpha = kPi * r;
    double s = std::sin(alpha) / r;
    return {s * X, s * Y, std::cos(alpha)};
}
// atan2 keeps full precision near the centre, where acos(z) loses half the digits.
inline FacePoint dir_to_face(double x, double y, double z) {
    double r_xy = std::hypot(x, y);
    double rad = std::atan2(r_xy, z) / kPi;
    if (r_xy == 0.0) return z >= 0.0 ? FacePoint{0, 0.0, 0.0} : FacePoint{0, 1.0, 0.0};
    if (r_xy < 1e-150) {
        // Subnormal (x, y) carry too few bits for x / r_xy (5e-324 / hypot(5e-324, 5e-324) is
        // 1, not 0.707): scale them by an exact power of two first.
        x = std::ldexp(x, 600);
        y = std::ldexp(y, 600);
        r_xy = std::hypot(x, y);
    }
    return {0, rad * (x / r_xy), -rad * (y / r_xy)};
}
// pi |sin(pi R)| / R sr per unit area; pi^2 at the centre.
inline double density(int, double a, double b) {
    double r = std::sqrt(a * a + b * b);
    if (r < 1e-9) return kPi * kPi;
    return kPi * std::fabs(std::sin(kPi * r)) / r;
}
}  // namespace angular

// Dual paraboloid (Heidrich & Seidel): front (face 0, z >= 0) (X, Y) = (x, y) / (1 + z), back
// (face 1, z < 0) (X, Y) = (x, y) / (1 - z); X = a, Y = -b. Inverse with s = 1 + X^2 + Y^2:
// d = (2X, 2Y, +-(1 - X^2 - Y^2)) / s. Continued: the same formula past the circle.
namespace paraboloid {
inline Vec3 face_to_dir(int face, double a, double b) {
    double X = a, Y = -b;
    double r2 = X * X + Y * Y;
    double s = 1.0 / (1.0 + r2);
    double z = (1.0 - r2) * s;
    if (face == 1) z = -z;
    return {2.0 * X * s, 2.0 * Y * s, z};
}
inline FacePoint dir_to_face(double x, double y, double z) {
    if (z >= 0.0) {
        double k = 1.0 / (1.0 + z);
        return {0, x * k, -y * k};
    }
    double k = 1.0 / (1.0 - z);
    return {1, x * k, -y * k};
}
// 4 / (1 + X^2 + Y^2)^2 sr per unit area.
inline double density(int, double a, double b) {
    double s = 1.0 + a * a + b * b;
    return 4.0 / (s * s);
}
}  // namespace paraboloid

// Tennisball: two 270 x 90 degree bands; phi = -3pi/4 a, theta = -pi/4 b.
// C1 (face 0): d = (sin phi cos theta, sin theta, cos phi cos theta), about +Y, centred on +Z.
// C2 (face 1): d = (sin theta, sin phi cos theta, -cos phi cos theta), about +X, centred on -Z.
// A direction belongs to C1 if (z >= 0 and |y| <= sqrt2/2) or (z <= 0 and |x| >= sqrt2/2).
namespace tennisball {
constexpr double kPhiHalf = 0.75 * kPi;
constexpr double kThetaHalf = 0.25 * kPi;
constexpr double kHalfSqrt2 = 0.70710678118654757;  // 0.5 * sqrt(2) rounded as Python does
inline Vec3 face_to_dir(int face, double a, double b) {
    double phi = -kPhiHalf * a, theta = -kThetaHalf * b;
    double ct = std::cos(theta);
    if (face == 0) return {std::sin(phi) * ct, std::sin(theta), std::cos(phi) * ct};
    return {std::sin(theta), std::sin(phi) * ct, -std::cos(phi) * ct};
}
inline FacePoint dir_to_face(double x, double y, double z) {
    if ((z >= 0.0 && std::fabs(y) <= kHalfSqrt2) || (z <= 0.0 && std::fabs(x) >= kHalfSqrt2)) {
        double theta = std::asin(std::min(1.0, std::max(-1.0, y)));
        double phi = std::atan2(x, z);
        return {0, -phi / kPhiHalf, -theta / kThetaHalf};
    }
    double theta = std::asin(std::min(1.0, std::max(-1.0, x)));
    double phi = std::atan2(y, -z);
    return {1, -phi / kPhiHalf, -theta / kThetaHalf};
}
// |cos theta| (3pi/4)(pi/4) sr per unit area.
inline double density(int, double, double b) {
    return std::fabs(std::cos(kThetaHalf * b)) * (kPhiHalf * kThetaHalf);
}
}  // namespace tennisball

// The two octahedral squares (one N x N cell each) share the papers' z-up frame t: the square's
// centre is t = +Z, a (right) runs along +X_t and b (down) along +Y_t; the diamond
// |a| + |b| <= 1 holds t_z >= 0 and the four corner triangles t_z < 0. envconv's direction is
// d = (t_x, t_z, -t_y): +Y at the centre, +X at the right edge's midpoint, +Z at the top edge's,
// -Y at every corner (the sky seen from inside looking up, +Z at the top, unmirrored).
namespace octa {
inline double sign_not_zero(double v) { return v >= 0.0 ? 1.0 : -1.0; }
// The octahedral fold, the continued map of both squares: the two halves of each edge hold the
// same directions ((1, b) and (1, -b) are one), so a point past an edge is the point mirrored
// across that edge and across its midpoint: (a, b) -> (2 - a, -b) past a = 1, (-2 - a, -b) past
// a = -1, (-a, 2 - b) past b = 1, (-a, -2 - b) past b = -1. pbrt-v4's WrapEqualAreaSquare
// (src/pbrt/util/math.cpp) in (a, b); RTXGI's probe borders (ProbeBorderUpdateCS) copy the same.
inline void fold(double& a, double& b) {
    for (int k = 0; k < 8 && (std::fabs(a) > 1.0 || std::fabs(b) > 1.0); ++k) {
        if (a > 1.0) {
            a = 2.0 - a;
            b = -b;
        } else if (a < -1.0) {
            a = -2.0 - a;
            b = -b;
        }
        if (b > 1.0) {
            b = 2.0 - b;
            a = -a;
        } else if (b < -1.0) {
            b = -2.0 - b;
            a = -a;
        }
    }
}
// The octahedron point over (a, b) in [-1, 1]^2: (a, b, 1 - |a| - |b|) inside the diamond; in the
// corner triangles (t_z < 0) the point unfolded, ((1 - |b|) sgn a, (1 - |a|) sgn b), sgn 0 = +1.
inline Vec3 octahedron_point(double a, double b) {
    double tz = 1.0 - std::fabs(a) - std::fabs(b);
    if (tz >= 0.0) return {a, b, tz};
    return {(1.0 - std::fabs(b)) * sign_not_zero(a), (1.0 - std::fabs(a)) * sign_not_zero(b), tz};
}
}  // namespace octa

// Octahedral encoding: Cigolle, Donow, Evangelakos, Mara, McGuire, Meyer, "A Survey of
// Efficient Representations for Independent Unit Vectors", JCGT 3(2), 2014 (float32x3_to_oct
// and oct_to_float32x3); DDGI/RTXGI's DDGIGetOctahedralDirection/Coordinates are the same code.
// In the frame t above: t = normalise(octahedron_point(a, b)); inverse
// (a, b) = (t_x, t_y) / (|t_x| + |t_y| + |t_z|), folded like octahedron_point where t_z < 0.
// Continued map: the fold.
namespace octahedral {
inline Vec3 face_to_dir(int, double a, double b) {
    octa::fold(a, b);
    Vec3 c = octa::octahedron_point(a, b);
    Vec3 t = normalized(c.x, c.y, c.z);
    return {t.x, t.z, -t.y};
}
inline FacePoint dir_to_face(double x, double y, double z) {
    double tx = x, ty = -z, tz = y;
    double l1 = std::fabs(tx) + std::fabs(ty) + std::fabs(tz);
    double a = tx / l1, b = ty / l1;
    if (tz < 0.0) {
        double fa = (1.0 - std::fabs(b)) * octa::sign_not_zero(a);
        b = (1.0 - std::fabs(a)) * octa::sign_not_zero(b);
        a = fa;
    }
    return {0, a, b};
}
// A plane patch of the octahedron at distance |c|, seen at cos = 1/(sqrt3 |c|), over an (a, b)
// area 1/sqrt3 of its own: 1 / |c|^3 sr per unit area (1 on the axes, 3 sqrt3 mid-octant).
inline double density(int, double a, double b) {
    octa::fold(a, b);
    Vec3 c = octa::octahedron_point(a, b);
    double r2 = c.x * c.x + c.y * c.y + c.z * c.z;
    return 1.0 / (r2 * std::sqrt(r2));
}
}  // namespace octahedral

// Equal-area octahedral square: Clarberg, "Fast Equal-Area Mapping of the (Hemi)Sphere using
// SIMD", JGT 13(3), 2008, as pbrt-v4's EqualAreaSquareToSphere (src/pbrt/util/math.cpp) writes
// it, in the frame t above. With s = 1 - (|a| + |b|) the signed L1 distance from the horizon
// diamond, r = 1 - |s| (the L1 radius of the unfolded point), phi = ((|b| - |a|) / r + 1) pi/4:
// t = (r sqrt(2 - r^2) cos phi sgn a, r sqrt(2 - r^2) sin phi sgn b, (1 - r^2) sgn s).
// The cap above t_z holds r^2 of its hemisphere as the diamond of radius r holds r^2 of its
// area, so every point has 4 pi / 4 = pi sr per unit (a, b) area. Continued map: the fold.
namespace equal_area {
inline Vec3 face_to_dir(int, double a, double b) {
    octa::fold(a, b);
    double aa = std::fabs(a), ab = std::fabs(b);
    double s = 1.0 - (aa + ab);
    double r = 1.0 - std::fabs(s);
    double phi = (r == 0.0 ? 1.0 : (ab - aa) / r + 1.0) * (0.25 * kPi);
    double sin_theta = r * std::sqrt(std::max(2.0 - r * r, 0.0));
    double tx = std::copysign(std::cos(phi), a) * sin_theta;
    double ty = std::copysign(std::sin(phi), b) * sin_theta;
    double tz = std::copysign(1.0 - r * r, s);
    return {tx, tz, -ty};
}
// Inverse: r = sqrt(1 - |t_z|), computed as |(t_x, t_y)| / sqrt(1 + |t_z|) to keep its digits
// near the poles (pbrt's polynomial atan is replaced by atan2); b' = r 2phi/pi, a' = r - b',
// folded to (1 - b', 1 - a') where t_z < 0, then signed by t_x and t_y with a zero counting
// as positive, as in the octahedral square and the cube faces' tie rule (pbrt's copysign
// reads the sign bit of -0, so -Y, t = (0, -0, -1), would land on another corner than the
// octahedral square's; both corners are -Y, and the two squares now agree on the point).
inline FacePoint dir_to_face(double x, double y, double z) {
    double tx = x, ty = -z, tz = y;
    double ax = std::fabs(tx), ay = std::fabs(ty);
    double r = std::min(std::hypot(ax, ay) / std::sqrt(1.0 + std::fabs(tz)), 1.0);
    double bb = r * std::atan2(ay, ax) * (2.0 / kPi);
    double aa = r - bb;
    if (tz < 0.0) {
        double fa = 1.0 - bb;
        bb = 1.0 - aa;
        aa = fa;
    }
    return {0, aa * octa::sign_not_zero(tx), bb * octa::sign_not_zero(ty)};
}
inline double density(int, double, double) { return kPi; }
}  // namespace equal_area

// Dispatch on the family code.
inline Vec3 face_to_dir(const Chart& c, int face, double a, double b) {
    switch (c.family) {
        case kLatlong: return latlong::face_to_dir(face, a, b);
        case kCubeGL: return cube_gl::face_to_dir(face, a, b);
        case kCubeExr: return cube_exr::face_to_dir(face, a, b);
        case kSphere: return sphere::face_to_dir(face, a, b);
        case kAngular: return angular::face_to_dir(face, a, b);
        case kParaboloid: return paraboloid::face_to_dir(face, a, b);
        case kOctahedral: return octahedral::face_to_dir(face, a, b);
        case kEqualArea: return equal_area::face_to_dir(face, a, b);
        case kEac: return eac::face_to_dir(face, a, b);
        case kFisheye: return fisheye::face_to_dir(c, a, b);
        case kPerspective: return perspective::face_to_dir(c, a, b);
        default: return tennisball::face_to_dir(face, a, b);
    }
}

inline FacePoint dir_to_face(const Chart& c, double x, double y, double z) {
    switch (c.family) {
        case kLatlong: return latlong::dir_to_face(x, y, z);
        case kCubeGL: return cube_gl::dir_to_face(x, y, z);
        case kCubeExr: return cube_exr::dir_to_face(x, y, z);
        case kSphere: return sphere::dir_to_face(x, y, z);
        case kAngular: return angular::dir_to_face(x, y, z);
        case kParaboloid: return paraboloid::dir_to_face(x, y, z);
        case kOctahedral: return octahedral::dir_to_face(x, y, z);
        case kEqualArea: return equal_area::dir_to_face(x, y, z);
        case kEac: return eac::dir_to_face(x, y, z);
        case kFisheye: return fisheye::dir_to_face(c, x, y, z);
        case kPerspective: return perspective::dir_to_face(c, x, y, z);
        default: return tennisball::dir_to_face(x, y, z);
    }
}

inline double density(const Chart& c, int face, double a, double b) {
    switch (c.family) {
        case kLatlong: return latlong::density(face, a, b);
        case kCubeGL:
        case kCubeExr: return cube_gl::density(face, a, b);
        case kSphere: return sphere::density(face, a, b);
        case kAngular: return angular::density(face, a, b);
        case kParaboloid: return paraboloid::density(face, a, b);
        case kOctahedral: return octahedral::density(face, a, b);
        case kEqualArea: return equal_area::density(face, a, b);
        case kEac: return eac::density(face, a, b);
        case kFisheye: return fisheye::density(c, a, b);
        case kPerspective: return perspective::density(c, a, b);
        default: return tennisball::density(face, a, b);
    }
}

// Families whose valid region in a cell is the unit disk a^2 + b^2 <= 1.
inline bool is_disk(int family) {
    return family == kSphere || family == kAngular || family == kParaboloid || family == kFisheye;
}

}  // namespace envconv
