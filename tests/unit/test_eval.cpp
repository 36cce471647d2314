// SPDX-License-Identifier: MIT
// Unit tests of the one evaluation module (apps/common/sfd_eval.hpp): the nearest-rank percentile,
// the strict detection scores (an UNTESTED spurious observation is a miss), recall per fault kind,
// the 4-DOF position+yaw alignment, and the trajectory errors on hand-made trajectories whose
// answers are known in closed form.
#include <cmath>
#include <vector>

#include "sfd/sfd_prng.h"
#include "sfd_eval.hpp"

// cmocka last: its macros clash with the C++ standard headers.
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

extern "C" {
#include <cmocka.h>
}

namespace {

using sfdeval::Pose;

constexpr double kPi = 3.14159265358979323846;

Pose pose_at(int64_t t_us, double x, double y, double z, double yaw_rad) {
    Pose p;
    p.t_us = t_us;
    p.p[0] = x;
    p.p[1] = y;
    p.p[2] = z;
    p.q[0] = std::cos(0.5 * yaw_rad);
    p.q[3] = std::sin(0.5 * yaw_rad);
    return p;
}

// A 3-D path with horizontal spread: a helix-like curve, 20 Hz for `n` frames.
std::vector<Pose> curve(int n) {
    std::vector<Pose> v;
    for (int i = 0; i < n; ++i) {
        const double s = 0.05 * i;
        v.push_back(pose_at(int64_t(i) * 50000, 3.0 * std::cos(s) + 0.2 * s, 2.0 * std::sin(s),
                            0.5 * std::sin(0.7 * s), s));
    }
    return v;
}

// The estimate of `truth` in another world frame: x_e = R_z(−ψ)(x_g − t), yaw − ψ.
std::vector<Pose> seen_from(const std::vector<Pose> &truth, double psi, const double t[3]) {
    std::vector<Pose> v;
    const double c = std::cos(psi), s = std::sin(psi);
    for (const Pose &g : truth) {
        const double d[3] = {g.p[0] - t[0], g.p[1] - t[1], g.p[2] - t[2]};
        const double yaw = 2.0 * std::atan2(g.q[3], g.q[0]);
        v.push_back(pose_at(g.t_us, c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2], yaw - psi));
    }
    return v;
}

void percentile_is_nearest_rank(void **) {
    const std::vector<double> x = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    assert_true(sfdeval::percentile_sorted(x, 0.5) == 5.0);   // ceil(5) = rank 5
    assert_true(sfdeval::percentile_sorted(x, 0.51) == 6.0);  // ceil(5.1) = rank 6
    assert_true(sfdeval::percentile_sorted(x, 0.99) == 10.0);
    assert_true(sfdeval::percentile_sorted(x, 0.0) == 1.0);
    assert_true(sfdeval::percentile_sorted(x, 1.0) == 10.0);
    assert_true(std::isnan(sfdeval::percentile_sorted({}, 0.5)));
    std::vector<double> big;
    for (int i = 1000; i >= 1; --i) big.push_back(double(i));  // unsorted on purpose
    const sfdeval::Spread s = sfdeval::spread_of(big);
    assert_true(s.n == 1000 && s.min == 1.0 && s.max == 1000.0);
    assert_true(s.median == 500.0 && s.p99 == 990.0 && s.p999 == 999.0);
    assert_true(std::fabs(s.mean - 500.5) < 1e-12);
}

