// The clustering the SOG writer (gaussian_sog_write.cpp) quantises with, apart so it can be tested alone:
//   - codebook_1d: 256 values for a pool of numbers (the log scales, the DC coefficients, the SH palette's
//     coefficients), each number labelled with its nearest value. Up to 256 distinct numbers are kept
//     exactly; more are clustered the way splat-transform does: a histogram of at most 1024 bins placed
//     between uniform and quantile positions (more quantile when outliers stretch the range), weighted by
//     count^0.5 so sparse tails keep entries, split optimally into 256 ranges by dynamic programming.
//     −∞ (the log of a zero scale) gets its own first entry, 20 below the finite minimum (splat-transform's
//     sentinel: e^−20 of the smallest scale, flat for any renderer).
//   - palette: k-means over vectors (the SH bands of every Gaussian). Up to k distinct vectors are kept
//     exactly; otherwise Lloyd iterations (5 assignments), on all points when n·k is small, else two
//     levels: a coarse k-means of about √(5k) clusters (trained on a sample) splits the points, and each
//     coarse cluster gets its share of the k centroids (by its point count) and its own Lloyd iterations
//     (again in two levels if still large). Each point's label is then its nearest centroid within its
//     coarse cluster. Seeded: the same input gives the same output.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace sffd::gaussian::sog_detail {

inline constexpr int kCodebookSize = 256;

struct Codebook {
    std::vector<double> values;        // kCodebookSize, ascending (the last repeated when fewer are needed)
    std::vector<std::uint8_t> labels;  // per input: the index of its nearest value
};

// `values`: finite numbers or −∞ (nothing else; the writer validated the cloud).
Codebook codebook_1d(const std::vector<double>& values);

struct Palette {
    std::size_t count = 0;              // centroids (<= k)
    std::vector<float> centroids;       // count × dims
    std::vector<std::uint32_t> labels;  // per point
};

// `n` points of `dims` floats, point i at data + i·stride; at most `k` centroids.
Palette palette(const float* data, std::size_t n, std::size_t stride, std::size_t dims, std::size_t k);

}  // namespace sffd::gaussian::sog_detail
