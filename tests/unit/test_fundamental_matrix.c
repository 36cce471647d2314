/* SPDX-License-Identifier: MIT */
/* unit.fundamental_matrix: the normalized 8-point fit, the Sampson distance and the RANSAC loop of
 * Kilic 2014 Table 2 (core/docs/fundamental_matrix.md). Synthetic two-view scenes from a known
 * relative pose; every statistical test uses fixed seeds and states its margin. */
#include "sfd_test.h"

#include "euroc_calib.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#include <sfd/sfd_camera.h>
#include <sfd/sfd_chi2.h>
#include <sfd/sfd_fundamental.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_ransac.h>

/* EuRoC-like pinhole camera, 752 x 480 px. */
static const double kFx = 450.0, kFy = 440.0, kCx = 376.0, kCy = 240.0;
static const double kWidth = 752.0, kHeight = 480.0;

enum { kMaxPts = SFD_MAX_FEATURES };

/* One two-view scene: X_prev = R X_curr + t (current-camera coordinates into the previous camera),
 * F_true = K^-T R [R^T t]_x K^-1 (thesis eq. 26), unit Frobenius norm. */
typedef struct {
    int n;
    double x_prev[kMaxPts][2];
    double x_curr[kMaxPts][2];
    double clean_prev[kMaxPts][2]; /* noise-free projections */
    double clean_curr[kMaxPts][2];
    uint8_t outlier[kMaxPts];
    double F_true[9];
} scene_t;

static void mat3_mul(const double *A, const double *B, double *C) {
    double T[9];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            T[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k) T[3 * r + c] += A[3 * r + k] * B[3 * k + c];
        }
    memcpy(C, T, sizeof T);
}

static void mat3_transpose(const double *A, double *B) {
    double T[9];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) T[3 * c + r] = A[3 * r + c];
    memcpy(B, T, sizeof T);
}

static double frob(const double *A) {
    double s = 0.0;
    for (int k = 0; k < 9; ++k) s += A[k] * A[k];
    return sqrt(s);
}

static void normalize_unit(double *A) {
    const double s = frob(A);
    for (int k = 0; k < 9; ++k) A[k] /= s;
}

/* min(||A - B||, ||A + B||) for unit-norm A, B: distance up to the arbitrary sign of F. */
static double dist_up_to_sign(const double *A, const double *B) {
    double dm = 0.0, dp = 0.0;
    for (int k = 0; k < 9; ++k) {
        dm += (A[k] - B[k]) * (A[k] - B[k]);
        dp += (A[k] + B[k]) * (A[k] + B[k]);
    }
    return sqrt(dm < dp ? dm : dp);
}

/* Rodrigues: R = exp([w]_x). */
static void rotation_from_axis_angle(const double w[3], double *R) {
    const double th = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double k[3] = {w[0] / th, w[1] / th, w[2] / th};
    const double c = cos(th), s = sin(th), v = 1.0 - c;
    R[0] = c + k[0] * k[0] * v;
    R[1] = k[0] * k[1] * v - k[2] * s;
    R[2] = k[0] * k[2] * v + k[1] * s;
    R[3] = k[1] * k[0] * v + k[2] * s;
    R[4] = c + k[1] * k[1] * v;
    R[5] = k[1] * k[2] * v - k[0] * s;
    R[6] = k[2] * k[0] * v - k[1] * s;
    R[7] = k[2] * k[1] * v + k[0] * s;
    R[8] = c + k[2] * k[2] * v;
}

static void fundamental_from_pose(const double *R, const double *t, double *F) {
    const double Kinv[9] = {1.0 / kFx, 0, -kCx / kFx, 0, 1.0 / kFy, -kCy / kFy, 0, 0, 1};
    double KinvT[9], Rt[9], a[3];
    mat3_transpose(Kinv, KinvT);
    mat3_transpose(R, Rt);
    for (size_t r = 0; r < 3; ++r)
        a[r] = Rt[3 * r] * t[0] + Rt[3 * r + 1] * t[1] + Rt[3 * r + 2] * t[2];
    const double ax[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0}; /* [R^T t]_x */
    mat3_mul(KinvT, R, F);
    mat3_mul(F, ax, F);
    mat3_mul(F, Kinv, F);
    normalize_unit(F);
}

static void project(const double *X, double *uv) {
    uv[0] = kFx * X[0] / X[2] + kCx;
    uv[1] = kFy * X[1] / X[2] + kCy;
}

/* Scene options: plane_normal != NULL puts every point on the plane n . X_curr = 1. */
typedef struct {
    double w[3];             /* rotation vector of R (rad) */
    double t[3];             /* translation (m) */
    double sigma_px;         /* Gaussian pixel noise in both images */
    double outlier_fraction; /* matches whose previous point is uniform in the image */
    const double *plane_n;   /* NULL: depths uniform in [4, 12] m */
} scene_opts_t;

static void make_scene(sfd_prng_t *rng, const scene_opts_t *o, int n, scene_t *s) {
    double R[9];
    if (o->w[0] == 0.0 && o->w[1] == 0.0 && o->w[2] == 0.0) {
        const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(R, I, sizeof I);
    } else {
        rotation_from_axis_angle(o->w, R);
    }
    fundamental_from_pose(R, o->t, s->F_true);
    s->n = n;
    const int n_out = (int)(o->outlier_fraction * n + 0.5);
    for (int i = 0; i < n; ++i) {
        double Xc[3], Xp[3];
        /* Draw until the point is in front of both cameras and inside the previous image
         * (bounded: after 100 tries the last draw is kept as long as it is in front). */
        for (int tries = 0; tries < 100; ++tries) {
            const double u = kWidth * sfd_prng_uniform(rng);
            const double v = kHeight * sfd_prng_uniform(rng);
            const double ray[3] = {(u - kCx) / kFx, (v - kCy) / kFy, 1.0};
            double depth = 4.0 + 8.0 * sfd_prng_uniform(rng);
            if (o->plane_n) {
                const double d =
                    o->plane_n[0] * ray[0] + o->plane_n[1] * ray[1] + o->plane_n[2] * ray[2];
                depth = 1.0 / d;
            }
            for (int k = 0; k < 3; ++k) Xc[k] = depth * ray[k];
            for (size_t r = 0; r < 3; ++r)
                Xp[r] = R[3 * r] * Xc[0] + R[3 * r + 1] * Xc[1] + R[3 * r + 2] * Xc[2] + o->t[r];
            double uvp[2];
            if (Xp[2] > 0.5) {
                project(Xp, uvp);
                if (uvp[0] >= 0 && uvp[0] <= kWidth && uvp[1] >= 0 && uvp[1] <= kHeight) break;
            }
        }
        assert_true(Xp[2] > 0.0 && Xc[2] > 0.0);
        project(Xp, s->clean_prev[i]);
        project(Xc, s->clean_curr[i]);
        s->outlier[i] = (uint8_t)(i < n_out); /* positions are arbitrary: RANSAC is order-blind */
        for (int k = 0; k < 2; ++k) {
            s->x_prev[i][k] = s->clean_prev[i][k] + o->sigma_px * sfd_prng_gaussian(rng);
            s->x_curr[i][k] = s->clean_curr[i][k] + o->sigma_px * sfd_prng_gaussian(rng);
        }
        if (s->outlier[i]) {
            s->x_prev[i][0] = kWidth * sfd_prng_uniform(rng);
            s->x_prev[i][1] = kHeight * sfd_prng_uniform(rng);
        }
    }
}

