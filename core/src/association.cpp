// SPDX-License-Identifier: MIT
// Data association inside the EKF: OPRF (Kilic 2014 Section 3.2, Table 1), 1-point RANSAC
// (Civera et al. 2010, Table 1), fundamental-matrix RANSAC (Table 2) and no association.
// Readings chosen where the thesis is ambiguous: core/docs/association.md.
#include "bits_equal.h"
#include "ekf.hpp"
#include "rotation.hpp"
#include "sampson.hpp"
#include "sfd/sfd_assoc.h"
#include "sfd/sfd_chi2.h"
#include "sfd/sfd_fundamental.h"
#include "sfd/sfd_parity.h"
#include "sfd/sfd_ransac.h"

namespace sfd {
namespace {

/// How a hypothesis scores a match.
enum class Score {
    kSampson,   ///< OPRF: first-order epipolar (Sampson) distance of eq. (25), px^2
    kReproj,    ///< RANSAC1: reprojection distance of the landmark, px^2
    kTransfer,  ///< OPRF, degenerate motion: rotation-only transfer of the previous pixel, px^2
};

/// The model a hypothesis (or an updated filter) defines for scoring.
struct Model {
    CameraPose cur;  ///< current camera pose
    double F[9];     ///< eq. (26), x_prev^T F x_curr = 0 (kSampson)
    float E[9];      ///< K^T F K = R [R^T t]x scaled to unit largest entry, single precision
    Mat3 H_inf;      ///< K R_CprevToCcur K^-1 (kTransfer)
};

Mat3 intrinsics(const sfd_ekf_camera_t &cam) {
    Mat3 K;
    K << cam.fx_px, 0.0, cam.cx_px, 0.0, cam.fy_px, cam.cy_px, 0.0, 0.0, 1.0;
    return K;
}

Mat3 intrinsics_inverse(const sfd_ekf_camera_t &cam) {
    Mat3 Ki;
    Ki << 1.0 / cam.fx_px, 0.0, -cam.cx_px / cam.fx_px, 0.0, 1.0 / cam.fy_px,
        -cam.cy_px / cam.fy_px, 0.0, 0.0, 1.0;
    return Ki;
}

/// Which parts of a Model to build: the single-precision E only (OPRF's hypothesis loop) or all.
enum class Parts { kEpipolarOnly, kAll };

/// Builds the scoring model of a current IMU pose. With X_prev = R X_cur + t the coordinates of a
/// point in the previous and current cameras, R = R_WtoCprev R_CcurToW and t = R_WtoCprev
/// (p_Ccur - p_Cprev); then x_prev^T [t]x R x_cur = 0, and [t]x R = R [R^T t]x gives eq. (26):
/// F = K^-T R [R^T t]x K^-1, E = R [R^T t]x its normalized-coordinate form.
Model make_model(const sfd_ekf_camera_t &cam, const CameraPose &prev, const Mat3 &R_ItoW,
                 const Vec3 &p_IinW, Parts parts) {
    Model m{};
    m.cur = camera_pose(R_ItoW, p_IinW, cam.ext);
    const Mat3 R = prev.R_WtoC * m.cur.R_WtoC.transpose();
    const Vec3 t = prev.R_WtoC * (m.cur.p_CinW - prev.p_CinW);
    const Mat3 E = R * skew(R.transpose() * t);
    const double e_max = E.cwiseAbs().maxCoeff();
    const double e_scale = (e_max > 0.0 && std::isfinite(e_max)) ? 1.0 / e_max : 0.0;
    for (int k = 0; k < 9; ++k) m.E[k] = static_cast<float>(E(k / 3, k % 3) * e_scale);
    if (parts == Parts::kEpipolarOnly) return m;
    const Mat3 Ki = intrinsics_inverse(cam);
    const Mat3 F = Ki.transpose() * E * Ki;
    for (int k = 0; k < 9; ++k) m.F[k] = F(k / 3, k % 3);
    m.H_inf = intrinsics(cam) * R.transpose() * Ki;
    return m;
}

/// Squared distance (px^2) of match @p mt under @p model, or +inf when it cannot be formed.
double distance_px2(Score score, const sfd_ekf_camera_t &cam, const Model &model,
                    const sfd_match_t &mt) {
    const double inf = std::numeric_limits<double>::infinity();
    if (score == Score::kSampson) return sampson_px2(model.F, mt.prev_uv_px, mt.obs.uv_px);
    if (score == Score::kTransfer) {
        const Vec3 x = model.H_inf * Vec3(mt.prev_uv_px[0], mt.prev_uv_px[1], 1.0);
        if (!(std::fabs(x.z()) > 1e-12)) return inf;
        const double du = x.x() / x.z() - mt.obs.uv_px[0];
        const double dv = x.y() / x.z() - mt.obs.uv_px[1];
        const double d = du * du + dv * dv;
        return std::isfinite(d) ? d : inf;
    }
    Vec2 uv;
    if (!project(cam, model.cur,
                 Vec3(mt.obs.landmark_W_m[0], mt.obs.landmark_W_m[1], mt.obs.landmark_W_m[2]),
                 &uv)) {
        return inf;
    }
    const double du = uv(0) - mt.obs.uv_px[0];
    const double dv = uv(1) - mt.obs.uv_px[1];
    return du * du + dv * dv;
}

/// Fewest matches for OPRF's noise scale, and the median of chi2(1).
constexpr int32_t kScaleMinMatches = 16;
constexpr double kChi2Dof1Median = 0.454936423119572;

/// Threshold of a match in px^2 and its normalizer (the sigma^2 of the statistic).
struct Gate {
    double thr_px2;
    double unit_px2;
};

Gate gate_of(Score score, const sfd_assoc_t &a, double sigma2, double noise_px2) {
    switch (score) {
        case Score::kSampson:  // Sampson / (s sigma^2) ~ chi2(1) for a true match
            return Gate{a.chi2_1 * a.sampson_scale * sigma2, a.sampson_scale * sigma2};
        case Score::kReproj:  // reprojection / (sigma^2 + landmark spread) ~ chi2(2)
            return Gate{a.chi2_2 * noise_px2, noise_px2};
        case Score::kTransfer:  // both pixels noisy: 2 sigma^2 per axis, plus allowed parallax
        default:
            return Gate{
                a.chi2_2 * 2.0 * sigma2 + a.params.min_parallax_px * a.params.min_parallax_px,
                2.0 * sigma2};
    }
}

/// Single-precision form of eq. (25) in normalized coordinates (see sampson_count_packed()): the
/// residual e = x~_prev^T E x~_curr and the Sampson denominator weighted per axis,
/// wx (g0^2 + h0^2) + wy (g1^2 + h1^2) with g = E x~_curr, h = E^T x~_prev.
inline void sampson_terms_f(const float *E, float u1, float v1, float u2, float v2, float wx,
                            float wy, float *e, float *den) {
    const float g0 = E[0] * u2 + E[1] * v2 + E[2];
    const float g1 = E[3] * u2 + E[4] * v2 + E[5];
    const float g2 = E[6] * u2 + E[7] * v2 + E[8];
    const float h0 = E[0] * u1 + E[3] * v1 + E[6];
    const float h1 = E[1] * u1 + E[4] * v1 + E[7];
    *e = u1 * g0 + v1 * g1 + g2;
    *den = wx * (g0 * g0 + h0 * h0) + wy * (g1 * g1 + h1 * h1);
}

/// Counts the inliers of one OPRF hypothesis among the packed valid matches: the Sampson distance
/// of eq. (25) in px^2 is at most @p thr_px2. It is evaluated in normalized coordinates x~ = K^-1
/// x, where F = K^-T E K^-1 gives the same residual e = x~_prev^T E x~_curr and the pixel Sampson
/// denominator |(F x_curr)_12|^2 + |(F^T x_prev)_12|^2 = (g0^2 + h0^2) / fx^2 + (g1^2 + h1^2) /
/// fy^2 with g = E x~_curr, h = E^T x~_prev; the test e^2 <= thr (...) needs no division and, E
/// being scaled to unit largest entry, is well conditioned in single precision. Blocks of
/// SFD_ASSOC_SCORE_BLOCK matches are scored together (vectorizable; the NaN padding is never an
/// inlier). Stops early, returning a count below @p need, once even all remaining matches could not
/// reach @p need: only a hypothesis with more inliers than the best so far matters. Single
/// precision only ranks the hypotheses: the verdicts of the chosen one are computed in double
/// precision with sampson_px2().
int32_t sampson_count_packed(const sfd_assoc_t *a, const float E[9], float thr_u, float thr_v,
                             int32_t nv, int32_t need) {
    constexpr int32_t kBlock = SFD_ASSOC_SCORE_BLOCK;
    float Ek[9];  // a local copy: provably not aliased by the loop, so it stays in registers
    for (int k = 0; k < 9; ++k) Ek[k] = E[k];
    int32_t count = 0;
    for (int32_t k0 = 0; k0 < nv; k0 += kBlock) {
        if (count + (nv - k0) < need) return count;
        const float *u1 = a->nx_prev_u + k0;
        const float *v1 = a->nx_prev_v + k0;
        const float *u2 = a->nx_curr_u + k0;
        const float *v2 = a->nx_curr_v + k0;
        int32_t block_count = 0;
        for (int32_t j = 0; j < kBlock; ++j) {
            float e = 0.0F;
            float rhs = 0.0F;
            sampson_terms_f(Ek, u1[j], v1[j], u2[j], v2[j], thr_u, thr_v, &e, &rhs);
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
void sampson_stat_packed(sfd_assoc_t *a, const float E[9], float inv_fx2, float inv_fy2,
                         float inv_sigma2, int32_t nv) {
    constexpr int32_t kBlock = SFD_ASSOC_SCORE_BLOCK;
    float Ek[9];
    for (int k = 0; k < 9; ++k) Ek[k] = E[k];
    for (int32_t k0 = 0; k0 < nv; k0 += kBlock) {
        const float *u1 = a->nx_prev_u + k0;
        const float *v1 = a->nx_prev_v + k0;
        const float *u2 = a->nx_curr_u + k0;
        const float *v2 = a->nx_curr_v + k0;
        float *stat = a->packed_stat + k0;
        for (int32_t j = 0; j < kBlock; ++j) {
            float e = 0.0F;
            float den = 0.0F;
            sampson_terms_f(Ek, u1[j], v1[j], u2[j], v2[j], inv_fx2, inv_fy2, &e, &den);
            const float d = (e * e * inv_sigma2) / den;
            stat[j] = (d <= 3.0e38F) ? d : 3.0e38F;  // den = 0 gives Inf or NaN: 3e38
        }
    }
}

/// Scores every valid match (restricted to @p only when given) under @p model into a.cur /
/// a.cur_stat; returns the inlier count. (The hypothesis loop scores OPRF's Sampson distance with
/// sampson_count_packed(); this serves the stage-2 rescue and the other distances.)
int32_t score_all(sfd_assoc_t *a, Score score, const sfd_ekf_camera_t &cam, const Model &model,
                  const sfd_match_t *m, int32_t n, const uint8_t *only) {
    const double sigma2 = cam.pixel_sigma_px * cam.pixel_sigma_px;
    int32_t count = 0;
    for (int32_t i = 0; i < n; ++i) {
        a->cur[i] = 0U;
        if (a->valid[i] == 0U || (only != nullptr && only[i] == 0U)) continue;
        const double d = distance_px2(score, cam, model, m[i]);
        const Gate g = gate_of(score, *a, sigma2, a->noise_px2[i]);
        a->cur_stat[i] = static_cast<float>(std::fmin(d / g.unit_px2, 3.0e38));
        if (d <= g.thr_px2) {
            a->cur[i] = 1U;
            ++count;
        }
    }
    return count;
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
    const double det = s00 * s11 - s01 * s01;
    if (!(det > 0.0) || !(s00 > 0.0)) return std::numeric_limits<double>::infinity();
    const double x = lin.nu(0), y = lin.nu(1);
    return (s11 * x * x - 2.0 * s01 * x * y + s00 * y * y) / det;
}

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

/// Expected parallax (px) between the previous camera and the prior current camera: focal length
/// times the baseline times the mean inverse depth of the valid matches.
double expected_parallax_px(const sfd_ekf_camera_t &cam, const CameraPose &prev,
                            const CameraPose &cur, const double *inv_depth_sum, int32_t count) {
    if (count <= 0) return 0.0;
    const double baseline = (cur.p_CinW - prev.p_CinW).norm();
    const double f = 0.5 * (cam.fx_px + cam.fy_px);
    return f * baseline * (*inv_depth_sum / count);
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
        if (!lz.linearize(m[i].obs, &lin) || !passes_gate(*a, lin, Lss, &d2)) {
            set[i] = 0U;
            a->best_stat[i] = static_cast<float>(std::fmin(d2, 3.0e38));
            ++removed;
        }
    }
    return removed;
}

}  // namespace
}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_assoc_params_default(sfd_assoc_params_t *params) {
    if (params == nullptr) return SFD_ERR_INVAL;
    *params = sfd_assoc_params_t{};
    params->method = SFD_METHOD_OPRF;
    params->false_alarm_rate = 0.01;
    params->confidence = 0.99;
    params->max_hypotheses = (SFD_MAX_HYPOTHESES < 100) ? SFD_MAX_HYPOTHESES : 100;
    params->min_parallax_px = 1.0;
    params->seed = 1U;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_assoc_params_from(const sfd_params_t *p, sfd_assoc_params_t *params) {
    if (p == nullptr || params == nullptr) return SFD_ERR_INVAL;
    sfd_assoc_params_default(params);
    params->method = p->method;
    params->false_alarm_rate = p->false_alarm_rate;
    params->confidence = p->ransac_confidence;
    params->max_hypotheses = p->max_hypotheses;
    params->seed = p->seed;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_assoc_init(sfd_assoc_t *assoc, const sfd_assoc_params_t *params) {
    if (assoc == nullptr || params == nullptr) return SFD_ERR_INVAL;
    const sfd_assoc_params_t &p = *params;
    if (p.method != SFD_METHOD_NONE && p.method != SFD_METHOD_OPRF &&
        p.method != SFD_METHOD_RANSAC1 && p.method != SFD_METHOD_RANSACF) {
        return SFD_ERR_INVAL;
    }
    if (!(p.false_alarm_rate > 0.0 && p.false_alarm_rate <= 0.5)) return SFD_ERR_INVAL;
    if (!(p.confidence > 0.0 && p.confidence < 1.0)) return SFD_ERR_INVAL;
    if (!(std::isfinite(p.min_parallax_px) && p.min_parallax_px >= 0.0)) return SFD_ERR_INVAL;
    if (p.max_hypotheses < 1) return SFD_ERR_INVAL;
    if (p.max_hypotheses > SFD_MAX_HYPOTHESES) return SFD_ERR_CAPACITY;
    *assoc = sfd_assoc_t{};
    assoc->params = p;
    if (sfd_prng_seed(&assoc->rng, p.seed) != SFD_OK) return SFD_ERR_INVAL;
    if (sfd_chi2_quantile_upper(p.false_alarm_rate, 1, &assoc->chi2_1) != SFD_OK ||
        sfd_chi2_quantile_upper(p.false_alarm_rate, 2, &assoc->chi2_2) != SFD_OK) {
        return SFD_ERR_NUMERIC;
    }
    assoc->initialized = 1;
    return SFD_OK;
}

namespace {

/// Above this the depth is not finite (overflow of the camera transform).
constexpr double kInfDepth_m = std::numeric_limits<double>::max();

/// A match is 16 doubles and nothing else (checked finite in one pass).
constexpr std::size_t kMatchDoubles = 16;
static_assert(sizeof(sfd_match_t) == kMatchDoubles * sizeof(double),
              "sfd_match_t must hold exactly its 16 doubles");

bool same_prior(const sfd_assoc_t &a, const sfd_ekf_t &ekf) {
    return sfd_bits_equal(a.prior_p_m, ekf.p_IinW_m, 3) != 0 &&
           sfd_bits_equal(a.prior_q, ekf.q_ItoW, 4) != 0;
}

void write_verdicts(const sfd_assoc_t &a, sfd_assoc_result_t *out) {
    int32_t tested = 0;
    int32_t consistent = 0;
    for (int32_t i = 0; i < a.n; ++i) {
        const bool valid = (a.valid[i] != 0U);
        const bool in = valid && (a.best[i] != 0U);
        out->status[i] = static_cast<int8_t>(
            valid ? (in ? SFD_VERDICT_CONSISTENT : SFD_VERDICT_SPURIOUS) : SFD_VERDICT_UNTESTED);
        out->stage[i] = valid ? a.stage : static_cast<int8_t>(SFD_STAGE_NONE);
        out->statistic[i] = valid ? a.best_stat[i] : 0.0F;
        tested += valid ? 1 : 0;
        consistent += in ? 1 : 0;
    }
    out->num_consistent = consistent;
    out->num_spurious = tested - consistent;
    out->num_untested = a.n - tested;
}

}  // namespace

extern "C" sfd_status_t sfd_assoc_select(sfd_assoc_t *assoc, const sfd_ekf_t *ekf,
                                         const sfd_ekf_camera_t *cam, const double prev_R_CtoW[9],
                                         const double prev_p_CinW_m[3], const sfd_match_t *matches,
                                         int32_t n, sfd_assoc_result_t *out) {
    if (assoc == nullptr || ekf == nullptr || cam == nullptr || prev_R_CtoW == nullptr ||
        prev_p_CinW_m == nullptr || out == nullptr || (matches == nullptr && n > 0)) {
        return SFD_ERR_INVAL;
    }
    if (n < 0 || n > SFD_MAX_FEATURES) return SFD_ERR_INVAL;
    if (assoc->initialized != 1 || ekf->initialized != 1) return SFD_ERR_STATE;
    if (!all_finite(prev_R_CtoW, 9) || !all_finite(prev_p_CinW_m, 3)) return SFD_ERR_INVAL;
    sfd_assoc_t &a = *assoc;
    const sfd_assoc_params_t &prm = a.params;
    *out = sfd_assoc_result_t{};
    out->n = n;
    out->update_status = SFD_OK;
    a.selected = 0;
    a.n = n;
    for (int k = 0; k < 9; ++k) a.prev_R_CtoW[k] = prev_R_CtoW[k];
    for (int k = 0; k < 3; ++k) {
        a.prev_p_CinW_m[k] = prev_p_CinW_m[k];
        a.prior_p_m[k] = ekf->p_IinW_m[k];
    }
    for (int k = 0; k < 4; ++k) a.prior_q[k] = ekf->q_ItoW[k];

    // Validity of every match at the prior (landmark in front of the camera, finite input) and
    // the mean inverse depth; RANSAC1 also needs each landmark's spread in pixels.
    const Mat3 R_prior = ekf_rotation(*ekf);
    const Linearizer lz(*ekf, R_prior, *cam);
    const double sigma2 = cam->pixel_sigma_px * cam->pixel_sigma_px;
    const bool need_spread = (prm.method == SFD_METHOD_RANSAC1);
    const bool pack_pixels = (prm.method == SFD_METHOD_RANSACF);
    const double inv_fx = 1.0 / cam->fx_px;
    const double inv_fy = 1.0 / cam->fy_px;
    const std::size_t nbytes = static_cast<std::size_t>(n);
    std::memset(a.valid, 0, nbytes);
    std::memset(a.cur, 0, nbytes);
    std::memset(a.best, 0, nbytes);
    std::memset(a.rescued, 0, nbytes);
    std::memset(a.best_stat, 0, nbytes * sizeof(float));  // all-zero bits: 0.0F
    std::memset(a.cur_stat, 0, nbytes * sizeof(float));
    int32_t nv = 0;
    double inv_depth_sum = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        const sfd_match_t &mt = matches[i];
        // All 16 inputs finite and the landmark in front of the prior camera. (A landmark whose
        // other camera coordinates overflow fails later, in linearize(), and is never an update.)
        if (!all_finite_repr<kMatchDoubles>(&mt)) continue;
        const double depth_m = lz.depth_m(mt.obs.landmark_W_m);
        if (!(depth_m > 1e-6 && depth_m < kInfDepth_m)) continue;
        if (need_spread) {
            Linearized lin;
            if (!lz.linearize(mt.obs, &lin)) continue;
            a.noise_px2[i] = 0.5 * (lin.R(0, 0) + lin.R(1, 1));  // sigma^2 + landmark spread
        } else {
            a.noise_px2[i] = sigma2;
        }
        a.valid[i] = 1U;
        if (pack_pixels) {  // the fundamental-matrix RANSAC's inputs
            a.x_prev[nv][0] = mt.prev_uv_px[0];
            a.x_prev[nv][1] = mt.prev_uv_px[1];
            a.x_curr[nv][0] = mt.obs.uv_px[0];
            a.x_curr[nv][1] = mt.obs.uv_px[1];
        } else {  // OPRF's scoring inputs (unused by the other methods)
            a.nx_prev_u[nv] = static_cast<float>((mt.prev_uv_px[0] - cam->cx_px) * inv_fx);
            a.nx_prev_v[nv] = static_cast<float>((mt.prev_uv_px[1] - cam->cy_px) * inv_fy);
            a.nx_curr_u[nv] = static_cast<float>((mt.obs.uv_px[0] - cam->cx_px) * inv_fx);
            a.nx_curr_v[nv] = static_cast<float>((mt.obs.uv_px[1] - cam->cy_px) * inv_fy);
        }
        a.valid_idx[nv++] = i;
        inv_depth_sum += 1.0 / depth_m;
    }
    for (int32_t k = nv; k < SFD_ASSOC_PACKED_CAP && (k % SFD_ASSOC_SCORE_BLOCK) != 0; ++k) {
        const float nan = std::numeric_limits<float>::quiet_NaN();  // never an inlier
        a.nx_prev_u[k] = a.nx_prev_v[k] = a.nx_curr_u[k] = a.nx_curr_v[k] = nan;
    }
    a.stage = SFD_STAGE_NONE;
    a.sampson_scale = 1.0;
    a.score_kind = static_cast<int32_t>(Score::kSampson);
    a.selected = 1;
    if (nv == 0) {
        write_verdicts(a, out);
        return SFD_OK;
    }

    CameraPose prev;
    prev.R_WtoC = Eigen::Map<const Mat3>(prev_R_CtoW).transpose();
    prev.p_CinW = Vec3(prev_p_CinW_m[0], prev_p_CinW_m[1], prev_p_CinW_m[2]);

    if (prm.method == SFD_METHOD_NONE) {
        for (int32_t k = 0; k < nv; ++k) a.best[a.valid_idx[k]] = 1U;
        out->inliers_stage1 = nv;
    } else if (prm.method == SFD_METHOD_RANSACF) {
        a.stage = SFD_STAGE_RANSAC_F;
        sfd_ransacf_result_t rf;
        // cur[] holds the compacted inlier flags of the nv valid matches.
        const sfd_status_t st = sfd_ransacf(a.x_prev, a.x_curr, nv, a.chi2_1 * sigma2,
                                            prm.confidence, prm.max_hypotheses, &a.rng, a.cur, &rf);
        if (st == SFD_ERR_RANGE || st == SFD_ERR_NUMERIC) {
            // fewer than 8 matches, or every sample degenerate: nothing can be judged
            for (int32_t k = 0; k < nv; ++k) a.valid[a.valid_idx[k]] = 0U;
        } else if (st != SFD_OK) {
            a.selected = 0;
            return st;
        } else {
            out->hypotheses_used = rf.hypotheses_used;
            out->budget_exhausted = rf.budget_exhausted;
            out->inliers_stage1 = rf.num_inliers;
            for (int32_t k = 0; k < nv; ++k) {
                const int32_t i = a.valid_idx[k];
                a.best[i] = a.cur[k];
                const double d = sampson_px2(rf.F, a.x_prev[k], a.x_curr[k]);
                a.best_stat[i] = static_cast<float>(std::fmin(d / sigma2, 3.0e38));
            }
        }
    } else {
        // OPRF / RANSAC1: the hypothesize-and-test loop of Table 1 (lines 1-7).
        const bool oprf = (prm.method == SFD_METHOD_OPRF);
        a.stage = oprf ? SFD_STAGE_OPRF : SFD_STAGE_RANSAC_1PT;
        Score score = oprf ? Score::kSampson : Score::kReproj;
        if (oprf) {
            const Vec3 p_prior(ekf->p_IinW_m[0], ekf->p_IinW_m[1], ekf->p_IinW_m[2]);
            const CameraPose cur_prior = camera_pose(R_prior, p_prior, cam->ext);
            if (expected_parallax_px(*cam, prev, cur_prior, &inv_depth_sum, nv) <
                prm.min_parallax_px) {
                score = Score::kTransfer;
                out->degenerate_motion = 1;
            }
        }
        a.score_kind = static_cast<int32_t>(score);
        const Mat6 Pss = pose_covariance(*ekf);
        // OPRF's Sampson scoring runs over packed pixel arrays of the valid matches.
        const bool packed = (score == Score::kSampson);
        const double thr_sampson = a.chi2_1 * sigma2;
        const float thr_u = static_cast<float>(thr_sampson * inv_fx * inv_fx);
        const float thr_v = static_cast<float>(thr_sampson * inv_fy * inv_fy);
        Model best_model{};
        int32_t best_count = -1;
        int32_t needed = prm.max_hypotheses;  // line 1: "a big value"
        int32_t h = 0;
        for (; h < prm.max_hypotheses && h < needed; ++h) {
            const int32_t pick =
                a.valid_idx[sfd_prng_uniform_index(&a.rng, static_cast<uint32_t>(nv))];
            Linearized lin;
            Mat3 R_h;
            Vec3 p_h;
            if (!lz.linearize(matches[pick].obs, &lin) ||
                !single_update_pose(*ekf, R_prior, Pss, lin, &R_h, &p_h)) {
                continue;  // a failed hypothesis still counts against the budget
            }
            const Model model =
                make_model(*cam, prev, R_h, p_h, packed ? Parts::kEpipolarOnly : Parts::kAll);
            const int32_t count =
                packed ? sampson_count_packed(&a, model.E, thr_u, thr_v, nv, best_count + 1)
                       : score_all(&a, score, *cam, model, matches, n, nullptr);
            if (count > best_count) {  // line 6
                best_count = count;
                best_model = model;
                if (!packed) {
                    for (int32_t i = 0; i < n; ++i) {
                        a.best[i] = a.cur[i];
                        a.best_stat[i] = a.cur_stat[i];
                    }
                }
                needed = sfd_ransac_hypothesis_count(
                    prm.confidence, static_cast<double>(count) / static_cast<double>(nv), 1,
                    prm.max_hypotheses);
            }
        }
        if (packed && best_count >= 0) {  // verdicts and statistics of the best hypothesis
            sampson_stat_packed(&a, best_model.E, static_cast<float>(inv_fx * inv_fx),
                                static_cast<float>(inv_fy * inv_fy),
                                static_cast<float>(1.0 / sigma2), nv);
            // Noise scale (core/docs/association.md "Noise scale"): the hypothesis' pose error
            // and a pixel_sigma_px that is off both change every distance; the median over the
            // matches, over the chi2(1) median 0.4549, measures it (robust while at most half
            // are spurious); kept within [1/25, 25], 1 below 16 matches.
            if (nv >= kScaleMinMatches) {
                for (int32_t k = 0; k < nv; ++k) a.cur_stat[k] = a.packed_stat[k];
                const double s = median_in_place(a.cur_stat, nv) / kChi2Dof1Median;
                a.sampson_scale = (s < 0.04) ? 0.04 : ((s > 25.0) ? 25.0 : s);
            }
            const float inv_scale = static_cast<float>(1.0 / a.sampson_scale);
            const float chi2_1 = static_cast<float>(a.chi2_1);
            best_count = 0;
            for (int32_t k = 0; k < nv; ++k) {
                const int32_t i = a.valid_idx[k];
                const float d = a.packed_stat[k] * inv_scale;
                a.best[i] = (d <= chi2_1) ? 1U : 0U;
                best_count += a.best[i];
                a.best_stat[i] = d;
            }
        }
        out->hypotheses_used = h;
        out->budget_exhausted = (needed >= prm.max_hypotheses) ? 1 : 0;
        if (best_count <= 0) {
            best_count = 0;
            for (int32_t i = 0; i < n; ++i) a.best[i] = 0U;
        }
        out->inliers_stage1 = best_count;
    }
    write_verdicts(a, out);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_assoc_apply(sfd_assoc_t *assoc, sfd_ekf_t *ekf,
                                        const sfd_ekf_camera_t *cam, const sfd_match_t *matches,
                                        int32_t n, sfd_assoc_result_t *out) {
    if (assoc == nullptr || ekf == nullptr || cam == nullptr || out == nullptr ||
        (matches == nullptr && n > 0)) {
        return SFD_ERR_INVAL;
    }
    sfd_assoc_t &a = *assoc;
    if (a.initialized != 1 || a.selected != 1 || ekf->initialized != 1 || n != a.n || out->n != n ||
        !same_prior(a, *ekf)) {
        return SFD_ERR_STATE;
    }
    a.selected = 0;
    const bool oprf = (a.params.method == SFD_METHOD_OPRF);
    // sfd addition (core/docs/association.md): an epipolar test cannot see an error along the
    // epipolar line, and such a match pulls the update by its full reprojection error. OPRF's
    // set 1 therefore also passes the individual-compatibility gate of its innovation under the
    // prior (thesis Section 1.2.1.1), nu^T (H P_ss H^T + R)^-1 nu <= chi2_{2,1-a}, computed from
    // the same linearization the update uses. Then line 8: update the filter with set 1.
    const Linearizer lz(*ekf, ekf_rotation(*ekf), *cam);
    const Mat6 Lss = pose_cholesky(pose_covariance(*ekf));
    PoseInformation pi;
    int32_t skipped = 0;
    for (int32_t i = 0; i < n; ++i) {
        if (a.valid[i] == 0U || a.best[i] == 0U) continue;
        Linearized lin;
        double d2 = 0.0;
        if (!lz.linearize(matches[i].obs, &lin)) {
            ++skipped;
            continue;
        }
        if (oprf && !passes_gate(a, lin, Lss, &d2)) {
            a.best[i] = 0U;
            a.best_stat[i] = static_cast<float>(std::fmin(d2, 3.0e38));
            out->inliers_stage1 -= 1;
            continue;
        }
        if (!pi.add(lin)) ++skipped;
    }
    out->update = sfd_ekf_update_info_t{};
    out->update.used = pi.used;
    out->update.skipped = skipped;
    sfd_status_t st = apply_pose_information(ekf, pi, &out->update.nis);
    out->update_status = st;
    const bool rescue =
        (a.params.method == SFD_METHOD_OPRF || a.params.method == SFD_METHOD_RANSAC1);
    // Lines 9-12: rescore set 1's outliers under the updated filter; the rescued form set 2.
    if (rescue && st == SFD_OK && out->inliers_stage1 > 0) {
        const Score score = static_cast<Score>(a.score_kind);
        const Mat3 R_post = ekf_rotation(*ekf);
        const Vec3 p_post(ekf->p_IinW_m[0], ekf->p_IinW_m[1], ekf->p_IinW_m[2]);
        CameraPose prev;
        prev.R_WtoC = Eigen::Map<const Mat3>(a.prev_R_CtoW).transpose();
        prev.p_CinW = Vec3(a.prev_p_CinW_m[0], a.prev_p_CinW_m[1], a.prev_p_CinW_m[2]);
        const Model model = make_model(*cam, prev, R_post, p_post, Parts::kAll);
        for (int32_t i = 0; i < n; ++i) a.rescued[i] = (a.best[i] == 0U) ? a.valid[i] : 0U;
        int32_t count2 = score_all(&a, score, *cam, model, matches, n, a.rescued);
        for (int32_t i = 0; i < n; ++i) {
            a.rescued[i] = a.cur[i];
            if (a.valid[i] != 0U && a.best[i] == 0U) a.best_stat[i] = a.cur_stat[i];
        }
        if (oprf && count2 > 0) {
            count2 -= gate_innovations(&a, *ekf, *cam, matches, n, a.rescued);
        }
        out->inliers_stage2 = count2;
        if (count2 > 0) {  // line 13: merge; set 2's update on top of set 1's
            sfd_ekf_update_info_t info2{};
            const MatchObs view{matches};
            st = update_camera(ekf, *cam, view, a.rescued, n, &info2);
            out->update_status = st;
            out->update.used += info2.used;
            out->update.skipped += info2.skipped;
            out->update.nis += info2.nis;
            for (int32_t i = 0; i < n; ++i) {
                if (a.rescued[i] != 0U) a.best[i] = 1U;
            }
        }
    }
    write_verdicts(a, out);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_assoc_run(sfd_assoc_t *assoc, sfd_ekf_t *ekf,
                                      const sfd_ekf_camera_t *cam, const double prev_R_CtoW[9],
                                      const double prev_p_CinW_m[3], const sfd_match_t *matches,
                                      int32_t n, sfd_assoc_result_t *out) {
    const sfd_status_t st =
        sfd_assoc_select(assoc, ekf, cam, prev_R_CtoW, prev_p_CinW_m, matches, n, out);
    if (st != SFD_OK) return st;
    return sfd_assoc_apply(assoc, ekf, cam, matches, n, out);
}
