// PlayCanvas SOG ("spatially ordered Gaussians", version 2 as splat-transform 3.x and the PlayCanvas
// engine read and write it), read and written: a `.sog` ZIP archive, or a folder, holding `meta.json` and
// lossless WebP images. Gaussian i is texel i of every image (row-major, RGBA):
//   meta.json  {"version": 2, "count": N, "means": {"mins": [3], "maxs": [3], "files": [lo, hi]},
//              "scales": {"codebook": [256], "files": [..]}, "quats": {"files": [..]},
//              "sh0": {"codebook": [256], "files": [..]},
//              "shN": {"count": P, "bands": 1..3, "codebook": [256], "files": [centroids, labels]}}
//              (shN optional)
//   means      16 bits per axis, low byte in `lo`, high in `hi` (R G B = x y z):
//              v = min + (max − min)·q/65535 (a zero range counts as 1), in the log space
//              v = sign(x)·ln(1 + |x|), so x = sign(v)·(e^|v| − 1)
//   quats      R G B = the three smaller components c = (b/255·2 − 1)/√2, A = 252 + index of the largest
//              (w x y z order), which is √(1 − Σc²)
//   scales     R G B index the codebook of log scales
//   sh0        R G B index the codebook of DC coefficients; A = opacity·255 (already through the sigmoid)
//   shN        labels: R + 256·G = a palette entry e (< P); centroids: 64 entries a row, each K − 1
//              texels wide (3, 8, 15 for 1..3 bands): texel (e mod 64)·(K − 1) + j of row e / 64 holds
//              coefficient j + 1 as R G B indices into the codebook.
// Axes: splat-transform reads and writes SOG in its PLY space, so SOG is read as stored, like 3DGS PLY
// (gaussian_axes.h).
//
// Quantisation (what reading cannot undo): a position is within ½·(max − min)/65535·(1 + |x|) per axis;
// a rotation component within 1/(255·√2) ≈ 0.0028 before renormalising; opacity within 1/510; scales,
// DC colours and SH coefficients are the nearest of 256 codebook values (k-means over the file's own
// values, so the error depends on the capture), and the higher bands are shared by all Gaussians of a
// palette entry (at most 65536 entries).
//
// Budgets and checks, each refused with "file: problem": the archive (gaussian_zip.h), meta.json
// (version 2 only: the legacy version 1 without a "version" field is refused with a hint; count within
// kMaxGaussians; codebooks of 256 finite numbers; finite mins and maxs; file names without directories),
// every image's width·height read from its header before decoding (at least the count, at most 2·count
// + 65536 texels; the centroids exactly 64·(K − 1) wide with room for P entries; lossy or animated WebP
// refused: the texels are indices and bit fields), quaternion tags and
// palette labels in range. What passes is validated like every other reader's output.
#pragma once

#include <filesystem>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian {

// `path` is a `.sog` archive or a SOG folder's `meta.json`.
Result<GaussianCloud> read_sog(const std::filesystem::path& path);

// Writes `cloud` as SOG version 2 (gaussian_sog_write.cpp): `path` ending in `.sog` is a ZIP archive of
// stored entries; a path named `meta.json` writes the folder (meta.json and the .webp images beside it).
// Texel i is Gaussian i (the cloud's order is kept) unless options.morton_order. Positions are written
// absolute (origin + position) in double; positions, rotation components and opacity are rounded to their
// nearest step (the bounds above); scales (log) and DC coefficients index codebooks of 256 (up to 256
// distinct values are kept exactly, more are clustered as splat-transform does, gaussian_sog_quantize.h; a
// zero scale gets an entry e^−20 below the smallest); the SH bands share a palette of min(65536, 2^⌊log2 n⌋)
// entries (up to that many distinct band vectors are kept exactly, else k-means), whose coefficients index
// one more codebook of 256. Refused with "path: problem": another file name, clouds validate() refuses
// (values not finite or out of range, per-splat SH frames: bake_sh_frames() first), more than kMaxGaussians.
// An empty cloud is written (4×4 images, "count": 0). The archive is written through a temporary and
// renamed; the folder's files each so, all written before any is renamed, meta.json last.
struct SogWriteOptions {
    // Texels along the Morton curve of the 16-bit centres, as splat-transform orders them: smaller images
    // (neighbours share high bytes, and often colours), but texel i is then no longer Gaussian i.
    bool morton_order = false;
};
Status write_sog(const std::filesystem::path& path, const GaussianCloud& cloud,
                 const SogWriteOptions& options = {});

}  // namespace sffd::gaussian
