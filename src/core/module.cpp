// Python bindings of the native core: envconv._core.
//
// Each function takes C-contiguous numpy arrays of the stated dtypes (envconv/resample/kernels.py makes
// them so, allocates the outputs and carries the docstrings), releases the GIL and runs on
// `threads` threads. A layout instance arrives as four arrays: geo = [family, N, G, N_x,
// columns, rows, then the chart's kParamCount parameters] (float64; N_x is a cell's width
// without guard, A N for a cell of aspect A) and the int32 tables cell -> face, cell -> half
// turns, face -> cell.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "area.h"
#include "ibl.h"
#include "kernels.h"
#include "parallel.h"
#include "ripmap.h"
#include "tiles.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

template <typename T, typename... Extra>
using Array = nb::ndarray<T, nb::numpy, nb::c_contig, nb::device::cpu, Extra...>;

using GeoArray = Array<const double, nb::shape<6 + envconv::kParamCount>>;
using ParamArray = Array<const double, nb::shape<envconv::kParamCount>>;
using TableArray = Array<const int32_t, nb::ndim<1>>;

envconv::Chart make_chart(int family, const ParamArray& params) {
    if (family < 0 || family >= envconv::kFamilyCount) throw std::invalid_argument("bad family");
    envconv::Chart c;
    c.family = family;
    for (int k = 0; k < envconv::kParamCount; ++k) c.param[k] = params(k);
    return c;
}

envconv::Geometry make_geometry(const GeoArray& geo, const TableArray& cell_face,
                                const TableArray& cell_turns, const TableArray& face_cell) {
    envconv::Geometry g;
    for (int k = 0; k < 6; ++k) {  // whole numbers, well inside int64 (NaN fails too)
        if (!(std::fabs(geo(k)) < 9.0e15 && geo(k) == std::floor(geo(k))))
            throw std::invalid_argument("invalid layout geometry");
    }
    g.family = int(geo(0));
    g.n = int64_t(geo(1));
    g.guard = int64_t(geo(2));
    g.nx = int64_t(geo(3));
    g.columns = int64_t(geo(4));
    g.rows = int64_t(geo(5));
    for (int k = 0; k < envconv::kParamCount; ++k) g.param[k] = geo(6 + k);
    if (g.family < 0 || g.family >= envconv::kFamilyCount || g.n < 1 || g.guard < 0 ||
        g.nx < 1 || g.columns < 1 || g.rows < 1)
        throw std::invalid_argument("invalid layout geometry");
    if (int64_t(cell_face.shape(0)) != g.columns * g.rows ||
        int64_t(cell_turns.shape(0)) != g.columns * g.rows || face_cell.shape(0) < 1)
        throw std::invalid_argument("layout tables do not match the geometry");
    g.cell_face = cell_face.data();
    g.cell_turns = cell_turns.data();
    g.face_cell = face_cell.data();
    return g;
}

envconv::Image make_image(const Array<const float, nb::ndim<3>>& a) {
    return {a.data(), int64_t(a.shape(0)), int64_t(a.shape(1)), int64_t(a.shape(2))};
}

