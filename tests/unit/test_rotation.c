/* SPDX-License-Identifier: MIT */
/* unit.rotation: SO(3) exp/log, quaternions and extrinsics. */
#include "sfd_test.h"

#include "euroc_calib.h"

#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>

static void matmul3(const double *A, const double *B, double *C) {
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            double s = 0;
            for (int k = 0; k < 3; ++k) s += A[3 * r + k] * B[3 * k + c];
            C[3 * r + c] = s;
        }
}

static void random_rotvec(sfd_prng_t *rng, double max_angle, double phi[3]) {
    double a[3], n = 0;
    for (int i = 0; i < 3; ++i) {
        a[i] = sfd_prng_gaussian(rng);
        n += a[i] * a[i];
    }
    n = sqrt(n);
    double angle = max_angle * sfd_prng_uniform(rng);
    for (int i = 0; i < 3; ++i) phi[i] = a[i] / n * angle;
}

/* GIVEN a rotation of 90 deg about z WHEN exp THEN the closed-form matrix (x -> y). */
static void so3_exp_quarter_turn_about_z_closed_form(void **state) {
    (void)state;
    SFD_REQ("SFD-ROT-001");
    const double phi[3] = {0, 0, M_PI / 2};
    double R[9];
    assert_status(sfd_so3_exp(phi, R), SFD_OK);
    const double ref[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    for (int i = 0; i < 9; ++i) assert_near(R[i], ref[i], 1e-15);
}

/* GIVEN random rotation vectors with angles in [0, pi) and tiny ones WHEN log(exp(phi)) THEN phi
 * back to 1e-12 (1e-9 within 1e-6 of pi where the axis is ill-conditioned). */
static void so3_log_inverts_exp_all_angles(void **state) {
    (void)state;
    SFD_REQ("SFD-ROT-001");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 3);
    for (int i = 0; i < 5000; ++i) {
        double phi[3], R[9], back[3];
        double maxang = (i % 3 == 0) ? 1e-7 : (M_PI - 1e-6);
        random_rotvec(&rng, maxang, phi);
        assert_status(sfd_so3_exp(phi, R), SFD_OK);
        assert_status(sfd_so3_log(R, back), SFD_OK);
        for (int k = 0; k < 3; ++k) assert_near(back[k], phi[k], 1e-9);
    }
    /* zero rotation */
    const double z[3] = {0, 0, 0};
    double R[9], back[3];
    sfd_so3_exp(z, R);
    sfd_so3_log(R, back);
    for (int k = 0; k < 3; ++k) assert_near(back[k], 0.0, 0.0);
}

/* GIVEN random rotations WHEN going phi -> q -> R and phi -> R THEN the same matrix; R -> q -> R
 * round trip; q*q^-1 = identity. */
static void quat_and_rotmat_agree(void **state) {
    (void)state;
    SFD_REQ("SFD-ROT-002");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 4);
    for (int i = 0; i < 2000; ++i) {
        double phi[3], q[4], R1[9], R2[9], q2[4], R3[9];
        random_rotvec(&rng, M_PI, phi);
        assert_status(sfd_quat_from_rotvec(phi, q), SFD_OK);
        assert_true(q[0] >= 0.0);
        assert_status(sfd_quat_to_rotmat(q, R1), SFD_OK);
        sfd_so3_exp(phi, R2);
        for (int k = 0; k < 9; ++k) assert_near(R1[k], R2[k], 1e-14);
        assert_status(sfd_rotmat_to_quat(R1, q2), SFD_OK);
        sfd_quat_to_rotmat(q2, R3);
        for (int k = 0; k < 9; ++k) assert_near(R3[k], R1[k], 1e-14);
        double qinv[4] = {q[0], -q[1], -q[2], -q[3]}, id[4];
        sfd_quat_multiply(q, qinv, id);
        assert_near(id[0], 1.0, 1e-15);
        double back[3];
        assert_status(sfd_quat_to_rotvec(q, back), SFD_OK);
        for (int k = 0; k < 3; ++k) assert_near(back[k], phi[k], 1e-9);
    }
}

/* GIVEN two rotations WHEN multiplying quaternions THEN the product matches R(a) R(b) (Hamilton:
 * apply b first, then a). */
static void quat_multiply_matches_matrix_product(void **state) {
    (void)state;
    SFD_REQ("SFD-ROT-002");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 5);
    for (int i = 0; i < 500; ++i) {
        double pa[3], pb[3], qa[4], qb[4], q[4], Ra[9], Rb[9], Rab[9], Rq[9];
        random_rotvec(&rng, 3.0, pa);
        random_rotvec(&rng, 3.0, pb);
        sfd_quat_from_rotvec(pa, qa);
        sfd_quat_from_rotvec(pb, qb);
        sfd_quat_multiply(qa, qb, q);
        sfd_quat_normalize(q);
        sfd_quat_to_rotmat(q, Rq);
        sfd_so3_exp(pa, Ra);
        sfd_so3_exp(pb, Rb);
        matmul3(Ra, Rb, Rab);
        for (int k = 0; k < 9; ++k) assert_near(Rq[k], Rab[k], 1e-14);
    }
}

