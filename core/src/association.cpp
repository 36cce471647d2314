// SPDX-License-Identifier: MIT
// Data association inside the EKF (sfd/sfd_assoc.h): the entry points, the validity of each
// match at the prior, the scoring model shared by the methods, the update with set 1 and the
// set-2 rescue. The methods: OPRF (oprf.cpp; Kilic 2014 Section 3.2, Table 1), 1-point RANSAC
// (ransac_1pt.cpp; Civera et al. 2010, Table 1), fundamental-matrix RANSAC (fundamental_matrix.cpp;
// Table 2) and no association. Readings chosen where the thesis is ambiguous:
// core/docs/association.md.
#include "association_internal.hpp"
#include "bits_equal.h"
#include "ekf.hpp"
#include "rotation.hpp"
#include "sampson.hpp"
#include "small_linalg.hpp"
#include "sfd/sfd_assoc.h"
#include "sfd/sfd_chi2.h"
#include "sfd/sfd_parity.h"

namespace sfd {
namespace assoc {
namespace {

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

/// Distance of match @p mt under @p model, or +inf when it cannot be formed, with the pixel noise
/// of both observations carried through the distortion Jacobian (mt.noise, C = I + dC):
/// - kSampson: e^2 / (g1^T C_prev g1 + g2^T C_curr g2) (sampson.hpp), px^2;
/// - kTransfer: r^T M^-1 r with r = H_inf x_prev - x_curr and M = (C_prev + C_curr) / 2, px^2
///   (Cov(r) = sigma^2 (C_prev + C_curr) = 2 sigma^2 M, taking d(H_inf x)/dx = I: a rotation of a
///   frame's interval moves pixels rigidly to first order);
/// - kReproj: r^T S^-1 r with r = h(landmark) - x_curr and @p S_px2 = sigma^2 C_curr + J_L C_L
///   J_L^T (xx, xy, yy), dimensionless (chi2(2) for a true match).
double distance_px2(Score score, const sfd_ekf_camera_t &cam, const Model &model,
                    const sfd_match_t &mt, const double *S_px2) {
    const double inf = std::numeric_limits<double>::infinity();
    if (score == Score::kSampson) {
        return sampson_px2(model.F, mt.prev_uv_px, mt.uv_px, mt.noise.prev_dC, mt.noise.curr_dC);
    }
    if (score == Score::kTransfer) {
        const Vec3 x = model.H_inf * Vec3(mt.prev_uv_px[0], mt.prev_uv_px[1], 1.0);
        if (!(std::fabs(x.z()) > 1e-12)) return inf;
        const double du = x.x() / x.z() - mt.uv_px[0];
        const double dv = x.y() / x.z() - mt.uv_px[1];
        const float *p = mt.noise.prev_dC;
        const float *c = mt.noise.curr_dC;
        const double d = quad_inv_excess(du, dv, 0.5 * (static_cast<double>(p[0]) + c[0]),
                                         0.5 * (static_cast<double>(p[1]) + c[1]),
                                         0.5 * (static_cast<double>(p[2]) + c[2]));
        return std::isfinite(d) ? d : inf;
    }
    Vec2 uv;
    if (!project(cam, model.cur, Vec3(mt.landmark_W_m[0], mt.landmark_W_m[1], mt.landmark_W_m[2]),
                 &uv)) {
        return inf;
    }
    const double du = uv(0) - mt.uv_px[0];
    const double dv = uv(1) - mt.uv_px[1];
    double q = 0.0;
    if (!la::inv_quadratic_2x2(S_px2[0], S_px2[1], S_px2[1], S_px2[2], du, dv, &q)) return inf;
    return std::isfinite(q) ? q : inf;
}

/// Threshold of a match in px^2 and its normalizer (the sigma^2 of the statistic).
struct Gate {
    double thr_px2;
    double unit_px2;
};

Gate gate_of(Score score, const sfd_assoc_t &a, double sigma2) {
    switch (score) {
        case Score::kSampson:  // Sampson / (s sigma^2) ~ chi2(1) for a true match
            return Gate{a.chi2_1 * a.sampson_scale * sigma2, a.sampson_scale * sigma2};
        case Score::kReproj:  // r^T S^-1 r ~ chi2(2), already normalized
            return Gate{a.chi2_2, 1.0};
        case Score::kTransfer:  // both pixels noisy: 2 sigma^2 per axis, plus allowed parallax
        default:
            return Gate{
                a.chi2_2 * 2.0 * sigma2 + a.params.min_parallax_px * a.params.min_parallax_px,
                2.0 * sigma2};
    }
}

}  // namespace

/// R of a linearized match becomes sigma^2 C_curr + J_L C_L J_L^T: the isotropic sigma^2 I that
/// linearize() put in plus sigma^2 dC_curr (exactly R for dC = 0). Used by the tests (RANSAC1's
/// reprojection covariance, OPRF's gate); the association's own filter updates keep sigma^2 I
/// (in the pipeline the window filter makes the update, with its own cov_xn).
void add_pixel_noise(Linearized *lin, double sigma2, const sfd_match_t &m) {
    const float *dc = m.noise.curr_dC;
    lin->R(0, 0) += sigma2 * dc[0];
    lin->R(0, 1) += sigma2 * dc[1];
    lin->R(1, 0) += sigma2 * dc[1];
    lin->R(1, 1) += sigma2 * dc[2];
}

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

// (OPRF's hypothesis loop scores its Sampson distance with sampson_count_packed(), oprf.cpp;
// score_all() serves the stage-2 rescue and the other distances.)
int32_t score_all(sfd_assoc_t *a, Score score, const sfd_ekf_camera_t &cam, const Model &model,
                  const sfd_match_t *m, int32_t n, const uint8_t *only) {
    const double sigma2 = cam.pixel_sigma_px * cam.pixel_sigma_px;
    int32_t count = 0;
    for (int32_t i = 0; i < n; ++i) {
        a->cur[i] = 0U;
        if (a->valid[i] == 0U || (only != nullptr && only[i] == 0U)) continue;
        const double d = distance_px2(score, cam, model, m[i], a->work->ransac1.S_px2[i]);
        const Gate g = gate_of(score, *a, sigma2);
        a->cur_stat[i] = static_cast<float>(std::fmin(d / g.unit_px2, 3.0e38));
        if (d <= g.thr_px2) {
            a->cur[i] = 1U;
            ++count;
        }
    }
    return count;
}

}  // namespace assoc
}  // namespace sfd

