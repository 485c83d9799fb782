#include "runtime/assets/formats/gaussian/gaussian_sog_quantize.h"

#include <algorithm>
#include <array>
#include <functional>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace sffd::gaussian::sog_detail {

namespace {

// ---- 1-D codebook ------------------------------------------------------------------------------------

// Up to `k` centres for the ascending `sorted` (more than k distinct values): the histogram and its
// optimal weighted split (quantize-1d in splat-transform), over the non-empty bins only.
std::vector<double> histogram_centres(const std::vector<double>& sorted, int k) {
    const std::size_t n = sorted.size();
    const std::size_t h = std::min<std::size_t>(1024, n);
    const double lo = sorted.front(), range = sorted.back() - lo;
    const double iqr = sorted[n * 3 / 4] - sorted[n / 4];
    const double beta = std::clamp(1.0 - iqr / range, 0.5, 0.999);
    std::vector<double> count(h, 0.0), sum(h, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        const double u = (sorted[i] - lo) / range, q = double(i) / double(n);
        const std::size_t b = std::min(h - 1, std::size_t(double(h) * (beta * q + (1 - beta) * u)));
        count[b] += 1.0, sum[b] += sorted[i];
    }
    std::vector<double> centre, weight;
    for (std::size_t b = 0; b < h; ++b)
        if (count[b] > 0) centre.push_back(sum[b] / count[b]), weight.push_back(std::sqrt(count[b]));
    const int m = int(centre.size());
    const int kk = std::min(k, m);
    std::vector<double> pw(std::size_t(m) + 1, 0.0), pwx(pw), pwxx(pw);
    for (int i = 0; i < m; ++i) {
        pw[std::size_t(i) + 1] = pw[std::size_t(i)] + weight[std::size_t(i)];
        pwx[std::size_t(i) + 1] = pwx[std::size_t(i)] + weight[std::size_t(i)] * centre[std::size_t(i)];
        pwxx[std::size_t(i) + 1] =
            pwxx[std::size_t(i)] + weight[std::size_t(i)] * centre[std::size_t(i)] * centre[std::size_t(i)];
    }
    // Weighted squared error of bins a..b around their weighted mean.
    const auto cost = [&](int a, int b) {
        const double w = pw[std::size_t(b) + 1] - pw[std::size_t(a)];
        const double wx = pwx[std::size_t(b) + 1] - pwx[std::size_t(a)];
        return std::max(0.0, pwxx[std::size_t(b) + 1] - pwxx[std::size_t(a)] - wx * wx / w);
    };
    const double inf = std::numeric_limits<double>::infinity();
    // dp over ranges: the best split of bins 0..j into r ranges; the last range's start is monotone in j
    // (the squared error satisfies the quadrangle inequality), so each row is solved by divide and conquer.
    std::vector<double> prev(std::size_t(m), 0.0), cur(std::size_t(m), inf);
    std::vector<std::vector<int>> split(std::size_t(kk) + 1, std::vector<int>(std::size_t(m), -1));
    for (int j = 0; j < m; ++j) prev[std::size_t(j)] = cost(0, j);
    for (int r = 2; r <= kk; ++r) {
        std::fill(cur.begin(), cur.end(), inf);
        std::vector<int>& sp = split[std::size_t(r)];
        // Iterative divide and conquer: (jlo, jhi, slo, shi).
        std::vector<std::array<int, 4>> stack{{r - 1, m - 1, r - 2, m - 2}};
        while (!stack.empty()) {
            const auto [jlo, jhi, slo, shi] = stack.back();
            stack.pop_back();
            if (jlo > jhi) continue;
            const int mid = (jlo + jhi) / 2;
            double best = inf;
            int bs = std::max(slo, r - 2);
            for (int s = std::max(slo, r - 2); s <= std::min(shi, mid - 1); ++s) {
                const double c = prev[std::size_t(s)] + cost(s + 1, mid);
                if (c < best) best = c, bs = s;
            }
            cur[std::size_t(mid)] = best, sp[std::size_t(mid)] = bs;
            stack.push_back({jlo, mid - 1, slo, bs});
            stack.push_back({mid + 1, jhi, bs, shi});
        }
        std::swap(prev, cur);
    }
    std::vector<double> out(std::size_t(kk), 0.0);
    for (int r = kk, j = m - 1; r >= 1; --r) {
        const int s = r > 1 ? split[std::size_t(r)][std::size_t(j)] : -1;
        out[std::size_t(r) - 1] = (pwx[std::size_t(j) + 1] - pwx[std::size_t(s + 1)]) /
                                  (pw[std::size_t(j) + 1] - pw[std::size_t(s + 1)]);
        j = s;
    }
    std::sort(out.begin(), out.end());
    return out;
}

// ---- k-means ------------------------------------------------------------------------------------------

constexpr std::size_t kLanes = 8;              // centroids compared per step (vectorised across them)
constexpr float kFar = 1e18f;                  // padding lanes: never the nearest
constexpr std::size_t kFlatBudget = 1u << 25;  // points × centroids for one flat k-means
constexpr int kIterations = 5;                 // assignments; one update fewer

struct Points {
    const float* data;
    std::size_t stride, dims;
    const float* at(std::size_t i) const { return data + i * stride; }
};

// Centroids in blocks of kLanes, coordinate-major inside a block, so one point meets kLanes at a time.
struct Blocks {
    std::size_t count = 0, dims = 0;
    std::vector<float> soa;
    void build(const std::vector<float>& c, std::size_t k, std::size_t d) {
        count = k, dims = d;
        const std::size_t blocks = (k + 4 * kLanes - 1) / (4 * kLanes) * 4;  // nearest_in takes 4 at a time
        soa.assign(blocks * d * kLanes, kFar);
        for (std::size_t i = 0; i < k; ++i)
            for (std::size_t j = 0; j < d; ++j)
                soa[((i / kLanes) * d + j) * kLanes + i % kLanes] = c[i * d + j];
    }
    std::uint32_t nearest(const float* x) const;
};

// The nearest of the centroids in `soa` (`blocks`, a multiple of 4) to x: four blocks of 8 lanes at once,
// in GCC vector types (2 SSE or 1 AVX register each), so four independent sums hide the add latency.
// Compiled for AVX2 too and picked when the CPU has it: the same operations in the same order, so both
// give the same labels.
using v8 = float __attribute__((vector_size(32)));
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
std::uint32_t
nearest_in(const float* soa, std::size_t blocks, std::size_t dims, const float* x) {
    float best = std::numeric_limits<float>::infinity();
    std::uint32_t bi = 0;
    for (std::size_t b = 0; b < blocks; b += 4) {
        v8 acc[4] = {};
        for (std::size_t j = 0; j < dims; ++j) {
            const float xj = x[j];
            for (std::size_t q = 0; q < 4; ++q) {
                v8 c;
                std::memcpy(&c, soa + ((b + q) * dims + j) * kLanes, sizeof c);
                const v8 t = xj - c;
                acc[q] += t * t;
            }
        }
        for (std::size_t q = 0; q < 4; ++q)
            for (std::size_t l = 0; l < kLanes; ++l)
                if (acc[q][l] < best) best = acc[q][l], bi = std::uint32_t((b + q) * kLanes + l);
    }
    return bi;
}

std::uint32_t Blocks::nearest(const float* x) const {
    return nearest_in(soa.data(), (count + 4 * kLanes - 1) / (4 * kLanes) * 4, dims, x);
}

void assign(const Points& p, const std::vector<std::uint32_t>& idx, const Blocks& b,
            std::vector<std::uint32_t>& labels) {
    labels.resize(idx.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, idx.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              labels[i] = b.nearest(p.at(idx[i]));
                      });
}