void resample(Array<const float, nb::ndim<3>> src, Array<const float, nb::ndim<3>> rip,
              int rip_levels, int64_t rip_rows, GeoArray sgeo, TableArray s_cell_face,
              TableArray s_cell_turns, TableArray s_face_cell, GeoArray dgeo,
              TableArray d_cell_face, TableArray d_cell_turns, TableArray d_face_cell,
              double scale_x, double scale_y, int samples, int filter,
              Array<const double, nb::shape<3, 3>> rot, bool fill, Array<float, nb::ndim<3>> out,
              Array<float, nb::ndim<2>> alpha, Array<float, nb::ndim<2>> weights, int threads,
              Array<int64_t, nb::shape<1>> progress, bool zeroed, bool coverage_channel,
              bool linear, int valid_channel) {
    envconv::Conversion cv;
    cv.src = make_geometry(sgeo, s_cell_face, s_cell_turns, s_face_cell);
    cv.dst = make_geometry(dgeo, d_cell_face, d_cell_turns, d_face_cell);
    for (int k = 0; k < 9; ++k) cv.rot.m[k] = rot.data()[k];
    cv.scale_x = scale_x;
    cv.scale_y = scale_y;
    cv.fill = fill;
    // coverage_channel: `out` has one channel more than `src`, which receives the coverage.
    int64_t height = out.shape(0), width = out.shape(1), nch = out.shape(2) - coverage_channel;
    auto sw = cv.src.columns * cv.src.cell_width(), sh = cv.src.rows * cv.src.cell_height();
    if (int64_t(src.shape(0)) != sh || int64_t(src.shape(1)) != sw)
        throw std::invalid_argument("source array does not match its layout's size");
    if (int64_t(src.shape(2)) != nch || int64_t(rip.shape(2)) != nch)
        throw std::invalid_argument("source and output channel counts differ");
    if (filter < envconv::kNearest || filter > envconv::kArea)
        throw std::invalid_argument("unknown filter code");
    if (linear && filter != envconv::kArea)
        throw std::invalid_argument("the linear reconstruction is the area filter's");
    if (valid_channel >= int64_t(src.shape(2)))
        throw std::invalid_argument("valid_channel is past the source's channels");
    bool has_alpha = alpha.is_valid(), has_weights = weights.is_valid();
    if (coverage_channel && (has_alpha || nch < 1))
        throw std::invalid_argument("coverage goes to the output's last channel or to alpha");
    if ((has_alpha && (int64_t(alpha.shape(0)) != height || int64_t(alpha.shape(1)) != width)) ||
        (has_weights &&
         (int64_t(weights.shape(0)) != height || int64_t(weights.shape(1)) != width)))
        throw std::invalid_argument("alpha and weights must have the output's height and width");
    if (rip_levels > 0 && (int64_t(rip.shape(0)) != sh || cv.src.family != envconv::kLatlong))
        throw std::invalid_argument("a rip-map needs a lat-long source of its height");
    envconv::RipMap rips{make_image(rip), rip_levels, rip_rows};
    envconv::ResampleOutput o{out.data(), height, width, nch,
                              has_alpha ? alpha.data() : nullptr,
                              has_weights ? weights.data() : nullptr, zeroed};
    if (coverage_channel) {
        o.stride = o.alpha_stride = nch + 1;
        o.alpha = out.data() + nch;
    }
    envconv::Image image = make_image(src);
    int64_t* counter = progress.is_valid() ? progress.data() : nullptr;
    nb::gil_scoped_release release;
    if (filter == envconv::kArea) {
        envconv::resample_area(image, cv, samples, o, threads, counter, linear, valid_channel);
        return;
    }
    envconv::resample(image, rips, cv, samples, filter, o, threads, counter);
}

void fill_rips(Array<const float, nb::ndim<3>> src, int levels, int64_t rows,
               Array<float, nb::ndim<3>> out, int threads) {
    int64_t width = src.shape(1);
    if (levels < 1 || (width >> levels) < 1 || out.shape(0) != src.shape(0) ||
        int64_t(out.shape(1)) != width - (width >> levels) || out.shape(2) != src.shape(2))
        throw std::invalid_argument("rip-map array has the wrong shape");
    envconv::Image image = make_image(src);
    nb::gil_scoped_release release;
    envconv::fill_rips(image, levels, std::max<int64_t>(0, rows), out.data(), threads);
}

