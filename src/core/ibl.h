// Image-based lighting kernels: the GGX (Trowbridge-Reitz) prefilter of the split-sum
// approximation, the clamped-cosine (irradiance) convolution, and the order-2 spherical-harmonic
// projection. envconv/resample/ibl.py and envconv/resample/harmonics.py wrap them and carry the docs.
//
// Prefilter. With N = V = R the lobe is zonal: level k holds
//   L_k(n) = Int L(l) K(n.l) dl / Int K(n.l) dl,   K(t) = D(h) t+,  n.h = sqrt((1 + t) / 2),
//   D(h) = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2),    a = roughness^2,
// so K(t) = a^2 t / (pi q(t)^2) with q(t) = 1 + (a^2 - 1)(1 + t) / 2, a rational function of t.
// a = 1 gives K = t+ / pi: the clamped cosine, and L_k = E / pi (irradiance over pi).
//
// Evaluation is a Barnes-Hut sum over a pyramid of the source cube's texels (Barnes & Hut,
// Nature 324, 1986): each node stores its solid angle, Int L dl per channel, and two mean
// directions, the geometric one and the luminance-weighted one (as unit vectors and lengths
// |m|: 1 - |m|^2 is the spread of directions in the node). A node far enough from n that K is
// smooth over it contributes by a second-order expansion of K about the node's mean t = n.m:
//   Int_node L K(n.l) dl ~ S [K(t) + K''(t) Var(t) / 2],  Var(t) ~ (1 - t^2)(1 - |m|^2) / 2,
// exact for a constant node to second order and, with each channel's first moment, exact to
// first order for any radiance inside it (a one-texel sun is placed where it is, not at the
// node's centre). A node is expanded when its spread of t, dt, is small against K's own scale
// there, q(t) / |q'| (dt |b| <= tau q, tighter for nodes brighter than the map's mean), and it
// does not straddle n's horizon (where K has a kink) unless K is negligible there (a node that
// does is integrated over its part above the horizon); other nodes are opened, and texels of
// the finest level still too close are integrated by 3 x 3 sub-samples. prefilter.cpp walks
// tiles of output samples together (a dual-tree walk) and gives the details. Sums are normalised per output sample by
// the same expansion of Int K with the geometric means, so a constant environment stays that
// constant. An output pixel is the solid-angle mean of S x S such point evaluations.
#pragma once

#include <cstdint>

#include "cells.h"

namespace envconv {

// A pyramid of the six faces of a cube (GL face table), level 0 of p x p texels per face, each
// level halving down to 1 x 1. Node (level s, face f, row j, column i) starts at
// data + offset(s) + ((f * (p >> s) + j) * (p >> s) + i) * stride, with fields
// [omega, W, ugx, ugy, ugz, |g|, ulx, uly, ulz, |l|, 1 - cos r, sin r, S_0 .. S_{C-1},
//  P_0 .. P_{C-1}]: solid angle, luminance weight Int max(lum, 0) dl, the geometric and the
// luminance-weighted mean directions each as a unit vector and a length (1 - |m|^2 is the
// spread of directions in the node), the node's angular radius r about the unit geometric mean
// (the largest angle to its four corners: its edges are great-circle arcs), Int L_c dl, and
// Int L_c (l - m_l) dl (three floats each), m_l = ul |l| as stored: the expansion about the
// luminance-weighted mean carries each channel's own first moment about it, so channels that
// differ are exact to first order too (and a uniform node's is 0, not a difference of floats).
struct Pyramid {
    static constexpr int64_t kFields = 12;
    const float* data;
    int64_t p;
    int levels;
    int64_t channels;
    static int64_t stride_for(int64_t channels) { return kFields + 4 * channels; }
    int64_t stride() const { return stride_for(channels); }
    // Nodes in levels 0 .. s - 1 of a pyramid of p (every level while p >> k >= 1): the one
    // place the pyramid's size is computed; Python allocates through floats_for
    // (envconv._core.ibl_pyramid_floats).
    static int64_t nodes_before(int64_t p, int s) {
        int64_t count = 0;
        for (int k = 0; k < s && (p >> k) >= 1; ++k) count += 6 * (p >> k) * (p >> k);
        return count;
    }
    int64_t offset(int s) const { return nodes_before(p, s) * stride(); }
    static int64_t node_count(int64_t p) { return nodes_before(p, 63); }
    // Floats of a whole pyramid of p with `channels` channels.
    static int64_t floats_for(int64_t p, int64_t channels) {
        return node_count(p) * stride_for(channels);
    }
};

// Build the pyramid of `faces` (6, p, p, C) float32, p a power of two, into `out`
// (Pyramid::node_count(p) * Pyramid::stride_for(C) floats).
void build_pyramid(const float* faces, int64_t p, int64_t channels, float* out, int threads);

// The pyramid of p straight from a lat-long image (height x 2 height, C channels, no guard):
// each pixel is sub x sub points, and every point's solid angle (centre rule), radiance and
// direction, turned by `to_pyramid`, land in the level-0 texel that holds that direction.
// Energy is kept exactly, a one-pixel sun keeps its direction, and each texel's solid angle,
// mean direction and radiance are its points', so a constant map stays constant. False (the
// pyramid unfinished) when a texel received no point: the source is too coarse for p.
bool build_pyramid_binned(const float* image, int64_t height, int64_t width, int64_t channels,
                          const Rotation& to_pyramid, int64_t p, int sub, float* out,
                          int threads);

// build_pyramid_binned for an image of any layout g (its cells, guard rings, disks): each pixel
// is sub x sub points, or at least 16 x 16 where only part of it is owned (sh_project's rule);
// delta bounds half the diagonal of a point, in radians.
bool build_pyramid_binned_any(const float* image, int64_t height, int64_t width,
                              int64_t channels, const Geometry& g, const Rotation& to_pyramid,
                              int64_t p, int sub, double delta, float* out, int threads);

// One prefiltered level: every pixel of `out` (H, W, C) is the solid-angle mean over its
// footprint (pixels scale_x x scale_y level-0 pixels wide in layout `dst`) of L_k, for
// roughness^2 = `alpha`, from `samples` x `samples` sub-samples per pixel. `rot` maps output
// directions to the pyramid's (source) directions. `tau` bounds the expansion's step.
void prefilter(const Pyramid& pyr, const Geometry& dst, double scale_x, double scale_y,
               double alpha, int samples, const Rotation& rot, bool fill, double tau,
               float* out, int64_t height, int64_t width, int threads);

// Order-2 SH projection of an image in layout `g`: out (9, C) float64 += Int L Y_lm, by
// `samples` x `samples` sub-samples per whole pixel and 16 x 16 where the valid region's edge
// cuts the pixel. sign_x = -1 evaluates the basis on (-x, y, z).
void sh_project(const float* image, int64_t height, int64_t width, int64_t channels,
                const Geometry& g, int samples, double sign_x, double* out, int threads);

}  // namespace envconv