// Lloyd's k-means over the points `idx` with `k` (<= idx.size()) centroids seeded from distinct points;
// the labels are each point's nearest of the final centroids.
void lloyd(const Points& p, const std::vector<std::uint32_t>& idx, std::size_t k, std::uint64_t seed,
           std::vector<float>& centroids, std::vector<std::uint32_t>& labels) {
    const std::size_t n = idx.size(), d = p.dims;
    std::mt19937_64 rng(seed);
    std::vector<std::uint32_t> order(idx);
    for (std::size_t i = 0; i < k; ++i) std::swap(order[i], order[i + rng() % (n - i)]);
    centroids.assign(k * d, 0.0f);
    for (std::size_t i = 0; i < k; ++i) std::memcpy(&centroids[i * d], p.at(order[i]), d * sizeof(float));
    Blocks b;
    std::vector<double> sums(k * d);
    std::vector<std::size_t> counts(k);
    for (int it = 0;; ++it) {
        b.build(centroids, k, d);
        assign(p, idx, b, labels);
        if (it + 1 == kIterations) break;
        std::fill(sums.begin(), sums.end(), 0.0), std::fill(counts.begin(), counts.end(), 0);
        for (std::size_t i = 0; i < n; ++i) {
            const float* x = p.at(idx[i]);
            double* s = &sums[labels[i] * d];
            for (std::size_t j = 0; j < d; ++j) s[j] += double(x[j]);
            ++counts[labels[i]];
        }
        for (std::size_t c = 0; c < k; ++c) {
            if (counts[c] == 0) {  // an empty cluster moves to a random point
                std::memcpy(&centroids[c * d], p.at(idx[rng() % n]), d * sizeof(float));
                continue;
            }
            for (std::size_t j = 0; j < d; ++j)
                centroids[c * d + j] = float(sums[c * d + j] / double(counts[c]));
        }
    }
}