void reduce_blocks(Array<const float, nb::ndim<3>> src, Array<const float, nb::ndim<2>> wsrc,
                   Array<const float, nb::ndim<2>> asrc, int64_t bx, int64_t by,
                   Array<float, nb::ndim<3>> out, Array<float, nb::ndim<2>> wout,
                   Array<float, nb::ndim<2>> aout, int threads) {
    int64_t height = out.shape(0), width = out.shape(1);
    if (bx < 1 || by < 1 || int64_t(src.shape(0)) < height * by ||
        int64_t(src.shape(1)) < width * bx || src.shape(2) != out.shape(2) ||
        wsrc.shape(0) != src.shape(0) || wsrc.shape(1) != src.shape(1) ||
        int64_t(wout.shape(0)) != height || int64_t(wout.shape(1)) != width ||
        asrc.is_valid() != aout.is_valid() ||
        (asrc.is_valid() && (asrc.shape(0) != src.shape(0) || asrc.shape(1) != src.shape(1) ||
                             int64_t(aout.shape(0)) != height || int64_t(aout.shape(1)) != width)))
        throw std::invalid_argument("block reduction arrays have mismatched shapes");
    envconv::Image image = make_image(src);
    const float* coverage = asrc.is_valid() ? asrc.data() : nullptr;
    float* coverage_out = aout.is_valid() ? aout.data() : nullptr;
    nb::gil_scoped_release release;
    envconv::reduce_blocks(image, wsrc.data(), coverage, bx, by, out.data(), height, width,
                           wout.data(), coverage_out, threads);
}

void map_points_to_dirs(GeoArray geo, TableArray cell_face, TableArray cell_turns,
                        TableArray face_cell, Array<const double, nb::shape<-1, 2>> points,
                        bool fill, Array<double, nb::shape<-1, 3>> dirs,
                        Array<int8_t, nb::ndim<1>> flags, int threads) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    int64_t count = points.shape(0);
    if (int64_t(dirs.shape(0)) != count || int64_t(flags.shape(0)) != count)
        throw std::invalid_argument("points, dirs and flags differ in length");
    nb::gil_scoped_release release;
    envconv::map_points_to_dirs(g, points.data(), count, fill, dirs.data(), flags.data(), threads);
}

void map_dirs_to_points(GeoArray geo, TableArray cell_face, TableArray cell_turns,
                        TableArray face_cell, Array<const double, nb::shape<-1, 3>> dirs,
                        Array<double, nb::shape<-1, 2>> points, int threads) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    int64_t count = dirs.shape(0);
    if (int64_t(points.shape(0)) != count)
        throw std::invalid_argument("dirs and points differ in length");
    nb::gil_scoped_release release;
    envconv::map_dirs_to_points(g, dirs.data(), count, points.data(), threads);
}

void pixel_solid_angles(GeoArray geo, TableArray cell_face, TableArray cell_turns,
                        TableArray face_cell, double scale_x, double scale_y, int samples,
                        Array<double, nb::ndim<2>> out, int threads) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    if (samples < 1) throw std::invalid_argument("samples must be at least 1");
    nb::gil_scoped_release release;
    envconv::pixel_solid_angles(g, scale_x, scale_y, samples, out.data(), out.shape(0),
                                out.shape(1), threads);
}

void dir_density(GeoArray geo, TableArray cell_face, TableArray cell_turns, TableArray face_cell,
                 Array<const double, nb::shape<-1, 3>> dirs, Array<double, nb::ndim<1>> out) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    if (out.shape(0) != dirs.shape(0)) throw std::invalid_argument("dirs and out differ in length");
    nb::gil_scoped_release release;
    envconv::dir_density(g, dirs.data(), dirs.shape(0), out.data());
}

// Per-family maps on flat arrays, for the layout modules and the tests.
void face_to_dir(int family, ParamArray params, Array<const int32_t, nb::ndim<1>> face,
                 Array<const double, nb::ndim<1>> a, Array<const double, nb::ndim<1>> b,
                 Array<double, nb::shape<-1, 3>> out) {
    envconv::Chart chart = make_chart(family, params);
    size_t n = a.shape(0);
    if (face.shape(0) != n || b.shape(0) != n || out.shape(0) != n)
        throw std::invalid_argument("face, a, b and out differ in length");
    nb::gil_scoped_release release;
    for (size_t k = 0; k < n; ++k) {
        envconv::Vec3 d = envconv::face_to_dir(chart, face(k), a(k), b(k));
        out(k, 0) = d.x;
        out(k, 1) = d.y;
        out(k, 2) = d.z;
    }
}

