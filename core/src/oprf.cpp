// SPDX-License-Identifier: MIT
// OPRF, Kilic 2014 Section 3.2 / Table 1: the hypothesis loop scored by the Sampson distance of
// eq. (25) in single precision, the noise scale of the chosen hypothesis, the rotation-only
// transfer under degenerate motion, and the individual-compatibility gate of set 1 and set 2
// (core/docs/association.md "OPRF", "Noise scale", "Gate").
#include "association_internal.hpp"
#include "small_linalg.hpp"
#include "sfd/sfd_prng.h"
#include "sfd/sfd_ransac.h"

namespace sfd {
namespace assoc {
namespace {

/// Fewest matches for OPRF's noise scale, the median of chi2(1), and the most refinements of the
/// scale over the matches inside its own gate.
constexpr int32_t kScaleMinMatches = 16;
constexpr double kChi2Dof1Median = 0.454936423119572;
constexpr int32_t kScaleRefinements = 3;

inline double clamp_scale(double s) {
    return (s < 0.04) ? 0.04 : ((s > 25.0) ? 25.0 : s);
}

/// Order statistics of one array taken in turn: the array stays partitioned at every index
/// selected so far, so each selection partitions only between the two nearest of them.
class OrderStats {
  public:
    OrderStats(float *v, int32_t n) : v_(v), n_(n) {}
    /// The k-th smallest value (0 <= k < n).
    float kth(int32_t k) {
        const int32_t lo = bracket_low(k);
        int32_t hi = n_;
        for (int32_t i = 0; i < np_; ++i) {
            if (part_[i] == k) return v_[k];
            if (part_[i] > k && part_[i] < hi) hi = part_[i];
        }
        const float x = select_kth(v_ + lo, hi - lo, k - lo);
        if (np_ < kMaxParts) part_[np_++] = k;  // a full list only costs speed
        return x;
    }
    /// The median of the m smallest values (1 <= m <= n), as median_in_place() defines it: for
    /// an even m the (m/2 - 1)-th smallest is the largest below the (m/2)-th, found among the
    /// entries above the nearest partition below it.
    double median_of_smallest(int32_t m) {
        const int32_t k = m / 2;
        const double upper = static_cast<double>(kth(k));
        if (m % 2 == 1) return upper;
        const int32_t lo = bracket_low(k);
        float lower = v_[lo == k ? k - 1 : lo];
        for (int32_t i = lo + 1; i < k; ++i) lower = (lower < v_[i]) ? v_[i] : lower;
        return 0.5 * (static_cast<double>(lower) + upper);
    }

