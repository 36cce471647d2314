/* SPDX-License-Identifier: MIT */
/* EuRoC MAV cam0 calibration (sensor.yaml of the dataset): shared by the tests. */
#ifndef SFD_EUROC_CALIB_H
#define SFD_EUROC_CALIB_H

/* T_BS: cam0 pose in the body (IMU) frame, row-major 4x4. */
static const double kEurocTimuCam[16] = {0.0148655429818,
                                         -0.999880929698,
                                         0.00414029679422,
                                         -0.0216401454975,
                                         0.999557249008,
                                         0.0149672133247,
                                         0.025715529948,
                                         -0.064676986768,
                                         -0.0257744366974,
                                         0.00375618835797,
                                         0.999660727178,
                                         0.00981073058949,
                                         0.0,
                                         0.0,
                                         0.0,
                                         1.0};

/* Intrinsics (px) and radial-tangential distortion k1 k2 p1 p2, 752 x 480. */
static const double kEurocFx = 458.654, kEurocFy = 457.296, kEurocCx = 367.215, kEurocCy = 248.375;
static const double kEurocRadtan[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};

#endif /* SFD_EUROC_CALIB_H */