void dir_to_face(int family, ParamArray params, Array<const double, nb::shape<-1, 3>> dirs,
                 Array<int32_t, nb::ndim<1>> face, Array<double, nb::ndim<1>> a,
                 Array<double, nb::ndim<1>> b) {
    envconv::Chart chart = make_chart(family, params);
    size_t n = dirs.shape(0);
    if (face.shape(0) != n || a.shape(0) != n || b.shape(0) != n)
        throw std::invalid_argument("dirs, face, a and b differ in length");
    nb::gil_scoped_release release;
    for (size_t k = 0; k < n; ++k) {
        envconv::FacePoint f = envconv::dir_to_face(chart, dirs(k, 0), dirs(k, 1), dirs(k, 2));
        face(k) = f.face;
        a(k) = f.a;
        b(k) = f.b;
    }
}

void density(int family, ParamArray params, Array<const int32_t, nb::ndim<1>> face,
             Array<const double, nb::ndim<1>> a, Array<const double, nb::ndim<1>> b,
             Array<double, nb::ndim<1>> out) {
    envconv::Chart chart = make_chart(family, params);
    size_t n = a.shape(0);
    if (face.shape(0) != n || b.shape(0) != n || out.shape(0) != n)
        throw std::invalid_argument("face, a, b and out differ in length");
    nb::gil_scoped_release release;
    for (size_t k = 0; k < n; ++k) out(k) = envconv::density(chart, face(k), a(k), b(k));
}

// Test hooks: one filtered read of a source image, and one read of a rip-map level.
void filtered_reads(Array<const float, nb::ndim<3>> src, GeoArray geo, TableArray cell_face,
                    TableArray cell_turns, TableArray face_cell,
                    Array<const int64_t, nb::ndim<1>> cells,
                    Array<const double, nb::shape<-1, 2>> points, int filter,
                    Array<double, nb::ndim<2>> out) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    envconv::Image image = make_image(src);
    size_t n = points.shape(0);
    if (cells.shape(0) != n || out.shape(0) != n || int64_t(out.shape(1)) != image.channels)
        throw std::invalid_argument("cells, points and out differ in length");
    std::vector<double> tmp(3 * image.channels);
    nb::gil_scoped_release release;
    for (size_t k = 0; k < n; ++k) {
        double* acc = out.data() + k * image.channels;
        for (int64_t c = 0; c < image.channels; ++c) acc[c] = 0.0;
        envconv::accumulate_sample(image, g, cells(k), points(k, 0), points(k, 1), filter, 1.0,
                                   acc, tmp.data());
    }
}

void level_reads(Array<const float, nb::ndim<3>> rip, int64_t start, int64_t level_width,
                 Array<const double, nb::shape<-1, 2>> points, Array<double, nb::ndim<2>> out) {
    envconv::Image image = make_image(rip);
    size_t n = points.shape(0);
    if (out.shape(0) != n || int64_t(out.shape(1)) != image.channels || level_width < 1 ||
        start < 0 || start + level_width > image.width)
        throw std::invalid_argument("bad level read arguments");
    nb::gil_scoped_release release;
    for (size_t k = 0; k < n; ++k) {
        double* acc = out.data() + k * image.channels;
        for (int64_t c = 0; c < image.channels; ++c) acc[c] = 0.0;
        envconv::level_tap(image, start, level_width, points(k, 0), points(k, 1), 1.0, acc);
    }
}

