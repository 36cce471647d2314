// SPDX-License-Identifier: MIT
// 1-point RANSAC inside the EKF (Civera et al. 2010; Kilic 2014 Table 1): one match per
// hypothesis, a single-match EKF update of the pose, every match scored by its reprojection
// distance (core/docs/association.md "1-point RANSAC"). The hypothesize-and-test loop here also
// serves OPRF under degenerate motion (the rotation-only transfer).
#include "association_internal.hpp"
#include "sfd/sfd_prng.h"
#include "sfd/sfd_ransac.h"

namespace sfd {
namespace assoc {

bool draw_hypothesis(sfd_assoc_t *a, const SelectInputs &in, const Mat6 &Pss, Mat3 *R_h,
                     Vec3 *p_h) {
    const int32_t pick =
        a->valid_idx[sfd_prng_uniform_index(&a->rng, static_cast<uint32_t>(in.nv))];
    Linearized lin;
    const sfd_match_t &mp = in.matches[pick];
    return in.lz.linearize(mp.uv_px, mp.landmark_W_m, mp.landmark_cov_m2, &lin) &&
           single_update_pose(in.ekf, in.R_prior, Pss, lin, R_h, p_h);
}

void end_hypotheses(sfd_assoc_t *a, const SelectInputs &in, int32_t h, int32_t needed,
                    int32_t best_count, sfd_assoc_result_t *out) {
    out->hypotheses_used = h;
    out->budget_exhausted = (needed >= a->params.max_hypotheses) ? 1 : 0;
    if (best_count <= 0) {
        best_count = 0;
        for (int32_t i = 0; i < in.n; ++i) a->best[i] = 0U;
    }
    out->inliers_stage1 = best_count;
}

void hypothesize_and_test(sfd_assoc_t *a, const SelectInputs &in, Score score,
                          sfd_assoc_result_t *out) {
    const sfd_assoc_params_t &prm = a->params;
    const int32_t n = in.n;
    const Mat6 Pss = pose_covariance(in.ekf);
    int32_t best_count = -1;
    int32_t needed = prm.max_hypotheses;  // line 1: "a big value"
    int32_t h = 0;
    for (; h < prm.max_hypotheses && h < needed; ++h) {
        Mat3 R_h;
        Vec3 p_h;
        if (!draw_hypothesis(a, in, Pss, &R_h, &p_h)) {
            continue;  // a failed hypothesis still counts against the budget
        }
        const Model model = make_model(in.cam, in.prev, R_h, p_h, Parts::kAll);
        const int32_t count = score_all(a, score, in.cam, model, in.matches, n, nullptr);
        if (count > best_count) {  // line 6
            best_count = count;
            for (int32_t i = 0; i < n; ++i) {
                a->best[i] = a->cur[i];
                a->best_stat[i] = a->cur_stat[i];
            }
            needed = sfd_ransac_hypothesis_count(
                prm.confidence, static_cast<double>(count) / static_cast<double>(in.nv), 1,
                prm.max_hypotheses);
        }
    }
    end_hypotheses(a, in, h, needed, best_count, out);
}

void ransac1_select(sfd_assoc_t *a, const SelectInputs &in, sfd_assoc_result_t *out) {
    a->stage = SFD_STAGE_RANSAC_1PT;
    a->score_kind = static_cast<int32_t>(Score::kReproj);
    hypothesize_and_test(a, in, Score::kReproj, out);
}

}  // namespace assoc
}  // namespace sfd