static double epipolar_algebraic(const double *F, const double *x1, const double *x2) {
    const double p[3] = {x1[0], x1[1], 1.0}, q[3] = {x2[0], x2[1], 1.0};
    double e = 0.0;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) e += p[r] * F[3 * r + c] * q[c];
    return e;
}

static const scene_opts_t kGeneric = {{0.03, -0.05, 0.02}, {0.4, -0.1, 0.15}, 0.0, 0.0, NULL};

static void identity_idx(int32_t *idx, int n) {
    for (int i = 0; i < n; ++i) idx[i] = i;
}

/* ------------------------------------------------------------------------------------------
 * 8-point fit
 * ---------------------------------------------------------------------------------------- */

/* GIVEN a synthetic pose with X_prev = R X_curr + t WHEN building F by eq. (26) THEN the noise-free
 * matches satisfy x_prev^T F x_curr = 0 (the convention), and the transposed pairing does not. */
static void synthetic_scene_satisfies_eq25_convention(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-001");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 1);
    static scene_t s;
    make_scene(&rng, &kGeneric, 100, &s);
    double worst = 0.0, worst_swapped = 0.0;
    for (int i = 0; i < s.n; ++i) {
        worst = fmax(worst, sfd_sampson_sq_px2(s.F_true, s.clean_prev[i], s.clean_curr[i]));
        worst_swapped =
            fmax(worst_swapped, sfd_sampson_sq_px2(s.F_true, s.clean_curr[i], s.clean_prev[i]));
        assert_near(epipolar_algebraic(s.F_true, s.clean_prev[i], s.clean_curr[i]), 0.0, 1e-12);
    }
    assert_true(worst < 1e-18);
    assert_true(worst_swapped > 1.0); /* the convention is not symmetric: it is pinned */
}

/* GIVEN 8 noise-free matches in general position WHEN fitting THEN F equals the true F (up to
 * sign) to 1e-9 and every other noise-free match of the scene satisfies it (Sampson < 1e-14 px^2).
 */
static void fundamental_8point_noise_free_8_matches_recovers_true_F(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-002");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 2);
    static scene_t s;
    for (int trial = 0; trial < 20; ++trial) {
        scene_opts_t o = kGeneric;
        for (int k = 0; k < 3; ++k) {
            o.w[k] = 0.1 * sfd_prng_gaussian(&rng);
            o.t[k] = 0.5 * sfd_prng_gaussian(&rng);
        }
        make_scene(&rng, &o, 50, &s);
        int32_t idx[8];
        identity_idx(idx, 8);
        double F[9];
        assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 8, F), SFD_OK);
        assert_near(frob(F), 1.0, 1e-12);
        assert_true(dist_up_to_sign(F, s.F_true) < 1e-9);
        for (int i = 0; i < s.n; ++i)
            assert_true(sfd_sampson_sq_px2(F, s.x_prev[i], s.x_curr[i]) < 1e-14);
    }
}

/* GIVEN 100 matches with sigma = 1 px noise in both images (20 scenes) WHEN fitting by least
 * squares THEN the mean Sampson residual of the data is near sigma^2 (its chi2(1) expectation minus
 * the 7 fitted dof: (1 - 7/100) sigma^2; standard error of the 2000-sample mean ~0.03 sigma^2) and
 * the fitted F explains the noise-free matches to well below sigma^2 (model error ~ 7/100 sigma^2).
 */
static void fundamental_8point_noisy_100_matches_sampson_near_sigma2(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-003");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 3);
    static scene_t s;
    const double sigma = 1.0;
    double sum_fit = 0.0, sum_true = 0.0, sum_model = 0.0;
    int count = 0;
    for (int trial = 0; trial < 20; ++trial) {
        scene_opts_t o = kGeneric;
        o.sigma_px = sigma;
        make_scene(&rng, &o, 100, &s);
        int32_t idx[100];
        identity_idx(idx, 100);
        double F[9];
        assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 100, F), SFD_OK);
        for (int i = 0; i < s.n; ++i) {
            sum_fit += sfd_sampson_sq_px2(F, s.x_prev[i], s.x_curr[i]);
            sum_true += sfd_sampson_sq_px2(s.F_true, s.x_prev[i], s.x_curr[i]);
            sum_model += sfd_sampson_sq_px2(F, s.clean_prev[i], s.clean_curr[i]);
            ++count;
        }
    }
    const double s2 = sigma * sigma;
    assert_near(sum_true / count, s2, 0.1 * s2); /* the chi2(1) claim itself */
    assert_near(sum_fit / count, 0.93 * s2, 0.12 * s2);
    assert_true(sum_model / count < 0.2 * s2);
}

/* s3 <= sqrt(3) |det F| / ||adj F||_F (since ||adj F||_F <= sqrt(3) s1 s2). */
static double smallest_singular_bound(const double *F) {
    double adj[9];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            adj[3 * c + r] = F[3 * r1 + c1] * F[3 * r2 + c2] - F[3 * r1 + c2] * F[3 * r2 + c1];
        }
    const double det = F[0] * adj[0] + F[1] * adj[3] + F[2] * adj[6];
    return sqrt(3.0) * fabs(det) / frob(adj);
}

/* GIVEN noisy matches (whose unconstrained least-squares F has full rank) WHEN fitting THEN
 * rank(F) = 2: the smallest singular value is below 1e-12 (||F|| = 1) while the unconstrained
 * fit's would be ~1e-3, and ||F||_F = 1 with the largest entry positive. */
static void fundamental_8point_result_has_rank_2_and_unit_norm(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-004");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 4);
    static scene_t s;
    for (int trial = 0; trial < 20; ++trial) {
        scene_opts_t o = kGeneric;
        o.sigma_px = 2.0;
        make_scene(&rng, &o, 8 + 10 * trial, &s);
        int32_t idx[kMaxPts];
        identity_idx(idx, s.n);
        double F[9];
        assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, s.n, F), SFD_OK);
        assert_true(smallest_singular_bound(F) < 1e-12);
        assert_near(frob(F), 1.0, 1e-12);
        int imax = 0;
        for (int k = 1; k < 9; ++k)
            if (fabs(F[k]) > fabs(F[imax])) imax = k;
        assert_true(F[imax] > 0.0);
    }
}

/* Similarity x' = a Q(phi) x + b of one image, as a 3x3 matrix. */
static void similarity(double a, double phi, double bx, double by, double *T) {
    const double c = a * cos(phi), s = a * sin(phi);
    const double M[9] = {c, -s, bx, s, c, by, 0, 0, 1};
    memcpy(T, M, sizeof M);
}