// 10 spurious observations (4 jump, 3 drift, 2 moving, 1 mismatch) and 90 clean ones with known
// verdicts: the strict recall counts the 3 untested spurious ones as misses, the lenient one not.
void strict_recall_counts_untested_spurious_as_misses(void **) {
    using namespace sfdeval;
    DetectionCounts c;
    // jump: 2 found, 1 missed, 1 untested; drift: 1 found, 2 untested; moving: 1 found, 1 missed;
    // mismatch: 1 found.
    c.add(kJump, kSpurious);
    c.add(kJump, kSpurious);
    c.add(kJump, kConsistent);
    c.add(kJump, kUntested);
    c.add(kDrift, kSpurious);
    c.add(kDrift, kUntested);
    c.add(kDrift, 7);  // an unknown status counts as untested
    c.add(kMoving, kSpurious);
    c.add(kMoving, kConsistent);
    c.add(kMismatch, kSpurious);
    for (int i = 0; i < 80; ++i) c.add(kClean, kConsistent);
    for (int i = 0; i < 4; ++i) c.add(kClean, kSpurious);
    for (int i = 0; i < 6; ++i) c.add(kClean, kUntested);
    assert_int_equal(c.tp, 5);
    assert_int_equal(c.fn, 2);
    assert_int_equal(c.untested_spurious, 3);
    assert_int_equal(c.fp, 4);
    assert_int_equal(c.tn, 80);
    assert_int_equal(c.untested_clean, 6);
    assert_int_equal(c.labelled(), 100);
    const DetectionScores s = score(c);
    assert_true(std::fabs(s.recall - 5.0 / 10.0) < 1e-15);        // strict: 5 of 10
    assert_true(std::fabs(s.recall_tested - 5.0 / 7.0) < 1e-15);  // lenient: 5 of 7 tested
    assert_true(std::fabs(s.precision - 5.0 / 9.0) < 1e-15);
    assert_true(std::fabs(s.f1 - 10.0 / (10.0 + 4 + 2 + 3)) < 1e-15);
    const double hm = 2 * s.precision * s.recall / (s.precision + s.recall);
    assert_true(std::fabs(s.f1 - hm) < 1e-15);  // = the harmonic mean of the strict pair
    assert_true(std::fabs(s.false_alarm_rate - 4.0 / 90.0) < 1e-15);
    assert_true(std::fabs(s.false_alarm_rate_tested - 4.0 / 84.0) < 1e-15);
    assert_true(std::fabs(s.coverage - 91.0 / 100.0) < 1e-15);
    assert_true(std::fabs(s.kind_recall[kJump] - 0.5) < 1e-15);
    assert_true(std::fabs(s.kind_recall[kDrift] - 1.0 / 3.0) < 1e-15);
    assert_true(std::fabs(s.kind_recall[kMoving] - 0.5) < 1e-15);
    assert_true(s.kind_recall[kMismatch] == 1.0);
    assert_true(std::isnan(s.kind_recall[kUnspecified]));
    assert_int_equal(c.kind_untested[kDrift], 2);
}

// A frame's TRUTH against its verdict by track id: a labelled feature missing from the verdict,
// or a frame with no verdict at all, is untested; verdict entries TRUTH does not label are not
// scored; an out-of-range kind of a spurious feature counts as unspecified.
void frames_match_verdicts_by_track_id(void **) {
    using namespace sfdeval;
    DetectionCounts c;
    c.add_frame({10, 11, 12, 13}, {kClean, kJump, kMoving, 9}, {13, 12, 10, 99},
                {kSpurious, kConsistent, kSpurious, kSpurious});
    assert_int_equal(c.fp, 1);                 // 10
    assert_int_equal(c.untested_spurious, 1);  // 11: not in the verdict
    assert_int_equal(c.fn, 1);                 // 12
    assert_int_equal(c.tp, 1);                 // 13, kind 9
    assert_int_equal(c.kind_detected[kUnspecified], 1);
    DetectionCounts d;
    d.add_frame({1, 2}, {kClean, kDrift}, {}, {});  // no verdict for the frame
    assert_int_equal(d.untested_clean, 1);
    assert_int_equal(d.untested_spurious, 1);
    c += d;
    assert_int_equal(c.labelled(), 6);
    const DetectionScores s = score(c);
    assert_true(std::fabs(s.recall - 1.0 / 4.0) < 1e-15);
    // Nothing labelled: every score undefined, none is 0.
    const DetectionScores e = score(DetectionCounts{});
    assert_true(std::isnan(e.precision) && std::isnan(e.recall) && std::isnan(e.f1));
    assert_true(std::isnan(e.false_alarm_rate) && std::isnan(e.coverage));
}