using namespace sfd;
using namespace sfd::assoc;

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
        sfd_chi2_quantile_upper(p.false_alarm_rate, 2, &assoc->chi2_2) != SFD_OK ||
        sfd_chi2_quantile_upper(0.5 * (1.0 + p.false_alarm_rate), 1, &assoc->chi2_1_trunc_median) !=
            SFD_OK) {
        return SFD_ERR_NUMERIC;
    }
    assoc->initialized = 1;
    return SFD_OK;
}

namespace {

/// Above this the depth is not finite (overflow of the camera transform).
constexpr double kInfDepth_m = std::numeric_limits<double>::max();

/// A match starts with its 4 pixel coordinates (checked finite in one pass); its landmark is
/// referred to (3 + 9 values, checked where they are).
constexpr std::size_t kMatchDoubles = 4;
static_assert(offsetof(sfd_match_t, landmark_W_m) == kMatchDoubles * sizeof(double),
              "sfd_match_t must start with exactly its 4 pixel coordinates");

/// Every input of a match present and finite: pixels, landmark, its covariance, pixel noise.
bool match_usable(const sfd_match_t &mt) {
    return all_finite_repr<kMatchDoubles>(&mt) && mt.landmark_W_m != nullptr &&
           mt.landmark_cov_m2 != nullptr && all_finite(mt.landmark_W_m, 3) &&
           all_finite(mt.landmark_cov_m2, 9) && pixel_noise_valid(mt.noise);
}

// Binds the caller's work space to the association for one call of sfd_assoc_select() or
// sfd_assoc_apply() (sfd_assoc_t::work), and unbinds it on every return.
class WorkBinding {
  public:
    WorkBinding(sfd_assoc_t &a, sfd_assoc_work_t *work) : a_(a) { a_.work = work; }
    ~WorkBinding() { a_.work = nullptr; }
    WorkBinding(const WorkBinding &) = delete;
    WorkBinding &operator=(const WorkBinding &) = delete;

