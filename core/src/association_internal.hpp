// SPDX-License-Identifier: MIT
// Private to the association sources (core/docs/association.md): what the dispatcher
// (association.cpp), OPRF (oprf.cpp), 1-point RANSAC (ransac_1pt.cpp) and the fundamental-matrix
// RANSAC glue (fundamental_matrix.cpp) share. Defined in association.cpp unless noted.
#ifndef SFD_ASSOCIATION_INTERNAL_HPP
#define SFD_ASSOCIATION_INTERNAL_HPP

#include "core_private.hpp"
#include "ekf.hpp"
#include "sfd/sfd_assoc.h"
#include "sfd/sfd_parity.h"  // SFD_STAGE_*

namespace sfd {
namespace assoc {

/// How a hypothesis scores a match.
enum class Score {
    kSampson,   ///< OPRF: Sampson distance of eq. (25) with per-point covariances, px^2
    kReproj,    ///< RANSAC1: reprojection distance r^T S^-1 r of the landmark (chi2(2))
    kTransfer,  ///< OPRF, degenerate motion: rotation-only transfer of the previous pixel, px^2
};

/// The model a hypothesis (or an updated filter) defines for scoring.
struct Model {
    CameraPose cur;  ///< current camera pose
    double F[9];     ///< eq. (26), x_prev^T F x_curr = 0 (kSampson)
    float E[9];      ///< K^T F K = R [R^T t]x scaled to unit largest entry, single precision
    Mat3 H_inf;      ///< K R_CprevToCcur K^-1 (kTransfer)
};

/// Which parts of a Model to build: the single-precision E only (OPRF's hypothesis loop) or all.
enum class Parts { kEpipolarOnly, kAll };

/// What select() prepared for the method: the prior, the previous camera and the nv valid
/// matches (a.valid, a.valid_idx and the method's packed inputs filled in).
struct SelectInputs {
    const sfd_ekf_t &ekf;
    const sfd_ekf_camera_t &cam;
    const CameraPose &prev;  ///< the previous frame's camera
    const Mat3 &R_prior;     ///< the prior's IMU rotation
    const Linearizer &lz;    ///< linearization at the prior
    const sfd_match_t *matches;
    int32_t n;             ///< matches
    int32_t nv;            ///< valid matches (a.valid_idx[0..nv))
    double sigma2;         ///< pixel_sigma_px^2 (px^2)
    double inv_fx;         ///< 1 / fx (1/px)
    double inv_fy;         ///< 1 / fy (1/px)
    double inv_depth_sum;  ///< sum of 1/depth of the valid matches (1/m)
};

/// Adds the pixel noise through the distortion of the match's current observation to a
/// linearized R: R += sigma^2 dC_curr, so R = sigma^2 C_curr + J_L C_L J_L^T.
void add_pixel_noise(Linearized *lin, double sigma2, const sfd_match_t &m);

/// Builds the scoring model of a current IMU pose (eq. (26)).
Model make_model(const sfd_ekf_camera_t &cam, const CameraPose &prev, const Mat3 &R_ItoW,
                 const Vec3 &p_IinW, Parts parts);

/// Scores every valid match (restricted to @p only when given) under @p model into a.cur /
/// a.cur_stat; returns the inlier count.
int32_t score_all(sfd_assoc_t *a, Score score, const sfd_ekf_camera_t &cam, const Model &model,
                  const sfd_match_t *m, int32_t n, const uint8_t *only);

/// One hypothesis of Table 1 (lines 2-3): draws a valid match with the PRNG and applies the
/// single-match EKF update to a scratch copy of the pose; false when it fails (the hypothesis
/// still counts against the budget). (ransac_1pt.cpp)
bool draw_hypothesis(sfd_assoc_t *a, const SelectInputs &in, const Mat6 &Pss, Mat3 *R_h, Vec3 *p_h);

/// The end of a hypothesis loop: h hypotheses drawn, @p needed the last adaptive count, the best
/// hypothesis with @p best_count inliers (none: no match is an inlier). (ransac_1pt.cpp)
void end_hypotheses(sfd_assoc_t *a, const SelectInputs &in, int32_t h, int32_t needed,
                    int32_t best_count, sfd_assoc_result_t *out);

/// The hypothesize-and-test loop of Table 1 (lines 1-7) scoring each hypothesis with
/// score_all() under @p score (RANSAC1's reprojection, OPRF's rotation-only transfer): leaves
/// the best hypothesis' flags and statistics in a.best / a.best_stat and fills the result's
/// hypotheses_used, budget_exhausted and inliers_stage1. (ransac_1pt.cpp)
void hypothesize_and_test(sfd_assoc_t *a, const SelectInputs &in, Score score,
                          sfd_assoc_result_t *out);

/// RANSAC1's selection (Civera et al. 2010, Table 1). (ransac_1pt.cpp)
void ransac1_select(sfd_assoc_t *a, const SelectInputs &in, sfd_assoc_result_t *out);

/// OPRF's selection (Kilic 2014 Section 3.2): the hypothesis loop with Sampson scoring, its
/// noise scale, or the rotation-only transfer under degenerate motion. (oprf.cpp)
void oprf_select(sfd_assoc_t *a, const SelectInputs &in, sfd_assoc_result_t *out);

/// The fundamental-matrix RANSAC's selection (Table 2) over a.x_prev / a.x_curr; SFD_OK, or the
/// error of sfd_ransacf() that is not a verdict. (fundamental_matrix.cpp)
sfd_status_t ransacf_select(sfd_assoc_t *a, const SelectInputs &in, sfd_assoc_result_t *out);

/// Cholesky factor of the pose covariance (lower), with a tiny diagonal load. (oprf.cpp)
Mat6 pose_cholesky(const Mat6 &Pss);

/// OPRF's individual-compatibility gate of one linearized match: nu^T (H P_ss H^T + R)^-1 nu
/// (into @p d2) <= chi2_{2,1-a}. (oprf.cpp)
bool passes_gate(const sfd_assoc_t &a, const Linearized &lin, const Mat6 &Lss, double *d2);

/// Removes from @p set the matches failing the gate at the filter @p ekf; returns how many.
/// (oprf.cpp)
int32_t gate_innovations(sfd_assoc_t *a, const sfd_ekf_t &ekf, const sfd_ekf_camera_t &cam,
                         const sfd_match_t *m, int32_t n, uint8_t *set);

}  // namespace assoc
}  // namespace sfd

#endif  // SFD_ASSOCIATION_INTERNAL_HPP