  private:
    /// One past the nearest partition below k, 0 when there is none.
    int32_t bracket_low(int32_t k) const {
        int32_t lo = 0;
        for (int32_t i = 0; i < np_; ++i) {
            if (part_[i] < k && part_[i] + 1 > lo) lo = part_[i] + 1;
        }
        return lo;
    }
    static constexpr int32_t kMaxParts = kScaleRefinements + 1;
    float *v_;
    int32_t n_;
    int32_t part_[kMaxParts] = {};
    int32_t np_ = 0;
};

/// The frame's noise scale s of the Sampson distances d[0..n) (units of sigma^2; n >=
/// kScaleMinMatches; core/docs/association.md "Noise scale"). Start: median(d) / median of
/// chi2(1), robust while fewer than half are spurious but inflated by the spurious ones (30 %
/// of them far out move the median to about the 0.71 quantile of chi2(1): s = 2.4 measured,
/// about 2.5 in theory, instead of 1). Then
/// at most kScaleRefinements fixed-point steps over the matches inside the gate, d <= c s with
/// c = chi2_{1,1-alpha}: if those are chi2(1) in units of s, they are a chi2(1) truncated at c,
/// whose median is the chi2(1) quantile at (1 - alpha) / 2 (@p trunc_median), so s' = median{d
/// <= c s} / trunc_median. The m matches inside are the m smallest distances, so their median
/// is an order statistic of d. The step is a contraction around the true scale (an s that is
/// low cuts off more of the inliers' tail, but the median of what is left falls by less than
/// s did, so s moves back up; slope about 0.09 at alpha = 1 %), stops when it changes s by under
/// 1 %, and keeps the last s when fewer than kScaleMinMatches are inside. It runs only when the
/// start leaves more matches outside the gate than alpha explains (over n alpha + 8 sqrt(n
/// alpha (1 - alpha)), a binomial bound widened for the frame-to-frame spread of the
/// hypothesis' pose error: at 3 standard deviations, clean frames of unit.association's edge
/// test refined too and their false-alarm rate rose from 1.12 % to 1.17 %). @p tmp (n entries)
/// is overwritten.
double noise_scale(const float *d, int32_t n, double c, double alpha, double trunc_median,
                   float *tmp) {
    for (int32_t k = 0; k < n; ++k) tmp[k] = d[k];
    OrderStats order(tmp, n);
    double s = clamp_scale(order.median_of_smallest(n) / kChi2Dof1Median);
    for (int32_t it = 0; it < kScaleRefinements; ++it) {
        const float cut = static_cast<float>(c * s);
        int32_t m = 0;
        for (int32_t k = 0; k < n; ++k) m += (d[k] <= cut) ? 1 : 0;
        if (m < kScaleMinMatches) break;
        if (it == 0) {
            const double nd = static_cast<double>(n);
            const double explained = nd * alpha + 8.0 * std::sqrt(nd * alpha * (1.0 - alpha));
            if (static_cast<double>(n - m) <= explained) break;
        }
        const double s_next = clamp_scale(order.median_of_smallest(m) / trunc_median);
        const bool settled = std::fabs(s_next - s) < 0.01 * s;
        s = s_next;
        if (settled) break;
    }
    return s;
}

/// Per-axis weights of the packed Sampson denominator: wx = w / fx^2, wy = w / fy^2,
/// wxy = w / (fx fy) for a common factor w (the threshold or 1).
struct AxisWeights {
    float wx, wy, wxy;
};

/// Single-precision form of eq. (25) with per-point covariances, in normalized coordinates (see
/// sampson_count_packed()) for packed match @p j of @p w: the residual e = x~_prev^T E x~_curr and
/// the first-order variance of e in pixel units (sampson.hpp), g_px^T C_prev g_px + h_px^T C_curr
/// h_px with g = E x~_curr = de/dx~_prev, h = E^T x~_prev = de/dx~_curr, g_px = (g0 / fx,
/// g1 / fy) (likewise h) and C = I + dC: the isotropic part wx (g0^2 + h0^2) + wy (g1^2 + h1^2)
/// plus the excess wx (dCp_xx g0^2 + dCc_xx h0^2) + wy (dCp_yy g1^2 + dCc_yy h1^2) +
/// 2 wxy (dCp_xy g0 g1 + dCc_xy h0 h1), added last so that dC = 0 leaves it bit-for-bit.
inline void sampson_terms_f(const float *E, const sfd_assoc_oprf_work_t &w, int32_t j,
                            const AxisWeights &aw, float *e, float *den) {
    const float u1 = w.nx_prev_u[j], v1 = w.nx_prev_v[j];
    const float u2 = w.nx_curr_u[j], v2 = w.nx_curr_v[j];
    const float g0 = E[0] * u2 + E[1] * v2 + E[2];
    const float g1 = E[3] * u2 + E[4] * v2 + E[5];
    const float g2 = E[6] * u2 + E[7] * v2 + E[8];
    const float h0 = E[0] * u1 + E[3] * v1 + E[6];
    const float h1 = E[1] * u1 + E[4] * v1 + E[7];
    *e = u1 * g0 + v1 * g1 + g2;
    const float excess = aw.wx * (w.dc_prev_xx[j] * g0 * g0 + w.dc_curr_xx[j] * h0 * h0) +
                         aw.wy * (w.dc_prev_yy[j] * g1 * g1 + w.dc_curr_yy[j] * h1 * h1) +
                         2.0F * aw.wxy * (w.dc_prev_xy[j] * g0 * g1 + w.dc_curr_xy[j] * h0 * h1);
    *den = aw.wx * (g0 * g0 + h0 * h0) + aw.wy * (g1 * g1 + h1 * h1) + excess;
}

/// Counts the inliers of one OPRF hypothesis among the packed valid matches: the Sampson distance
/// of eq. (25) with per-point covariances, in px^2, is at most thr_px2 (@p thr holds thr_px2 /
/// fx^2, thr_px2 / fy^2, thr_px2 / (fx fy)). It is evaluated in normalized coordinates x~ = K^-1
/// x, where F = K^-T E K^-1 gives the same residual e = x~_prev^T E x~_curr and the pixel Sampson
/// denominator g_px^T C_prev g_px + h_px^T C_curr h_px of sampson_terms_f() (for C = I:
/// (g0^2 + h0^2) / fx^2 + (g1^2 + h1^2) / fy^2); the test e^2 <= thr (...) needs no division and, E
/// being scaled to unit largest entry, is well conditioned in single precision. Blocks of
/// SFD_ASSOC_SCORE_BLOCK matches are scored together (vectorizable; the NaN padding is never an
/// inlier). Stops early, returning a count below @p need, once even all remaining matches could not
/// reach @p need: only a hypothesis with more inliers than the best so far matters. Single
/// precision only ranks the hypotheses: the verdicts of the chosen one are computed in double
/// precision with sampson_px2().
int32_t sampson_count_packed(const sfd_assoc_t *a, const float E[9], const AxisWeights &thr,
                             int32_t nv, int32_t need) {
    constexpr int32_t kBlock = SFD_ASSOC_SCORE_BLOCK;
    float Ek[9];  // a local copy: provably not aliased by the loop, so it stays in registers
    for (int k = 0; k < 9; ++k) Ek[k] = E[k];
    int32_t count = 0;
    for (int32_t k0 = 0; k0 < nv; k0 += kBlock) {
        if (count + (nv - k0) < need) return count;
        int32_t block_count = 0;
        for (int32_t j = k0; j < k0 + kBlock; ++j) {
            float e = 0.0F;
            float rhs = 0.0F;
            sampson_terms_f(Ek, a->work->oprf, j, thr, &e, &rhs);
            const int32_t in =
                static_cast<int32_t>(e * e <= rhs) & static_cast<int32_t>(rhs > 0.0F);
            block_count += in;
        }
        count += block_count;
    }
    return count;
}

/// The Sampson distance of eq. (25) of every packed valid match under @p E, in units of sigma^2
/// (the same normalized-coordinate form and precision as sampson_count_packed()), into
/// a.packed_stat; 3e38 where the denominator vanishes or the value is not finite.
void sampson_stat_packed(sfd_assoc_t *a, const float E[9], const AxisWeights &inv_f2,
                         float inv_sigma2, int32_t nv) {
    constexpr int32_t kBlock = SFD_ASSOC_SCORE_BLOCK;
    float Ek[9];
    for (int k = 0; k < 9; ++k) Ek[k] = E[k];
    for (int32_t k0 = 0; k0 < nv; k0 += kBlock) {
        float *stat = a->work->oprf.packed_stat;
        for (int32_t j = k0; j < k0 + kBlock; ++j) {
            float e = 0.0F;
            float den = 0.0F;
            sampson_terms_f(Ek, a->work->oprf, j, inv_f2, &e, &den);
            const float d = (e * e * inv_sigma2) / den;
            stat[j] = (d <= 3.0e38F) ? d : 3.0e38F;  // den = 0 gives Inf or NaN: 3e38
        }
    }
}

/// nu^T (H P_ss H^T + R)^-1 nu with P_ss = L L^T given by its Cholesky factor (H L computed
/// once, 2x6 times lower-triangular 6x6); +inf when S is not PD.
double mahalanobis2(const Linearized &lin, const Mat6 &Lss) {
    double hl0[6], hl1[6];  // rows of H L (L lower triangular)
    for (int k = 0; k < 6; ++k) {
        double s0 = 0.0, s1 = 0.0;
        for (int j = k; j < 6; ++j) {
            s0 += lin.H(0, j) * Lss(j, k);
            s1 += lin.H(1, j) * Lss(j, k);
        }
        hl0[k] = s0;
        hl1[k] = s1;
    }
    double s00 = lin.R(0, 0), s11 = lin.R(1, 1), s01 = 0.5 * (lin.R(0, 1) + lin.R(1, 0));
    for (int k = 0; k < 6; ++k) {
        s00 += hl0[k] * hl0[k];
        s11 += hl1[k] * hl1[k];
        s01 += hl0[k] * hl1[k];
    }
    double q = 0.0;
    if (!la::inv_quadratic_2x2(s00, s01, s01, s11, lin.nu(0), lin.nu(1), &q)) {
        return std::numeric_limits<double>::infinity();
    }
    return q;
}

/// Expected parallax (px) between the previous camera and the prior current camera: focal length
/// times the baseline times the mean inverse depth of the valid matches.
double expected_parallax_px(const sfd_ekf_camera_t &cam, const CameraPose &prev,
                            const CameraPose &cur, const double *inv_depth_sum, int32_t count) {
    if (count <= 0) return 0.0;
    const double baseline = (cur.p_CinW - prev.p_CinW).norm();
    const double f = 0.5 * (cam.fx_px + cam.fy_px);
    return f * baseline * (*inv_depth_sum / count);
}

}  // namespace

/// Cholesky factor of the pose covariance (lower); a tiny diagonal load keeps a PSD-but-singular
/// P_ss factorizable (the gate then treats that direction as known).
Mat6 pose_cholesky(const Mat6 &Pss) {
    Mat6 L = Mat6::Zero();
    double max_diag = 0.0;
    for (int i = 0; i < 6; ++i) max_diag = std::fmax(max_diag, Pss(i, i));
    const double load = 1e-12 * max_diag + 1e-300;
    for (int j = 0; j < 6; ++j) {
        double sjj = Pss(j, j) + load;
        for (int k = 0; k < j; ++k) sjj -= L(j, k) * L(j, k);
        const double ljj = (sjj > 0.0) ? std::sqrt(sjj) : 0.0;
        L(j, j) = ljj;
        for (int i = j + 1; i < 6; ++i) {
            double t = Pss(i, j);
            for (int k = 0; k < j; ++k) t -= L(i, k) * L(j, k);
            L(i, j) = (ljj > 0.0) ? t / ljj : 0.0;
        }
    }
    return L;
}

/// Individual compatibility (thesis Section 1.2.1.1) of one linearized match under the
/// filter's pose covariance (Cholesky factor @p Lss): nu^T (H P_ss H^T + R)^-1 nu.
bool passes_gate(const sfd_assoc_t &a, const Linearized &lin, const Mat6 &Lss, double *d2) {
    *d2 = mahalanobis2(lin, Lss);
    return *d2 <= a.chi2_2;
}

/// Removes from @p set the matches failing the gate at the filter @p ekf (each linearized there);
/// their statistic becomes the Mahalanobis value. Returns how many were removed.
int32_t gate_innovations(sfd_assoc_t *a, const sfd_ekf_t &ekf, const sfd_ekf_camera_t &cam,
                         const sfd_match_t *m, int32_t n, uint8_t *set) {
    const Mat6 Lss = pose_cholesky(pose_covariance(ekf));
    const Linearizer lz(ekf, ekf_rotation(ekf), cam);
    int32_t removed = 0;
    for (int32_t i = 0; i < n; ++i) {
        if (set[i] == 0U) continue;
        Linearized lin;
        double d2 = std::numeric_limits<double>::infinity();
        const bool ok = lz.linearize(m[i].uv_px, m[i].landmark_W_m, m[i].landmark_cov_m2, &lin);
        if (ok) add_pixel_noise(&lin, cam.pixel_sigma_px * cam.pixel_sigma_px, m[i]);
        if (!ok || !passes_gate(*a, lin, Lss, &d2)) {
            set[i] = 0U;
            a->best_stat[i] = static_cast<float>(std::fmin(d2, 3.0e38));
            ++removed;
        }
    }
    return removed;
}

void oprf_select(sfd_assoc_t *a, const SelectInputs &in, sfd_assoc_result_t *out) {
    const sfd_assoc_params_t &prm = a->params;
    a->stage = SFD_STAGE_OPRF;
    const Vec3 p_prior(in.ekf.p_IinW_m[0], in.ekf.p_IinW_m[1], in.ekf.p_IinW_m[2]);
    const CameraPose cur_prior = camera_pose(in.R_prior, p_prior, in.cam.ext);
    if (expected_parallax_px(in.cam, in.prev, cur_prior, &in.inv_depth_sum, in.nv) <
        prm.min_parallax_px) {
        // Degenerate motion: the epipolar geometry is undefined; the hypotheses are scored by
        // the rotation-only transfer instead.
        a->score_kind = static_cast<int32_t>(Score::kTransfer);
        out->degenerate_motion = 1;
        hypothesize_and_test(a, in, Score::kTransfer, out);
        return;
    }
    a->score_kind = static_cast<int32_t>(Score::kSampson);
    const int32_t nv = in.nv;
    const Mat6 Pss = pose_covariance(in.ekf);
    // The Sampson scoring runs over the packed pixel arrays of the valid matches.
    const double thr_sampson = a->chi2_1 * in.sigma2;
    const AxisWeights thr{static_cast<float>(thr_sampson * in.inv_fx * in.inv_fx),
                          static_cast<float>(thr_sampson * in.inv_fy * in.inv_fy),
                          static_cast<float>(thr_sampson * in.inv_fx * in.inv_fy)};
    Model best_model{};
    int32_t best_count = -1;
    int32_t needed = prm.max_hypotheses;  // line 1: "a big value"
    int32_t h = 0;
    for (; h < prm.max_hypotheses && h < needed; ++h) {
        Mat3 R_h;
        Vec3 p_h;
        if (!draw_hypothesis(a, in, Pss, &R_h, &p_h)) {
            continue;  // a failed hypothesis still counts against the budget
        }
        const Model model = make_model(in.cam, in.prev, R_h, p_h, Parts::kEpipolarOnly);
        const int32_t count = sampson_count_packed(a, model.E, thr, nv, best_count + 1);
        if (count > best_count) {  // line 6
            best_count = count;
            best_model = model;
            needed = sfd_ransac_hypothesis_count(
                prm.confidence, static_cast<double>(count) / static_cast<double>(nv), 1,
                prm.max_hypotheses);
        }
    }
    if (best_count >= 0) {  // verdicts and statistics of the best hypothesis
        const AxisWeights inv_f2{static_cast<float>(in.inv_fx * in.inv_fx),
                                 static_cast<float>(in.inv_fy * in.inv_fy),
                                 static_cast<float>(in.inv_fx * in.inv_fy)};
        sampson_stat_packed(a, best_model.E, inv_f2, static_cast<float>(1.0 / in.sigma2), nv);
        // Noise scale (core/docs/association.md "Noise scale"): the hypothesis' pose error
        // and a pixel_sigma_px that is off both change every distance; noise_scale() measures
        // it; 1 below 16 matches.
        if (nv >= kScaleMinMatches) {
            a->sampson_scale =
                noise_scale(a->work->oprf.packed_stat, nv, a->chi2_1, prm.false_alarm_rate,
                            a->chi2_1_trunc_median, a->cur_stat);
        }
        const float inv_scale = static_cast<float>(1.0 / a->sampson_scale);
        const float chi2_1 = static_cast<float>(a->chi2_1);
        best_count = 0;
        for (int32_t k = 0; k < nv; ++k) {
            const int32_t i = a->valid_idx[k];
            const float d = a->work->oprf.packed_stat[k] * inv_scale;
            a->best[i] = (d <= chi2_1) ? 1U : 0U;
            best_count += a->best[i];
            a->best_stat[i] = d;
        }
    }
    end_hypotheses(a, in, h, needed, best_count, out);
}

}  // namespace assoc
}  // namespace sfd
