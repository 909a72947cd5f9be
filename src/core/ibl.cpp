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
constexpr double kGaussX[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr double kGaussW[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};

void build_level0(const float* faces, int64_t p, int64_t nch, float* out, int threads) {
    const int64_t stride = 8 + 4 * nch;
    const double h = 1.0 / double(p);  // half a texel in (a, b)
    parallel_for(6 * p, threads, [&](int64_t task) {
        int face = int(task / p);
        int64_t j = task % p;
        for (int64_t i = 0; i < p; ++i) {
            double ca = -1.0 + (2.0 * double(i) + 1.0) * h, cb = -1.0 + (2.0 * double(j) + 1.0) * h;
            double omega = 0.0, mx = 0.0, my = 0.0, mz = 0.0;
            for (int u = 0; u < 3; ++u) {
                for (int v = 0; v < 3; ++v) {
                    double a = ca + kGaussX[u] * h, b = cb + kGaussX[v] * h;
                    double w = kGaussW[u] * kGaussW[v] * h * h * cube_gl::density(face, a, b);
                    Vec3 d = cube_gl::face_to_dir(face, a, b);
                    omega += w;
                    mx += w * d.x;
                    my += w * d.y;
                    mz += w * d.z;
                }
            }
            const float* px = faces + ((face * p + j) * p + i) * nch;
            float* node = out + ((face * p + j) * p + i) * stride;
            node[0] = float(omega);
            node[1] = float(omega * luminance(px, nch));
            node[2] = node[5] = float(mx / omega);
            node[3] = node[6] = float(my / omega);
            node[4] = node[7] = float(mz / omega);
            for (int64_t c = 0; c < nch; ++c) {
                double sc = omega * double(px[c]);
                node[8 + c] = float(sc);
                node[8 + nch + 3 * c] = float(sc * mx / omega);
                node[9 + nch + 3 * c] = float(sc * my / omega);
                node[10 + nch + 3 * c] = float(sc * mz / omega);
            }
        }
    });
}

void build_parent(const float* child, int64_t q, int64_t nch, float* out, int threads) {
    const int64_t stride = 8 + 4 * nch, cq = 2 * q;
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
                        g[k] += double(c[0]) * c[2 + k];
                        l[k] += double(c[1]) * c[5 + k];
                    }
                    for (int64_t ch = 0; ch < 4 * nch; ++ch) sum[ch] += c[8 + ch];
                }
            }
            float* node = out + ((face * q + j) * q + i) * stride;
            node[0] = float(omega);
            node[1] = float(weight);
            for (int k = 0; k < 3; ++k) {
                node[2 + k] = float(g[k] / omega);
                node[5 + k] = float(weight > 0.0 ? l[k] / weight : g[k] / omega);
            }
            for (int64_t ch = 0; ch < 4 * nch; ++ch) node[8 + ch] = float(sum[ch]);
        }
    });
}

// The zonal GGX lobe as a function of t = n.l (see ibl.h), with its second derivative.
struct Lobe {
    double c0, b;
    explicit Lobe(double alpha) : c0(alpha * alpha / kPi), b(0.5 * (alpha * alpha - 1.0)) {}
    double q(double t) const { return 1.0 + b * (1.0 + t); }
    // Int K dl over the sphere = 2 pi Int_0^1 K(t) dt (Simpson in u = t^(1/4)... in t with a
    // substitution that crowds samples at t = 1, where K peaks with width ~alpha^2).
    double integral() const {
        const int n = 4096;  // even
        double sum = 0.0;
        for (int k = 0; k <= n; ++k) {
            double u = double(k) / n, t = 1.0 - (1.0 - u) * (1.0 - u) * (1.0 - u);
            double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
            sum += w * value(t) * 3.0 * (1.0 - u) * (1.0 - u);
        }
        return 2.0 * kPi * sum / (3.0 * n);
    }
    double value(double t) const {
        if (t <= 0.0) return 0.0;
        double qt = q(t);
        return c0 * t / (qt * qt);
    }
    double slope(double t) const {
        if (t <= 0.0) return 0.0;
        double qt = q(t);
        return c0 * (qt - 2.0 * b * t) / (qt * qt * qt);
    }
    // K(t) + K''(t) var / 2, the expectation of K over a spread of t with variance var.
    double expected(double t, double var) const {
        if (t <= 0.0) return 0.0;
        double qt = q(t), q2 = qt * qt;
        double k = c0 * t / q2;
        double k2 = c0 * 2.0 * b * (3.0 * b * t - 2.0 * qt) / (q2 * q2);
        return k + 0.5 * k2 * var;
    }
};