static void apply(const double *T, const double *x, double *y) {
    y[0] = T[0] * x[0] + T[1] * x[1] + T[2];
    y[1] = T[3] * x[0] + T[4] * x[1] + T[5];
}

/* GIVEN noisy matches and similarity transforms T1, T2 of each image (scale, rotation, offset) WHEN
 * fitting the transformed matches THEN F' = T1^-T F T2^-1 to 1e-9: the normalization makes the
 * least-squares fit independent of pixel units and origin (an unnormalized fit differs at ~1e-3).
 */
static void fundamental_8point_covariant_under_image_similarities(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-005");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 5);
    static scene_t s, t;
    scene_opts_t o = kGeneric;
    o.sigma_px = 1.0;
    make_scene(&rng, &o, 60, &s);
    int32_t idx[60];
    identity_idx(idx, 60);
    double F[9];
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 60, F), SFD_OK);
    const double params[3][6] = {{0.001, 0.3, 5.0, -2.0, 1.0, 0.0},
                                 {1000.0, -1.0, -3e5, 1e5, 0.5, 2.0},
                                 {1.0, 0.0, 1e4, 1e4, 1.0, 0.0}};
    for (int c = 0; c < 3; ++c) {
        const double *p = params[c];
        double T1[9], T2[9];
        similarity(p[0], p[1], p[2], p[3], T1);
        similarity(p[4], p[5], -p[3], p[2], T2);
        t = s;
        for (int i = 0; i < s.n; ++i) {
            apply(T1, s.x_prev[i], t.x_prev[i]);
            apply(T2, s.x_curr[i], t.x_curr[i]);
        }
        double Ft[9];
        assert_status(sfd_fundamental_8point(t.x_prev, t.x_curr, idx, 60, Ft), SFD_OK);
        /* expected F' = T1^-T F T2^-1: invert the similarities in closed form */
        double T1i[9], T2i[9], T1iT[9], E[9];
        const double a1 = p[0], a2 = p[4];
        similarity(1.0 / a1, -p[1], 0.0, 0.0, T1i);
        similarity(1.0 / a2, -p[5], 0.0, 0.0, T2i);
        double b1[2], b2[2];
        const double o1[2] = {p[2], p[3]}, o2[2] = {-p[3], p[2]};
        apply(T1i, o1, b1);
        apply(T2i, o2, b2);
        T1i[2] = -b1[0];
        T1i[5] = -b1[1];
        T2i[2] = -b2[0];
        T2i[5] = -b2[1];
        mat3_transpose(T1i, T1iT);
        mat3_mul(T1iT, F, E);
        mat3_mul(E, T2i, E);
        normalize_unit(E);
        assert_true(dist_up_to_sign(Ft, E) < 1e-9);
    }
}

/* Objective of true_sq_distance(): |x1 - p|^2 + squared distance of x2 to the line F^T p. */
static double two_view_cost(const double *F, const double *x1, const double *x2, const double *p) {
    const double l0 = F[0] * p[0] + F[3] * p[1] + F[6];
    const double l1 = F[1] * p[0] + F[4] * p[1] + F[7];
    const double l2 = F[2] * p[0] + F[5] * p[1] + F[8];
    const double e = l0 * x2[0] + l1 * x2[1] + l2;
    return (p[0] - x1[0]) * (p[0] - x1[0]) + (p[1] - x1[1]) * (p[1] - x1[1]) +
           e * e / (l0 * l0 + l1 * l1);
}

/* Squared distance of (x1, x2) to the variety x1'^T F x2' = 0, by direct minimization over x1'
 * (for a fixed x1' the closest x2' is the foot on the epipolar line F^T x1'). Compass search with
 * halving steps from step h: bounded, derivative-free; 400 rounds end far below 1e-15 h. */
static double true_sq_distance(const double *F, const double *x1, const double *x2, double h) {
    double p[2] = {x1[0], x1[1]};
    double best = two_view_cost(F, x1, x2, p);
    for (int it = 0; it < 400; ++it) {
        int moved = 0;
        for (int d = 0; d < 4 && !moved; ++d) {
            double q[2] = {p[0], p[1]};
            q[d / 2] += (d % 2) ? -h : h;
            const double v = two_view_cost(F, x1, x2, q);
            if (v < best) {
                p[0] = q[0];
                p[1] = q[1];
                best = v;
                moved = 1;
            }
        }
        if (!moved) h *= 0.5;
    }
    return best;
}

/* GIVEN exact matches perturbed by eps in a random 4-D direction WHEN comparing the Sampson
 * distance with the true squared distance to the variety THEN they agree to first order: the
 * difference, relative to eps^2, shrinks with eps (below 5e-4 at 1 px, 5e-5 at 0.1 px, 5e-6 at
 * 0.01 px). One-sided epipolar distance or the algebraic error would be off by
 * factors ~2 or ~1e5. */
static void sampson_equals_true_squared_distance_to_first_order(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-006");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 6);
    static scene_t s;
    make_scene(&rng, &kGeneric, 40, &s);
    const double eps[3] = {1.0, 0.1, 0.01};
    const double tol[3] = {5e-4, 5e-5, 5e-6}; /* measured 1e-4, 8e-6, 5e-7 */
    for (int e = 0; e < 3; ++e) {
        double worst = 0.0;
        for (int i = 0; i < s.n; ++i) {
            double d[4], nrm = 0.0;
            for (int k = 0; k < 4; ++k) {
                d[k] = sfd_prng_gaussian(&rng);
                nrm += d[k] * d[k];
            }
            nrm = sqrt(nrm);
            const double x1[2] = {s.clean_prev[i][0] + eps[e] * d[0] / nrm,
                                  s.clean_prev[i][1] + eps[e] * d[1] / nrm};
            const double x2[2] = {s.clean_curr[i][0] + eps[e] * d[2] / nrm,
                                  s.clean_curr[i][1] + eps[e] * d[3] / nrm};
            const double truth = true_sq_distance(s.F_true, x1, x2, eps[e]);
            const double samp = sfd_sampson_sq_px2(s.F_true, x1, x2);
            /* relative to eps^2, the scale of the perturbation (truth may be ~0 when the
             * perturbation happens to be nearly tangent) */
            worst = fmax(worst, fabs(samp - truth) / (eps[e] * eps[e]));
        }
        if (!(worst < tol[e])) fail_msg("eps %g: worst relative difference %g", eps[e], worst);
    }
    /* scale of F does not matter */
    double F2[9];
    for (int k = 0; k < 9; ++k) F2[k] = -37.0 * s.F_true[k];
    const double x1[2] = {s.clean_prev[0][0] + 0.7, s.clean_prev[0][1]};
    assert_near(sfd_sampson_sq_px2(F2, x1, s.clean_curr[0]),
                sfd_sampson_sq_px2(s.F_true, x1, s.clean_curr[0]), 1e-12);
}