/* GIVEN bad inputs THEN SFD_ERR_INVAL: null, NaN, non-rotation matrix, non-unit quaternion. */
static void rotation_bad_inputs_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-ROT-003");
    double R[9], q[4], phi[3] = {0, NAN, 0};
    assert_status(sfd_so3_exp(phi, R), SFD_ERR_INVAL);
    assert_status(sfd_so3_exp(NULL, R), SFD_ERR_INVAL);
    const double notrot[9] = {1, 0, 0, 0, 1, 0, 0, 0, -1}; /* reflection: det -1 */
    assert_status(sfd_so3_log(notrot, phi), SFD_ERR_INVAL);
    assert_status(sfd_rotmat_to_quat(notrot, q), SFD_ERR_INVAL);
    const double scaled[9] = {2, 0, 0, 0, 2, 0, 0, 0, 2};
    assert_status(sfd_so3_log(scaled, phi), SFD_ERR_INVAL);
    const double qbad[4] = {1.1, 0, 0, 0};
    assert_status(sfd_quat_to_rotmat(qbad, R), SFD_ERR_INVAL);
    assert_status(sfd_quat_to_rotvec(qbad, phi), SFD_ERR_INVAL);
    double qz[4] = {0, 0, 0, 0};
    assert_status(sfd_quat_normalize(qz), SFD_ERR_INVAL);
    double qn[4] = {-2, 0, 0, 0};
    assert_status(sfd_quat_normalize(qn), SFD_OK);
    assert_near(qn[0], 1.0, 0.0);
}

/* GIVEN EuRoC cam0's T_BS (camera in IMU/body frame) WHEN parsed THEN R_CtoI and p_CinI are the
 * blocks; a camera rotation R_C1toC0 = R_CtoI^T R_I1toI0 R_CtoI maps camera bearings consistently:
 * rotating a point with the IMU rotation equals rotating it in camera coordinates. */
static void extrinsics_euroc_parse_and_camera_rotation_consistent(void **state) {
    (void)state;
    SFD_REQ("SFD-ROT-004");
    const double *T = kEurocTimuCam;
    sfd_extrinsics_t ext;
    assert_status(sfd_extrinsics_from_matrix(&ext, T), SFD_OK);
    assert_near(ext.R_CtoI[1], -0.999880929698, 0.0);
    assert_near(ext.p_CinI[1], -0.064676986768, 0.0);
    const double phi[3] = {0.1, -0.2, 0.05};
    double RI[9], RC[9];
    sfd_so3_exp(phi, RI);
    assert_status(sfd_extrinsics_camera_rotation(&ext, RI, RC), SFD_OK);
    /* v_C1 arbitrary; v_I1 = R_CtoI v_C1; v_I0 = RI v_I1; v_C0 = R_CtoI^T v_I0 must equal RC v_C1
     */
    const double vC1[3] = {0.3, -0.4, 1.0};
    double vI1[3] = {0}, vI0[3] = {0}, vC0[3] = {0}, vC0b[3] = {0};
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) vI1[r] += ext.R_CtoI[3 * r + k] * vC1[k];
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) vI0[r] += RI[3 * r + k] * vI1[k];
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) vC0[r] += ext.R_CtoI[3 * k + r] * vI0[k];
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) vC0b[r] += RC[3 * r + k] * vC1[k];
    for (int r = 0; r < 3; ++r) assert_near(vC0b[r], vC0[r], 1e-15);
    /* bad last row, non-orthonormal block */
    double Tbad[16];
    for (int i = 0; i < 16; ++i) Tbad[i] = T[i];
    Tbad[14] = 0.5;
    assert_status(sfd_extrinsics_from_matrix(&ext, Tbad), SFD_ERR_INVAL);
    for (int i = 0; i < 16; ++i) Tbad[i] = T[i];
    Tbad[0] = 0.5;
    assert_status(sfd_extrinsics_from_matrix(&ext, Tbad), SFD_ERR_INVAL);
    assert_status(sfd_extrinsics_from_matrix(NULL, T), SFD_ERR_INVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(so3_exp_quarter_turn_about_z_closed_form),
        cmocka_unit_test(so3_log_inverts_exp_all_angles),
        cmocka_unit_test(quat_and_rotmat_agree),
        cmocka_unit_test(quat_multiply_matches_matrix_product),
        cmocka_unit_test(rotation_bad_inputs_rejected),
        cmocka_unit_test(extrinsics_euroc_parse_and_camera_rotation_consistent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
