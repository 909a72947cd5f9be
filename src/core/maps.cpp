// The smaller kernels: point <-> direction maps, pixel solid angles, direction density, the
// rip-map fill and the mip chain's exact block reduction.
#include <algorithm>
#include <vector>

#include "kernels.h"
#include "parallel.h"
#include "ripmap.h"

namespace envconv {
namespace {
// Points per task of the vectorised maps: large enough that a task outweighs its hand-out.
constexpr int64_t kPointsPerTask = 4096;
}  // namespace

void map_points_to_dirs(const Geometry& g, const double* points, int64_t count, bool fill,
                        double* dirs, int8_t* flags, int threads) {
    int64_t tasks = (count + kPointsPerTask - 1) / kPointsPerTask;
    parallel_for(tasks, threads, [&](int64_t task) {
        int64_t end = std::min(count, (task + 1) * kPointsPerTask);
        for (int64_t k = task * kPointsPerTask; k < end; ++k) {
            OutputSample s = output_sample(g, points[2 * k], points[2 * k + 1], fill);
            Vec3 d{0.0, 0.0, 0.0};
            if (s.readable) d = face_to_dir(g, s.face, s.a, s.b);
            dirs[3 * k] = d.x;
            dirs[3 * k + 1] = d.y;
            dirs[3 * k + 2] = d.z;
            flags[k] = s.valid ? 2 : (s.readable ? 1 : 0);
        }
    });
}

void map_dirs_to_points(const Geometry& g, const double* dirs, int64_t count, double* points,
                        int threads) {
    int64_t tasks = (count + kPointsPerTask - 1) / kPointsPerTask;
    parallel_for(tasks, threads, [&](int64_t task) {
        int64_t end = std::min(count, (task + 1) * kPointsPerTask);
        for (int64_t k = task * kPointsPerTask; k < end; ++k) {
            FacePoint f = dir_to_face(g, dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
            ImagePoint p = face_to_image(g, f.face, f.a, f.b);
            points[2 * k] = p.x;
            points[2 * k + 1] = p.y;
        }
    });
}

void pixel_solid_angles(const Geometry& g, double scale_x, double scale_y, int samples,
                        double* out, int64_t height, int64_t width, int threads) {
    // Area of one sub-sample in (a, b) units.
    double sub_area = (2.0 * scale_x / double(g.nx)) * (2.0 * scale_y / double(g.n)) /
                      double(samples * samples);
    parallel_for(height, threads, [&](int64_t j) {
        for (int64_t i = 0; i < width; ++i) {
            double total = 0.0;
            for (int sy = 0; sy < samples; ++sy) {
                double py = (double(j) + (sy + 0.5) / samples) * scale_y;
                for (int sx = 0; sx < samples; ++sx) {
                    double px = (double(i) + (sx + 0.5) / samples) * scale_x;
                    Located at = locate(g, px, py);
                    if (point_valid(g, at.face, at.a, at.b))
                        total += density(g, at.face, at.a, at.b) * sub_area;
                }
            }
            out[j * width + i] = total;
        }
    });
}

void dir_density(const Geometry& g, const double* dirs, int64_t count, double* out) {
    for (int64_t k = 0; k < count; ++k) {
        FacePoint f = dir_to_face(g, dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
        out[k] = density(g, f.face, f.a, f.b);
    }
}

void fill_rips(const Image& src, int levels, int64_t rows, float* out, int threads) {
    const int64_t height = src.height, width = src.width, nch = src.channels;
    const int64_t out_width = width - (width >> levels);
    const int64_t filled = std::min(2 * rows, height);
    parallel_for(filled, threads, [&](int64_t r) {
        int64_t j = r >= rows ? r + height - filled : r;
        float* row = out + j * out_width * nch;
        const float* in = src.texel(j, 0);
        for (int64_t i = 0; i < (width >> 1); ++i) {
            for (int64_t c = 0; c < nch; ++c) {
                row[i * nch + c] =
                    float(0.5 * (double(in[2 * i * nch + c]) + double(in[(2 * i + 1) * nch + c])));
            }
        }
        int64_t prev = 0;
        for (int k = 2; k <= levels; ++k) {
            int64_t start = rip_offset(width, k);
            for (int64_t i = 0; i < (width >> k); ++i) {
                for (int64_t c = 0; c < nch; ++c) {
                    row[(start + i) * nch + c] =
                        float(0.5 * (double(row[(prev + 2 * i) * nch + c]) +
                                     double(row[(prev + 2 * i + 1) * nch + c])));
                }
            }
            prev = start;
        }
    });
}

void reduce_blocks(const Image& src, const float* wsrc, const float* asrc, int64_t bx,
                   int64_t by, float* out, int64_t height, int64_t width, float* wout,
                   float* aout, int threads) {
    const int64_t nch = src.channels, sw = src.width;
    const double inv_area = 1.0 / double(bx * by);
    parallel_for(height, threads, [&](int64_t j) {
        std::vector<double> acc(nch);
        for (int64_t i = 0; i < width; ++i) {
            std::fill(acc.begin(), acc.end(), 0.0);
            double wt = 0.0, at = 0.0;
            for (int64_t y = j * by; y < (j + 1) * by; ++y) {
                for (int64_t x = i * bx; x < (i + 1) * bx; ++x) {
                    if (asrc) at += asrc[y * sw + x];
                    double w = wsrc[y * sw + x];
                    if (w > 0.0) {
                        wt += w;
                        const float* t = src.texel(y, x);
                        for (int64_t c = 0; c < nch; ++c) acc[c] += w * double(t[c]);
                    }
                }
            }
            float* px = out + (j * width + i) * nch;
            double inv = wt > 0.0 ? 1.0 / wt : 0.0;
            for (int64_t c = 0; c < nch; ++c) px[c] = float(acc[c] * inv);
            if (aout) aout[j * width + i] = float(at * inv_area);
            wout[j * width + i] = float(wt);
        }
    });
}

}  // namespace envconv
