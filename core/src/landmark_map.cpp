// SPDX-License-Identifier: MIT
// Landmark map: fixed-capacity table of 3-D landmarks keyed by track id, initialized from a ray
// and a depth prior and refined by a gated, iterated 3x3 EKF update.
// Derivations: core/docs/landmark_map.md.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "bits_equal.h"
#include "core_private.hpp"
#include "ekf.hpp"
#include "rotation.hpp"
#include "small_linalg.hpp"
#include "sfd/sfd_landmarks.h"
#include "track_index.h"

namespace sfd {
namespace {

constexpr int32_t kCap = SFD_MAX_LANDMARKS;
constexpr int32_t kSlots = SFD_LANDMARK_INDEX_SLOTS;
constexpr double kRotTol = 1e-6;
constexpr double kMinDepth = 1e-6;  // m, as the EKF's "in front of the camera"
/// Most Gauss-Newton steps of one refinement (iterated EKF); 1 = the EKF step, relinearized.
constexpr int kRefineIterations = SFD_LANDMARK_REFINE_ITERATIONS;
/// The iterated update stops once a step is below 1e-6 of the prior's standard deviation in
/// every direction (squared Mahalanobis length 1e-12): what is left moves the landmark by far less
/// than its uncertainty, and the iterations that remain cost as much as the first.
constexpr double kConvergedStep2 = 1e-12;
/// Step halvings tried per Gauss-Newton step (smallest step 2^-(kHalvings-1) of the full one).
constexpr int kHalvings = 12;

using Mat36 = Eigen::Matrix<double, 3, 6, Eigen::RowMajor>;
using Mat23 = Eigen::Matrix<double, 2, 3, Eigen::RowMajor>;
using Mat32 = Eigen::Matrix<double, 3, 2, Eigen::RowMajor>;

static_assert(kSlots >= 2 * kCap, "the index must keep its load factor <= 1/2");

/// Home slot of a track id (track_index.h).
int32_t home_slot(int64_t track_id) {
    return sfd_track_index_home(track_id, kSlots);
}

int32_t next_slot(int32_t s) {
    return sfd_track_index_next(s, kSlots);
}

bool entry_in_range(int32_t e) {
    return e >= 0 && e < kCap;
}

/// Linear probe for @p track_id. Returns the entry index (or -1) and, in @p slot_out, the slot
/// where it was found or the first empty slot of its cluster (-1 if the probe ran through the
/// whole index, which a map with load factor <= 1/2 cannot do). A slot holding an index out of
/// range (a corrupted caller-owned struct) ends the probe as if empty: nothing is ever read or
/// written outside the arrays. At most count + 1 probes.
int32_t probe(const sfd_landmark_map_t &map, int64_t track_id, int32_t *slot_out) {
    const sfd_track_index_t t = sfd_track_index_view_i32(
        map.index, kSlots, &map.entries[0].track_id, sizeof map.entries[0], kCap);
    return sfd_track_index_probe(&t, track_id, slot_out);
}

/// Deletes index slot @p s by backward shifting (Knuth 6.4 Algorithm R): later members of the
/// cluster move up unless their home lies cyclically in (gap, j], so no tombstones accumulate
/// and probe lengths stay those of a table that never saw the removed keys.
void index_delete(sfd_landmark_map_t *map, int32_t s) {
    int32_t gap = s;
    int32_t j = s;
    for (int32_t n = 0; n < kSlots; ++n) {
        j = next_slot(j);
        const int32_t e = map->index[j];
        if (!entry_in_range(e)) break;
        const int32_t k = home_slot(map->entries[e].track_id);
        const bool stays = (gap <= j) ? (gap < k && k <= j) : (gap < k || k <= j);
        if (stays) continue;
        map->index[gap] = e;
        gap = j;
    }
    map->index[gap] = -1;
}

/// Removes entry @p e (in use) found at index slot @p s: repairs the index, clears the entry
/// (all bytes: determinism of the whole struct) and returns it to the free stack.
void remove_entry(sfd_landmark_map_t *map, int32_t e, int32_t s) {
    index_delete(map, s);
    std::memset(&map->entries[e], 0, sizeof(map->entries[e]));
    if (map->num_free >= 0 && map->num_free < kCap) {
        map->free_list[map->num_free] = e;
        map->num_free += 1;
    }
    map->count -= 1;
}

/// Least recently seen landmark last seen strictly before @p utime and not kept for the current
/// frame (sfd_landmark_keep_in_frame; ties: lowest index), or -1.
int32_t lru_victim(const sfd_landmark_map_t &map, int64_t utime) {
    int32_t victim = -1;
    for (int32_t e = 0; e < kCap; ++e) {
        const sfd_landmark_t &l = map.entries[e];
        if (l.used == 0U || l.last_seen_utime >= utime) continue;
        if (map.frame_stamp != 0U && l.frame_stamp == map.frame_stamp) continue;
        if (victim < 0 || l.last_seen_utime < map.entries[victim].last_seen_utime) victim = e;
    }
    return victim;
}

/// True for a finite 6x6 pose covariance with a non-negative diagonal (NULL is valid: exact).
bool pose_cov_valid(const double *c) {
    if (c == nullptr) return true;
    if (!all_finite(c, 36)) return false;
    for (int i = 0; i < 36; i += 7) {  // the diagonal
        if (c[i] < 0.0) return false;
    }
    return true;
}

/// The symmetric part of a 6x6 row-major covariance.
Mat6 load_pose_cov(const double *c) {
    const Eigen::Map<const Mat6> C(c);
    return 0.5 * (C + C.transpose());
}

bool rotation_arg(const double *R9, Mat3 *R) {
    if (!all_finite(R9, 9)) return false;
    *R = Eigen::Map<const Mat3>(R9);
    return is_rotation(*R, kRotTol);
}

/// The camera pose arguments of init_from_ray and refine checked (a rotation, a finite position,
/// a finite covariance with a non-negative diagonal, or none) and loaded: R, and the symmetric
/// part of the covariance (zero without one). A frame's landmarks share one pose, so the last
/// pose that passed is kept in the map with its bits: the same bits again skip the checks, with
/// the result checking again would give. A pose that fails is never kept.
bool pose_args(sfd_landmark_map_t *map, const double *R9, const double *p3, const double *cov36,
               Mat3 *R, Mat6 *Cpose) {
    const int32_t state = (cov36 != nullptr) ? 2 : 1;
    double *key = map->pose_key_;
    if (map->pose_key_state_ == state && sfd_bits_equal(key, R9, 9) &&
        sfd_bits_equal(key + 9, p3, 3) &&
        (cov36 == nullptr || sfd_bits_equal(key + 12, cov36, 36))) {
        *R = Eigen::Map<const Mat3>(R9);
        *Cpose = Eigen::Map<const Mat6>(map->pose_cov_sym_);
        return true;
    }
    if (!rotation_arg(R9, R) || !all_finite(p3, 3) || !pose_cov_valid(cov36)) return false;
    *Cpose = (cov36 != nullptr) ? load_pose_cov(cov36) : Mat6::Zero();
    std::memcpy(key, R9, 9 * sizeof(double));
    std::memcpy(key + 9, p3, 3 * sizeof(double));
    if (cov36 != nullptr) std::memcpy(key + 12, cov36, 36 * sizeof(double));
    Eigen::Map<Mat6>(map->pose_cov_sym_) = *Cpose;
    map->pose_key_state_ = state;
    return true;
}

/// Symmetrized copy.
Mat3 sym(const Mat3 &P) {
    return 0.5 * (P + P.transpose());
}

/// Measurement model of a landmark seen from a known camera, linearized at p:
/// c = R^T (p - p_C), h = (c_x / c_z, c_y / c_z), H = J_pi R^T, and the noise
/// R_n = s^2 I + H_pose C_pose H_pose^T with H_pose = J_pi [ -R^T | [c]x ].
struct Linear {
    Vec2 h;
    Mat23 H;
    Mat2 Rn;
    Mat2 S;
};

/// False when p is not in front of the camera (depth <= kMinDepth) or a value is not finite.
bool linearize(const Mat3 &R, const Vec3 &pC, const Vec3 &p, const Mat6 &Cpose, bool with_pose,
               double s2, Linear *out) {
    const Vec3 c = R.transpose() * (p - pC);
    if (!(c.z() > kMinDepth) || !all_finite(c.data(), 3)) return false;
    const double iz = 1.0 / c.z();
    Mat23 Jpi;
    Jpi << iz, 0.0, -c.x() * iz * iz, 0.0, iz, -c.y() * iz * iz;
    out->h = Vec2(c.x() * iz, c.y() * iz);
    out->H = Jpi * R.transpose();
    out->Rn = Mat2::Identity() * s2;
    if (with_pose) {
        // dc/d(dp) = -R^T; dc/d(dtheta) = [c]x (R = R^ Exp(dtheta): c = Exp(-dtheta) c^).
        Mat26 Hp;
        Hp.block<2, 3>(0, 0) = -out->H;
        Hp.block<2, 3>(0, 3) = Jpi * skew(c);
        out->Rn.noalias() += Hp * Cpose * Hp.transpose();
        out->Rn = 0.5 * (out->Rn + out->Rn.transpose());
    }
    return all_finite(out->h.data(), 2) && all_finite(out->H.data(), 6) &&
           all_finite(out->Rn.data(), 4);
}

/// S = H P H^T + R_n, its inverse and P H^T; false when S is not positive definite.
bool innovation(const Mat3 &P, const Linear &lin, Mat32 *PHt, Mat2 *Sinv, Mat2 *S) {
    *PHt = P * lin.H.transpose();
    Mat2 s = lin.H * (*PHt) + lin.Rn;
    s = 0.5 * (s + s.transpose());
    const double det = la::det_2x2(s(0, 0), s(0, 1), s(1, 0), s(1, 1));
    if (!(s(0, 0) > 0.0) || !(det > 0.0) || !std::isfinite(det)) return false;
    *Sinv = la::inverse_2x2(s(0, 0), s(0, 1), s(1, 0), s(1, 1), det);
    *S = s;
    return all_finite(Sinv->data(), 4);
}

/// J(x) = (x - x0)^T P^-1 (x - x0) + (z - h(x))^T R_n^-1 (z - h(x)), with P = L L^T; the
/// measurement part at the linearization @p lin of x (its h and R_n). Infinite when R_n is not
/// positive definite.
/// Squared length of @p v in the metric of the prior covariance P = L L^T: |L^-1 v|^2.
double prior_mahalanobis2(const double (*L)[3], const Vec3 &v) {
    const double d[3] = {v(0), v(1), v(2)};
    double w[3] = {0.0, 0.0, 0.0};
    la::forward_solve<3>(L, 3, d, w);
    return w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
}

double map_cost(const double (*L)[3], const Vec3 &x0, const Vec3 &x, const Vec2 &z,
                const Linear &lin) {
    const double d[3] = {x(0) - x0(0), x(1) - x0(1), x(2) - x0(2)};
    double w[3] = {0.0, 0.0, 0.0};
    la::forward_solve<3>(L, 3, d, w);
    const Vec2 r = z - lin.h;
    const Mat2 &N = lin.Rn;
    double q = 0.0;
    if (!la::inv_quadratic_2x2(N(0, 0), N(0, 1), N(1, 0), N(1, 1), r(0), r(1), &q)) {
        return std::numeric_limits<double>::infinity();
    }
    return w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + q;
}

// The entry of a track: its own, or a free one (the least recently seen landmark before utime
// evicted when the map is full). SFD_ERR_CAPACITY when nothing may be evicted.
sfd_status_t acquire_entry(sfd_landmark_map_t *map, int64_t track_id, int64_t utime, int32_t *out) {
    int32_t slot = -1;
    int32_t e = probe(*map, track_id, &slot);
    if (e < 0) {
        if (map->count >= kCap || map->num_free <= 0) {
            const int32_t victim = lru_victim(*map, utime);
            if (victim < 0) return SFD_ERR_CAPACITY;
            int32_t vslot = -1;
            if (probe(*map, map->entries[victim].track_id, &vslot) != victim) {
                return SFD_ERR_STATE;  // index and entries disagree: a corrupted map
            }
            remove_entry(map, victim, vslot);
            map->evictions += 1U;
            // The removal may have shifted this id's cluster: probe again for the empty slot.
            (void)probe(*map, track_id, &slot);
        }
        if (slot < 0 || map->num_free <= 0 || map->num_free > kCap) return SFD_ERR_STATE;
        map->num_free -= 1;
        e = map->free_list[map->num_free];
        if (!entry_in_range(e) || map->entries[e].used != 0U) return SFD_ERR_STATE;
        map->index[slot] = e;
        map->count += 1;
    }
    *out = e;
    return SFD_OK;
}

// A track's new landmark (its entry from acquire_entry): position, covariance (row-major), one
// observation, seen at utime; `fixed` for a known point (sfd_landmark_set).
sfd_status_t store_landmark(sfd_landmark_map_t *map, int64_t track_id, const double p[3],
                            const double cov_m2[9], int64_t utime, uint8_t fixed,
                            int32_t *index_out) {
    int32_t e = -1;
    const sfd_status_t ae = acquire_entry(map, track_id, utime, &e);
    if (ae != SFD_OK) return ae;
    sfd_landmark_t &l = map->entries[e];
    std::memset(&l, 0, sizeof(l));
    l.track_id = track_id;
    for (int k = 0; k < 3; ++k) l.p_W_m[k] = p[k];
    std::memcpy(l.cov_m2, cov_m2, sizeof(l.cov_m2));
    l.last_seen_utime = utime;
    l.observations = 1;
    l.used = 1U;
    l.fixed = fixed;
    if (index_out != nullptr) *index_out = e;
    return SFD_OK;
}

bool usable_entry(const sfd_landmark_map_t &map, int32_t index) {
    return entry_in_range(index) && map.entries[index].used == 1U;
}

}  // namespace
}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_landmark_map_init(sfd_landmark_map_t *map) {
    if (map == nullptr) return SFD_ERR_INVAL;
    std::memset(map, 0, sizeof(*map));
    for (int32_t s = 0; s < kSlots; ++s) map->index[s] = -1;
    // Popped from the top: entries are handed out 0, 1, 2, ... (deterministic, cache friendly).
    for (int32_t k = 0; k < kCap; ++k) map->free_list[k] = kCap - 1 - k;
    map->num_free = kCap;
    map->initialized = 1;
    return SFD_OK;
}

