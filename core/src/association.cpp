// SPDX-License-Identifier: MIT
// Data association inside the EKF: OPRF (Kilic 2014 Section 3.2, Table 1), 1-point RANSAC
// (Civera et al. 2010, Table 1), fundamental-matrix RANSAC (Table 2) and no association.
// Readings chosen where the thesis is ambiguous: core/docs/association.md.
#include "ekf.hpp"
#include "rotation.hpp"
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

/// Builds the scoring model of a current IMU pose. With X_prev = R X_cur + t the coordinates of a
/// point in the previous and current cameras, R = R_WtoCprev R_CcurToW and t = R_WtoCprev
/// (p_Ccur - p_Cprev); then x_prev^T [t]x R x_cur = 0, and [t]x R = R [R^T t]x gives eq. (26):
/// F = K^-T R [R^T t]x K^-1.
Model make_model(const sfd_ekf_camera_t &cam, const CameraPose &prev, const Mat3 &R_ItoW,
                 const Vec3 &p_IinW) {
    Model m;
    m.cur = camera_pose(R_ItoW, p_IinW, cam.ext);
    const Mat3 R = prev.R_WtoC * m.cur.R_WtoC.transpose();
    const Vec3 t = prev.R_WtoC * (m.cur.p_CinW - prev.p_CinW);
    const Mat3 Ki = intrinsics_inverse(cam);
    const Mat3 F = Ki.transpose() * R * skew(R.transpose() * t) * Ki;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m.F[3 * r + c] = F(r, c);
    }
    m.H_inf = intrinsics(cam) * R.transpose() * Ki;
    return m;
}