/* GIVEN a zero F, non-finite coordinates or null pointers WHEN computing the Sampson distance THEN
 * +infinity (never an inlier); and a match on an epipole (zero gradient, e = 0) is +infinity too.
 */
static void sampson_degenerate_inputs_return_infinity(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-006");
    const double Z[9] = {0};
    const double F[9] = {0, -1, 0, 1, 0, 0, 0, 0, 0}; /* [e]_x with e = (0,0,1): epipole at 0 */
    const double a[2] = {1.0, 2.0}, b[2] = {3.0, 4.0}, nanp[2] = {NAN, 1.0};
    const double infp[2] = {INFINITY, 1.0}, origin[2] = {0.0, 0.0};
    assert_true(isinf(sfd_sampson_sq_px2(Z, a, b)));
    assert_true(isinf(sfd_sampson_sq_px2(F, nanp, b)));
    assert_true(isinf(sfd_sampson_sq_px2(F, a, infp)));
    assert_true(isinf(sfd_sampson_sq_px2(NULL, a, b)));
    assert_true(isinf(sfd_sampson_sq_px2(F, NULL, b)));
    assert_true(isinf(sfd_sampson_sq_px2(F, a, NULL)));
    assert_true(isinf(sfd_sampson_sq_px2(F, origin, origin)));
    assert_true(isfinite(sfd_sampson_sq_px2(F, a, b)));
}

static void assert_untouched(const double *F) {
    for (int k = 0; k < 9; ++k) assert_true(F[k] == 42.0);
}

/* GIVEN configurations where F is not unique (pure rotation, all points on one plane, only 7
 * distinct matches among 8, every point identical) WHEN fitting THEN SFD_ERR_NUMERIC and F is
 * untouched: never an arbitrary member of the solution family. */
static void fundamental_8point_degenerate_configurations_return_numeric(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-007");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 7);
    static scene_t s;
    int32_t idx[100];
    identity_idx(idx, 100);
    double F[9];
    /* pure rotation: x_prev = K R K^-1 x_curr, a homography */
    scene_opts_t o = kGeneric;
    o.t[0] = o.t[1] = o.t[2] = 0.0;
    make_scene(&rng, &o, 100, &s);
    for (int k = 0; k < 9; ++k) F[k] = 42.0;
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 8, F), SFD_ERR_NUMERIC);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 100, F), SFD_ERR_NUMERIC);
    assert_untouched(F);
    /* coplanar points with a general motion (plane 0.02 X + 0.05 Y + 0.1 Z = 1) */
    const double plane[3] = {0.02, 0.05, 0.1};
    o = kGeneric;
    o.plane_n = plane;
    make_scene(&rng, &o, 100, &s);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 8, F), SFD_ERR_NUMERIC);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 100, F), SFD_ERR_NUMERIC);
    assert_untouched(F);
    /* the same motion with depth: fine (positive control for the two cases above) */
    make_scene(&rng, &kGeneric, 100, &s);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 8, F), SFD_OK);
    /* only 7 distinct matches: a repeated index, and a duplicated point */
    for (int k = 0; k < 9; ++k) F[k] = 42.0;
    const int32_t rep[8] = {0, 1, 2, 3, 4, 5, 6, 6};
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, rep, 8, F), SFD_ERR_NUMERIC);
    static scene_t d;
    d = s;
    d.x_prev[7][0] = d.x_prev[3][0];
    d.x_prev[7][1] = d.x_prev[3][1];
    d.x_curr[7][0] = d.x_curr[3][0];
    d.x_curr[7][1] = d.x_curr[3][1];
    assert_status(sfd_fundamental_8point(d.x_prev, d.x_curr, idx, 8, F), SFD_ERR_NUMERIC);
    /* every point the same */
    for (int i = 0; i < 8; ++i) {
        d.x_prev[i][0] = 100.0;
        d.x_prev[i][1] = 200.0;
        d.x_curr[i][0] = 110.0;
        d.x_curr[i][1] = 190.0;
    }
    assert_status(sfd_fundamental_8point(d.x_prev, d.x_curr, idx, 8, F), SFD_ERR_NUMERIC);
    assert_untouched(F);
}

/* GIVEN null pointers, n outside [8, SFD_MAX_FEATURES], indices outside [0, SFD_MAX_FEATURES) or
 * a non-finite listed coordinate WHEN fitting THEN SFD_ERR_INVAL with F untouched; a non-finite
 * coordinate of an unlisted match is never read. */
static void fundamental_8point_invalid_arguments_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-008");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 8);
    static scene_t s;
    make_scene(&rng, &kGeneric, 20, &s);
    static int32_t idx[kMaxPts + 1];
    identity_idx(idx, kMaxPts + 1);
    double F[9];
    for (int k = 0; k < 9; ++k) F[k] = 42.0;
    assert_status(sfd_fundamental_8point(NULL, s.x_curr, idx, 8, F), SFD_ERR_INVAL);
    assert_status(sfd_fundamental_8point(s.x_prev, NULL, idx, 8, F), SFD_ERR_INVAL);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, NULL, 8, F), SFD_ERR_INVAL);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 8, NULL), SFD_ERR_INVAL);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, 7, F), SFD_ERR_INVAL);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, -1, F), SFD_ERR_INVAL);
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, idx, kMaxPts + 1, F), SFD_ERR_INVAL);
    int32_t bad[8] = {0, 1, 2, 3, 4, 5, 6, -1};
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, bad, 8, F), SFD_ERR_INVAL);
    bad[7] = kMaxPts;
    assert_status(sfd_fundamental_8point(s.x_prev, s.x_curr, bad, 8, F), SFD_ERR_INVAL);
    static scene_t b;
    b = s;
    b.x_curr[5][1] = NAN;
    assert_status(sfd_fundamental_8point(b.x_prev, b.x_curr, idx, 8, F), SFD_ERR_INVAL);
    b = s;
    b.x_prev[2][0] = -INFINITY;
    assert_status(sfd_fundamental_8point(b.x_prev, b.x_curr, idx, 8, F), SFD_ERR_INVAL);
    assert_untouched(F);
    b.x_prev[2][0] = s.x_prev[2][0];
    b.x_prev[15][0] = NAN; /* not listed */
    assert_status(sfd_fundamental_8point(b.x_prev, b.x_curr, idx, 8, F), SFD_OK);
}

/* ------------------------------------------------------------------------------------------
 * RANSAC (Table 2)
 * ---------------------------------------------------------------------------------------- */

static double chi2_threshold(double sigma, double alpha) {
    double q = 0.0;
    assert_status(sfd_chi2_quantile_upper(alpha, 1, &q), SFD_OK);
    return sigma * sigma * q;
}

/* The reported F classifies exactly the reported inliers, and the count matches. */
static void assert_result_consistent(const scene_t *s, const uint8_t *inlier,
                                     const sfd_ransacf_result_t *r, double thr) {
    int count = 0;
    for (int i = 0; i < s->n; ++i) {
        const int in = sfd_sampson_sq_px2(r->F, s->x_prev[i], s->x_curr[i]) <= thr;
        assert_int_equal(inlier[i], in);
        count += in;
    }
    assert_int_equal(r->num_inliers, count);
    assert_near(frob(r->F), 1.0, 1e-12);
}

