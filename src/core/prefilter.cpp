// The GGX prefilter's walk over the pyramid (see ibl.h for the method).
//
// Output samples are walked in tiles, a dual-tree walk (Gray & Moore, NIPS 2000): a tile of
// samples is a spherical cap (centre c, radius R) and a node a cap (u, r), so over every pair
// of a sample and a point of the node, t = n.l lies within the same bounds the single-sample
// test uses, widened by R. A node that passes the single-sample test for every sample of the
// tile is expanded for all of them at once (a loop over the tile's samples, which vectorises);
// a node that fails it for some is opened while it is larger than the tile and otherwise handed
// to the tile's four quarters, down to single samples. Every node is thus expanded only where
// the single-sample test would accept it (or a finer one), and the tile test only adds openings:
// accuracy is never below that of a walk per sample, and the coarse part of the walk is shared.
#include <algorithm>
#include <cmath>
#include <vector>

#include "ibl.h"
#include "parallel.h"

namespace envconv {
namespace {

// The zonal GGX lobe as a function of t = n.l (see ibl.h).
struct Lobe {
    double c0, b;
    explicit Lobe(double alpha) : c0(alpha * alpha / kPi), b(0.5 * (alpha * alpha - 1.0)) {}
    double q(double t) const { return 1.0 + b * (1.0 + t); }
    double value(double t) const {
        double qt = q(t);
        return t > 0.0 ? c0 * t / (qt * qt) : 0.0;
    }
    // Int K dl over the sphere = 2 pi Int_0^1 K(t) dt (Simpson in u, t = 1 - (1 - u)^3, which
    // crowds samples at t = 1, where K peaks with width ~alpha^2).
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
};

struct NodeRef {
    int32_t level, face, j, i;
};

constexpr int kLeafSamples = 3;
// A node across n's horizon (where K has a kink) is expanded anyway, by expand_across(), when
// its weight (see classify) times K there is below this fraction of Int K; otherwise it is
// opened. Narrow lobes are ~0 at
// the horizon; broad lobes (the cosine) meet it along the whole horizon, where expand_across()
// errs by a few per cent of omega K' sigma (sigma the node's spread of t) instead of the whole
// omega K of the plain expansion: 1e-3 leaves the irradiance of a sun on the horizon within
// 0.1% of the brute-force integral (1e-6 without it gave 0.07%).
constexpr double kKinkToleranceNarrow = 1e-4, kKinkToleranceBroad = 1e-3;
// Output samples per tile side (a tile is about this many samples square).
constexpr int kTileSamples = 8;

enum Verdict { kCull, kExpand, kExpandAcross, kOpen, kDefer, kLeaf };

// Per-thread state of the walk over one tile of output samples.
struct Walk {
    const Pyramid& pyr;
    const Lobe& lobe;
    double tau, kink_tol, inv_mean_lum = 0.0;
    int64_t nch, stride;
    const float* base[64];
    // The tile's samples, row-major in a grid of gw x gh: direction, weight, sums.
    int gw = 0, gh = 0;
    std::vector<double> nx, ny, nz, weight, den, num;  // num: channel-major, gw * gh each
    // Gathered samples of the current sub-tile, and per-sample scratch.
    std::vector<double> sx, sy, sz, sden, snum;
    std::vector<float> fx, fy, fz, fden, fk, fk1;
    std::vector<int> index;
    std::vector<std::vector<NodeRef>> lists;
    std::vector<NodeRef> stack;