/// Squared distance (px^2) of match @p mt under @p model, or +inf when it cannot be formed.
double distance_px2(Score score, const sfd_ekf_camera_t &cam, const Model &model,
                    const sfd_match_t &mt) {
    const double inf = std::numeric_limits<double>::infinity();
    if (score == Score::kSampson) return sfd_sampson_sq_px2(model.F, mt.prev_uv_px, mt.obs.uv_px);
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

/// Threshold of a match in px^2 and its normalizer (the sigma^2 of the statistic).
struct Gate {
    double thr_px2;
    double unit_px2;
};

Gate gate_of(Score score, const sfd_assoc_t &a, double sigma2, double noise_px2) {
    switch (score) {
        case Score::kSampson:  // Sampson / sigma^2 ~ chi2(1) for a true match, exact pose
            return Gate{a.chi2_1 * sigma2, sigma2};
        case Score::kReproj:  // reprojection / (sigma^2 + landmark spread) ~ chi2(2)
            return Gate{a.chi2_2 * noise_px2, noise_px2};
        case Score::kTransfer:  // both pixels noisy: 2 sigma^2 per axis, plus allowed parallax
        default:
            return Gate{
                a.chi2_2 * 2.0 * sigma2 + a.params.min_parallax_px * a.params.min_parallax_px,
                2.0 * sigma2};
    }
}

/// Scores every valid match under @p model into a.cur / a.cur_stat; returns the inlier count.
int32_t score_all(sfd_assoc_t *a, Score score, const sfd_ekf_camera_t &cam, const Model &model,
                  const sfd_match_t *m, int32_t n, const uint8_t *only) {
    const double sigma2 = cam.pixel_sigma_px * cam.pixel_sigma_px;
    int32_t count = 0;
    for (int32_t i = 0; i < n; ++i) {
        a->cur[i] = 0U;
        if (a->valid[i] == 0U || (only != nullptr && only[i] == 0U)) continue;
        const double d = distance_px2(score, cam, model, m[i]);
        const Gate g = gate_of(score, *a, sigma2, a->noise_px2[i]);
        const double stat = d / g.unit_px2;
        a->cur_stat[i] = static_cast<float>(std::fmin(stat, 3.0e38));
        if (d <= g.thr_px2) {
            a->cur[i] = 1U;
            ++count;
        }
    }
    return count;
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

/// Individual compatibility (thesis Section 1.2.1.1): removes from @p set the matches whose
/// innovation under the filter (R_ItoW, P_ss) fails nu^T (H P_ss H^T + R)^-1 nu <= chi2_{2,1-a};
/// their statistic becomes that Mahalanobis value. Returns how many were removed.
int32_t gate_innovations(sfd_assoc_t *a, const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const Mat6 &Pss,
                         const sfd_ekf_camera_t &cam, const sfd_match_t *m, int32_t n,
                         uint8_t *set) {
    int32_t removed = 0;
    for (int32_t i = 0; i < n; ++i) {
        if (set[i] == 0U) continue;
        Linearized lin;
        double d2 = std::numeric_limits<double>::infinity();
        if (linearize(ekf, R_ItoW, cam, m[i].obs, &lin)) {
            const Mat2 S = lin.H * Pss * lin.H.transpose() + lin.R;
            const double det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
            if (det > 0.0 && S(0, 0) > 0.0) {
                const Vec2 &v = lin.nu;
                d2 = (S(1, 1) * v(0) * v(0) - (S(0, 1) + S(1, 0)) * v(0) * v(1) +
                      S(0, 0) * v(1) * v(1)) /
                     det;
            }
        }
        if (!(d2 <= a->chi2_2)) {
            set[i] = 0U;
            a->best_stat[i] = static_cast<float>(std::fmin(d2, 3.0e38));
            ++removed;
        }
    }
    return removed;
}

void finish_counts(sfd_assoc_result_t *out) {
    out->num_consistent = out->num_spurious = out->num_untested = 0;
    for (int32_t i = 0; i < out->n; ++i) {
        if (out->status[i] == SFD_VERDICT_CONSISTENT) ++out->num_consistent;
        if (out->status[i] == SFD_VERDICT_SPURIOUS) ++out->num_spurious;
        if (out->status[i] == SFD_VERDICT_UNTESTED) ++out->num_untested;
    }
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

extern "C" sfd_status_t sfd_assoc_run(sfd_assoc_t *assoc, sfd_ekf_t *ekf,
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

    // Linearize at the prior once: validity, landmark spread, mean inverse depth.
    const Mat3 R_prior = ekf_rotation(*ekf);
    const Vec3 p_prior(ekf->p_IinW_m[0], ekf->p_IinW_m[1], ekf->p_IinW_m[2]);
    const double sigma2 = cam->pixel_sigma_px * cam->pixel_sigma_px;
    int32_t nv = 0;
    double inv_depth_sum = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        const sfd_match_t &mt = matches[i];
        a.valid[i] = 0U;
        a.cur[i] = a.best[i] = a.rescued[i] = 0U;
        a.best_stat[i] = a.cur_stat[i] = 0.0F;
        out->status[i] = SFD_VERDICT_UNTESTED;
        out->stage[i] = SFD_STAGE_NONE;
        out->statistic[i] = 0.0F;
        Linearized lin;
        if (!all_finite(mt.prev_uv_px, 2) || !all_finite(mt.obs.uv_px, 2) ||
            !all_finite(mt.obs.landmark_W_m, 3) || !all_finite(mt.obs.landmark_cov_m2, 9) ||
            !linearize(*ekf, R_prior, *cam, mt.obs, &lin)) {
            continue;
        }
        a.valid[i] = 1U;
        a.valid_idx[nv++] = i;
        a.noise_px2[i] = 0.5 * (lin.R(0, 0) + lin.R(1, 1));  // sigma^2 + landmark spread
        inv_depth_sum += 1.0 / lin.p_LinC.z();
    }
    if (nv == 0) {
        finish_counts(out);
        return SFD_OK;
    }

    Eigen::Map<const Mat3> Rp(prev_R_CtoW);
    CameraPose prev;
    prev.R_WtoC = Rp.transpose();
    prev.p_CinW = Vec3(prev_p_CinW_m[0], prev_p_CinW_m[1], prev_p_CinW_m[2]);

    int8_t stage = SFD_STAGE_NONE;
    if (prm.method == SFD_METHOD_NONE) {
        for (int32_t k = 0; k < nv; ++k) a.best[a.valid_idx[k]] = 1U;
        out->inliers_stage1 = nv;
    } else if (prm.method == SFD_METHOD_RANSACF) {
        stage = SFD_STAGE_RANSAC_F;
        for (int32_t k = 0; k < nv; ++k) {
            const sfd_match_t &mt = matches[a.valid_idx[k]];
            a.x_prev[k][0] = mt.prev_uv_px[0];
            a.x_prev[k][1] = mt.prev_uv_px[1];
            a.x_curr[k][0] = mt.obs.uv_px[0];
            a.x_curr[k][1] = mt.obs.uv_px[1];
        }
        sfd_ransacf_result_t rf;
        // cur[] holds the compacted inlier flags of the nv valid matches.
        const sfd_status_t st = sfd_ransacf(a.x_prev, a.x_curr, nv, a.chi2_1 * sigma2,
                                            prm.confidence, prm.max_hypotheses, &a.rng, a.cur, &rf);
        if (st == SFD_ERR_RANGE || st == SFD_ERR_NUMERIC) {
            // fewer than 8 matches, or every sample degenerate: nothing can be judged
            for (int32_t k = 0; k < nv; ++k) a.valid[a.valid_idx[k]] = 0U;
        } else if (st != SFD_OK) {
            return st;
        } else {
            out->hypotheses_used = rf.hypotheses_used;
            out->budget_exhausted = rf.budget_exhausted;
            out->inliers_stage1 = rf.num_inliers;
            for (int32_t k = 0; k < nv; ++k) {
                const int32_t i = a.valid_idx[k];
                a.best[i] = a.cur[k];
                const double d = sfd_sampson_sq_px2(rf.F, a.x_prev[k], a.x_curr[k]);
                a.best_stat[i] = static_cast<float>(std::fmin(d / sigma2, 3.0e38));
            }
        }
    } else {
        // OPRF / RANSAC1: the hypothesize-and-test loop of Table 1 (lines 1-7).
        const bool oprf = (prm.method == SFD_METHOD_OPRF);
        stage = oprf ? SFD_STAGE_OPRF : SFD_STAGE_RANSAC_1PT;
        Score score = oprf ? Score::kSampson : Score::kReproj;
        if (oprf) {
            const CameraPose cur_prior = camera_pose(R_prior, p_prior, cam->ext);
            if (expected_parallax_px(*cam, prev, cur_prior, &inv_depth_sum, nv) <
                prm.min_parallax_px) {
                score = Score::kTransfer;
                out->degenerate_motion = 1;
            }
        }
        const Mat6 Pss = pose_covariance(*ekf);
        int32_t best_count = -1;
        int32_t needed = prm.max_hypotheses;  // line 1: "a big value"
        int32_t h = 0;
        for (; h < prm.max_hypotheses && h < needed; ++h) {
            const int32_t pick =
                a.valid_idx[sfd_prng_uniform_index(&a.rng, static_cast<uint32_t>(nv))];
            Linearized lin;
            Mat3 R_h;
            Vec3 p_h;
            if (!linearize(*ekf, R_prior, *cam, matches[pick].obs, &lin) ||
                !single_update_pose(*ekf, R_prior, Pss, lin, &R_h, &p_h)) {
                continue;  // a failed hypothesis still counts against the budget
            }
            const Model model = make_model(*cam, prev, R_h, p_h);
            const int32_t count = score_all(&a, score, *cam, model, matches, n, nullptr);
            if (count > best_count) {  // line 6
                best_count = count;
                for (int32_t i = 0; i < n; ++i) {
                    a.best[i] = a.cur[i];
                    a.best_stat[i] = a.cur_stat[i];
                }
                needed = sfd_ransac_hypothesis_count(
                    prm.confidence, static_cast<double>(count) / static_cast<double>(nv), 1,
                    prm.max_hypotheses);
            }
        }
        out->hypotheses_used = h;
        out->budget_exhausted = (needed >= prm.max_hypotheses) ? 1 : 0;
        out->inliers_stage1 = (best_count > 0) ? best_count : 0;
        if (best_count <= 0) {
            for (int32_t i = 0; i < n; ++i) a.best[i] = 0U;
        }
        // sfd addition (core/docs/association.md): an epipolar test cannot see an error along
        // the epipolar line, and such a match pulls the update by its full reprojection error.
        // Before line 8, OPRF's set 1 therefore also passes the individual-compatibility gate of
        // its innovation under the prior (thesis Section 1.2.1.1), nu^T S^-1 nu <= chi2_{2,1-a}.
        if (oprf && best_count > 0) {
            best_count -= gate_innovations(&a, *ekf, R_prior, Pss, *cam, matches, n, a.best);
        }
        // Line 8: update the filter with inlier set 1.
        const MatchObs view{matches};
        sfd_ekf_update_info_t info1{};
        sfd_status_t st = update_camera(ekf, *cam, view, a.best, n, &info1);
        out->update = info1;
        out->update_status = st;
        // Lines 9-12: rescore set 1's outliers under the updated filter; the rescued form set 2.
        if (st == SFD_OK && best_count > 0) {
            const Mat3 R_post = ekf_rotation(*ekf);
            const Vec3 p_post(ekf->p_IinW_m[0], ekf->p_IinW_m[1], ekf->p_IinW_m[2]);
            const Model model = make_model(*cam, prev, R_post, p_post);
            for (int32_t i = 0; i < n; ++i) a.rescued[i] = (a.best[i] == 0U) ? a.valid[i] : 0U;
            int32_t count2 = score_all(&a, score, *cam, model, matches, n, a.rescued);
            for (int32_t i = 0; i < n; ++i) {
                a.rescued[i] = a.cur[i];
                if (a.valid[i] != 0U && a.best[i] == 0U) a.best_stat[i] = a.cur_stat[i];
            }
            if (oprf && count2 > 0) {
                count2 -= gate_innovations(&a, *ekf, R_post, pose_covariance(*ekf), *cam, matches,
                                           n, a.rescued);
            }
            out->inliers_stage2 = count2;
            if (count2 > 0) {  // line 13: merge; the merged set's update is set 2's on top of 1
                sfd_ekf_update_info_t info2{};
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
    }
    if (prm.method == SFD_METHOD_NONE || prm.method == SFD_METHOD_RANSACF) {
        const MatchObs view{matches};
        sfd_ekf_update_info_t info{};
        out->update_status = update_camera(ekf, *cam, view, a.best, n, &info);
        out->update = info;
    }
    for (int32_t i = 0; i < n; ++i) {
        if (a.valid[i] == 0U) continue;
        out->status[i] = (a.best[i] != 0U) ? SFD_VERDICT_CONSISTENT : SFD_VERDICT_SPURIOUS;
        out->stage[i] = stage;
        out->statistic[i] = a.best_stat[i];
    }
    finish_counts(out);
    return SFD_OK;
}
