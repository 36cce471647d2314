/* SPDX-License-Identifier: MIT */
#include "sfd_lcm_codec.h"

#include <math.h>
#include <string.h>

static int all_finite(const double *v, int n) {
    for (int i = 0; i < n; ++i) {
        if (!isfinite(v[i])) return 0;
    }
    return 1;
}

int sfd_lcm_decode_imu(const void *data, int size, sfd_imu_sample_t *out) {
    sfd_imu_t msg;
    if (data == NULL || size < 0 || out == NULL) return SFD_REJECT_DECODE;
    if (sfd_imu_t_decode(data, 0, size, &msg) < 0) return SFD_REJECT_DECODE;
    if (!all_finite(msg.gyro, 3) || !all_finite(msg.accel, 3)) return SFD_REJECT_NONFINITE;
    out->t_us = msg.utime;
    memcpy(out->gyro_rad_s, msg.gyro, sizeof out->gyro_rad_s);
    memcpy(out->accel_m_s2, msg.accel, sizeof out->accel_m_s2);
    return SFD_REJECT_NONE;
}

int sfd_lcm_decode_camera_info(const void *data, int size, sfd_camera_info_t *msg,
                               sfd_camera_t *camera, sfd_extrinsics_t *ext, int32_t *camera_id) {
    if (data == NULL || size < 0 || msg == NULL || camera == NULL || ext == NULL ||
        camera_id == NULL) {
        return SFD_REJECT_DECODE;
    }
    if (sfd_camera_info_t_decode(data, 0, size, msg) < 0) return SFD_REJECT_DECODE;
    sfd_camera_t cam;
    sfd_extrinsics_t e;
    /* the cause, in the order the camera model checks it (calibration_valid) */
    const double k[4] = {msg->fx, msg->fy, msg->cx, msg->cy};
    if (msg->width <= 0 || msg->height <= 0 || !all_finite(k, 4) || !(msg->fx > 0.0) ||
        !(msg->fy > 0.0)) {
        return SFD_REJECT_CALIB_INTRINSICS;
    }
    if (sfd_camera_init(&cam, msg->distortion_model, msg->width, msg->height, msg->fx, msg->fy,
                        msg->cx, msg->cy, msg->distortion) != SFD_OK) {
        return SFD_REJECT_CALIB_DISTORTION; /* unknown model or its coefficients */
    }
    if (sfd_extrinsics_from_matrix(&e, msg->T_imu_cam) != SFD_OK) {
        return SFD_REJECT_CALIB_EXTRINSICS;
    }
    *camera = cam;
    *ext = e;
    *camera_id = msg->camera_id;
    return SFD_REJECT_NONE;
}

int sfd_lcm_decode_features(const void *data, int size, sfd_feature_frame_t *msg,
                            sfd_frame_t *frame, int32_t *camera_id, int *depth_fixed) {
    if (data == NULL || size < 0 || msg == NULL || frame == NULL || camera_id == NULL ||
        depth_fixed == NULL) {
        return SFD_REJECT_DECODE;
    }
    if (sfd_feature_frame_t_decode(data, 0, size, msg) < 0) return SFD_REJECT_DECODE;
    if (msg->num_features < 0 || msg->num_features > SFD_FEATURE_FRAME_T_CAPACITY) {
        return SFD_REJECT_COUNT;
    }
    if (msg->num_features > SFD_MAX_FEATURES) return SFD_REJECT_CAPACITY;
    int fixed = 0;
    frame->utime = msg->utime;
    frame->num_features = msg->num_features;
    for (int i = 0; i < msg->num_features; ++i) {
        sfd_feature_t *f = &frame->features[i];
        f->track_id = msg->track_id[i];
        f->u_px = msg->u[i];
        f->v_px = msg->v[i];
        f->depth_m = msg->depth[i];
        f->depth_var_m2 = msg->depth_var[i];
        const int usable =
            isfinite(f->depth_m) && isfinite(f->depth_var_m2) && f->depth_var_m2 >= 0.0;
        if (!usable) {
            f->depth_m = 0.0; /* unknown: the configured default applies */
            f->depth_var_m2 = 0.0;
            ++fixed;
        }
    }
    *camera_id = msg->camera_id;
    *depth_fixed = fixed;
    return SFD_REJECT_NONE;
}

int sfd_lcm_decode_truth(const void *data, int size, sfd_truth_t *out, sfd_truth_v1_t *legacy) {
    if (data == NULL || size < 0 || out == NULL || legacy == NULL) return SFD_REJECT_DECODE;
    if (sfd_truth_t_decode(data, 0, size, out) != size) {
        if (sfd_truth_v1_t_decode(data, 0, size, legacy) != size) return SFD_REJECT_DECODE;
        if (legacy->num_features < 0 || legacy->num_features > SFD_TRUTH_V1_T_CAPACITY) {
            return SFD_REJECT_COUNT;
        }
        out->utime = legacy->utime;
        memcpy(out->position, legacy->position, sizeof out->position);
        memcpy(out->orientation, legacy->orientation, sizeof out->orientation);
        out->num_features = legacy->num_features;
        for (int i = 0; i < legacy->num_features; ++i) {
            out->track_id[i] = legacy->track_id[i];
            out->spurious[i] = legacy->spurious[i];
            out->kind[i] = (int8_t)(legacy->spurious[i] != 0 ? SFD_TRUTH_T_KIND_UNSPECIFIED
                                                             : SFD_TRUTH_T_KIND_CLEAN);
        }
    }
    if (out->num_features < 0 || out->num_features > SFD_TRUTH_T_CAPACITY) return SFD_REJECT_COUNT;
    if (!all_finite(out->position, 3) || !all_finite(out->orientation, 4)) {
        return SFD_REJECT_NONFINITE;
    }
    for (int i = 0; i < out->num_features; ++i) {
        const int8_t k = out->kind[i];
        if (k < SFD_TRUTH_T_KIND_CLEAN || k > SFD_TRUTH_T_KIND_UNSPECIFIED)
            return SFD_REJECT_DECODE;
        if ((k != SFD_TRUTH_T_KIND_CLEAN) != (out->spurious[i] != 0)) return SFD_REJECT_DECODE;
    }
    return SFD_REJECT_NONE;
}