// Image-based lighting (src/core/ibl.h).
void ibl_pyramid(Array<const float, nb::ndim<4>> faces, Array<float, nb::ndim<1>> out,
                 int threads) {
    int64_t p = faces.shape(1), nch = faces.shape(3);
    if (faces.shape(0) != 6 || int64_t(faces.shape(2)) != p || p < 1 || (p & (p - 1)) ||
        int64_t(out.shape(0)) != envconv::Pyramid::floats_for(p, nch))
        throw std::invalid_argument("faces must be (6, p, p, C) with p a power of two");
    nb::gil_scoped_release release;
    envconv::build_pyramid(faces.data(), p, nch, out.data(), threads);
}

bool ibl_pyramid_binned(Array<const float, nb::ndim<3>> image,
                        Array<const double, nb::shape<3, 3>> to_pyramid, int64_t p, int sub,
                        Array<float, nb::ndim<1>> out, int threads) {
    int64_t height = image.shape(0), width = image.shape(1), nch = image.shape(2);
    if (width != 2 * height || height < 1 || p < 1 || (p & (p - 1)) || sub < 1 ||
        int64_t(out.shape(0)) != envconv::Pyramid::floats_for(p, nch))
        throw std::invalid_argument("image must be a lat-long (H, 2H, C), p a power of two");
    envconv::Rotation r;
    for (int k = 0; k < 9; ++k) r.m[k] = to_pyramid.data()[k];
    nb::gil_scoped_release release;
    return envconv::build_pyramid_binned(image.data(), height, width, nch, r, p, sub,
                                         out.data(), threads);
}

bool ibl_pyramid_binned_any(Array<const float, nb::ndim<3>> image, GeoArray geo,
                            TableArray cell_face, TableArray cell_turns, TableArray face_cell,
                            Array<const double, nb::shape<3, 3>> to_pyramid, int64_t p, int sub,
                            double delta, Array<float, nb::ndim<1>> out, int threads) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    int64_t nch = image.shape(2);
    if (int64_t(image.shape(0)) != g.rows * g.cell_height() ||
        int64_t(image.shape(1)) != g.columns * g.cell_width())
        throw std::invalid_argument("image does not match its layout's size");
    if (p < 1 || (p & (p - 1)) || sub < 1 || !(delta >= 0.0) ||
        int64_t(out.shape(0)) != envconv::Pyramid::floats_for(p, nch))
        throw std::invalid_argument("p must be a power of two and out sized for its pyramid");
    envconv::Rotation r;
    for (int k = 0; k < 9; ++k) r.m[k] = to_pyramid.data()[k];
    nb::gil_scoped_release release;
    return envconv::build_pyramid_binned_any(image.data(), image.shape(0), image.shape(1), nch, g,
                                             r, p, sub, delta, out.data(), threads);
}

void ibl_prefilter(Array<const float, nb::ndim<1>> pyramid, int64_t p, int64_t channels,
                   GeoArray geo, TableArray cell_face, TableArray cell_turns,
                   TableArray face_cell, double scale_x, double scale_y, double alpha,
                   int samples, Array<const double, nb::shape<3, 3>> rot, bool fill, double tau,
                   Array<float, nb::ndim<3>> out, int threads) {
    envconv::Pyramid pyr{pyramid.data(), p, 0, channels};
    for (int64_t q = p; q >= 1; q >>= 1) ++pyr.levels;
    if (p < 1 || (p & (p - 1)) ||
        int64_t(pyramid.shape(0)) != envconv::Pyramid::floats_for(p, channels) ||
        int64_t(out.shape(2)) != channels || samples < 1 || !(alpha > 0.0) || !(tau > 0.0))
        throw std::invalid_argument("bad prefilter arguments");
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    envconv::Rotation r;
    for (int k = 0; k < 9; ++k) r.m[k] = rot.data()[k];
    nb::gil_scoped_release release;
    envconv::prefilter(pyr, g, scale_x, scale_y, alpha, samples, r, fill, tau, out.data(),
                       out.shape(0), out.shape(1), threads);
}