struct NodeRef {
    int32_t level, face;
    int64_t j, i;
};

constexpr int kLeafSamples = 3;
// A node across n's horizon is expanded anyway when omega K there is below this fraction of
// Int K: each such node errs by at most that much. Narrow lobes are ~0 at the horizon and may
// skip the kink coarsely; broad lobes (the cosine) meet it along the whole horizon.
constexpr double kKinkToleranceNarrow = 1e-4, kKinkToleranceBroad = 1e-6;  // per edge, for texels of the finest level still too close

// Sum over the pyramid of Int L K and Int K (per channel into num, and den) at unit direction n.
void sum_lobe(const Pyramid& pyr, const Lobe& lobe, double tau, double kink_tol, const Vec3& n,
              double* num, double& den) {
    const int64_t nch = pyr.channels, stride = pyr.stride();
    NodeRef stack[256];
    double radius[64];  // angular radius bound of a node of each level, about its centre
    const float* base[64];
    for (int s = 0; s < pyr.levels; ++s) {
        radius[s] = std::atan(1.4142135623730951 / double(pyr.p >> s));
        base[s] = pyr.data + pyr.offset(s);
    }
    int top = 0;
    const int coarsest = pyr.levels - 1;
    for (int f = 0; f < 6; ++f) stack[top++] = {coarsest, f, 0, 0};
    while (top > 0) {
        NodeRef nd = stack[--top];

        const int64_t q = pyr.p >> nd.level;
        const float* node = base[nd.level] + ((nd.face * q + nd.j) * q + nd.i) * stride;
        double omega = node[0];
        double gx = node[2], gy = node[3], gz = node[4];
        double g2 = gx * gx + gy * gy + gz * gz, inv_g = 1.0 / std::sqrt(g2);
        double tu = (n.x * gx + n.y * gy + n.z * gz) * inv_g;
        double sin_g = std::sqrt(std::max(0.0, 1.0 - tu * tu));
        double r = radius[nd.level];
        double dt = sin_g * r + 0.5 * r * r;
        if (tu + dt <= 0.0) continue;  // wholly below n's horizon
        // Across the horizon K has a kink; the expansion may skip it where K is negligible
        // there (narrow lobes: K(dt) omega below kink_tol of the lobe's integral).
        bool across = tu - dt <= 0.0 && omega * lobe.value(std::min(1.0, 2.0 * dt)) > kink_tol;
        bool near = across || dt * std::fabs(lobe.b) > tau * lobe.q(std::min(1.0, tu + dt));
        if (!near) {
            double tg = tu / inv_g;
            double vg = 0.5 * (1.0 - tu * tu) * (1.0 - g2);
            den += omega * lobe.expected(tg, vg);
            double lx = node[5], ly = node[6], lz = node[7];
            double l2 = lx * lx + ly * ly + lz * lz;
            double tl = n.x * lx + n.y * ly + n.z * lz;
            double tlu = tl / std::sqrt(std::max(l2, 1e-30));
            double vl = 0.5 * (1.0 - tlu * tlu) * (1.0 - l2);
            double k = lobe.expected(tl, vl), k1 = lobe.slope(tl);
            for (int64_t c = 0; c < nch; ++c) {
                const float* pc = node + 8 + nch + 3 * c;
                double sc = node[8 + c];
                num[c] += sc * k + k1 * (n.x * pc[0] + n.y * pc[1] + n.z * pc[2] - tl * sc);
            }
            continue;
        }
        if (nd.level > 0) {
            for (int64_t y = 2 * nd.j; y < 2 * nd.j + 2; ++y)
                for (int64_t x = 2 * nd.i; x < 2 * nd.i + 2; ++x)
                    stack[top++] = {nd.level - 1, nd.face, y, x};
            continue;
        }
        // A texel of the finest level, too close for the expansion: its radiance is uniform,
        // so integrate K over it by kLeafSamples^2 midpoint sub-samples.
        const double h = 1.0 / double(q), step = 2.0 * h / kLeafSamples;
        double ksum = 0.0;
        for (int v = 0; v < kLeafSamples; ++v) {
            double b = -1.0 + 2.0 * double(nd.j) * h + (v + 0.5) * step;
            for (int u = 0; u < kLeafSamples; ++u) {
                double a = -1.0 + 2.0 * double(nd.i) * h + (u + 0.5) * step;
                Vec3 d = cube_gl::face_to_dir(nd.face, a, b);
                double w = cube_gl::density(nd.face, a, b) * step * step;
                ksum += w * lobe.value(n.x * d.x + n.y * d.y + n.z * d.z);
            }
        }
        den += ksum;
        for (int64_t c = 0; c < nch; ++c) num[c] += double(node[8 + c]) / omega * ksum;
    }
}

}  // namespace

