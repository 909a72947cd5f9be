// The area filter's entry point (area.cpp).
#pragma once

#include <cstdint>

#include "kernels.h"

namespace envconv {

// Fill `out` with the source integrated exactly over every output pixel's footprint (the box
// reconstruction, each texel weighted by the solid angle of its part; see area.cpp).
// samples >= 2 splits each pixel into samples x samples sub-pixels, each integrated exactly
// (the same integral, finer polygons); samples <= 1 integrates the pixel as one.
// linear: integrate the conservative piecewise-linear reconstruction of area_linear.h instead
// of the box (for magnifying conversions); valid_channel: the source's V channel (holes,
// partial views), whose texels below 1 keep the box with their neighbours, or -1.
void resample_area(const Image& src, const Conversion& cv, int samples, const ResampleOutput& out,
                   int threads, int64_t* progress, bool linear = false, int valid_channel = -1);

// Let the area filter integrate plain pixels directly (the default), or send every pixel
// through its general path; returns the previous setting. Both integrate the same footprints
// (tests/test_area.py compares them).
bool set_area_direct(bool allowed);

}  // namespace envconv
