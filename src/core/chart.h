// The pieces every layout map shares: the family codes, a chart (a family and its
// parameters), directions and face points, and two numeric helpers. src/core/layouts.h holds
// the maps themselves and dispatches on the code.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace envconv {

constexpr double kPi = 3.14159265358979323846;

enum Family : int {
    kLatlong = 0,
    kCubeGL = 1,
    kCubeExr = 2,
    kSphere = 3,
    kAngular = 4,
    kParaboloid = 5,
    kTennisball = 6,
    kOctahedral = 7,
    kEqualArea = 8,
    kEac = 9,
    kFisheye = 10,
    kPerspective = 11,
};

constexpr int kFamilyCount = 12;

// Parameters of a chart (envconv/layouts/base.py Layout.params, in this order):
//   scale x, scale y   fisheye: the half field of view (radians per unit radius), twice;
//                      perspective: tan(half field of view) across and down;
//   frame (9)          the view frame C, row-major: world direction = C * view direction;
//   reach              the largest |a|, |b| (fisheye: radius) dir_to_face returns for a
//                      direction the view does not cover (a partial source's guard ring).
constexpr int kParamCount = 12;
enum ParamIndex : int { kScaleX = 0, kScaleY = 1, kFrame = 2, kReach = 11 };

// A geometry family and its parameters.
struct Chart {
    int family = 0;
    double param[kParamCount] = {};
};

struct Vec3 {
    double x, y, z;
};

struct FacePoint {
    int face;
    double a, b;
};

// floor(x) as an index, without a libm call on the x86-64 baseline (which lacks roundsd).
// x is clamped to +-2^60 first (NaN to -2^60): far outside every image, so a caller's bounds
// checks send such values to the clamped slow path.
inline int64_t floor_index(double x) {
    constexpr double kFar = 1152921504606846976.0;  // 2^60
    x = std::min(kFar, std::max(-kFar, x));          // NaN compares false: -2^60
    int64_t i = int64_t(x);
    return i - int64_t(x < double(i));
}

inline Vec3 normalized(double x, double y, double z) {
    double inv = 1.0 / std::sqrt(x * x + y * y + z * z);
    return {x * inv, y * inv, z * inv};
}

}  // namespace envconv