void build_pyramid(const float* faces, int64_t p, int64_t channels, float* out, int threads) {
    Pyramid pyr{out, p, 0, channels};
    for (int64_t q = p; q >= 1; q >>= 1) ++pyr.levels;
    build_level0(faces, p, channels, out, threads);
    for (int s = 1; s < pyr.levels; ++s)
        build_parent(out + pyr.offset(s - 1), p >> s, channels, out + pyr.offset(s), threads);
}

void prefilter(const Pyramid& pyr, const Geometry& dst, double scale_x, double scale_y,
               double alpha, int samples, const Rotation& rot, bool fill, double tau,
               float* out, int64_t height, int64_t width, int threads) {
    const int64_t nch = pyr.channels;
    const Lobe lobe(std::max(alpha, 1e-4));
    const double kink_tol =
        (alpha > 0.1 ? kKinkToleranceBroad : kKinkToleranceNarrow) * lobe.integral();
    const double sub_area = (2.0 * scale_x / double(dst.aspect * dst.n)) *
                            (2.0 * scale_y / double(dst.n)) / double(samples * samples);
    parallel_for(height, threads, [&](int64_t j) {
        std::vector<double> num(nch), acc(nch);
        for (int64_t i = 0; i < width; ++i) {
            std::fill(acc.begin(), acc.end(), 0.0);
            double wsum = 0.0;
            for (int sy = 0; sy < samples; ++sy) {
                double py = (double(j) + (sy + 0.5) / samples) * scale_y;
                for (int sx = 0; sx < samples; ++sx) {
                    double px = (double(i) + (sx + 0.5) / samples) * scale_x;
                    OutputSample s = output_sample(dst, px, py, fill);
                    if (!s.readable) continue;
                    double w = density(dst.family, s.face, s.a, s.b) * sub_area;
                    Vec3 n = rot.apply(face_to_dir(dst.family, s.face, s.a, s.b));
                    std::fill(num.begin(), num.end(), 0.0);
                    double den = 0.0;
                    sum_lobe(pyr, lobe, tau, kink_tol, n, num.data(), den);
                    if (!(den > 0.0)) continue;
                    for (int64_t c = 0; c < nch; ++c) acc[c] += w * num[c] / den;
                    wsum += w;
                }
            }
            float* px = out + (j * width + i) * nch;
            for (int64_t c = 0; c < nch; ++c) px[c] = wsum > 0.0 ? float(acc[c] / wsum) : 0.0f;
        }
    });
}

void sh_project(const float* image, int64_t height, int64_t width, int64_t channels,
                const Geometry& g, int samples, double sign_x, double* out, int threads) {
    const int64_t terms = 9 * channels;
    std::vector<double> rows(height * terms, 0.0);
    const double area = (2.0 / double(g.aspect * g.n)) * (2.0 / double(g.n));
    const double c0 = 0.28209479177387814, c1 = 0.4886025119029199, c2 = 1.0925484305920792,
                 c3 = 0.31539156525252005, c4 = 0.5462742152960396;
    // A point counts when it is valid and its direction belongs to its own cell (tennisball's
    // bands overlap); returns its direction and solid-angle density.
    auto owned = [&](double px, double py, Vec3& d, double& dens) {
        Located at = locate(g, px, py);
        if (!point_valid(g, at.face, at.a, at.b)) return false;
        d = face_to_dir(g.family, at.face, at.a, at.b);
        FacePoint back = dir_to_face(g.family, d.x, d.y, d.z);
        if (face_to_image(g, back.face, back.a, back.b).cell != at.cell) return false;
        dens = density(g.family, at.face, at.a, at.b);
        return true;
    };
    parallel_for(height, threads, [&](int64_t j) {
        double* acc = rows.data() + j * terms;
        double basis[9];
        for (int64_t i = 0; i < width; ++i) {
            int inside = 0;
            Vec3 d;
            double dens;
            for (double cy : {0.01, 0.99})
                for (double cx : {0.01, 0.99}) inside += owned(i + cx, j + cy, d, dens);
            if (inside == 0) continue;
            int s = inside == 4 ? samples : 16;
            double sums[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
            for (int sy = 0; sy < s; ++sy) {
                for (int sx = 0; sx < s; ++sx) {
                    if (!owned(i + (sx + 0.5) / s, j + (sy + 0.5) / s, d, dens)) continue;
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
