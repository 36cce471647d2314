// SPDX-License-Identifier: MIT
// Parity-space mathematics (Tornqvist, Schon, Gustafsson 2008), exploiting the structure of the
// extended observability matrix instead of factorizing the stacked (2nL x 3n[+3L]) matrix:
//
//  1. O (eq. 27) is block diagonal with one identical 2L x 3 block per feature,
//     O_i = [(I 0) R_0; ...; (I 0) R_{L-1}], so its orthogonal complement is I_n (x) B with B
//     (2L x d, d = 2L - rank O_i) computed once per window.
//  2. The translation columns O_2 (eqs. 31-33) act on every feature's reduced residual
//     r_i = B^T Z_i through the same matrix G = B^T T_i, which has full row rank d (T_i =
//     -blockdiag((I 0) R_t) has full row rank 2L). Eliminating them therefore removes exactly the
//     component common to all features: the complement is (H (x) I_d) with H an orthonormal basis
//     of 1_n's complement, and the GLR of the group equals the generalized-least-squares form
//          T = sum_i r_i^T C_i^{-1} r_i - b^T A^{-1} b,  A = sum_i C_i^{-1},  b = sum_i C_i^{-1}
//          r_i,
//     where C_i = B^T S_i B. The residual dimension is (n - 1) d = (2L - 3) n - 2L + 3 for
//     rank O_i = 3, the paper's count.
// Cost per feature O(L d^2 + d^3) with d <= 2L - 2; per group one d x d Cholesky.
#ifndef SFD_PARITY_SPACE_HPP
#define SFD_PARITY_SPACE_HPP

#include "core_private.hpp"
#include "sfd/sfd_parity.h"

namespace sfd {
namespace parity {

constexpr int kMaxL = SFD_MAX_WINDOW;
constexpr int kMaxRows = 2 * kMaxL;
constexpr int kMaxD = 2 * kMaxL - 2;
constexpr int kMaxN = SFD_MAX_GROUP;

/// Rank decision for O_i: singular values below this (O_i's largest is ~sqrt(L)) count as zero.
/// Above it the complement is accurate to ~eps / s_min, i.e. better than 1e-7 (see the note).
constexpr double kRankTol = 1e-9;

/// Per-window complement basis of the per-feature block O_i.
struct WindowBasis {
    int L = 0;
    int rank = 0;  // rank of O_i (3 for generic rotations, 2 when all optical axes coincide)
    int d = 0;     // 2L - rank
    double B[kMaxRows][kMaxD] = {};
};

/// Computes O_i from the rotations R_C0toCt (t < L), its rank, and B with B^T O_i = 0, B^T B = I.
/// Returns false for non-finite input.
bool window_basis(const double (*R_C0toCt)[9], int L, WindowBasis *wb);

/// One feature's window data (depth-scaled measurement model, eqs. 21-24).
struct FeatureWindow {
    double y[kMaxL][2];       // measured normalized coordinates
    double y_dir[kMaxL][2];   // direction of the depth-noise term: predicted (22) or measured (28)
    double cov_y[kMaxL][3];   // sensor noise xx, xy, yy
    double depth[kMaxL];      // zhat
    double depth_var[kMaxL];  // P_z
};

/// Reduced residual and its covariance for one feature: r = B^T Z_i, C = B^T S_i B, C^{-1}, and
/// the reduced fault signatures of a jump (newest frame) and a drift (linear in t).
struct FeatureReduced {
    double r[kMaxD] = {};
    double Cinv[kMaxD][kMaxD] = {};
    double Lc[kMaxD][kMaxD] = {};  // Cholesky factor of C
    double q = 0.0;                // r^T C^{-1} r
    double phi_jump[kMaxD][2] = {};
    double phi_drift[kMaxD][2] = {};
};

/// Z_{i,t} = zhat y (+ (I 0) R_t p_t for known translation), eq. (24)-(25); S_{i,t} =
/// zhat^2 Cov(e^c) + P_z y_dir y_dir^T (eq. 22 in the depth-scaled form). Returns false when C is
/// not positive definite.
bool reduce_feature(const WindowBasis &wb, const FeatureWindow &fw, const double (*R_C0toCt)[9],
                    const double (*p_CtInC0)[3], bool translation_known, FeatureReduced *out);

/// Group statistics from reduced features.
struct GroupStats {
    int nu = 0;        // residual dimension
    double glr = 0.0;  // eq. (13), general fault
    double feature_glr[kMaxN] = {};
    int feature_dof[kMaxN] = {};
    double jump_glr[kMaxN] = {};
    int jump_dof[kMaxN] = {};
    double drift_glr[kMaxN] = {};
    int drift_dof[kMaxN] = {};
    double x[kMaxD] = {};  // A^{-1} b: the common (translation) component, unknown case
};

/// Group GLR and the per-feature fault-signature GLRs. `features` holds n pointers. With
/// signatures = false only glr and nu (and, for known translation, the per-feature GLRs, free
/// there) are computed: the detector's first pass.
bool group_stats(const FeatureReduced *const *features, int n, int d, bool translation_known,
                 bool signatures, GroupStats *out);

}  // namespace parity
}  // namespace sfd

#endif  // SFD_PARITY_SPACE_HPP
