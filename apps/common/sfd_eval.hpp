// SPDX-License-Identifier: MIT
// One evaluation for every sfd tool (sfd-replay's summary, sfd-bench's tables, sfd-hil's latency
// statistics; the Python reports read sfd-replay's numbers instead of recomputing them):
//
//  - order statistics with one percentile rule (nearest rank);
//  - detection scores with one rule for every method: every labelled observation counts, and a
//    spurious observation left UNTESTED (or in a frame that got no verdict) is a miss;
//  - trajectory errors of a VIO estimate against ground truth: ATE after the 4-DOF
//    position + yaw alignment (what rpg_trajectory_evaluation calls "posyaw", the alignment a
//    visual-inertial estimate that starts at rest allows), the raw RMSE, the final drift as a
//    percentage of the distance travelled, relative errors over 1 s and 10 m segments, and the
//    NEES of the position against the filter's reported variances.
//
// The formulas are written out at each declaration and in docs/evaluation.md. Host-side code
// (std::vector), not part of the flight core.
#ifndef SFD_APP_EVAL_HPP
#define SFD_APP_EVAL_HPP

#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace sfdeval {

/// "Not defined" in every score below (no samples, empty denominator); JSON writes it as null.
constexpr double kUndefined = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Order statistics

/// Nearest-rank percentile of ascending samples: the smallest sample x with at least q·n samples
/// at or below it, x_(ceil(q n)) (1-based), x_(1) for q = 0. numpy's
/// percentile(x, 100 q, method="inverted_cdf") is the same rule. kUndefined for no samples.
double percentile_sorted(const std::vector<double> &ascending, double q);

/// Summary of a sample: nearest-rank percentiles, mean, and the sample standard deviation
/// (n − 1 in the denominator; 0 for one sample). Every field kUndefined for no samples.
struct Spread {
    size_t n = 0;
    double min = kUndefined, median = kUndefined, p99 = kUndefined, p999 = kUndefined;
    double max = kUndefined, mean = kUndefined, sd = kUndefined;
};
Spread spread_of(std::vector<double> samples);

// ---------------------------------------------------------------------------------------------
// Detection

/// What made an observation spurious (TRUTH kind[]; truth_t's KIND_* numbering).
enum Kind { kClean = 0, kJump, kDrift, kMoving, kMismatch, kUnspecified, kNumKinds };
/// "clean", "jump", "drift", "moving", "mismatch", "unspecified"; "unknown" out of range.
const char *kind_name(int kind);

/// Verdict status (feature_verdict_t's numbering).
enum Status { kUntested = 0, kConsistent = 1, kSpurious = 2 };

/// Counts over labelled observations (one feature in one frame with a TRUTH label).
struct DetectionCounts {
    long tp = 0;                         // spurious, judged SPURIOUS
    long fp = 0;                         // clean, judged SPURIOUS
    long tn = 0;                         // clean, judged CONSISTENT
    long fn = 0;                         // spurious, judged CONSISTENT
    long untested_spurious = 0;          // spurious, UNTESTED or without a verdict: a miss
    long untested_clean = 0;             // clean, UNTESTED or without a verdict
    long kind_spurious[kNumKinds] = {};  // spurious observations per kind
    long kind_detected[kNumKinds] = {};  // of those, judged SPURIOUS
    long kind_untested[kNumKinds] = {};  // of those, UNTESTED or without a verdict

    /// One labelled observation: its TRUTH kind (kClean when not spurious; an out-of-range kind
    /// of a spurious observation counts as kUnspecified) and its verdict status (any value other
    /// than kConsistent and kSpurious counts as untested).
    void add(int kind, int status);
    /// Labelled observations of one frame: TRUTH's ids and kinds against the verdict's ids and
    /// statuses, matched by track id (the first verdict entry of an id; a labelled id the verdict
    /// does not list counts as untested). A frame without a verdict: pass empty verdict arrays.
    void add_frame(const std::vector<int64_t> &truth_ids, const std::vector<int8_t> &truth_kinds,
                   const std::vector<int64_t> &verdict_ids,
                   const std::vector<int8_t> &verdict_status);
    DetectionCounts &operator+=(const DetectionCounts &o);

    long spurious() const { return tp + fn + untested_spurious; }
    long clean() const { return fp + tn + untested_clean; }
    long labelled() const { return spurious() + clean(); }
};

/// Fault events and how soon each is caught. An event is a maximal run of one track's
/// observations labelled with one spurious kind in consecutive frames (the frames TRUTH lists, in
/// time order; a frame without the track, or with another label, ends it). It is caught within W
/// frames when one of its own observations at most W - 1 frames after its first is judged
/// SPURIOUS (a verdict on a frame its label no longer covers does not count; UNTESTED is not a
/// catch). W takes the values of kCatchWindows. An id TRUTH lists twice in one frame counts once
/// (its first entry).
struct FaultEvents {
    static constexpr int kWindows = 4;
    static constexpr int kCatchWindows[kWindows] = {1, 3, 5, 10};
    long events[kNumKinds] = {};            // events per kind
    long caught[kNumKinds][kWindows] = {};  // of those, caught within kCatchWindows[w] frames

    /// The labelled observations of the next frame, as DetectionCounts::add_frame() takes them.
    void add_frame(const std::vector<int64_t> &truth_ids, const std::vector<int8_t> &truth_kinds,
                   const std::vector<int64_t> &verdict_ids,
                   const std::vector<int8_t> &verdict_status);
    /// caught[kind][w] / events[kind]; kUndefined without events.
    double fraction(int kind, int w) const;