// Fault events (a track's run of one fault kind in consecutive frames) and how soon each is
// caught: by a SPURIOUS verdict on one of its own observations only (not UNTESTED, not a
// verdict after its label ends); a gap in the track's frames or a change of kind starts a new
// event; a catch counts in every window longer than its latency.
void fault_events_count_runs_and_their_latency(void **) {
    using namespace sfdeval;
    FaultEvents ev;
    // frame 0..11; track 1: drift in 0..4, caught at 2; track 2: drift in 0..1, gone in 2, drift
    // again in 3..4 (two events, neither caught: UNTESTED at 1, SPURIOUS only at 5 when clean);
    // track 3: jump at 0, then drift from 1 (two events; the drift caught at 1 + 0); track 4:
    // moving in 0..11, first caught at 11 (latency 11: in no window).
    for (int f = 0; f < 12; ++f) {
        std::vector<int64_t> ids;
        std::vector<int8_t> kinds;
        std::vector<int64_t> vids;
        std::vector<int8_t> vst;
        auto add = [&](int64_t id, int kind, int status) {
            ids.push_back(id);
            kinds.push_back(int8_t(kind));
            vids.push_back(id);
            vst.push_back(int8_t(status));
        };
        add(1, f <= 4 ? kDrift : kClean, f == 2 ? kSpurious : kConsistent);
        if (f != 2)
            add(2, f <= 4 ? kDrift : kClean,
                f == 1 ? kUntested : (f == 5 ? kSpurious : kConsistent));
        add(3, f == 0 ? kJump : (f <= 3 ? kDrift : kClean), f == 1 ? kSpurious : kConsistent);
        add(4, kMoving, f == 11 ? kSpurious : kConsistent);
        ev.add_frame(ids, kinds, vids, vst);
    }
    assert_int_equal(ev.events[kDrift], 4);  // track 1, track 2 twice, track 3
    assert_int_equal(ev.events[kJump], 1);
    assert_int_equal(ev.events[kMoving], 1);
    assert_int_equal(ev.caught[kDrift][0], 1);  // track 3 at latency 0
    assert_int_equal(ev.caught[kDrift][1], 2);  // and track 1 at latency 2
    assert_int_equal(ev.caught[kDrift][3], 2);
    assert_int_equal(ev.caught[kJump][3], 0);
    assert_int_equal(ev.caught[kMoving][3], 0);  // latency 11 > 10 frames
    assert_true(std::fabs(ev.fraction(kDrift, 3) - 0.5) < 1e-15);
    assert_true(std::isnan(ev.fraction(kMismatch, 3)));  // no event: undefined
    assert_true(std::isnan(ev.fraction(kDrift, 4)));     // no such window
    // An id TRUTH lists twice in one frame counts once: one event, its catch kept.
    FaultEvents dup;
    dup.add_frame({7, 7}, {kJump, kJump}, {7}, {kSpurious});
    dup.add_frame({7, 7}, {kJump, kClean}, {7}, {kConsistent});
    assert_int_equal(dup.events[kJump], 1);
    assert_int_equal(dup.caught[kJump][0], 1);
}

void posyaw_alignment_recovers_known_yaw_and_translation(void **) {
    const std::vector<Pose> truth = curve(300);
    const double cases[][4] = {{0.7, 1.5, -2.0, 0.3}, {-2.9, -10.0, 4.0, -1.0}, {kPi, 0, 0, 0}};
    for (const auto &k : cases) {
        const double t[3] = {k[1], k[2], k[3]};
        const std::vector<Pose> est = seen_from(truth, k[0], t);
        const sfdeval::PosYaw a = sfdeval::align_posyaw(est, truth);
        double dyaw = std::remainder(a.yaw_rad - k[0], 2 * kPi);
        assert_true(std::fabs(dyaw) < 1e-12);
        for (int i = 0; i < 3; ++i) assert_true(std::fabs(a.t[i] - t[i]) < 1e-9);
        const sfdeval::TrajectoryErrors e = sfdeval::evaluate_trajectory(est, truth);
        assert_true(e.ate_m < 1e-9);
        assert_true(e.rmse_raw_m > 1.0);  // the frames differ: the raw error is large
        assert_true(e.final_error_m < 1e-9 && e.drift_percent < 1e-9);
        assert_true(e.rpe_1s.rmse_m < 1e-9 && e.rpe_10m.segments > 0 && e.rpe_10m.rmse_m < 1e-9);
        // The first-pose alignment finds the same yaw from the orientations alone.
        const sfdeval::PosYaw f = sfdeval::align_pose(est[0], truth[0]);
        dyaw = std::remainder(f.yaw_rad - k[0], 2 * kPi);
        assert_true(std::fabs(dyaw) < 1e-12);
    }
}

// A roll/pitch difference must not leak into the yaw of the first-pose alignment.
void pose_alignment_takes_only_the_yaw(void **) {
    Pose g = pose_at(0, 1, 2, 3, 0.4);
    Pose e = pose_at(0, 0, 0, 0, 0.0);
    // e's orientation: R_x(0.2) (a tilt). R_g R_eᵀ = R_z(0.4) R_x(−0.2), whose
    // atan2(M₁₀ − M₀₁, M₀₀ + M₁₁) = atan2(s(1 + cos 0.2), c(1 + cos 0.2)) is exactly 0.4.
    e.q[0] = std::cos(0.1);
    e.q[1] = std::sin(0.1);
    e.q[3] = 0.0;
    const sfdeval::PosYaw a = sfdeval::align_pose(e, g);
    assert_true(std::fabs(a.yaw_rad - 0.4) < 1e-12);
    double out[3];
    a.apply(e.p, out);
    for (int k = 0; k < 3; ++k) assert_true(std::fabs(out[k] - g.p[k]) < 1e-12);
}

