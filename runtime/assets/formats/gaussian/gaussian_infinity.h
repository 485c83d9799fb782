// The infinities real Gaussian writers put into files (one mapping for every reader).
//
// splat-transform (and trainers that export through it) write the logit opacity of a fully opaque
// splat as +inf and the log scale of a flat axis as -inf, and document it. These are the limits of
// the stored quantities, not corrupt data, so every reader maps them the same way instead of refusing
// the whole file: logit opacity +inf -> opacity 1, -inf -> 0; log scale -inf -> a zero axis (the
// Gaussian is flat). NaN stays an error, and so does a log scale of +inf (an infinite Gaussian has no
// finite meaning). The readers count what they mapped and log one line per file
// (`file: read N infinite values as limits (...)`) so a user sees that the file was not read verbatim.
#pragma once

#include <cstddef>
#include <string>

namespace sffd::gaussian {

struct InfinityCount {
    std::size_t opacity = 0;  // logit opacity ±inf read as 1 / 0
    std::size_t scale = 0;    // log scale -inf read as a zero axis
    std::size_t total() const { return opacity + scale; }
};

// Linear opacity of a stored logit. False for NaN (the caller names file and row).
bool opacity_from_logit(double logit_value, float& opacity, InfinityCount& mapped);
// Linear scale of a stored natural-log scale. False for NaN, +inf, or a finite value whose exponential
// overflows a float.
bool scale_from_log(double log_scale, float& scale, InfinityCount& mapped);
// The one log line (info level) a reader writes when it mapped anything; nothing when it did not.
void report_infinities(const std::string& file, const InfinityCount& mapped);

}  // namespace sffd::gaussian
