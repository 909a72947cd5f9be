// GGX prefilter, clamped-cosine convolution and SH projection; see ibl.h for the method.
#include "ibl.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "parallel.h"

namespace envconv {
namespace {

// Rec. 709 luminance of the first three channels (one channel: itself); 0 when not finite.
inline double luminance(const float* px, int64_t channels) {
    double y = channels >= 3 ? 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2] : double(px[0]);
    return std::isfinite(y) ? std::max(y, 0.0) : 0.0;
}

// 3-point Gauss-Legendre on [-1, 1].
// Row bands of the source binned separately (build_pyramid_binned), then added in order.
constexpr int64_t kBinBands = 2;

constexpr double kGaussX[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr double kGaussW[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};

// Unit mean direction and length of a raw mean `m` into node[at .. at + 3].
inline void put_direction(float* node, int at, const double* m) {
    double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    double inv = len > 0.0 ? 1.0 / len : 0.0;
    for (int k = 0; k < 3; ++k) node[at + k] = float(m[k] * inv);
    node[at + 3] = float(std::min(len, 1.0));
}

// The node's angular radius r about its unit geometric mean u: the largest angle to a corner
// (the edges are great-circle arcs and the node is convex, so no point is farther than a
// corner). Stored as 1 - cos r = |u - d|^2 / 2 (exact for small r, unlike cos r in a float)
// and sin r, both rounded outwards.
inline void put_radius(float* node, const double* m, int face, int64_t q, int64_t j, int64_t i) {
    double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    double u[3] = {m[0] / len, m[1] / len, m[2] / len};
    double vers = 0.0;
    for (int64_t y = j; y <= j + 1; ++y) {
        for (int64_t x = i; x <= i + 1; ++x) {
            Vec3 d = cube_gl::face_to_dir(face, -1.0 + 2.0 * double(x) / double(q),
                                          -1.0 + 2.0 * double(y) / double(q));
            double dx = u[0] - d.x, dy = u[1] - d.y, dz = u[2] - d.z;
            vers = std::max(vers, 0.5 * (dx * dx + dy * dy + dz * dz));
        }
    }
    vers = std::min(1.0, vers * (1.0 + 1e-5) + 1e-12);
    node[10] = float(vers);
    node[11] = float(std::min(1.0, std::sqrt(vers * (2.0 - vers)) * (1.0 + 1e-5)));
}

// Face `face`'s direction for the face-independent vector (a, b, c) = (a, b, 1): the signed
// permutation cube_gl::face_to_dir applies (exact, so a face's geometry is any other's, moved).
inline void on_face(int face, const double* r, double* out) {
    const double a = r[0], b = r[1], c = r[2];
    switch (face) {
        case 0: out[0] = -c, out[1] = -b, out[2] = -a; break;
        case 1: out[0] = c, out[1] = -b, out[2] = a; break;
        case 2: out[0] = -a, out[1] = c, out[2] = b; break;
        case 3: out[0] = -a, out[1] = -c, out[2] = -b; break;
        case 4: out[0] = -a, out[1] = -b, out[2] = c; break;
        default: out[0] = a, out[1] = -b, out[2] = -c; break;
    }
}

// Geometry of texel (i, j) of a face of p, in the face-independent frame (a, b, 1): solid
// angle, mean direction (3-point Gauss in a and b) and the radius fields of put_radius.
struct TexelGeometry {
    double omega, m[3];
    float vers, sine;
};

TexelGeometry texel_geometry(int64_t p, int64_t j, int64_t i) {
    const double h = 1.0 / double(p);  // half a texel in (a, b)
    const double ca = -1.0 + (2.0 * double(i) + 1.0) * h, cb = -1.0 + (2.0 * double(j) + 1.0) * h;
    TexelGeometry g{0.0, {0.0, 0.0, 0.0}, 0.0f, 0.0f};
    for (int u = 0; u < 3; ++u) {
        for (int v = 0; v < 3; ++v) {
            double a = ca + kGaussX[u] * h, b = cb + kGaussX[v] * h;
            double w = kGaussW[u] * kGaussW[v] * h * h * cube_gl::density(0, a, b);
            Vec3 d = normalized(a, b, 1.0);
            g.omega += w;
            g.m[0] += w * d.x;
            g.m[1] += w * d.y;
            g.m[2] += w * d.z;
        }
    }
    for (double& v : g.m) v /= g.omega;
    double len = std::sqrt(g.m[0] * g.m[0] + g.m[1] * g.m[1] + g.m[2] * g.m[2]);
    double vers = 0.0;
    for (int64_t y = j; y <= j + 1; ++y) {
        for (int64_t x = i; x <= i + 1; ++x) {
            Vec3 d = normalized(-1.0 + 2.0 * double(x) / double(p), -1.0 + 2.0 * double(y) / double(p),
                                1.0);
            double dx = g.m[0] / len - d.x, dy = g.m[1] / len - d.y, dz = g.m[2] / len - d.z;
            vers = std::max(vers, 0.5 * (dx * dx + dy * dy + dz * dz));
        }
    }
    vers = std::min(1.0, vers * (1.0 + 1e-5) + 1e-12);
    g.vers = float(vers);
    g.sine = float(std::min(1.0, std::sqrt(vers * (2.0 - vers)) * (1.0 + 1e-5)));
    return g;
}

void build_level0(const float* faces, int64_t p, int64_t nch, float* out, int threads) {
    const int64_t stride = Pyramid::stride_for(nch), f0 = Pyramid::kFields;
    // Every face has the same texel geometry up to its signed permutation: map one face.
    std::vector<TexelGeometry> geometry(size_t(p * p));
    parallel_for(p, threads, [&](int64_t j) {
        for (int64_t i = 0; i < p; ++i) geometry[size_t(j * p + i)] = texel_geometry(p, j, i);
    });
    parallel_for(6 * p, threads, [&](int64_t task) {
        int face = int(task / p);
        int64_t j = task % p;
        for (int64_t i = 0; i < p; ++i) {
            const TexelGeometry& g = geometry[size_t(j * p + i)];
            double m[3];
            on_face(face, g.m, m);
            const float* px = faces + ((face * p + j) * p + i) * nch;
            float* node = out + ((face * p + j) * p + i) * stride;
            node[0] = float(g.omega);
            node[1] = float(g.omega * luminance(px, nch));
            put_direction(node, 2, m);
            put_direction(node, 6, m);
            node[10] = g.vers;
            node[11] = g.sine;
            for (int64_t c = 0; c < nch; ++c) {
                double sc = g.omega * double(px[c]);
                node[f0 + c] = float(sc);
                // A texel's radiance is uniform over it: no first moment of its own.
                for (int k = 0; k < 3; ++k) node[f0 + nch + 3 * c + k] = 0.0f;
            }
        }
    });
}

void build_parent(const float* child, int64_t q, int64_t nch, float* out, int threads) {
    const int64_t stride = Pyramid::stride_for(nch), f0 = Pyramid::kFields, cq = 2 * q;
    parallel_for(6 * q, threads, [&](int64_t task) {
        int64_t face = task / q, j = task % q;
        std::vector<double> sum(4 * nch);
        for (int64_t i = 0; i < q; ++i) {
            double omega = 0.0, weight = 0.0, g[3] = {0, 0, 0}, l[3] = {0, 0, 0};
            std::fill(sum.begin(), sum.end(), 0.0);
            for (int64_t y = 2 * j; y < 2 * j + 2; ++y) {
                for (int64_t x = 2 * i; x < 2 * i + 2; ++x) {
                    const float* c = child + ((face * cq + y) * cq + x) * stride;
                    omega += c[0];
                    weight += c[1];
                    for (int k = 0; k < 3; ++k) {
                        g[k] += double(c[0]) * c[2 + k] * c[5];
                        l[k] += double(c[1]) * c[6 + k] * c[9];
                    }
                    // Each child's first moment about the origin: its own about its mean
                    // direction (as stored) plus S times that direction.
                    for (int64_t ch = 0; ch < nch; ++ch) {
                        double sc = c[f0 + ch];
                        sum[ch] += sc;
                        for (int k = 0; k < 3; ++k)
                            sum[nch + 3 * ch + k] += double(c[f0 + nch + 3 * ch + k]) +
                                                     sc * double(c[6 + k]) * double(c[9]);
                    }
                }
            }
            float* node = out + ((face * q + j) * q + i) * stride;
            node[0] = float(omega);
            node[1] = float(weight);
            for (int k = 0; k < 3; ++k) {
                l[k] = weight > 0.0 ? l[k] / weight : g[k] / omega;
                g[k] /= omega;
            }
            put_direction(node, 2, g);
            put_direction(node, 6, l);
            put_radius(node, g, int(face), q, j, i);
            // The first moments about the node's luminance-weighted mean direction as stored
            // (the expansion's centre): small where the node is nearly uniform, and exactly
            // what the expansion needs, without the cancellation of n.P - t S at evaluation.
            for (int64_t ch = 0; ch < nch; ++ch) {
                node[f0 + ch] = float(sum[ch]);
                double sc = node[f0 + ch];
                for (int k = 0; k < 3; ++k)
                    node[f0 + nch + 3 * ch + k] = float(
                        sum[nch + 3 * ch + k] - sc * double(node[6 + k]) * double(node[9]));
            }
        }
    });
}

// The node fields of level-0 texel (face, j, i) of a pyramid of p from the sums over the
// source points binned into it (fields: omega, omega d, omega luminance, omega luminance d,
// then omega c per channel): solid angle, mean directions and radiance all from the points,
// so that a constant map stays constant and a sun keeps its direction. The radius is the
// texel's about the points' mean, widened by delta (half a point's diagonal). Like
// build_level0, a texel has no first moments of its own. False when no point landed in it.
bool put_binned(float* node, const double* bin, int face, int64_t p, int64_t j, int64_t i,
                int64_t nch, double delta) {
    const int64_t f0 = Pyramid::kFields;
    if (!(bin[0] > 0.0)) return false;
    double m[3], l[3];
    for (int k = 0; k < 3; ++k) {
        m[k] = bin[1 + k] / bin[0];
        l[k] = bin[4] > 0.0 ? bin[5 + k] / bin[4] : m[k];
    }
    node[0] = float(bin[0]);
    node[1] = float(bin[4]);
    put_direction(node, 2, m);
    put_direction(node, 6, l);
    put_radius(node, m, face, p, j, i);
    double r = 2.0 * std::asin(std::min(1.0, std::sqrt(0.5 * double(node[10])))) + delta;
    r = std::min(r, kPi);
    double vers = std::min(1.0, (1.0 - std::cos(r)) * (1.0 + 1e-5) + 1e-12);
    node[10] = float(vers);
    node[11] = float(std::min(1.0, std::sqrt(vers * (2.0 - vers)) * (1.0 + 1e-5)));
    for (int64_t c = 0; c < nch; ++c) {
        node[f0 + c] = float(bin[8 + c]);
        for (int k = 0; k < 3; ++k) node[f0 + nch + 3 * c + k] = 0.0f;
    }
    return true;
}

}  // namespace

namespace {

// Sums of points binned into the level-0 texels of a pyramid of p: per texel omega, omega d,
// omega luminance, omega luminance d, omega c per channel (put_binned's fields), kept per
// fixed row band of the source and added in band order, so that the bytes do not depend on
// the thread count.
struct Bins {
    int64_t p, nch, fields, count, bands;
    std::vector<double> sums;
    Bins(int64_t p_, int64_t nch_, int64_t rows)
        : p(p_), nch(nch_), fields(8 + nch_), count(6 * p_ * p_),
          bands(std::min<int64_t>(kBinBands, rows)),
          sums(size_t(bands * count * fields), 0.0) {}
    double* band(int64_t b) { return sums.data() + b * count * fields; }
    // Point of solid angle w and pyramid direction d, of pixel px, into band sums acc.
    void add(double* acc, const Vec3& d, double w, const float* px) const {
        FacePoint f = cube_gl::dir_to_face(d.x, d.y, d.z);
        int64_t bi = std::clamp<int64_t>(int64_t((f.a + 1.0) * 0.5 * double(p)), 0, p - 1);
        int64_t bj = std::clamp<int64_t>(int64_t((f.b + 1.0) * 0.5 * double(p)), 0, p - 1);
        double* bin = acc + ((f.face * p + bj) * p + bi) * fields;
        double wl = w * luminance(px, nch);
        bin[0] += w;
        bin[1] += w * d.x;
        bin[2] += w * d.y;
        bin[3] += w * d.z;
        bin[4] += wl;
        bin[5] += wl * d.x;
        bin[6] += wl * d.y;
        bin[7] += wl * d.z;
        for (int64_t c = 0; c < nch; ++c) bin[8 + c] += w * double(px[c]);
    }
    // The pyramid from the sums (delta: half the diagonal of the largest point, radians).
    // False when a texel received no point.
    bool finish(float* out, double delta, int threads) {
        for (int64_t b = 1; b < bands; ++b) {
            const double* from = band(b);
            for (int64_t k = 0; k < count * fields; ++k) sums[size_t(k)] += from[k];
        }
        Pyramid pyr{out, p, 0, nch};
        for (int64_t q = p; q >= 1; q >>= 1) ++pyr.levels;
        const int64_t stride = Pyramid::stride_for(nch);
        std::vector<char> filled(size_t(6 * p), 1);
        parallel_for(6 * p, threads, [&](int64_t task) {
            int face = int(task / p);
            int64_t j = task % p;
            for (int64_t i = 0; i < p; ++i) {
                int64_t at = (face * p + j) * p + i;
                if (!put_binned(out + at * stride, sums.data() + at * fields, face, p, j, i, nch,
                                delta))
                    filled[size_t(task)] = 0;
            }
        });
        if (std::find(filled.begin(), filled.end(), 0) != filled.end()) return false;
        for (int s = 1; s < pyr.levels; ++s)
            build_parent(out + pyr.offset(s - 1), p >> s, nch, out + pyr.offset(s), threads);
        return true;
    }
};

// A point (px, py) of image geometry g counts when it is valid and its direction belongs to
// its own cell (tennisball's bands overlap); then its direction and solid-angle density.
inline bool owned_point(const Geometry& g, double px, double py, Vec3& d, double& dens) {
    Located at = locate(g, px, py);
    if (!point_valid(g, at.face, at.a, at.b)) return false;
    d = face_to_dir(g, at.face, at.a, at.b);
    FacePoint back = dir_to_face(g, d.x, d.y, d.z);
    if (face_to_image(g, back.face, back.a, back.b).cell != at.cell) return false;
    dens = density(g, at.face, at.a, at.b);
    return true;
}

// Points a pixel side for a pixel of g: sub where all of it is owned, else at least
// kPartialPoints (a disk's rim, a cell's edge), as sh_project does.
constexpr int kPartialPoints = 16;
inline int pixel_points(const Geometry& g, int64_t i, int64_t j, int sub) {
    int inside = 0;
    Vec3 d;
    double dens;
    for (double cy : {0.01, 0.99})
        for (double cx : {0.01, 0.99}) inside += owned_point(g, i + cx, j + cy, d, dens);
    if (inside == 0) return 0;
    return inside == 4 ? sub : std::max(sub, kPartialPoints);
}

}  // namespace

bool build_pyramid_binned(const float* image, int64_t height, int64_t width, int64_t nch,
                          const Rotation& to_pyramid, int64_t p, int sub, float* out,
                          int threads) {
    Bins bins(p, nch, height);
    // Each pixel is sub x sub points, at the centres of its sub-pixels. Lat-long
    // (a, b) = (-1 + 2 x / W, -1 + 2 y / H) at image point (x, y): lon = -pi a, lat = -pi b / 2.
    const int64_t sw = width * sub;
    std::vector<double> sin_lon(sw), cos_lon(sw);
    for (int64_t x = 0; x < sw; ++x) {
        double lon = -kPi * (-1.0 + (2.0 * double(x) + 1.0) / double(sw));
        sin_lon[x] = std::sin(lon);
        cos_lon[x] = std::cos(lon);
    }
    const double area = (2.0 / double(sw)) * (2.0 / double(height * sub));
    parallel_for(bins.bands, threads, [&](int64_t band) {
        double* acc = bins.band(band);
        for (int64_t j = band * height / bins.bands; j < (band + 1) * height / bins.bands; ++j) {
            for (int sy = 0; sy < sub; ++sy) {
                double b = -1.0 + (2.0 * double(j * sub + sy) + 1.0) / double(height * sub);
                double lat = -0.5 * kPi * b, cl = std::cos(lat), sl = std::sin(lat);
                double w = std::fabs(cl) * (0.5 * kPi * kPi) * area;
                for (int64_t x = 0; x < sw; ++x)
                    bins.add(acc, to_pyramid.apply({sin_lon[x] * cl, sl, cos_lon[x] * cl}), w,
                             image + (j * width + x / sub) * nch);
            }
        }
    });
    // Half the diagonal of the largest point (a sub-pixel at the equator), in radians.
    return bins.finish(out, 0.5 * std::hypot(kPi / double(height * sub), 2.0 * kPi / double(width * sub)),
                       threads);
}

bool build_pyramid_binned_any(const float* image, int64_t height, int64_t width, int64_t nch,
                              const Geometry& g, const Rotation& to_pyramid, int64_t p, int sub,
                              double delta, float* out, int threads) {
    Bins bins(p, nch, height);
    const double area = (2.0 / double(g.nx)) * (2.0 / double(g.n));
    parallel_for(bins.bands, threads, [&](int64_t band) {
        double* acc = bins.band(band);
        for (int64_t j = band * height / bins.bands; j < (band + 1) * height / bins.bands; ++j) {
            for (int64_t i = 0; i < width; ++i) {
                const int s = pixel_points(g, i, j, sub);
                const float* px = image + (j * width + i) * nch;
                for (int sy = 0; sy < s; ++sy) {
                    for (int sx = 0; sx < s; ++sx) {
                        Vec3 d;
                        double dens;
                        if (!owned_point(g, i + (sx + 0.5) / s, j + (sy + 0.5) / s, d, dens))
                            continue;
                        bins.add(acc, to_pyramid.apply(d), dens * area / double(s * s), px);
                    }
                }
            }
        }
    });
    return bins.finish(out, delta, threads);
}

void build_pyramid(const float* faces, int64_t p, int64_t channels, float* out, int threads) {
    Pyramid pyr{out, p, 0, channels};
    for (int64_t q = p; q >= 1; q >>= 1) ++pyr.levels;
    build_level0(faces, p, channels, out, threads);
    for (int s = 1; s < pyr.levels; ++s)
        build_parent(out + pyr.offset(s - 1), p >> s, channels, out + pyr.offset(s), threads);
}

void sh_project(const float* image, int64_t height, int64_t width, int64_t channels,
                const Geometry& g, int samples, double sign_x, double* out, int threads) {
    const int64_t terms = 9 * channels;
    std::vector<double> rows(height * terms, 0.0);
    const double area = (2.0 / double(g.nx)) * (2.0 / double(g.n));
    const double c0 = 0.28209479177387814, c1 = 0.4886025119029199, c2 = 1.0925484305920792,
                 c3 = 0.31539156525252005, c4 = 0.5462742152960396;
    parallel_for(height, threads, [&](int64_t j) {
        double* acc = rows.data() + j * terms;
        double basis[9];
        for (int64_t i = 0; i < width; ++i) {
            const int s = pixel_points(g, i, j, samples);
            Vec3 d;
            double dens;
            double sums[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
            for (int sy = 0; sy < s; ++sy) {
                for (int sx = 0; sx < s; ++sx) {
                    if (!owned_point(g, i + (sx + 0.5) / s, j + (sy + 0.5) / s, d, dens))
                        continue;
                    double w = dens * area / double(s * s);
                    double x = sign_x * d.x, y = d.y, z = d.z;
                    basis[0] = c0;
                    basis[1] = c1 * y;
                    basis[2] = c1 * z;
                    basis[3] = c1 * x;
                    basis[4] = c2 * x * y;
                    basis[5] = c2 * y * z;
                    basis[6] = c3 * (3.0 * z * z - 1.0);
                    basis[7] = c2 * x * z;
                    basis[8] = c4 * (x * x - y * y);
                    for (int k = 0; k < 9; ++k) sums[k] += w * basis[k];
                }
            }
            const float* px = image + (j * width + i) * channels;
            for (int k = 0; k < 9; ++k)
                for (int64_t c = 0; c < channels; ++c) acc[k * channels + c] += sums[k] * px[c];
        }
    });
    for (int64_t j = 0; j < height; ++j)
        for (int64_t k = 0; k < terms; ++k) out[k] += rows[j * terms + k];
}

}  // namespace envconv