    Walk(const Pyramid& p, const Lobe& l, double t, double kt)
        : pyr(p), lobe(l), tau(t), kink_tol(kt), nch(p.channels), stride(p.stride()) {
        for (int s = 0; s < p.levels; ++s) base[s] = p.data + p.offset(s);
    }
    const float* node(const NodeRef& nd) const {
        const int64_t q = pyr.p >> nd.level;
        return base[nd.level] + ((int64_t(nd.face) * q + nd.j) * q + nd.i) * stride;
    }
    Verdict classify(const NodeRef& nd, const float* f, const Vec3& c, double cR, double sR) const;
    void expand(const float* f, int m);
    void expand_across(const float* f, int m);
    void leaf(const NodeRef& nd, const float* f);
    int gather(int x0, int y0, int w, int h, Vec3& c, double& cR);
    void quarters(int x0, int y0, int w, int h, int depth, const std::vector<NodeRef>& in);
    void tile(int x0, int y0, int w, int h, int depth, const std::vector<NodeRef>& in);
    void reset(int w, int h);
    void write(int samples, int64_t pw, int64_t ph, float* out, int64_t width) const;
};

// What the single-sample test says of node `f` for every sample in the cap (c, R), cos R = cR.
// t = n.u over the cap spans [cos(theta + R), cos(theta - R)] (theta the angle from c to u);
// the node adds its own spread dt = sin(theta_n) sin r + 1 - cos r about each sample's n.u.
Verdict Walk::classify(const NodeRef& nd, const float* f, const Vec3& c, double cR,
                       double sR) const {
    double tc = std::clamp(c.x * f[2] + c.y * f[3] + c.z * f[4], -1.0, 1.0);
    double sc = std::sqrt(std::max(0.0, 1.0 - tc * tc));
    double cos_lo = tc * cR - sc * sR, sin_lo = sc * cR + tc * sR;  // at theta + R
    double cos_hi = tc * cR + sc * sR, sin_hi = sc * cR - tc * sR;  // at theta - R
    double tu_max = tc >= cR ? 1.0 : cos_hi;
    double tu_min = sin_lo < 0.0 ? -1.0 : cos_lo;
    double sin_max = cos_lo >= 0.0 ? sin_lo : (cos_hi <= 0.0 ? sin_hi : 1.0);
    double dt = sin_max * double(f[11]) + double(f[10]);
    if (tu_max + dt <= 0.0) return kCull;  // below every sample's horizon
    // Across the horizon K has a kink; the expansion may skip it where K is negligible there:
    // K(2 dt) times the node's weight below kink_tol of the lobe's integral. The weight is the
    // larger of omega and the solid angle that the node's luminance would fill at the map's mean
    // radiance, so that a sun on the horizon is opened though its solid angle is small.
    double weight = std::max(double(f[0]), double(f[1]) * inv_mean_lum);
    bool across = tu_min - dt <= 0.0 && weight * lobe.value(std::min(1.0, 2.0 * dt)) > kink_tol;
    double step = dt * std::fabs(lobe.b), room = tau * lobe.q(std::min(1.0, tu_max + dt));
    // A node brighter than the map's mean (weight > omega) is held to a tighter step, by the
    // square root of the ratio: a sun stays exact where the expansion of sky is already good.
    bool near = across || step > room ||
                (weight > f[0] && step * step * weight > room * room * f[0]);
    if (!near) return tu_min - dt <= 0.0 ? kExpandAcross : kExpand;
    if (sR > 0.0) return (nd.level == 0 || double(f[11]) <= sR) ? kDefer : kOpen;
    return nd.level == 0 ? kLeaf : kOpen;
}

// Per sample: K's expansion about the geometric mean (fden, times omega) and about the
// luminance-weighted one (fk) with its slope (fk1), in float, four samples to a vector: t enters
// as 1 - t = |n - u|^2 / 2, so that q(t) = a^2 + (1 - a^2)(1 - t) / 2 keeps its relative
// precision at the peak, where q ~ a^2.
void lobe_terms(const Lobe& lobe, const float* f, int m, const float* __restrict fx,
                const float* __restrict fy, const float* __restrict fz, float* __restrict fden,
                float* __restrict fk, float* __restrict fk1) {
    using real = float;  // four to an SSE vector
    const real c0 = real(lobe.c0), b = real(lobe.b), a2 = real(1.0 + 2.0 * lobe.b);
    const real hb = real(-lobe.b), omega = f[0];
    const double gn = f[5], ln = f[9];
    const real ugx = f[2], ugy = f[3], ugz = f[4], fgn = f[5];
    const real og = real(1.0 - gn), vg = real(0.5 * (1.0 - gn) * (1.0 + gn));
    const real ulx = f[6], uly = f[7], ulz = f[8], fln = f[9];
    const real ol = real(1.0 - ln), vl = real(0.5 * (1.0 - ln) * (1.0 + ln));
    for (int s = 0; s < m; ++s) {
        real dx = fx[s] - ugx, dy = fy[s] - ugy, dz = fz[s] - ugz;
        real wu = 0.5f * (dx * dx + dy * dy + dz * dz);  // 1 - n.u
        real wg = og + fgn * wu, tg = 1.0f - wg;           // 1 - t and t
        real qg = a2 + hb * wg, ig = 1.0f / qg, ig2 = ig * ig;
        real kg = c0 * tg * ig2 +
                   c0 * b * (3.0f * b * tg - 2.0f * qg) * ig2 * ig2 * vg * (wu * (2.0f - wu));
        fden[s] = tg > 0.0f ? omega * kg : 0.0f;
        real ex = fx[s] - ulx, ey = fy[s] - uly, ez = fz[s] - ulz;
        real wv = 0.5f * (ex * ex + ey * ey + ez * ez);
        real wl = ol + fln * wv, tl = 1.0f - wl;
        real ql = a2 + hb * wl, il = 1.0f / ql, il2 = il * il;
        real kl = c0 * tl * il2 +
                   c0 * b * (3.0f * b * tl - 2.0f * ql) * il2 * il2 * vl * (wv * (2.0f - wv));
        real k1 = c0 * (ql - 2.0f * b * tl) * il2 * il;
        fk[s] = tl > 0.0f ? kl : 0.0f;
        fk1[s] = tl > 0.0f ? k1 : 0.0f;
    }
}

// Add node f's expansion to the m gathered samples: Int_node L K(n.l) dl ~
// S [K(t) + K''(t) Var(t) / 2] + K'(t) n.P about the luminance-weighted mean (P each channel's
// first moment about it), Int_node K with the geometric mean into den. The sums are in double.
void Walk::expand(const float* f, int m) {
    lobe_terms(lobe, f, m, fx.data(), fy.data(), fz.data(), fden.data(), fk.data(), fk1.data());
    for (int s = 0; s < m; ++s) sden[s] += fden[s];
    for (int64_t ch = 0; ch < nch; ++ch) {
        const double sc = f[Pyramid::kFields + ch];
        const float* pc = f + Pyramid::kFields + nch + 3 * ch;
        const double px = pc[0], py = pc[1], pz = pc[2];
        double* acc = snum.data() + ch * m;
        for (int s = 0; s < m; ++s)
            acc[s] += sc * fk[s] + fk1[s] * (sx[s] * px + sy[s] * py + sz[s] * pz);
    }
}

// Int_0^x K(t) g(t) dt for x in [0, 2] by 2-point Gauss-Legendre (K is smooth on [0, x]).
template <typename G>
inline double positive_part(const Lobe& lobe, double x, G g) {
    const double h = 0.5 * x, d = h * 0.5773502691896258;
    return h * (lobe.value(h - d) * g(h - d) + lobe.value(h + d) * g(h + d));
}

// expand() for a node that may straddle a sample's horizon, where K has a kink at t = 0: there
// t over the node is taken as uniform on [t - w, t + w] (w^2 = 3 Var(t)) and K's mean and its
// covariance with t (which carries each channel's first moment) are integrated over the part
// above the horizon. Where the interval does not reach the horizon this is expand() itself.
void Walk::expand_across(const float* f, int m) {
    const double omega = f[0];
    const double ugx = f[2], ugy = f[3], ugz = f[4], gn = f[5], vg0 = 0.5 * (1.0 - gn * gn);
    const double ulx = f[6], uly = f[7], ulz = f[8], ln = f[9], vl0 = 0.5 * (1.0 - ln * ln);
    const double c0 = lobe.c0, b = lobe.b;
    for (int s = 0; s < m; ++s) {
        double tu = sx[s] * ugx + sy[s] * ugy + sz[s] * ugz, tg = tu * gn;
        double vg = vg0 * (1.0 - tu * tu), wg = std::sqrt(3.0 * vg);
        if (tg - wg >= 0.0) {
            double qg = 1.0 + b * (1.0 + tg), ig2 = 1.0 / (qg * qg);
            sden[s] += omega * (c0 * tg * ig2 + c0 * b * (3.0 * b * tg - 2.0 * qg) * ig2 * ig2 * vg);
        } else if (tg + wg > 0.0) {
            sden[s] += omega * positive_part(lobe, tg + wg, [](double) { return 1.0; }) / (2.0 * wg);
        }
        double tlu = sx[s] * ulx + sy[s] * uly + sz[s] * ulz, tl = tlu * ln;
        double vl = vl0 * (1.0 - tlu * tlu), wl = std::sqrt(3.0 * vl), k = 0.0, k1 = 0.0;
        if (tl - wl >= 0.0) {
            double ql = 1.0 + b * (1.0 + tl), il = 1.0 / ql, il2 = il * il;
            k = c0 * tl * il2 + c0 * b * (3.0 * b * tl - 2.0 * ql) * il2 * il2 * vl;
            k1 = c0 * (ql - 2.0 * b * tl) * il2 * il;
        } else if (tl + wl > 0.0) {
            k = positive_part(lobe, tl + wl, [](double) { return 1.0; }) / (2.0 * wl);
            if (vl > 1e-30)
                k1 = positive_part(lobe, tl + wl, [tl](double t) { return t - tl; }) /
                     (2.0 * wl * vl);
        }
        for (int64_t ch = 0; ch < nch; ++ch) {
            const double sc = f[Pyramid::kFields + ch];
            const float* pc = f + Pyramid::kFields + nch + 3 * ch;
            snum[ch * m + s] += sc * k + k1 * (sx[s] * pc[0] + sy[s] * pc[1] + sz[s] * pc[2]);
        }
    }
}

// A texel of the finest level, too close for the expansion at the one gathered sample: its
// radiance is uniform, so integrate K over it by kLeafSamples^2 midpoint sub-samples.
void Walk::leaf(const NodeRef& nd, const float* f) {
    const double h = 1.0 / double(pyr.p), step = 2.0 * h / kLeafSamples;
    double ksum = 0.0;
    for (int v = 0; v < kLeafSamples; ++v) {
        double b = -1.0 + 2.0 * double(nd.j) * h + (v + 0.5) * step;
        for (int u = 0; u < kLeafSamples; ++u) {
            double a = -1.0 + 2.0 * double(nd.i) * h + (u + 0.5) * step;
            Vec3 d = cube_gl::face_to_dir(nd.face, a, b);
            double w = cube_gl::density(nd.face, a, b) * step * step;
            ksum += w * lobe.value(sx[0] * d.x + sy[0] * d.y + sz[0] * d.z);
        }
    }
    sden[0] += ksum;
    for (int64_t c = 0; c < nch; ++c)
        snum[c] += double(f[Pyramid::kFields + c]) / double(f[0]) * ksum;
}

// Gather the valid samples of grid rectangle (x0, y0, w, h) into sx, sy, sz (and fx, fy, fz),
// clear their sums; their cap's centre into c and the cosine of its radius into cR. The count.
int Walk::gather(int x0, int y0, int w, int h, Vec3& c, double& cR) {
    index.clear();
    double cx = 0.0, cy = 0.0, cz = 0.0;
    for (int y = y0; y < y0 + h; ++y) {
        for (int x = x0; x < x0 + w; ++x) {
            int k = y * gw + x;
            if (!(weight[k] > 0.0)) continue;
            index.push_back(k);
            cx += nx[k];
            cy += ny[k];
            cz += nz[k];
        }
    }
    const int m = int(index.size());
    double len = std::sqrt(cx * cx + cy * cy + cz * cz);
    c = m ? Vec3{cx / len, cy / len, cz / len} : Vec3{0.0, 0.0, 1.0};
    cR = 1.0;
    for (int s = 0; s < m; ++s) {
        sx[s] = nx[index[s]];
        sy[s] = ny[index[s]];
        sz[s] = nz[index[s]];
        fx[s] = float(sx[s]);
        fy[s] = float(sy[s]);
        fz[s] = float(sz[s]);
        sden[s] = 0.0;
        cR = std::min(cR, sx[s] * c.x + sy[s] * c.y + sz[s] * c.z);
    }
    std::fill(snum.begin(), snum.begin() + nch * m, 0.0);
    return m;
}

// tile() on each quarter of grid rectangle (x0, y0, w, h).
void Walk::quarters(int x0, int y0, int w, int h, int depth, const std::vector<NodeRef>& in) {
    int hw = (w + 1) / 2, hh = (h + 1) / 2;
    for (int qy = 0; qy < 2; ++qy)
        for (int qx = 0; qx < 2; ++qx)
            if (qx * hw < w && qy * hh < h)
                tile(x0 + qx * hw, y0 + qy * hh, qx ? w - hw : hw, qy ? h - hh : hh, depth, in);
}

// Walk the nodes `in` for the samples of grid rectangle (x0, y0, w, h), then its quarters.
void Walk::tile(int x0, int y0, int w, int h, int depth, const std::vector<NodeRef>& in) {
    Vec3 c;
    double cR;
    const int m = gather(x0, y0, w, h, c, cR);
    if (m == 0) return;
    const bool split = m > 1;  // one sample is resolved here; more go on to the quarters
    if (split && !(cR > 0.5)) return quarters(x0, y0, w, h, depth, in);  // too wide to share
    // Bounds rounded outwards, so that float error never lets a node through.
    cR = split ? std::max(0.0, cR - 1e-12) : 1.0;
    const double sR = split ? std::sqrt(std::max(0.0, 1.0 - cR * cR)) + 1e-12 : 0.0;
    if (int(lists.size()) <= depth) lists.resize(depth + 1);
    std::vector<NodeRef>& deferred = lists[depth];
    deferred.clear();
    stack.assign(in.begin(), in.end());
    while (!stack.empty()) {
        NodeRef nd = stack.back();
        stack.pop_back();
        const float* f = node(nd);
        switch (classify(nd, f, c, cR, sR)) {
            case kCull: break;
            case kExpandAcross: expand_across(f, m); break;
            case kExpand: expand(f, m); break;
            case kDefer: deferred.push_back(nd); break;
            case kLeaf: leaf(nd, f); break;
            case kOpen:
                for (int32_t y = 2 * nd.j; y < 2 * nd.j + 2; ++y)
                    for (int32_t x = 2 * nd.i; x < 2 * nd.i + 2; ++x)
                        stack.push_back({nd.level - 1, nd.face, y, x});
                break;
        }
    }
    for (int s = 0; s < m; ++s) {
        den[index[s]] += sden[s];
        for (int64_t ch = 0; ch < nch; ++ch) num[ch * gw * gh + index[s]] += snum[ch * m + s];
    }
    if (deferred.empty() || !split) return;
    std::vector<NodeRef> mine;
    mine.swap(deferred);  // the quarters reuse lists[depth + 1 ...] only
    quarters(x0, y0, w, h, depth + 1, mine);
    mine.swap(lists[depth]);
}

// Size the tile's buffers for a grid of gw x gh samples, all zero (weight 0: not readable).
void Walk::reset(int w, int h) {
    gw = w;
    gh = h;
    const int cells = gw * gh;
    for (auto* v : {&nx, &ny, &nz, &weight, &den, &sx, &sy, &sz, &sden}) v->assign(cells, 0.0);
    for (auto* v : {&fx, &fy, &fz, &fden, &fk, &fk1}) v->assign(cells, 0.0f);
    num.assign(nch * cells, 0.0);
    snum.assign(nch * cells, 0.0);
}

// Each pixel of the tile (pw x ph pixels of samples x samples sub-samples) into `out` (rows of
// `width` pixels): the solid-angle mean of num / den over its sub-samples.
void Walk::write(int samples, int64_t pw, int64_t ph, float* out, int64_t width) const {
    std::vector<double> acc(nch);
    for (int64_t j = 0; j < ph; ++j) {
        for (int64_t i = 0; i < pw; ++i) {
            std::fill(acc.begin(), acc.end(), 0.0);
            double wsum = 0.0;
            for (int sy = 0; sy < samples; ++sy) {
                for (int sx = 0; sx < samples; ++sx) {
                    int k = int((j * samples + sy) * gw + i * samples + sx);
                    double w = weight[k], d = den[k];
                    if (!(w > 0.0) || !(d > 0.0)) continue;
                    for (int64_t c = 0; c < nch; ++c) acc[c] += w * num[c * gw * gh + k] / d;
                    wsum += w;
                }
            }
            float* px = out + (j * width + i) * nch;
            for (int64_t c = 0; c < nch; ++c) px[c] = wsum > 0.0 ? float(acc[c] / wsum) : 0.0f;
        }
    }
}

// 1 / the map's mean luminance (from the six root nodes), 0 for a black map: a node's
// luminance weight times it is the solid angle the node would fill at that mean radiance.
double inverse_mean_luminance(const Pyramid& pyr) {
    double lum = 0.0, area = 0.0;
    const float* top = pyr.data + pyr.offset(pyr.levels - 1);
    for (int f = 0; f < 6; ++f) {
        area += top[f * pyr.stride()];
        lum += top[f * pyr.stride() + 1];
    }
    return lum > 0.0 ? area / lum : 0.0;
}

}  // namespace

void prefilter(const Pyramid& pyr, const Geometry& dst, double scale_x, double scale_y,
               double alpha, int samples, const Rotation& rot, bool fill, double tau,
               float* out, int64_t height, int64_t width, int threads) {
    const int64_t nch = pyr.channels;
    const Lobe lobe(std::max(alpha, 1e-4));
    const double kink_tol =
        (alpha > 0.1 ? kKinkToleranceBroad : kKinkToleranceNarrow) * lobe.integral();
    const double sub_area = (2.0 * scale_x / double(dst.nx)) *
                            (2.0 * scale_y / double(dst.n)) / double(samples * samples);
    const int64_t span = std::max(1, kTileSamples / samples);  // pixels per tile side
    const int64_t tiles_x = (width + span - 1) / span, tiles_y = (height + span - 1) / span;
    const double inv_mean_lum = inverse_mean_luminance(pyr);
    std::vector<NodeRef> roots;
    for (int32_t f = 0; f < 6; ++f) roots.push_back({pyr.levels - 1, f, 0, 0});
    parallel_for(tiles_x * tiles_y, threads, [&](int64_t task) {
        const int64_t i0 = (task % tiles_x) * span, j0 = (task / tiles_x) * span;
        const int64_t pw = std::min(span, width - i0), ph = std::min(span, height - j0);
        Walk walk(pyr, lobe, tau, kink_tol);
        walk.inv_mean_lum = inv_mean_lum;
        const int gw = int(pw * samples), gh = int(ph * samples);
        walk.reset(gw, gh);
        for (int y = 0; y < gh; ++y) {
            double py = (double(j0) + (y + 0.5) / samples) * scale_y;
            for (int x = 0; x < gw; ++x) {
                double px = (double(i0) + (x + 0.5) / samples) * scale_x;
                OutputSample s = output_sample(dst, px, py, fill);
                if (!s.readable) continue;
                int k = y * gw + x;
                walk.weight[k] = density(dst, s.face, s.a, s.b) * sub_area;
                Vec3 n = rot.apply(face_to_dir(dst, s.face, s.a, s.b));
                walk.nx[k] = n.x;
                walk.ny[k] = n.y;
                walk.nz[k] = n.z;
            }
        }
        walk.tile(0, 0, gw, gh, 0, roots);
        walk.write(samples, pw, ph, out + (j0 * width + i0) * nch, width);
    });
}

}  // namespace envconv
