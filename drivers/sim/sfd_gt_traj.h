/* SPDX-License-Identifier: MIT */
/* Ground-truth trajectory helpers of the semi-real feed (header-only C, heap-free): interpolation
 * of a recorded body (IMU) pose between two ground-truth samples, the camera pose from the body
 * pose and the camera-IMU extrinsics (EuRoC's T_BS), the raw (distorted) pixel of a world point,
 * and the first hit of a ray on the inside of an axis-aligned room.
 *
 * Conventions (core/include/sfd/sfd_rotation.h, sfd_camera.h): R_AtoB maps coordinates in A to B;
 * quaternions are Hamilton (w, x, y, z); q_ItoW is the IMU orientation in the world, as EuRoC's
 * q_RS (S = IMU, R = world) and TRUTH's orientation; the camera frame has z forward, x right, y
 * down; pixels are raw (distorted) with OpenCV's pixel-centre convention.
 * Used by sfd-sim euroc-semireal (apps/sim/euroc_semireal.cpp) and unit.gt_traj. */
#ifndef SFD_GT_TRAJ_H
#define SFD_GT_TRAJ_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include <sfd/sfd_camera.h>
#include <sfd/sfd_rotation.h>

/** One ground-truth state: time (ns), IMU position in the world (m), orientation q_ItoW. */
typedef struct {
    int64_t t_ns;
    double p_IinW_m[3];
    double q_ItoW[4];
} sfd_gt_pose_t;

/* Interpolates the pose at t_ns, a->t_ns <= t_ns <= b->t_ns, a->t_ns < b->t_ns:
 *   s = (t - t_a) / (t_b - t_a),
 *   p(t) = (1 - s) p_a + s p_b                                   (linear),
 *   q(t) = q_a (q_a^-1 q_b)^s = q_a Exp(s Log(q_a^-1 q_b))       (slerp, shortest arc: q_b is
 *          negated when q_a . q_b < 0, since q and -q are the same rotation).
 * Linear position is enough for EuRoC's 200 Hz (here 40 Hz) ground truth: the error is bounded
 * by |a| dt^2 / 8 = 0.08 mm for 1 m/s^2 over 25 ms.
 * Returns 0 on success; -1 for t outside [t_a, t_b], non-increasing times, or a quaternion the
 * core's functions refuse (zero norm, non-finite). */
static inline int sfd_gt_interpolate(const sfd_gt_pose_t *a, const sfd_gt_pose_t *b, int64_t t_ns,
                                     sfd_gt_pose_t *out) {
    if (!(a->t_ns < b->t_ns) || t_ns < a->t_ns || t_ns > b->t_ns) return -1;
    const double s = (double)(t_ns - a->t_ns) / (double)(b->t_ns - a->t_ns);
    double qa[4], qb[4], qa_inv[4], dq[4], phi[3], qs[4], q[4];
    memcpy(qa, a->q_ItoW, sizeof qa);
    memcpy(qb, b->q_ItoW, sizeof qb);
    if (sfd_quat_normalize(qa) != SFD_OK || sfd_quat_normalize(qb) != SFD_OK) return -1;
    qa_inv[0] = qa[0];
    for (int k = 1; k < 4; ++k) qa_inv[k] = -qa[k];
    if (sfd_quat_multiply(qa_inv, qb, dq) != SFD_OK || sfd_quat_normalize(dq) != SFD_OK ||
        sfd_quat_to_rotvec(dq, phi) != SFD_OK) {
        return -1;
    }
    /* sfd_quat_normalize fixes w >= 0, so |phi| <= pi: the shortest arc. */
    for (int k = 0; k < 3; ++k) phi[k] *= s;
    if (sfd_quat_from_rotvec(phi, qs) != SFD_OK || sfd_quat_multiply(qa, qs, q) != SFD_OK ||
        sfd_quat_normalize(q) != SFD_OK) {
        return -1;
    }
    out->t_ns = t_ns;
    for (int k = 0; k < 3; ++k) out->p_IinW_m[k] = (1.0 - s) * a->p_IinW_m[k] + s * b->p_IinW_m[k];
    memcpy(out->q_ItoW, q, sizeof q);
    return 0;
}

/* Camera pose in the world from the IMU pose and the extrinsics (camera pose in the IMU frame):
 *   R_CtoW = R_ItoW R_CtoI,   p_CinW = p_IinW + R_ItoW p_CinI.
 * Returns 0, or -1 for a quaternion that is not unit. */
static inline int sfd_gt_camera_pose(const sfd_gt_pose_t *I, const sfd_extrinsics_t *ext,
                                     double R_CtoW[9], double p_CinW_m[3]) {
    double R_ItoW[9];
    if (sfd_quat_to_rotmat(I->q_ItoW, R_ItoW) != SFD_OK) return -1;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double acc = 0.0;
            for (int k = 0; k < 3; ++k) acc += R_ItoW[3 * r + k] * ext->R_CtoI[3 * k + c];
            R_CtoW[3 * r + c] = acc;
        }
        p_CinW_m[r] = I->p_IinW_m[r];
        for (int k = 0; k < 3; ++k) p_CinW_m[r] += R_ItoW[3 * r + k] * ext->p_CinI[k];
    }
    return 0;
}

/* Raw pixel of the world point p_W seen by the camera (R_CtoW, p_CinW):
 *   p_C = R_CtoW^T (p_W - p_CinW), uv = K d(p_C.xy / p_C.z) (sfd_camera_project, distortion
 *   included). *depth_m = p_C.z. Returns 1 when the point is in front of the camera (z >= 0.1 m)
 *   and projects inside the image [0, width) x [0, height), else 0 (uv then undefined). */
static inline int sfd_gt_project(const sfd_camera_t *cam, const double R_CtoW[9],
                                 const double p_CinW_m[3], const double p_W_m[3], double uv_px[2],
                                 double *depth_m) {
    double c[3];
    for (int r = 0; r < 3; ++r) {
        c[r] = 0.0;
        for (int k = 0; k < 3; ++k) c[r] += R_CtoW[3 * k + r] * (p_W_m[k] - p_CinW_m[k]);
    }
    *depth_m = c[2];
    if (!(c[2] >= 0.1)) return 0;
    if (sfd_camera_project(cam, c, uv_px, NULL) != SFD_OK) return 0;
    return uv_px[0] >= 0.0 && uv_px[0] < (double)cam->width_px && uv_px[1] >= 0.0 &&
           uv_px[1] < (double)cam->height_px;
}

/* First point where the ray o + s d (s > 0) leaves the axis-aligned box [lo, hi] (its walls,
 * floor and ceiling seen from inside): s = min over the axes with d_k != 0 of the distance to the
 * wall the ray heads for. The origin must be strictly inside. Returns 0 and the hit, or -1. */
static inline int sfd_gt_room_hit(const double lo[3], const double hi[3], const double o[3],
                                  const double d[3], double hit[3]) {
    double s_min = INFINITY;
    for (int k = 0; k < 3; ++k) {
        if (!(o[k] > lo[k] && o[k] < hi[k])) return -1;
        if (d[k] > 1e-12) {
            const double s = (hi[k] - o[k]) / d[k];
            if (s < s_min) s_min = s;
        } else if (d[k] < -1e-12) {
            const double s = (lo[k] - o[k]) / d[k];
            if (s < s_min) s_min = s;
        }
    }
    if (!(s_min > 0.0 && isfinite(s_min))) return -1;
    for (int k = 0; k < 3; ++k) hit[k] = o[k] + s_min * d[k];
    return 0;
}

#endif /* SFD_GT_TRAJ_H */
