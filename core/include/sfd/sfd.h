/* SPDX-License-Identifier: MIT */
/**
 * @file sfd.h
 * @brief Umbrella header of the sfd core C API.
 *
 * Threading: every object is caller-owned; functions are reentrant on distinct objects and not
 * on the same one (one detector per thread). The core never allocates, never reads a clock and
 * never prints.
 */
#ifndef SFD_H
#define SFD_H

#include "sfd_version.h"

#include "sfd_camera.h"
#include "sfd_chi2.h"
#include "sfd_config.h"
#include "sfd_fundamental.h"
#include "sfd_imu.h"
#include "sfd_landmarks.h"
#include "sfd_params.h"
#include "sfd_parity.h"
#include "sfd_assoc.h"
#include "sfd_ekf.h"
#include "sfd_msckf.h"
#include "sfd_rest.h"
#include "sfd_window.h"
#include "sfd_reject.h"
#include "sfd_imu_ring.h"
#include "sfd_nav.h"
#include "sfd_pipeline.h"
#include "sfd_prng.h"
#include "sfd_ransac.h"
#include "sfd_rotation.h"
#include "sfd_status.h"
#include "sfd_time_guard.h"

#endif /* SFD_H */