extern "C" int32_t sfd_landmark_find(const sfd_landmark_map_t *map, int64_t track_id) {
    if (map == nullptr || map->initialized != 1) return -1;
    int32_t slot = -1;
    return probe(*map, track_id, &slot);
}

extern "C" sfd_status_t sfd_landmark_init_from_ray(sfd_landmark_map_t *map, int64_t track_id,
                                                   const double R_CtoW[9], const double p_CinW_m[3],
                                                   const double cov_pose6[36], const double xn[2],
                                                   double depth_m, double depth_var_m2,
                                                   double sigma_xn, int64_t utime,
                                                   int32_t *index_out) {
    if (map == nullptr || R_CtoW == nullptr || p_CinW_m == nullptr || xn == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (map->initialized != 1) return SFD_ERR_STATE;
    Mat3 R;
    Mat6 Cp;
    if (!all_finite(xn, 2) || !pose_args(map, R_CtoW, p_CinW_m, cov_pose6, &R, &Cp)) {
        return SFD_ERR_INVAL;
    }
    if (!std::isfinite(depth_m) || !(depth_m > 0.0) || !std::isfinite(depth_var_m2) ||
        !(depth_var_m2 >= 0.0) || !std::isfinite(sigma_xn) || !(sigma_xn >= 0.0)) {
        return SFD_ERR_INVAL;
    }

    // p_W = p_C + d R r with r = (xn, yn, 1): d is the depth along the optical axis.
    const Vec3 r(xn[0], xn[1], 1.0);
    const Vec3 Rr = R * r;
    const Vec3 p = Vec3(p_CinW_m[0], p_CinW_m[1], p_CinW_m[2]) + depth_m * Rr;
    // Depth along the ray: dp/dd = R r. Bearing noise on the image axes: dp/dxn = d R [e1 e2].
    // The depth error multiplies the bearing and rotation errors; for independent errors the
    // exact second moment of such a product uses E[d^2] = d^2 + sd2 where the first-order
    // Jacobian has d^2. The difference matters for an unknown depth (sd ~ d): it widens the
    // bearing "cylinder" to cover landmarks farther than the prior depth.
    const double Ed2 = depth_m * depth_m + depth_var_m2;
    Mat3 C = depth_var_m2 * (Rr * Rr.transpose());
    const double s2 = Ed2 * sigma_xn * sigma_xn;
    C.noalias() += s2 * (R.col(0) * R.col(0).transpose() + R.col(1) * R.col(1).transpose());
    if (cov_pose6 != nullptr) {
        // p_W = p_C + dp + d R Exp(dtheta) r ~ p_W + dp - d R [r]x dtheta: first order J C J^T,
        // plus sd2 (R [r]x) C_theta (R [r]x)^T for the depth-rotation product (as above).
        const Mat3 Rrx = R * skew(r);
        Mat36 J;
        J.block<3, 3>(0, 0) = Mat3::Identity();
        J.block<3, 3>(0, 3) = -depth_m * Rrx;
        C.noalias() += J * Cp * J.transpose();
        C.noalias() += depth_var_m2 * (Rrx * Cp.block<3, 3>(3, 3) * Rrx.transpose());
    }
    C = sym(C);
    if (!all_finite(p.data(), 3) || !all_finite(C.data(), 9)) return SFD_ERR_NUMERIC;

    double Cr[9];  // row-major, as the entry stores it
    Eigen::Map<Mat3> Cm(Cr);
    Cm = C;
    return store_landmark(map, track_id, p.data(), Cr, utime, 0U, index_out);
}

extern "C" sfd_status_t sfd_landmark_set(sfd_landmark_map_t *map, int64_t track_id,
                                         const double p_W_m[3], const double cov_m2[9],
                                         int64_t utime, int32_t *index_out) {
    if (map == nullptr || p_W_m == nullptr || cov_m2 == nullptr) return SFD_ERR_INVAL;
    if (map->initialized == 0) return SFD_ERR_STATE;
    if (!all_finite(p_W_m, 3) || !all_finite(cov_m2, 9)) return SFD_ERR_INVAL;
    // symmetric within rounding, then positive definite by its leading minors (Sylvester): a
    // known point still has some uncertainty
    double C[9];
    double scale = 0.0;
    for (int k = 0; k < 9; ++k) scale = std::max(scale, std::fabs(cov_m2[k]));
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            const double a = cov_m2[3 * r + c], b = cov_m2[3 * c + r];
            if (std::fabs(a - b) > 1e-12 * (1.0 + scale)) return SFD_ERR_INVAL;
            C[3 * r + c] = 0.5 * (a + b);
        }
    }
    const double m1 = C[0], m2 = C[0] * C[4] - C[1] * C[3];
    const double m3 = C[0] * (C[4] * C[8] - C[5] * C[7]) - C[1] * (C[3] * C[8] - C[5] * C[6]) +
                      C[2] * (C[3] * C[7] - C[4] * C[6]);
    if (!(m1 > 0.0 && m2 > 0.0 && m3 > 0.0)) return SFD_ERR_INVAL;
    return store_landmark(map, track_id, p_W_m, C, utime, 1U, index_out);
}