void sh_project(Array<const float, nb::ndim<3>> image, GeoArray geo, TableArray cell_face,
                TableArray cell_turns, TableArray face_cell, int samples, double sign_x,
                Array<double, nb::ndim<2>> out, int threads) {
    auto g = make_geometry(geo, cell_face, cell_turns, face_cell);
    if (out.shape(0) != 9 || out.shape(1) != image.shape(2) || samples < 1)
        throw std::invalid_argument("out must be (9, C)");
    if (int64_t(image.shape(0)) != g.rows * g.cell_height() ||
        int64_t(image.shape(1)) != g.columns * g.cell_width())
        throw std::invalid_argument("image does not match its layout's size");
    nb::gil_scoped_release release;
    envconv::sh_project(image.data(), image.shape(0), image.shape(1), image.shape(2), g,
                        samples, sign_x, out.data(), threads);
}

}  // namespace

NB_MODULE(_core, m) {
    m.doc() = "envconv's native kernels; use them through envconv.resample.kernels.";
    m.def("resample", &resample, "src"_a, "rip"_a, "rip_levels"_a, "rip_rows"_a, "sgeo"_a,
          "s_cell_face"_a, "s_cell_turns"_a, "s_face_cell"_a, "dgeo"_a, "d_cell_face"_a,
          "d_cell_turns"_a, "d_face_cell"_a, "scale_x"_a, "scale_y"_a, "samples"_a, "filter"_a,
          "rot"_a, "fill"_a, "out"_a, "alpha"_a.none(), "weights"_a.none(), "threads"_a,
          "progress"_a.none() = nb::none(), "zeroed"_a = false, "coverage_channel"_a = false,
          "linear"_a = false, "valid_channel"_a = -1);
    m.def("fill_rips", &fill_rips, "src"_a, "levels"_a, "rows"_a, "out"_a, "threads"_a);
    m.def("reduce_blocks", &reduce_blocks, "src"_a, "wsrc"_a, "asrc"_a.none(), "bx"_a, "by"_a,
          "out"_a, "wout"_a, "aout"_a.none(), "threads"_a);
    m.def("map_points_to_dirs", &map_points_to_dirs, "geo"_a, "cell_face"_a, "cell_turns"_a,
          "face_cell"_a, "points"_a, "fill"_a, "dirs"_a, "flags"_a, "threads"_a);
    m.def("map_dirs_to_points", &map_dirs_to_points, "geo"_a, "cell_face"_a, "cell_turns"_a,
          "face_cell"_a, "dirs"_a, "points"_a, "threads"_a);
    m.def("pixel_solid_angles", &pixel_solid_angles, "geo"_a, "cell_face"_a, "cell_turns"_a,
          "face_cell"_a, "scale_x"_a, "scale_y"_a, "samples"_a, "out"_a, "threads"_a);
    m.def("dir_density", &dir_density, "geo"_a, "cell_face"_a, "cell_turns"_a, "face_cell"_a,
          "dirs"_a, "out"_a);
    m.def("face_to_dir", &face_to_dir, "family"_a, "params"_a, "face"_a, "a"_a, "b"_a, "out"_a);
    m.def("dir_to_face", &dir_to_face, "family"_a, "params"_a, "dirs"_a, "face"_a, "a"_a, "b"_a);
    m.def("density", &density, "family"_a, "params"_a, "face"_a, "a"_a, "b"_a, "out"_a);
    m.def("filtered_reads", &filtered_reads, "src"_a, "geo"_a, "cell_face"_a, "cell_turns"_a,
          "face_cell"_a, "cells"_a, "points"_a, "filter"_a, "out"_a);
    m.def("level_reads", &level_reads, "rip"_a, "start"_a, "level_width"_a, "points"_a, "out"_a);
    m.def("ibl_pyramid", &ibl_pyramid, "faces"_a, "out"_a, "threads"_a);
    m.def("ibl_pyramid_binned", &ibl_pyramid_binned, "image"_a, "to_pyramid"_a, "p"_a, "sub"_a,
          "out"_a, "threads"_a);
    m.def("ibl_pyramid_binned_any", &ibl_pyramid_binned_any, "image"_a, "geo"_a, "cell_face"_a,
          "cell_turns"_a, "face_cell"_a, "to_pyramid"_a, "p"_a, "sub"_a, "delta"_a, "out"_a,
          "threads"_a);
    m.def("ibl_prefilter", &ibl_prefilter, "pyramid"_a, "p"_a, "channels"_a, "geo"_a,
          "cell_face"_a, "cell_turns"_a, "face_cell"_a, "scale_x"_a, "scale_y"_a, "alpha"_a,
          "samples"_a, "rot"_a, "fill"_a, "tau"_a, "out"_a, "threads"_a);
    m.def("sh_project", &sh_project, "image"_a, "geo"_a, "cell_face"_a, "cell_turns"_a,
          "face_cell"_a, "samples"_a, "sign_x"_a, "out"_a, "threads"_a);
    // Stop (true) every running kernel at its next task, or let kernels run again (false).
    m.def("cancel", [](bool on) { envconv::cancel_requested.store(on); }, "on"_a);
    m.def("set_wide_rows", &envconv::set_wide_rows, "allowed"_a);
    m.def("set_area_direct", &envconv::set_area_direct, "allowed"_a);
    m.attr("IBL_NODE_FIELDS") = envconv::Pyramid::kFields;
    m.def("ibl_pyramid_floats", &envconv::Pyramid::floats_for, "p"_a, "channels"_a,
          "Floats of the pyramid of a p-cube with `channels` channels (src/core/ibl.h).");
    m.attr("TILE") = envconv::kTile;  // output rows per band: the progress counter's unit
    m.attr("RIP_MIN_SPAN") = envconv::kRipMinSpan;
    m.attr("AUTO_MAX_SAMPLES") = envconv::kAutoMaxSamples;
    m.attr("AUTO_EDGE_SAMPLES") = envconv::kAutoEdgeSamples;
    m.attr("FAMILY_COUNT") = envconv::kFamilyCount;
    // The geometry family codes (src/core/chart.h), the one table Python reads them from
    // (envconv/layouts/base.py FAMILY_*), and the families whose cells hold a unit disk.
    m.attr("FILTER_NEAREST") = int(envconv::kNearest);
    m.attr("FILTER_BILINEAR") = int(envconv::kBilinear);
    m.attr("FILTER_BICUBIC") = int(envconv::kBicubic);
    m.attr("FILTER_AREA") = int(envconv::kArea);
    m.attr("FAMILY_LATLONG") = int(envconv::kLatlong);
    m.attr("FAMILY_CUBE_GL") = int(envconv::kCubeGL);
    m.attr("FAMILY_CUBE_EXR") = int(envconv::kCubeExr);
    m.attr("FAMILY_SPHERE") = int(envconv::kSphere);
    m.attr("FAMILY_ANGULAR") = int(envconv::kAngular);
    m.attr("FAMILY_PARABOLOID") = int(envconv::kParaboloid);
    m.attr("FAMILY_TENNISBALL") = int(envconv::kTennisball);
    m.attr("FAMILY_OCTAHEDRAL") = int(envconv::kOctahedral);
    m.attr("FAMILY_EQUAL_AREA") = int(envconv::kEqualArea);
    m.attr("FAMILY_EAC") = int(envconv::kEac);
    m.attr("FAMILY_FISHEYE") = int(envconv::kFisheye);
    m.attr("FAMILY_PERSPECTIVE") = int(envconv::kPerspective);
    nb::list disks;
    for (int family = 0; family < envconv::kFamilyCount; ++family)
        if (envconv::is_disk(family)) disks.append(family);
    m.attr("DISK_FAMILIES") = nb::steal<nb::tuple>(PyList_AsTuple(disks.ptr()));
    m.attr("PARAM_COUNT") = envconv::kParamCount;
}
