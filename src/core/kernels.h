// The kernels the Python side calls (envconv/resample/kernels.py wraps each one, validates its arrays and
// carries its docstring). Arrays arrive as raw C-contiguous views; the GIL is released by the
// bindings around every call.
#pragma once

#include <cstdint>

#include "footprint.h"
#include "taps.h"

namespace envconv {

// Output of the resampler: colour (H, W, C) float32, and optionally the coverage (H, W) float32
// and the per-pixel sum of sub-sample weights (H, W) float32 (nullptr when not wanted; float32
// halves the largest array of a mip chain, and keeps 7 digits of a sum accumulated in double).
struct ResampleOutput {
    float* pixels;
    int64_t height, width, channels;
    float* alpha;
    float* weights;
    bool zeroed;  // every output array already holds zeros: empty cells are left untouched
    // Floats from one pixel to the next in `pixels` (0: `channels`) and in `alpha` (1: a
    // plane); with stride channels + 1 and alpha = pixels + channels, the coverage lands in
    // the channel after the colour ones, so an alpha channel needs no second array.
    int64_t stride = 0;
    int64_t alpha_stride = 1;
    // The first row the arrays hold (the area filter's sub-pixel bands hold a few rows only).
    int64_t row0 = 0;
};

// A lat-long source's rip-map levels (rip_levels = 0: none), filled in rip_rows rows per pole.
struct RipMap {
    Image image;
    int levels;
    int64_t rows;
};

// Fill `out` with the resampled environment; see envconv/resample/convert.py for the rules.
// samples <= 0 asks for adaptive sampling. `progress`, when not null, counts the bands of
// kTile output rows finished (atomically), for a watcher on another thread.
void resample(const Image& src, const RipMap& rip, const Conversion& cv, int samples, int filter,
              const ResampleOutput& out, int threads, int64_t* progress = nullptr);

// Let the resampler map rows with AVX where the CPU has it (the default), or not; returns the
// previous setting. Either gives the same bytes (tests/test_core.py compares them).
bool set_wide_rows(bool allowed);

// Fill rows [0, rows) and [H - rows, H) of the packed rip-map `out` (H, W - W_K, C) from `src`.
void fill_rips(const Image& src, int levels, int64_t rows, float* out, int threads);

// Weighted means of bx x by blocks: out (h, w, C), weight sums wout, mean coverage aout
// (asrc and aout both nullptr when the coverage is not wanted).
void reduce_blocks(const Image& src, const float* wsrc, const float* asrc, int64_t bx,
                   int64_t by, float* out, int64_t height, int64_t width, float* wout,
                   float* aout, int threads);

// Directions of level-0 image points (n, 2); flags 2 valid, 1 guard/fill, 0 no data.
void map_points_to_dirs(const Geometry& g, const double* points, int64_t count, bool fill,
                        double* dirs, int8_t* flags, int threads);

// Level-0 image points (n, 2) of unit directions (n, 3).
void map_dirs_to_points(const Geometry& g, const double* dirs, int64_t count, double* points,
                        int threads);

// Solid angle (sr) of the valid part of every pixel of an (H, W) image of pixels scale_x x
// scale_y level-0 pixels wide, by S x S sub-samples.
void pixel_solid_angles(const Geometry& g, double scale_x, double scale_y, int samples,
                        double* out, int64_t height, int64_t width, int threads);

// Solid-angle density of the layout at each direction's (face, a, b).
void dir_density(const Geometry& g, const double* dirs, int64_t count, double* out);

}  // namespace envconv