extern "C" sfd_status_t sfd_landmark_refine(sfd_landmark_map_t *map, int32_t index,
                                            const double R_CtoW[9], const double p_CinW_m[3],
                                            const double cov_pose6[36], const double xn[2],
                                            double sigma_xn, double alpha, int64_t utime,
                                            sfd_landmark_update_t *info) {
    if (map == nullptr || R_CtoW == nullptr || p_CinW_m == nullptr || xn == nullptr ||
        info == nullptr) {
        return SFD_ERR_INVAL;
    }
    *info = sfd_landmark_update_t{};
    if (map->initialized != 1) return SFD_ERR_STATE;
    Mat3 R;
    Mat6 Cpose;
    if (!usable_entry(*map, index) || !all_finite(xn, 2) ||
        !pose_args(map, R_CtoW, p_CinW_m, cov_pose6, &R, &Cpose)) {
        return SFD_ERR_INVAL;
    }
    if (!std::isfinite(sigma_xn) || !(sigma_xn > 0.0) || !std::isfinite(alpha) || !(alpha > 0.0) ||
        !(alpha < 1.0)) {
        return SFD_ERR_INVAL;
    }
    sfd_landmark_t &l = map->entries[index];
    if (utime < l.last_seen_utime) return SFD_ERR_ORDER;
    const Vec3 p0(l.p_W_m[0], l.p_W_m[1], l.p_W_m[2]);
    const Mat3 P = sym(Eigen::Map<const Mat3>(l.cov_m2));
    if (!all_finite(p0.data(), 3) || !all_finite(P.data(), 9)) return SFD_ERR_NUMERIC;

    const Vec3 pC(p_CinW_m[0], p_CinW_m[1], p_CinW_m[2]);
    const Vec2 z(xn[0], xn[1]);
    const double s2 = sigma_xn * sigma_xn;

    // Innovation at the prior (reported; the plain EKF's gate statistic).
    Linear lin;
    if (!linearize(R, pC, p0, Cpose, cov_pose6 != nullptr, s2, &lin)) return SFD_ERR_DOMAIN;
    const Vec2 nu = z - lin.h;
    Mat2 Sinv;
    Mat32 PHt;
    if (!innovation(P, lin, &PHt, &Sinv, &lin.S)) return SFD_ERR_NUMERIC;
    info->innovation[0] = nu(0);
    info->innovation[1] = nu(1);
    for (int k = 0; k < 4; ++k) info->innovation_cov[k] = lin.S(k / 2, k % 2);
    info->nis_prior = nu.dot(Sinv * nu);
    // chi2(2) is exponential with mean 2: P(X > x) = exp(-x / 2), so the quantile is -2 ln(alpha).
    info->gate = -2.0 * std::log(alpha);
    if (!std::isfinite(info->nis_prior)) return SFD_ERR_NUMERIC;

    // Iterated EKF with a step-size control (Gauss-Newton on the MAP cost with backtracking,
    // Skoglund, Hendeby & Axehill 2015): at iterate x_i the IEKF step (Bell & Cathey 1993) aims at
    // x0 + K_i (z - h(x_i) - H_i (x0 - x_i)); the step is halved until the point is in front of
    // the camera and the cost
    //   J(x) = (x - x0)^T P^-1 (x - x0) + (z - h(x))^T R_n^-1 (z - h(x))
    // does not increase. The first full step is the plain EKF update. Why: with an unknown depth
    // (10 m +- 10 m) a linear step can overshoot through the camera; a halved one lands near the
    // true depth. Bounded: kRefineIterations steps of at most kHalvings halvings each; the
    // covariance uses the gain and Jacobian at the final iterate.
    double L[3][3];
    double Pa[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) Pa[i][j] = P(i, j);
    }
    const bool have_cost = la::cholesky<3>(Pa, 3, L);  // false for a singular P: front test only
    Vec3 x = p0;
    Linear at = lin;
    Mat32 K = PHt * Sinv;
    for (int it = 0; it < kRefineIterations; ++it) {
        const Vec3 target = p0 + K * (z - at.h - at.H * (p0 - x));
        const Vec3 step = target - x;
        if (!all_finite(step.data(), 3) || step.norm() <= 1e-12 * (x - pC).norm()) break;
        if (have_cost && prior_mahalanobis2(L, step) <= kConvergedStep2) break;
        const double J0 = have_cost ? map_cost(L, p0, x, z, at) : 0.0;
        double lambda = 1.0;
        bool accepted = false;
        Linear cand;
        Vec3 xc = x;
        for (int h = 0; h < kHalvings && !accepted; ++h) {
            xc = x + lambda * step;
            lambda *= 0.5;
            if (!linearize(R, pC, xc, Cpose, cov_pose6 != nullptr, s2, &cand)) continue;
            // The cost at the candidate is evaluated with the current iterate's R_n so that both
            // sides of the comparison use the same weights.
            Linear w = cand;
            w.Rn = at.Rn;
            accepted = !have_cost || map_cost(L, p0, xc, z, w) <= J0;
        }
        Mat32 PHtc;
        Mat2 Sinvc;
        if (!accepted || !innovation(P, cand, &PHtc, &Sinvc, &cand.S)) break;
        x = xc;
        at = cand;
        K = PHtc * Sinvc;
    }
    // Gate. Two statistics, each chi2(2) for a linear model: the prior's NIS and the NIS of the
    // measurement linearized at the refined estimate, nu* = z - h(x*) - H* (x0 - x*),
    // S* = H* P H*^T + R_n* (at the iterated EKF's fixed point nu*^T S*^-1 nu* is the minimum of
    // the MAP cost J). The observation is rejected when both exceed the gate. Why both: with an
    // unknown depth each can be inflated by linearization alone. The prior's cannot explain the
    // parallax of a landmark much nearer than the prior depth (2 m under 10 m +- 10 m: every
    // later observation would be gated out and the landmark never refined); the refined one
    // inherits the over-confidence of a landmark far beyond its prior depth (25 m: 60 of 9500
    // observations gated out instead of 13). A spurious observation of a converged landmark,
    // where the model is nearly linear, fails both (core/docs/landmark_map.md).
    const Vec3 p1 = x;
    {
        Mat32 PHt1;
        Mat2 Sinv1;
        Mat2 S1;
        if (!innovation(P, at, &PHt1, &Sinv1, &S1)) return SFD_ERR_NUMERIC;
        const Vec2 nu1 = z - at.h - at.H * (p0 - p1);
        info->nis = nu1.dot(Sinv1 * nu1);
    }
    if (!std::isfinite(info->nis)) return SFD_ERR_NUMERIC;
    if (info->nis > info->gate && info->nis_prior > info->gate) {
        info->rejected = 1U;
        l.rejections += 1;
        return SFD_OK;
    }
    const Mat3 IKH = Mat3::Identity() - K * at.H;
    const Mat3 P1 = sym(IKH * P * IKH.transpose() + K * at.Rn * K.transpose());
    if (!all_finite(p1.data(), 3) || !all_finite(P1.data(), 9) || !(P1(0, 0) >= 0.0) ||
        !(P1(1, 1) >= 0.0) || !(P1(2, 2) >= 0.0)) {
        *info = sfd_landmark_update_t{};
        return SFD_ERR_NUMERIC;
    }
    for (int k = 0; k < 3; ++k) l.p_W_m[k] = p1(k);
    Eigen::Map<Mat3> Pm(l.cov_m2);
    Pm = P1;
    l.observations += 1;
    l.last_seen_utime = utime;
    info->fused = 1U;
    return SFD_OK;
}