// k centroids for the points `idx`: flat when small, else coarse clusters each with a share of k.
void cluster(const Points& p, const std::vector<std::uint32_t>& idx, std::size_t k, std::uint64_t seed,
             std::vector<float>& centroids, std::vector<std::uint32_t>& labels) {
    const std::size_t n = idx.size(), d = p.dims;
    k = std::min(k, n);
    if (k <= 1 || n * k <= kFlatBudget) {
        if (k == 0) return centroids.clear(), labels.clear();
        return lloyd(p, idx, k, seed, centroids, labels);
    }
    // A point meets all k1 coarse centroids once and about k/k1 fine ones per iteration: k1 near
    // √(iterations·k) balances the two.
    const std::size_t k1 = std::clamp<std::size_t>(
        std::size_t(std::lround(std::sqrt(double(kIterations * k)))), 2, std::min<std::size_t>(1024, k / 2));
    // The coarse centroids from a sample, then every point's coarse cluster.
    std::vector<float> coarse;
    std::vector<std::uint32_t> coarse_labels;
    {
        std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
        std::vector<std::uint32_t> sample(idx);
        const std::size_t s = std::min(n, k1 * 64);
        for (std::size_t i = 0; i < s; ++i) std::swap(sample[i], sample[i + rng() % (n - i)]);
        sample.resize(s);
        std::vector<std::uint32_t> unused;
        lloyd(p, sample, k1, seed + 1, coarse, unused);
        Blocks b;
        b.build(coarse, k1, d);
        assign(p, idx, b, coarse_labels);
    }
    std::vector<std::vector<std::uint32_t>> groups(k1);
    for (std::size_t i = 0; i < n; ++i) groups[coarse_labels[i]].push_back(idx[i]);
    // Each group's share of k by its size (largest remainders), at least 1, at most its size; the total
    // stays exactly k (k <= n).
    std::vector<std::size_t> share(k1, 0);
    std::vector<std::pair<double, std::size_t>> rest;
    std::size_t total = 0;
    for (std::size_t c = 0; c < k1; ++c) {
        if (groups[c].empty()) continue;
        const double q = double(k) * double(groups[c].size()) / double(n);
        share[c] = std::clamp<std::size_t>(std::size_t(q), 1, groups[c].size());
        total += share[c];
        rest.emplace_back(q - double(share[c]), c);
    }
    std::sort(rest.begin(), rest.end(), std::greater<>());
    for (bool grew = true; total < k && grew;) {
        grew = false;
        for (std::size_t r = 0; r < rest.size() && total < k; ++r)
            if (share[rest[r].second] < groups[rest[r].second].size())
                ++share[rest[r].second], ++total, grew = true;
    }
    while (total > k) {  // the minimum of 1 per group overshot: take from the largest shares
        const std::size_t c = std::size_t(std::max_element(share.begin(), share.end()) - share.begin());
        --share[c], --total;
    }
    std::vector<std::size_t> first(k1 + 1, 0);
    for (std::size_t c = 0; c < k1; ++c) first[c + 1] = first[c] + share[c];
    centroids.assign(first[k1] * d, 0.0f);
    std::vector<std::vector<std::uint32_t>> local(k1);
    tbb::parallel_for(std::size_t(0), k1, [&](std::size_t c) {
        if (groups[c].empty()) return;
        std::vector<float> cc;
        cluster(p, groups[c], share[c], seed * 31 + c + 7, cc, local[c]);
        std::copy(cc.begin(), cc.end(), centroids.begin() + std::ptrdiff_t(first[c] * d));
    });
    // Back to the order of idx.
    labels.resize(n);
    std::vector<std::size_t> at(k1, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t c = coarse_labels[i];
        labels[i] = std::uint32_t(first[c] + local[c][at[c]++]);
    }
}

}  // namespace