// A known error: the estimate is the truth plus a constant offset (1, 0, 0) m, then a linear
// drift; ATE, drift % and the 10 m segment errors follow in closed form.
void trajectory_errors_of_a_known_drift(void **) {
    // A straight line along x at 2 m/s, 20 Hz, 30 s: 60 m.
    std::vector<Pose> truth, est;
    for (int i = 0; i <= 600; ++i) {
        const double x = 0.1 * i;
        truth.push_back(pose_at(int64_t(i) * 50000, x, 0, 0, 0));
        est.push_back(pose_at(int64_t(i) * 50000, x, 0.01 * x, 0, 0));  // 1 % lateral drift
    }
    const sfdeval::TrajectoryErrors e = sfdeval::evaluate_trajectory(est, truth);
    assert_int_equal(e.frames, 601);
    assert_true(std::fabs(e.distance_m - 60.0) < 1e-9);
    assert_true(std::fabs(e.final_error_m - 0.6) < 1e-9);  // first-pose aligned: y = 0.6 m
    assert_true(std::fabs(e.drift_percent - 1.0) < 1e-9);
    // 10 m segments (10 or 10.1 m: the first frame at or past 10 m): error 1 % of the length.
    assert_true(std::fabs(e.rpe_10m.mean_m - 0.1) < 1.5e-3);
    assert_true(std::fabs(e.rpe_10m.mean_percent - 1.0) < 1e-9);
    // 1 s segments (2 m): 0.02 m each.
    assert_true(std::fabs(e.rpe_1s.rmse_m - 0.02) < 1e-9);
    // The posyaw alignment absorbs the drift by a rotation of −atan(0.01); what stays is the
    // length difference, √1.0001 − 1 ≈ 5e-5 of the centred positions (RMS 17.3 m): 0.9 mm.
    assert_true(e.ate_m > 5e-4 && e.ate_m < 1.5e-3);
    assert_true(std::fabs(e.alignment.yaw_rad + std::atan(0.01)) < 1e-12);
}

// NEES: with errors drawn from the reported variances, the mean is near 3 and ~95 % of frames are
// in the band; with variances 100× too small, the mean is ~300.
void position_nees_matches_the_reported_variances(void **) {
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 42);
    const std::vector<Pose> truth = curve(4000);
    std::vector<Pose> est = truth, over = truth;
    const double var[3] = {0.01, 0.04, 0.0025};
    for (size_t i = 0; i < est.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            const double d = std::sqrt(var[k]) * sfd_prng_gaussian(&rng);
            est[i].p[k] += d;
            est[i].var[k] = var[k];
            over[i].p[k] += d;
            over[i].var[k] = var[k] / 100.0;
        }
        est[i].has_var = over[i].has_var = true;
    }
    est[0] = truth[0];  // the first pose defines the alignment: exact
    est[0].has_var = false;
    over[0] = est[0];
    const sfdeval::TrajectoryErrors e = sfdeval::evaluate_trajectory(est, truth);
    assert_int_equal(e.nees_frames, 3999);
    // mean of 3999 χ²(3): sd sqrt(6/3999) = 0.039; ±0.15 is ~4 sd.
    assert_true(std::fabs(e.nees_mean - 3.0) < 0.15);
    assert_true(std::fabs(e.nees_in_band_95 - 0.95) < 0.015);  // binomial sd 0.0034
    const sfdeval::TrajectoryErrors o = sfdeval::evaluate_trajectory(over, truth);
    assert_true(o.nees_mean > 250.0 && o.nees_in_band_95 < 0.1);
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(percentile_is_nearest_rank),
        cmocka_unit_test(strict_recall_counts_untested_spurious_as_misses),
        cmocka_unit_test(frames_match_verdicts_by_track_id),
        cmocka_unit_test(fault_events_count_runs_and_their_latency),
        cmocka_unit_test(posyaw_alignment_recovers_known_yaw_and_translation),
        cmocka_unit_test(pose_alignment_takes_only_the_yaw),
        cmocka_unit_test(trajectory_errors_of_a_known_drift),
        cmocka_unit_test(position_nees_matches_the_reported_variances),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