  private:
    struct Run {
        int kind = kClean;
        long first = 0, last = -2;  // frame indices of its first and latest observation
        bool caught = false;
    };
    std::unordered_map<int64_t, Run> runs_;
    long frame_ = 0;
};

/// Scores of one set of counts (kUndefined where the denominator is empty):
///   precision               = TP / (TP + FP)
///   recall (strict)         = TP / (TP + FN + untested spurious)
///   F1                      = 2 TP / (2 TP + FP + FN + untested spurious)
///                             (the harmonic mean of the two above where both exist; 0 when
///                             there are spurious observations and none is found)
///   false-alarm rate        = FP / (every clean observation, tested or not)
///   coverage                = tested labelled observations / labelled observations
///   recall_tested           = TP / (TP + FN)        (the lenient recall, beside the strict one)
///   false_alarm_rate_tested = FP / (FP + TN)
///   kind_recall[k]          = judged SPURIOUS / spurious observations of kind k (strict)
struct DetectionScores {
    double precision = kUndefined, recall = kUndefined, f1 = kUndefined;
    double false_alarm_rate = kUndefined, coverage = kUndefined;
    double recall_tested = kUndefined, false_alarm_rate_tested = kUndefined;
    double kind_recall[kNumKinds] = {kUndefined, kUndefined, kUndefined,
                                     kUndefined, kUndefined, kUndefined};
};
DetectionScores score(const DetectionCounts &c);

// ---------------------------------------------------------------------------------------------
// Trajectory

/// A pose at a frame time: IMU position and orientation (unit quaternion w, x, y, z, IMU to
/// world) in some world frame; the estimate may add its position variances (world axes, m²).
struct Pose {
    int64_t t_us = 0;
    double p[3] = {0, 0, 0};
    double q[4] = {1, 0, 0, 0};
    double var[3] = {0, 0, 0};
    bool has_var = false;
};

/// A rotation about the world's z axis and a translation: x ↦ R_z(yaw) x + t.
struct PosYaw {
    double yaw_rad = 0.0;
    double t[3] = {0, 0, 0};
    void apply(const double x[3], double out[3]) const;
};

/// Least-squares 4-DOF alignment of the estimate onto the truth over matched positions
/// (est[i] and truth[i] at the same time): minimizes Σ_i |R_z(ψ) e_i + t − g_i|². With the
/// centred positions e'_i = e_i − ē, g'_i = g_i − ḡ:
///   ψ = atan2(Σ (e'_x g'_y − e'_y g'_x), Σ (e'_x g'_x + e'_y g'_y)),   t = ḡ − R_z(ψ) ē
/// (the closed form of rpg_trajectory_evaluation's posyaw alignment, Umeyama restricted to yaw).
/// Fewer than 2 pairs or no horizontal spread: ψ = 0 and t from the means.
PosYaw align_posyaw(const std::vector<Pose> &est, const std::vector<Pose> &truth);

/// Alignment of one matched pose pair: ψ the yaw of R_g R_eᵀ (the rotation taking the estimate's
/// world to the truth's, projected on z: atan2(M₁₀ − M₀₁, M₀₀ + M₁₁) of M = R_g R_eᵀ), and t so
/// that the estimate's position lands on the truth's. The alignment at the first frame of an
/// at-rest start, and at the start of each relative-error segment.
PosYaw align_pose(const Pose &est, const Pose &truth);

struct SegmentErrors {
    long segments = 0;
    double mean_m = kUndefined, rmse_m = kUndefined;
    double mean_percent = kUndefined;  // mean of error / segment length (distance segments)
};

struct TrajectoryErrors {
    long frames = 0;                 // matched pairs
    double distance_m = 0.0;         // path length of the truth over them
    double rmse_raw_m = kUndefined;  // no alignment (meaningful when the filter started from TRUTH)
    double ate_m = kUndefined;       // RMSE after align_posyaw
    PosYaw alignment;                // align_posyaw's result
    double final_error_m = kUndefined;  // last frame, aligned at the first pose (align_pose)
    double drift_percent = kUndefined;  // 100 final_error / distance (distance ≥ 1 m)
    SegmentErrors rpe_1s;   // every start frame i, end j the first with t_j − t_i ≥ 1 s
    SegmentErrors rpe_10m;  // every start frame i, end j the first with path(i, j) ≥ 10 m
    long nees_frames = 0;   // frames whose estimate has three positive variances
    double nees_mean = kUndefined;
    double nees_in_band_95 = kUndefined;  // fraction inside χ²(3)'s [2.5 %, 97.5 %] quantiles
};

/// Trajectory errors of matched pairs (est[i], truth[i] at the same time, ascending).
/// Segment error: with the alignment A_i = align_pose(est[i], truth[i]),
///   e_ij = |R_z(ψ_i)(p_e,j − p_e,i) − (p_g,j − p_g,i)|.
/// NEES: the truth mapped into the estimate's frame by the inverse of the first-pose alignment
/// (the frame an at-rest start defines, position 0, yaw 0, in which the filter's variances are
/// expressed), ε = Σ_k (p_e,k − p_g,k)² / var_k over the three axes; only the variances'
/// diagonal is on the wire, so ε ignores their correlations (say so wherever it is shown).
TrajectoryErrors evaluate_trajectory(const std::vector<Pose> &est, const std::vector<Pose> &truth);

}  // namespace sfdeval

#endif