typedef struct {
    int tp, fp, fn;           /* outliers flagged, inliers flagged, outliers kept */
    double mean_model_sq_px2; /* Sampson of the final F on the noise-free inliers, mean */
} detection_t;

/* Runs RANSAC on `scenes` scenes of 200 matches, 30% outliers uniform in the previous image, sigma
 * = 0.5 px, gate sigma^2 chi2_{1,0.99}, budget SFD_MAX_HYPOTHESES, baseline 0.25-0.45 m at depths
 * 4-12 m. forward = 0: translation mostly parallel to the image plane (epipoles far outside the
 * image); forward = 1: mostly along the optical axis (epipoles inside the image). Checks every
 * result's internal consistency and the budget. */
static detection_t run_outlier_scenes(int forward, int scenes, uint64_t seed) {
    sfd_prng_t gen, rng;
    sfd_prng_seed(&gen, seed);
    sfd_prng_seed(&rng, seed + 1000);
    static scene_t s;
    const double sigma = 0.5, thr = chi2_threshold(sigma, 0.01);
    detection_t d = {0, 0, 0, 0.0};
    for (int trial = 0; trial < scenes; ++trial) {
        scene_opts_t o = kGeneric;
        for (int k = 0; k < 3; ++k) o.w[k] = 0.05 * sfd_prng_gaussian(&gen);
        const double b = 0.35 * (0.7 + 0.6 * sfd_prng_uniform(&gen));
        const double ang = 6.3 * sfd_prng_uniform(&gen);
        o.t[0] = (forward ? 0.3 : 1.0) * b * cos(ang);
        o.t[1] = (forward ? 0.3 : 1.0) * b * sin(ang);
        o.t[2] = forward ? b : 0.2 * b * sfd_prng_gaussian(&gen);
        o.sigma_px = sigma;
        o.outlier_fraction = 0.3;
        make_scene(&gen, &o, 200, &s);
        uint8_t inlier[200];
        sfd_ransacf_result_t r;
        assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 200, thr, 0.99, SFD_MAX_HYPOTHESES,
                                  &rng, inlier, &r),
                      SFD_OK);
        assert_result_consistent(&s, inlier, &r, thr);
        /* eq. (27) counts on the true inlier ratio, but a minimal sample's F at this gate keeps
         * only ~half of the inliers (OpenCV's 8-point does the same on the same samples), so N
         * stays high here: only the budget is a hard bound (adaptation: ransacf_adapts_*). */
        assert_true(r.hypotheses_used >= 1 && r.hypotheses_used <= SFD_MAX_HYPOTHESES);
        double model = 0.0;
        for (int i = 0; i < 200; ++i) {
            const int flagged = !inlier[i];
            d.tp += flagged && s.outlier[i];
            d.fp += flagged && !s.outlier[i];
            d.fn += !flagged && s.outlier[i];
            if (!s.outlier[i]) model += sfd_sampson_sq_px2(r.F, s.clean_prev[i], s.clean_curr[i]);
        }
        d.mean_model_sq_px2 += model / 140.0 / scenes;
    }
    return d;
}

/* GIVEN 40 scenes each of sideways and forward motion, 200 matches, 30% outliers uniform in the
 * image, sigma = 0.5 px, gate sigma^2 chi2_{1,0.99} WHEN running RANSAC THEN
 * - outlier recall >= 0.95 (measured 0.97-0.99; even with the true F ~0.7% of the outliers land
 *   within the gate of their epipolar line by chance),
 * - inlier precision and recall >= 0.95 (measured 0.988-0.994 and 0.970-0.976),
 * - outlier precision >= 0.90 (measured 0.934-0.945): inliers the final F loses beyond the 1% of
 *   the true F. Cause: the winning minimal sample's inlier set often holds an outlier that passes
 *   its gate; the one least-squares refit bends towards it (a single such outlier added to the
 *   true inlier set raises the model error ~10x) and rescoring then drops a few true inliers.
 *   OpenCV 4.6 on the same scenes: FM_RANSAC 0.78 / 0.82, USAC_* (local optimization) 0.99.
 * - mean model error of the final F on the noise-free inliers < sigma^2 (measured ~0.45 sigma^2;
 *   the least-squares F of the true inliers: ~0.1 sigma^2). */
static void ransacf_30pct_outliers_recall_095_outlier_precision_090(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-009");
    for (int forward = 0; forward <= 1; ++forward) {
        const detection_t d = run_outlier_scenes(forward, 40, 9 + (uint64_t)forward);
        const int n_out = d.tp + d.fn, n_in = 40 * 140, kept_in = n_in - d.fp;
        const double out_recall = (double)d.tp / n_out,
                     out_precision = (double)d.tp / (d.tp + d.fp);
        const double in_recall = (double)kept_in / n_in,
                     in_precision = (double)kept_in / (kept_in + d.fn);
        if (!(out_recall >= 0.95 && in_precision >= 0.95 && in_recall >= 0.95 &&
              out_precision >= 0.90 && d.mean_model_sq_px2 < 0.25)) {
            fail_msg("forward %d: outliers P %.4f R %.4f, inliers P %.4f R %.4f, model %.4f px^2",
                     forward, out_precision, out_recall, in_precision, in_recall,
                     d.mean_model_sq_px2);
        }
    }
}

/* GIVEN noise-free matches with 30% outliers WHEN running with budget SFD_MAX_HYPOTHESES THEN the
 * loop stops at eq. (27)'s count for the inlier ratio found (78 at 0.7 and p = 0.99), below the
 * budget; with budget 20 < 78 it stops at 20 and reports budget_exhausted. */
static void ransacf_adapts_hypothesis_count_by_eq27(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-010");
    sfd_prng_t gen, rng;
    sfd_prng_seed(&gen, 16);
    sfd_prng_seed(&rng, 160);
    static scene_t s;
    scene_opts_t o = kGeneric;
    o.outlier_fraction = 0.3;
    make_scene(&gen, &o, 200, &s);
    const double thr = chi2_threshold(0.5, 0.01);
    uint8_t inlier[200];
    sfd_ransacf_result_t r;
    for (int rep = 0; rep < 5; ++rep) {
        assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 200, thr, 0.99, SFD_MAX_HYPOTHESES,
                                  &rng, inlier, &r),
                      SFD_OK);
        assert_true(r.num_inliers >= 140 && r.num_inliers <= 143);
        assert_int_equal(r.hypotheses_used, sfd_ransac_hypothesis_count(0.99, r.num_inliers / 200.0,
                                                                        8, SFD_MAX_HYPOTHESES));
        assert_true(r.hypotheses_used <= 78);
        assert_int_equal(r.budget_exhausted, 0);
    }
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 200, thr, 0.99, 20, &rng, inlier, &r),
                  SFD_OK);
    assert_int_equal(r.hypotheses_used, 20);
    assert_int_equal(r.budget_exhausted, 1);
}