extern "C" int32_t sfd_landmark_remove(sfd_landmark_map_t *map, int64_t track_id) {
    if (map == nullptr) return SFD_ERR_INVAL;
    if (map->initialized != 1) return SFD_ERR_STATE;
    int32_t slot = -1;
    const int32_t e = probe(*map, track_id, &slot);
    if (e < 0) return 0;
    remove_entry(map, e, slot);
    return 1;
}

extern "C" sfd_status_t sfd_landmark_begin_frame(sfd_landmark_map_t *map) {
    if (map == nullptr) return SFD_ERR_INVAL;
    if (map->initialized != 1) return SFD_ERR_STATE;
    // 0 means "never": after 2^32 - 1 frames the stamp skips it (an entry stamped 2^32 frames
    // ago would look current for one frame: harmless, it only spares an eviction).
    map->frame_stamp = (map->frame_stamp == UINT32_MAX) ? 1U : map->frame_stamp + 1U;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_landmark_keep_in_frame(sfd_landmark_map_t *map, int32_t index) {
    if (map == nullptr) return SFD_ERR_INVAL;
    if (map->initialized != 1) return SFD_ERR_STATE;
    if (!entry_in_range(index) || map->entries[index].used == 0U) return SFD_ERR_INVAL;
    map->entries[index].frame_stamp = map->frame_stamp;
    return SFD_OK;
}

extern "C" int32_t sfd_landmark_evict_older_than(sfd_landmark_map_t *map, int64_t utime) {
    if (map == nullptr) return SFD_ERR_INVAL;
    if (map->initialized != 1) return SFD_ERR_STATE;
    int32_t removed = 0;
    for (int32_t e = 0; e < kCap; ++e) {
        const sfd_landmark_t &l = map->entries[e];
        if (l.used == 0U || l.last_seen_utime >= utime) continue;
        int32_t slot = -1;
        if (probe(*map, l.track_id, &slot) != e) continue;  // not indexed: leave it alone
        remove_entry(map, e, slot);
        removed += 1;
    }
    return removed;
}

extern "C" sfd_status_t sfd_landmark_to_obs(const sfd_landmark_map_t *map, int32_t index,
                                            const double uv_px[2], sfd_ekf_obs_t *obs) {
    if (map == nullptr || uv_px == nullptr || obs == nullptr) return SFD_ERR_INVAL;
    if (map->initialized != 1 || !usable_entry(*map, index)) return SFD_ERR_INVAL;
    const sfd_landmark_t &l = map->entries[index];
    obs->uv_px[0] = uv_px[0];
    obs->uv_px[1] = uv_px[1];
    for (int k = 0; k < 3; ++k) obs->landmark_W_m[k] = l.p_W_m[k];
    for (int k = 0; k < 9; ++k) obs->landmark_cov_m2[k] = l.cov_m2[k];
    return SFD_OK;
}

extern "C" sfd_status_t sfd_landmark_camera_pose_cov(const sfd_ekf_t *ekf,
                                                     const sfd_extrinsics_t *ext,
                                                     double cov_pose6[36]) {
    if (ekf == nullptr || ext == nullptr || cov_pose6 == nullptr) return SFD_ERR_INVAL;
    if (ekf->initialized != 1) return SFD_ERR_STATE;
    const Mat3 R_ItoW = ekf_rotation(*ekf);
    const Eigen::Map<const Mat3> R_CtoI(ext->R_CtoI);
    Mat6 T = Mat6::Zero();
    T.block<3, 3>(0, 0) = Mat3::Identity();
    T.block<3, 3>(0, 3) = -R_ItoW * skew(Vec3(ext->p_CinI[0], ext->p_CinI[1], ext->p_CinI[2]));
    T.block<3, 3>(3, 3) = R_CtoI.transpose();
    const Mat6 C = T * pose_covariance(*ekf) * T.transpose();
    Eigen::Map<Mat6> out(cov_pose6);
    out = 0.5 * (C + C.transpose());
    return SFD_OK;
}
