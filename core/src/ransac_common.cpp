// SPDX-License-Identifier: MIT
// Adaptive hypothesis count, Kilic 2014 eq. (27) (= eq. (24) with m = sample size).
#include "core_private.hpp"
#include "sfd/sfd_ransac.h"

extern "C" int32_t sfd_ransac_hypothesis_count(double confidence, double inlier_ratio,
                                               int32_t sample_size, int32_t budget) {
    const int32_t cap = (budget < 1) ? 1 : budget;
    if (!std::isfinite(confidence) || !std::isfinite(inlier_ratio)) return cap;
    if (sample_size < 1 || sample_size > 64) return cap;
    if (!(confidence > 0.0 && confidence < 1.0)) return cap;
    if (inlier_ratio >= 1.0) return 1;
    if (inlier_ratio <= 0.0) return cap;
    // (1 - eps)^m by repeated multiplication: m is small and this stays exact in the
    // rounding sense of IEEE * (no pow, whose last bit differs between C libraries).
    double clean = 1.0;
    for (int32_t i = 0; i < sample_size; ++i) clean *= inlier_ratio;
    if (!(clean > std::numeric_limits<double>::min())) return cap;
    // log1p keeps precision when clean is tiny (many hypotheses needed).
    const double n = std::log(1.0 - confidence) / std::log1p(-clean);
    if (!std::isfinite(n) || n >= static_cast<double>(cap)) return cap;
    const double up = std::ceil(n);
    if (up < 1.0) return 1;
    return static_cast<int32_t>(up);
}