/* GIVEN 200 matches that are all outliers WHEN running with budgets 1, 50 and SFD_MAX_HYPOTHESES
 * THEN exactly the budget is used (eq. 27 never gets satisfied), never more, and
 * budget_exhausted = 1. */
static void ransacf_all_outliers_budget_never_exceeded(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-011");
    sfd_prng_t gen, rng;
    sfd_prng_seed(&gen, 10);
    sfd_prng_seed(&rng, 100);
    static scene_t s;
    scene_opts_t o = kGeneric;
    o.outlier_fraction = 1.0;
    make_scene(&gen, &o, 200, &s);
    const double thr = chi2_threshold(1.0, 0.01);
    const int32_t budgets[3] = {1, 50, SFD_MAX_HYPOTHESES};
    for (int b = 0; b < 3; ++b) {
        uint8_t inlier[200];
        sfd_ransacf_result_t r;
        const sfd_status_t st =
            sfd_ransacf(s.x_prev, s.x_curr, NULL, 200, thr, 0.99, budgets[b], &rng, inlier, &r);
        assert_int_equal(st, SFD_OK);
        assert_int_equal(r.hypotheses_used, budgets[b]);
        assert_int_equal(r.budget_exhausted, 1);
        assert_true(r.num_inliers < 40); /* the best random model explains a handful by chance */
    }
}

/* GIVEN 200 matches without outliers (noise-free, and sigma = 0.5 px with a 1e-9 gate) WHEN
 * running THEN every match is kept; noise-free data stop after one hypothesis (eq. 27 at ratio 1).
 */
static void ransacf_no_outliers_every_match_kept(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-012");
    sfd_prng_t gen, rng;
    sfd_prng_seed(&gen, 11);
    sfd_prng_seed(&rng, 110);
    static scene_t s;
    for (int noisy = 0; noisy <= 1; ++noisy) {
        scene_opts_t o = kGeneric;
        o.sigma_px = noisy ? 0.5 : 0.0;
        make_scene(&gen, &o, 200, &s);
        const double thr = chi2_threshold(0.5, noisy ? 1e-9 : 0.01);
        uint8_t inlier[200];
        sfd_ransacf_result_t r;
        assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 200, thr, 0.99, SFD_MAX_HYPOTHESES,
                                  &rng, inlier, &r),
                      SFD_OK);
        assert_int_equal(r.num_inliers, 200);
        for (int i = 0; i < 200; ++i) assert_int_equal(inlier[i], 1);
        assert_int_equal(r.budget_exhausted, 0);
        if (!noisy) {
            assert_int_equal(r.hypotheses_used, 1);
            assert_true(dist_up_to_sign(r.F, s.F_true) < 1e-9);
        }
        assert_result_consistent(&s, inlier, &r, thr);
    }
}

/* GIVEN the same inputs and the same seed WHEN running twice THEN inlier flags, result and the
 * PRNG state after the call are bit-identical; another seed still gives a valid result. */
static void ransacf_same_seed_identical_output(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-013");
    sfd_prng_t gen;
    sfd_prng_seed(&gen, 12);
    static scene_t s;
    scene_opts_t o = kGeneric;
    o.sigma_px = 1.0;
    o.outlier_fraction = 0.3;
    make_scene(&gen, &o, 150, &s);
    const double thr = chi2_threshold(1.0, 0.01);
    sfd_prng_t r1, r2, r3;
    sfd_prng_seed(&r1, 777);
    sfd_prng_seed(&r2, 777);
    sfd_prng_seed(&r3, 778);
    uint8_t in1[150], in2[150], in3[150];
    sfd_ransacf_result_t o1, o2, o3;
    memset(&o1, 0x11, sizeof o1);
    memset(&o2, 0x22, sizeof o2);
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 150, thr, 0.99, 200, &r1, in1, &o1),
                  SFD_OK);
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 150, thr, 0.99, 200, &r2, in2, &o2),
                  SFD_OK);
    assert_memory_equal(in1, in2, sizeof in1);
    assert_memory_equal(&o1, &o2, sizeof o1);
    assert_memory_equal(&r1, &r2, sizeof r1);
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 150, thr, 0.99, 200, &r3, in3, &o3),
                  SFD_OK);
    assert_result_consistent(&s, in3, &o3, thr);
    assert_true(o1.num_inliers >= 95 && o3.num_inliers >= 95); /* of 105 true inliers */
}

/* GIVEN fewer than 8 matches (0 and 7) WHEN running THEN SFD_ERR_RANGE, inlier[0..n) all 0 (the
 * caller reports them untested), out zeroed, nothing written past n, PRNG not advanced. */
static void ransacf_fewer_than_8_matches_range_all_untested(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-014");
    sfd_prng_t gen, rng, rng0;
    sfd_prng_seed(&gen, 13);
    sfd_prng_seed(&rng, 130);
    rng0 = rng;
    static scene_t s;
    make_scene(&gen, &kGeneric, 7, &s);
    uint8_t inlier[16];
    sfd_ransacf_result_t r;
    memset(inlier, 0xAA, sizeof inlier);
    memset(&r, 0xAA, sizeof r);
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 7, 1.0, 0.99, 10, &rng, inlier, &r),
                  SFD_ERR_RANGE);
    for (int i = 0; i < 7; ++i) assert_int_equal(inlier[i], 0);
    for (int i = 7; i < 16; ++i) assert_int_equal(inlier[i], 0xAA);
    const sfd_ransacf_result_t zero = {0};
    assert_memory_equal(&r, &zero, sizeof r);
    assert_memory_equal(&rng, &rng0, sizeof rng);
    memset(inlier, 0xAA, sizeof inlier);
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 0, 1.0, 0.99, 10, &rng, inlier, &r),
                  SFD_ERR_RANGE);
    assert_int_equal(inlier[0], 0xAA);
}

/* GIVEN matches where every 8-sample is degenerate (noise-free pure rotation) WHEN running THEN
 * SFD_ERR_NUMERIC after exactly the budget, inlier[] all 0, F zero, budget_exhausted = 1. */
static void ransacf_all_samples_degenerate_numeric_all_untested(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-014");
    sfd_prng_t gen, rng;
    sfd_prng_seed(&gen, 14);
    sfd_prng_seed(&rng, 140);
    static scene_t s;
    scene_opts_t o = kGeneric;
    o.t[0] = o.t[1] = o.t[2] = 0.0;
    make_scene(&gen, &o, 50, &s);
    uint8_t inlier[50];
    memset(inlier, 0xAA, sizeof inlier);
    sfd_ransacf_result_t r;
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 50, 1.0, 0.99, 20, &rng, inlier, &r),
                  SFD_ERR_NUMERIC);
    for (int i = 0; i < 50; ++i) assert_int_equal(inlier[i], 0);
    assert_int_equal(r.hypotheses_used, 20);
    assert_int_equal(r.budget_exhausted, 1);
    assert_int_equal(r.num_inliers, 0);
    for (int k = 0; k < 9; ++k) assert_true(r.F[k] == 0.0);
}