  private:
    sfd_assoc_t &a_;
};

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

extern "C" sfd_status_t sfd_assoc_select(sfd_assoc_t *assoc, sfd_assoc_work_t *work,
                                         const sfd_ekf_t *ekf, const sfd_ekf_camera_t *cam,
                                         const double prev_R_CtoW[9], const double prev_p_CinW_m[3],
                                         const sfd_match_t *matches, int32_t n,
                                         sfd_assoc_result_t *out) {
    if (assoc == nullptr || work == nullptr || ekf == nullptr || cam == nullptr ||
        prev_R_CtoW == nullptr || prev_p_CinW_m == nullptr || out == nullptr ||
        (matches == nullptr && n > 0)) {
        return SFD_ERR_INVAL;
    }
    if (n < 0 || n > SFD_MAX_FEATURES) return SFD_ERR_INVAL;
    if (assoc->initialized != 1 || ekf->initialized != 1) return SFD_ERR_STATE;
    if (!all_finite(prev_R_CtoW, 9) || !all_finite(prev_p_CinW_m, 3)) return SFD_ERR_INVAL;
    sfd_assoc_t &a = *assoc;
    const WorkBinding bound(a, work);
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
    // the mean inverse depth; RANSAC1 also needs each match's reprojection covariance.
    const Mat3 R_prior = ekf_rotation(*ekf);
    const Linearizer lz(*ekf, R_prior, *cam);
    const double sigma2 = cam->pixel_sigma_px * cam->pixel_sigma_px;
    const bool need_spread = (prm.method == SFD_METHOD_RANSAC1);
    const bool pack_pixels = (prm.method == SFD_METHOD_RANSACF);
    const bool pack_oprf = (prm.method == SFD_METHOD_OPRF);
    const double inv_fx = 1.0 / cam->fx_px;
    const double inv_fy = 1.0 / cam->fy_px;
    // locals: the loop's byte stores (valid[]) could alias the camera for the compiler
    const double cx_px = cam->cx_px;
    const double cy_px = cam->cy_px;
    sfd_assoc_oprf_work_t *const ow = pack_oprf ? &a.work->oprf : nullptr;
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
        if (!match_usable(mt)) continue;
        const double depth_m = lz.depth_m(mt.landmark_W_m);
        if (!(depth_m > 1e-6 && depth_m < kInfDepth_m)) continue;
        if (need_spread) {
            Linearized lin;
            if (!lz.linearize(mt.uv_px, mt.landmark_W_m, mt.landmark_cov_m2, &lin)) continue;
            add_pixel_noise(&lin, sigma2, mt);  // S = sigma^2 C_curr + landmark spread
            double *S = a.work->ransac1.S_px2[i];
            S[0] = lin.R(0, 0);
            S[1] = 0.5 * (lin.R(0, 1) + lin.R(1, 0));
            S[2] = lin.R(1, 1);
        }
        a.valid[i] = 1U;
        if (pack_pixels) {  // the fundamental-matrix RANSAC's inputs
            sfd_assoc_ransacf_work_t &w = a.work->ransacf;
            w.x_prev[nv][0] = mt.prev_uv_px[0];
            w.x_prev[nv][1] = mt.prev_uv_px[1];
            w.x_curr[nv][0] = mt.uv_px[0];
            w.x_curr[nv][1] = mt.uv_px[1];
            w.noise[nv] = mt.noise;
        } else if (ow != nullptr) {  // OPRF's scoring inputs
            sfd_assoc_oprf_work_t &w = *ow;
            w.nx_prev_u[nv] = static_cast<float>((mt.prev_uv_px[0] - cx_px) * inv_fx);
            w.nx_prev_v[nv] = static_cast<float>((mt.prev_uv_px[1] - cy_px) * inv_fy);
            w.nx_curr_u[nv] = static_cast<float>((mt.uv_px[0] - cx_px) * inv_fx);
            w.nx_curr_v[nv] = static_cast<float>((mt.uv_px[1] - cy_px) * inv_fy);
            w.dc_prev_xx[nv] = mt.noise.prev_dC[0];
            w.dc_prev_xy[nv] = mt.noise.prev_dC[1];
            w.dc_prev_yy[nv] = mt.noise.prev_dC[2];
            w.dc_curr_xx[nv] = mt.noise.curr_dC[0];
            w.dc_curr_xy[nv] = mt.noise.curr_dC[1];
            w.dc_curr_yy[nv] = mt.noise.curr_dC[2];
        }
        a.valid_idx[nv++] = i;
        inv_depth_sum += 1.0 / depth_m;
    }
    for (int32_t k = nv; pack_oprf && k < SFD_ASSOC_PACKED_CAP && (k % SFD_ASSOC_SCORE_BLOCK) != 0;
         ++k) {
        const float nan = std::numeric_limits<float>::quiet_NaN();  // never an inlier
        sfd_assoc_oprf_work_t &w = a.work->oprf;
        w.nx_prev_u[k] = w.nx_prev_v[k] = w.nx_curr_u[k] = w.nx_curr_v[k] = nan;
        w.dc_prev_xx[k] = w.dc_prev_xy[k] = w.dc_prev_yy[k] = 0.0F;
        w.dc_curr_xx[k] = w.dc_curr_xy[k] = w.dc_curr_yy[k] = 0.0F;
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
    } else {
        const SelectInputs in{*ekf, *cam, prev,   R_prior, lz,     matches,
                              n,    nv,   sigma2, inv_fx,  inv_fy, inv_depth_sum};
        if (prm.method == SFD_METHOD_RANSACF) {
            const sfd_status_t st = ransacf_select(&a, in, out);
            if (st != SFD_OK) {
                a.selected = 0;
                return st;
            }
        } else if (prm.method == SFD_METHOD_OPRF) {
            oprf_select(&a, in, out);
        } else {
            ransac1_select(&a, in, out);
        }
    }
    write_verdicts(a, out);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_assoc_apply(sfd_assoc_t *assoc, sfd_assoc_work_t *work, sfd_ekf_t *ekf,
                                        const sfd_ekf_camera_t *cam, const sfd_match_t *matches,
                                        int32_t n, sfd_assoc_result_t *out) {
    if (assoc == nullptr || work == nullptr || ekf == nullptr || cam == nullptr || out == nullptr ||
        (matches == nullptr && n > 0)) {
        return SFD_ERR_INVAL;
    }
    sfd_assoc_t &a = *assoc;
    const WorkBinding bound(a, work);
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
        const sfd_match_t &mi = matches[i];
        if (!lz.linearize(mi.uv_px, mi.landmark_W_m, mi.landmark_cov_m2, &lin)) {
            ++skipped;
            continue;
        }
        Linearized lin_test = lin;  // the gate's R carries the pixel noise through distortion
        add_pixel_noise(&lin_test, cam->pixel_sigma_px * cam->pixel_sigma_px, matches[i]);
        if (oprf && !passes_gate(a, lin_test, Lss, &d2)) {
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

extern "C" sfd_status_t sfd_assoc_run(sfd_assoc_t *assoc, sfd_assoc_work_t *work, sfd_ekf_t *ekf,
                                      const sfd_ekf_camera_t *cam, const double prev_R_CtoW[9],
                                      const double prev_p_CinW_m[3], const sfd_match_t *matches,
                                      int32_t n, sfd_assoc_result_t *out) {
    const sfd_status_t st =
        sfd_assoc_select(assoc, work, ekf, cam, prev_R_CtoW, prev_p_CinW_m, matches, n, out);
    if (st != SFD_OK) return st;
    return sfd_assoc_apply(assoc, work, ekf, cam, matches, n, out);
}