Codebook codebook_1d(const std::vector<double>& values) {
    Codebook cb;
    cb.values.assign(kCodebookSize, 0.0);
    cb.labels.assign(values.size(), 0);
    std::vector<double> finite;
    finite.reserve(values.size());
    bool neg_inf = false;
    for (const double v : values)
        if (std::isfinite(v)) finite.push_back(v);
        else neg_inf = true;  // the caller passes only finite values and −∞
    tbb::parallel_sort(finite.begin(), finite.end());
    const int slots = neg_inf ? 1 : 0, k = kCodebookSize - slots;
    std::vector<double> centres;
    for (std::size_t i = 0; i < finite.size() && int(centres.size()) <= k; ++i)
        if (i == 0 || finite[i] != finite[i - 1]) centres.push_back(finite[i]);
    if (int(centres.size()) > k) centres = histogram_centres(finite, k);
    if (centres.empty()) centres.push_back(0.0);  // only −∞ (or nothing): any finite value
    if (neg_inf) cb.values[0] = (finite.empty() ? 0.0 : finite.front()) - 20.0;
    for (int i = 0; i < k; ++i)
        cb.values[std::size_t(slots + i)] = centres[std::min(std::size_t(i), centres.size() - 1)];
    // Nearest value by binary search over the midpoints (the values ascend).
    const double* book = cb.values.data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size(), 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              const double v = values[i];
                              int lo = 0, hi = kCodebookSize - 1;
                              while (lo < hi) {
                                  const int mid = (lo + hi) / 2;
                                  if (v < 0.5 * (book[mid] + book[mid + 1])) hi = mid;
                                  else lo = mid + 1;
                              }
                              cb.labels[i] = std::uint8_t(lo);
                          }
                      });
    return cb;
}

Palette palette(const float* data, std::size_t n, std::size_t stride, std::size_t dims, std::size_t k) {
    Palette out;
    k = std::min(k, n);
    if (k == 0 || dims == 0) {
        out.labels.assign(n, 0);
        return out;
    }
    const Points p{data, stride, dims};
    // Up to k distinct vectors are kept exactly (their bytes compared; -0 and 0 count as two).
    {
        std::unordered_multimap<std::uint64_t, std::uint32_t> seen;
        std::vector<std::uint32_t> distinct;
        out.labels.resize(n);
        bool few = true;
        for (std::size_t i = 0; i < n && few; ++i) {
            std::uint64_t h = 1469598103934665603ull;
            const unsigned char* b = reinterpret_cast<const unsigned char*>(p.at(i));
            for (std::size_t j = 0; j < dims * sizeof(float); ++j) h = (h ^ b[j]) * 1099511628211ull;
            std::uint32_t label = std::uint32_t(distinct.size());
            for (auto [it, end] = seen.equal_range(h); it != end; ++it)
                if (std::memcmp(p.at(distinct[it->second]), p.at(i), dims * sizeof(float)) == 0)
                    label = it->second;
            if (label == distinct.size()) {
                if (distinct.size() == k) few = false;
                seen.emplace(h, label);
                distinct.push_back(std::uint32_t(i));
            }
            out.labels[i] = label;
        }
        if (few) {
            out.count = distinct.size();
            out.centroids.resize(out.count * dims);
            for (std::size_t c = 0; c < out.count; ++c)
                std::memcpy(&out.centroids[c * dims], p.at(distinct[c]), dims * sizeof(float));
            return out;
        }
    }
    std::vector<std::uint32_t> all(n);
    std::iota(all.begin(), all.end(), 0u);
    cluster(p, all, k, 12345, out.centroids, out.labels);
    out.count = out.centroids.size() / dims;
    return out;
}

}  // namespace sffd::gaussian::sog_detail