/* Calls with one bad argument: the status, and nothing written (inlier, out) at all. */
static void expect_rejected(const scene_t *s, int32_t n, double thr, double conf, int32_t budget,
                            sfd_prng_t *rng, int null_inlier, int null_out, sfd_status_t expected) {
    static uint8_t inlier[kMaxPts + 16];
    sfd_ransacf_result_t r;
    memset(inlier, 0xAA, sizeof inlier);
    memset(&r, 0xAA, sizeof r);
    assert_status(sfd_ransacf(s->x_prev, s->x_curr, NULL, n, thr, conf, budget, rng,
                              null_inlier ? NULL : inlier, null_out ? NULL : &r),
                  expected);
    for (size_t i = 0; i < sizeof inlier; ++i) assert_int_equal(inlier[i], 0xAA);
    const unsigned char *rb = (const unsigned char *)&r;
    for (size_t i = 0; i < sizeof r; ++i) assert_int_equal(rb[i], 0xAA);
}

/* GIVEN each bad argument in turn WHEN running THEN its status (SFD_ERR_INVAL for nulls, n < 0,
 * bad threshold/confidence, max_hypotheses < 1, non-finite coordinates; SFD_ERR_CAPACITY for
 * n > SFD_MAX_FEATURES or max_hypotheses > SFD_MAX_HYPOTHESES, as sfd_params_validate) with
 * nothing written; a valid call writes exactly n flags. */
static void ransacf_invalid_arguments_rejected_no_write_past_arrays(void **state) {
    (void)state;
    SFD_REQ("SFD-FMAT-015");
    sfd_prng_t gen, rng;
    sfd_prng_seed(&gen, 15);
    sfd_prng_seed(&rng, 150);
    static scene_t s;
    scene_opts_t o = kGeneric;
    o.sigma_px = 0.5;
    make_scene(&gen, &o, kMaxPts, &s);
    const double thr = 2.0;
    sfd_ransacf_result_t r;
    uint8_t inl[8];
    assert_status(sfd_ransacf(NULL, s.x_curr, NULL, 50, thr, 0.99, 10, &rng, inl, &r),
                  SFD_ERR_INVAL);
    assert_status(sfd_ransacf(s.x_prev, NULL, NULL, 50, thr, 0.99, 10, &rng, inl, &r),
                  SFD_ERR_INVAL);
    assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, 50, thr, 0.99, 10, NULL, inl, &r),
                  SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 0.99, 10, &rng, 1, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 0.99, 10, &rng, 0, 1, SFD_ERR_INVAL);
    expect_rejected(&s, -1, thr, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, 0.0, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, -1.0, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, NAN, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, INFINITY, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 0.0, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 1.0, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, NAN, 10, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 0.99, 0, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 0.99, -5, &rng, 0, 0, SFD_ERR_INVAL);
    expect_rejected(&s, 50, thr, 0.99, SFD_MAX_HYPOTHESES + 1, &rng, 0, 0, SFD_ERR_CAPACITY);
    expect_rejected(&s, kMaxPts + 1, thr, 0.99, 10, &rng, 0, 0, SFD_ERR_CAPACITY);
    static scene_t b;
    b = s;
    b.x_curr[33][0] = NAN;
    expect_rejected(&b, 50, thr, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    b.x_curr[33][0] = s.x_curr[33][0];
    b.x_prev[49][1] = INFINITY;
    expect_rejected(&b, 50, thr, 0.99, 10, &rng, 0, 0, SFD_ERR_INVAL);
    /* valid, at full capacity and below: flags written for [0, n) only */
    static uint8_t inlier[kMaxPts + 16];
    const int32_t ns[2] = {kMaxPts, 37};
    for (int c = 0; c < 2; ++c) {
        memset(inlier, 0xAA, sizeof inlier);
        assert_status(sfd_ransacf(s.x_prev, s.x_curr, NULL, ns[c], chi2_threshold(0.5, 0.01), 0.99,
                                  SFD_MAX_HYPOTHESES, &rng, inlier, &r),
                      SFD_OK);
        for (int i = 0; i < ns[c]; ++i) assert_true(inlier[i] <= 1);
        for (int i = ns[c]; i < kMaxPts + 16; ++i) assert_int_equal(inlier[i], 0xAA);
    }
}

/* ------------------------------------------------------------------------------------------
 * Pixel noise through the distortion Jacobian (issue 17 item 4)
 * ---------------------------------------------------------------------------------------- */

/* Rates of a Sampson test at alpha = 1 % on matches near the edges of a distorted image. */
typedef struct {
    long n, over_cov, over_iso;
    double mean_cov, mean_iso;
} edge_rates_t;

/* One clean match seen by the EuRoC cam0 (radtan) from two cameras X_prev = X_curr + t: the
 * previous raw pixel is drawn in the 60 px border band of the 752 x 480 image, depth 3-10 m;
 * both raw pixels get isotropic N(0, sigma^2) noise, are undistorted and judged against the true
 * F = K^-T [t]x K^-1 (eq. 26 with R = I) by the Sampson distance with the Jacobian covariances
 * (sfd_sampson_cov_sq_px2) and with isotropic noise (sfd_sampson_sq_px2). */
static edge_rates_t edge_sampson_rates(long n_matches, double sigma, uint64_t seed) {
    sfd_camera_t cam;
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 752, 480, kEurocFx, kEurocFy,
                                  kEurocCx, kEurocCy, kEurocRadtan),
                  SFD_OK);
    const double t[3] = {0.25, 0.04, 0.05};
    /* F = K^-T [t]x K^-1 */
    const double Ki[9] = {
        1.0 / kEurocFx, 0, -kEurocCx / kEurocFx, 0, 1.0 / kEurocFy, -kEurocCy / kEurocFy, 0, 0, 1};
    const double tx[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0};
    double A[9], F[9];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            A[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k) A[3 * r + c] += tx[3 * r + k] * Ki[3 * k + c];
        }
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            F[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k) F[3 * r + c] += Ki[3 * k + r] * A[3 * k + c];
        }
    double q = 0.0;
    assert_status(sfd_chi2_quantile_upper(0.01, 1, &q), SFD_OK);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed);
    edge_rates_t out = {0, 0, 0, 0.0, 0.0};
    for (long tries = 0; out.n < n_matches && tries < 20 * n_matches; ++tries) {
        double raw0[2];
        do { /* uniform in the image, kept when within 60 px of a border */
            raw0[0] = 752.0 * sfd_prng_uniform(&rng);
            raw0[1] = 480.0 * sfd_prng_uniform(&rng);
        } while (raw0[0] > 60.0 && raw0[0] < 692.0 && raw0[1] > 60.0 && raw0[1] < 420.0);
        double ray[3];
        if (sfd_camera_unproject(&cam, raw0, ray) != SFD_OK) continue;
        const double depth = 3.0 + 7.0 * sfd_prng_uniform(&rng);
        const double X_curr[3] = {ray[0] * depth - t[0], ray[1] * depth - t[1], depth - t[2]};
        double raw1[2];
        if (sfd_camera_project(&cam, X_curr, raw1, NULL) != SFD_OK || raw1[0] < 0.0 ||
            raw1[0] > 752.0 || raw1[1] < 0.0 || raw1[1] > 480.0) {
            continue;
        }
        double uv[2][2];
        sfd_pixel_noise_t noise;
        double *raw[2] = {raw0, raw1};
        float *dc[2] = {noise.prev_dC, noise.curr_dC};
        int ok = 1;
        for (int f = 0; f < 2 && ok; ++f) {
            const double noisy[2] = {raw[f][0] + sigma * sfd_prng_gaussian(&rng),
                                     raw[f][1] + sigma * sfd_prng_gaussian(&rng)};
            double xn[2];
            ok = sfd_camera_undistort(&cam, noisy, xn, NULL) == SFD_OK &&
                 sfd_camera_pixel_noise(&cam, xn, dc[f]) == SFD_OK;
            uv[f][0] = kEurocFx * xn[0] + kEurocCx;
            uv[f][1] = kEurocFy * xn[1] + kEurocCy;
        }
        if (!ok) continue;
        const double d_cov = sfd_sampson_cov_sq_px2(F, uv[0], uv[1], &noise) / (sigma * sigma);
        const double d_iso = sfd_sampson_sq_px2(F, uv[0], uv[1]) / (sigma * sigma);
        out.n++;
        out.over_cov += d_cov > q;
        out.over_iso += d_iso > q;
        out.mean_cov += d_cov;
        out.mean_iso += d_iso;
    }
    assert_int_equal(out.n, n_matches);
    out.mean_cov /= (double)out.n;
    out.mean_iso /= (double)out.n;
    return out;
}

/* GIVEN 20000 clean matches within 60 px of the border of the EuRoC cam0 (radtan) image, with
 * 1 px isotropic noise in raw pixels (seed 17) WHEN the Sampson distance is normalized with the
 * covariances carried through the distortion Jacobian THEN its rate above chi2_{1,0.99} is inside
 * the 99 % binomial interval of alpha = 1 % and its mean inside the 99 % interval of chi2(1)'s
 * mean 1; with isotropic noise in undistorted pixels (the former model) both are far above
 * (measured: Jacobian 0.97 % and 1.008, isotropic 6.0 % and 1.87), so the test can fail. */
static void sampson_with_distortion_jacobian_is_calibrated_at_the_image_edge(void **state) {
    (void)state;
    const long n = 20000;
    const edge_rates_t r = edge_sampson_rates(n, 1.0, 17U);
    const double alpha = 0.01;
    const double half = 2.576 * sqrt(alpha * (1.0 - alpha) / (double)n);
    const double rate_cov = (double)r.over_cov / (double)n;
    const double rate_iso = (double)r.over_iso / (double)n;
    const double mean_half = 2.576 * sqrt(2.0 / (double)n); /* chi2(1): variance 2 */
    printf(
        "edge Sampson: Jacobian rate %.4f mean %.3f; isotropic rate %.4f mean %.3f "
        "(99%% interval %.4f..%.4f)\n",
        rate_cov, r.mean_cov, rate_iso, r.mean_iso, alpha - half, alpha + half);
    assert_true(fabs(rate_cov - alpha) <= half);
    assert_true(fabs(r.mean_cov - 1.0) <= mean_half);
    assert_true(rate_iso > alpha + half);
    assert_true(r.mean_iso > 1.0 + mean_half);
}

/* GIVEN a pinhole camera WHEN the pixel noise is computed THEN it is exactly zero (C = I), and
 * the Sampson distance with it equals the isotropic one bit for bit. */
static void sampson_with_pinhole_noise_equals_isotropic_bit_for_bit(void **state) {
    (void)state;
    sfd_camera_t cam;
    const double zero[4] = {0, 0, 0, 0};
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 752, 480, kEurocFx, kEurocFy,
                                  kEurocCx, kEurocCy, zero),
                  SFD_OK);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 5U);
    const double F[9] = {1e-7, -3e-6, 1e-3, 4e-6, 2e-7, -2e-3, -1e-3, 2e-3, 0.01};
    for (int k = 0; k < 1000; ++k) {
        const double xn[2] = {sfd_prng_uniform(&rng) - 0.5, sfd_prng_uniform(&rng) - 0.5};
        sfd_pixel_noise_t nz;
        memset(&nz, 0xFF, sizeof nz);
        assert_status(sfd_camera_pixel_noise(&cam, xn, nz.prev_dC), SFD_OK);
        assert_status(sfd_camera_pixel_noise(&cam, xn, nz.curr_dC), SFD_OK);
        for (int j = 0; j < 3; ++j) assert_true(nz.prev_dC[j] == 0.0F && nz.curr_dC[j] == 0.0F);
        const double x1[2] = {752.0 * sfd_prng_uniform(&rng), 480.0 * sfd_prng_uniform(&rng)};
        const double x2[2] = {752.0 * sfd_prng_uniform(&rng), 480.0 * sfd_prng_uniform(&rng)};
        const double a = sfd_sampson_sq_px2(F, x1, x2);
        const double b = sfd_sampson_cov_sq_px2(F, x1, x2, &nz);
        assert_memory_equal(&a, &b, sizeof a);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(synthetic_scene_satisfies_eq25_convention),
        cmocka_unit_test(fundamental_8point_noise_free_8_matches_recovers_true_F),
        cmocka_unit_test(fundamental_8point_noisy_100_matches_sampson_near_sigma2),
        cmocka_unit_test(fundamental_8point_result_has_rank_2_and_unit_norm),
        cmocka_unit_test(fundamental_8point_covariant_under_image_similarities),
        cmocka_unit_test(sampson_equals_true_squared_distance_to_first_order),
        cmocka_unit_test(sampson_degenerate_inputs_return_infinity),
        cmocka_unit_test(fundamental_8point_degenerate_configurations_return_numeric),
        cmocka_unit_test(fundamental_8point_invalid_arguments_rejected),
        cmocka_unit_test(ransacf_30pct_outliers_recall_095_outlier_precision_090),
        cmocka_unit_test(ransacf_adapts_hypothesis_count_by_eq27),
        cmocka_unit_test(ransacf_all_outliers_budget_never_exceeded),
        cmocka_unit_test(ransacf_no_outliers_every_match_kept),
        cmocka_unit_test(ransacf_same_seed_identical_output),
        cmocka_unit_test(ransacf_fewer_than_8_matches_range_all_untested),
        cmocka_unit_test(ransacf_all_samples_degenerate_numeric_all_untested),
        cmocka_unit_test(ransacf_invalid_arguments_rejected_no_write_past_arrays),
        cmocka_unit_test(sampson_with_distortion_jacobian_is_calibrated_at_the_image_edge),
        cmocka_unit_test(sampson_with_pinhole_noise_equals_isotropic_bit_for_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
