// SPDX-License-Identifier: MIT
// One evaluation for every sfd tool: see sfd_eval.hpp for the formulas.
#include "sfd_eval.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "sfd/sfd_rotation.h"

namespace sfdeval {

double percentile_sorted(const std::vector<double> &ascending, double q) {
    if (ascending.empty()) return kUndefined;
    const double n = double(ascending.size());
    const double r = std::ceil(std::min(1.0, std::max(0.0, q)) * n);
    const size_t rank = r < 1.0 ? 1 : size_t(r);
    return ascending[std::min(ascending.size(), rank) - 1];
}

Spread spread_of(std::vector<double> v) {
    Spread s;
    s.n = v.size();
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    s.min = v.front();
    s.max = v.back();
    s.median = percentile_sorted(v, 0.5);
    s.p99 = percentile_sorted(v, 0.99);
    s.p999 = percentile_sorted(v, 0.999);
    double sum = 0.0;
    for (const double x : v) sum += x;
    s.mean = sum / double(v.size());
    double ss = 0.0;
    for (const double x : v) ss += (x - s.mean) * (x - s.mean);
    s.sd = v.size() > 1 ? std::sqrt(ss / double(v.size() - 1)) : 0.0;
    return s;
}

const char *kind_name(int kind) {
    static const char *const names[kNumKinds] = {"clean",  "jump",     "drift",
                                                 "moving", "mismatch", "unspecified"};
    return kind >= 0 && kind < kNumKinds ? names[kind] : "unknown";
}

void DetectionCounts::add(int kind, int status) {
    const bool tested = status == kConsistent || status == kSpurious;
    if (kind == kClean) {
        if (!tested) {
            ++untested_clean;
        } else if (status == kSpurious) {
            ++fp;
        } else {
            ++tn;
        }
        return;
    }
    const int k = kind > kClean && kind < kNumKinds ? kind : kUnspecified;
    ++kind_spurious[k];
    if (!tested) {
        ++untested_spurious;
        ++kind_untested[k];
    } else if (status == kSpurious) {
        ++tp;
        ++kind_detected[k];
    } else {
        ++fn;
    }
}

namespace {

// A frame's verdict status by track id: the first entry of an id.
std::unordered_map<int64_t, int8_t> status_by_id(const std::vector<int64_t> &verdict_ids,
                                                 const std::vector<int8_t> &verdict_status) {
    std::unordered_map<int64_t, int8_t> status;
    status.reserve(verdict_ids.size());
    for (size_t i = 0; i < verdict_ids.size() && i < verdict_status.size(); ++i) {
        status.emplace(verdict_ids[i], verdict_status[i]);
    }
    return status;
}

}  // namespace

void DetectionCounts::add_frame(const std::vector<int64_t> &truth_ids,
                                const std::vector<int8_t> &truth_kinds,
                                const std::vector<int64_t> &verdict_ids,
                                const std::vector<int8_t> &verdict_status) {
    const std::unordered_map<int64_t, int8_t> status = status_by_id(verdict_ids, verdict_status);
    for (size_t i = 0; i < truth_ids.size() && i < truth_kinds.size(); ++i) {
        const auto it = status.find(truth_ids[i]);
        add(truth_kinds[i], it == status.end() ? int(kUntested) : int(it->second));
    }
}

namespace {

// A TRUTH kind as the scores count it: kClean, or a spurious kind (out of range: kUnspecified).
int spurious_kind(int kind) {
    if (kind == kClean) return kClean;
    return (kind < kJump || kind >= kNumKinds) ? int(kUnspecified) : kind;
}

}  // namespace

void FaultEvents::add_frame(const std::vector<int64_t> &truth_ids,
                            const std::vector<int8_t> &truth_kinds,
                            const std::vector<int64_t> &verdict_ids,
                            const std::vector<int8_t> &verdict_status) {
    const std::unordered_map<int64_t, int8_t> status = status_by_id(verdict_ids, verdict_status);
    std::unordered_set<int64_t> seen;  // an id TRUTH lists twice in a frame: its first entry
    seen.reserve(truth_ids.size());
    for (size_t i = 0; i < truth_ids.size() && i < truth_kinds.size(); ++i) {
        if (!seen.insert(truth_ids[i]).second) continue;
        const int kind = spurious_kind(truth_kinds[i]);
        if (kind == kClean) {
            runs_.erase(truth_ids[i]);
            continue;
        }
        Run &r = runs_[truth_ids[i]];
        if (r.kind != kind || r.last != frame_ - 1) {  // a new event
            r = Run{};
            r.kind = kind;
            r.first = frame_;
            ++events[kind];
        }
        r.last = frame_;
        const auto it = status.find(truth_ids[i]);
        if (!r.caught && it != status.end() && it->second == kSpurious) {
            r.caught = true;
            const long latency = frame_ - r.first;
            for (int w = 0; w < kWindows; ++w) {
                if (latency < kCatchWindows[w]) ++caught[kind][w];
            }
        }
    }
    ++frame_;
}

double FaultEvents::fraction(int kind, int w) const {
    if (kind < 0 || kind >= kNumKinds || w < 0 || w >= kWindows || events[kind] == 0) {
        return kUndefined;
    }
    return double(caught[kind][w]) / double(events[kind]);
}

DetectionCounts &DetectionCounts::operator+=(const DetectionCounts &o) {
    tp += o.tp;
    fp += o.fp;
    tn += o.tn;
    fn += o.fn;
    untested_spurious += o.untested_spurious;
    untested_clean += o.untested_clean;
    for (int k = 0; k < kNumKinds; ++k) {
        kind_spurious[k] += o.kind_spurious[k];
        kind_detected[k] += o.kind_detected[k];
        kind_untested[k] += o.kind_untested[k];
    }
    return *this;
}

namespace {

double ratio(long num, long den) {
    return den > 0 ? double(num) / double(den) : kUndefined;
}

}  // namespace

DetectionScores score(const DetectionCounts &c) {
    DetectionScores s;
    s.precision = ratio(c.tp, c.tp + c.fp);
    s.recall = ratio(c.tp, c.spurious());
    s.f1 = ratio(2 * c.tp, 2 * c.tp + c.fp + c.fn + c.untested_spurious);
    s.false_alarm_rate = ratio(c.fp, c.clean());
    s.coverage = ratio(c.labelled() - c.untested_spurious - c.untested_clean, c.labelled());
    s.recall_tested = ratio(c.tp, c.tp + c.fn);
    s.false_alarm_rate_tested = ratio(c.fp, c.fp + c.tn);
    for (int k = 0; k < kNumKinds; ++k) {
        s.kind_recall[k] = k == kClean ? kUndefined : ratio(c.kind_detected[k], c.kind_spurious[k]);
    }
    return s;
}

void PosYaw::apply(const double x[3], double out[3]) const {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    const double x0 = x[0], x1 = x[1], x2 = x[2];
    out[0] = c * x0 - s * x1 + t[0];
    out[1] = s * x0 + c * x1 + t[1];
    out[2] = x2 + t[2];
}

namespace {

// Rotation matrix (row-major) of a quaternion (w, x, y, z), normalised first by the core's
// rotation module; the identity for a quaternion that cannot be normalised (zero, non-finite).
void rotation_of(const double q_in[4], double R[9]) {
    double q[4] = {q_in[0], q_in[1], q_in[2], q_in[3]};
    if (sfd_quat_normalize(q) != SFD_OK || sfd_quat_to_rotmat(q, R) != SFD_OK) {
        for (int k = 0; k < 9; ++k) R[k] = (k % 4 == 0) ? 1.0 : 0.0;
    }
}

double norm3(const double a[3]) {
    return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

// χ²(3) quantiles 0.025 and 0.975.
constexpr double kChi2_3_lo = 0.2157952826;
constexpr double kChi2_3_hi = 9.3484036045;

// |R_z(ψ_i)(p_e,j − p_e,i) − (p_g,j − p_g,i)|.
double segment_error(const Pose &ei, const Pose &ej, const Pose &gi, const Pose &gj) {
    PosYaw a = align_pose(ei, gi);
    a.t[0] = a.t[1] = a.t[2] = 0.0;
    const double de[3] = {ej.p[0] - ei.p[0], ej.p[1] - ei.p[1], ej.p[2] - ei.p[2]};
    double r[3];
    a.apply(de, r);
    const double d[3] = {r[0] - (gj.p[0] - gi.p[0]), r[1] - (gj.p[1] - gi.p[1]),
                         r[2] - (gj.p[2] - gi.p[2])};
    return norm3(d);
}

void finish_segments(const std::vector<double> &err, const std::vector<double> &len,
                     SegmentErrors *out) {
    out->segments = long(err.size());
    if (err.empty()) return;
    double sum = 0.0, ss = 0.0, pct = 0.0;
    for (size_t i = 0; i < err.size(); ++i) {
        sum += err[i];
        ss += err[i] * err[i];
        pct += len.empty() ? 0.0 : 100.0 * err[i] / len[i];
    }
    out->mean_m = sum / double(err.size());
    out->rmse_m = std::sqrt(ss / double(err.size()));
    if (!len.empty()) out->mean_percent = pct / double(err.size());
}

}  // namespace

PosYaw align_posyaw(const std::vector<Pose> &est, const std::vector<Pose> &truth) {
    PosYaw a;
    const size_t n = std::min(est.size(), truth.size());
    if (n == 0) return a;
    double me[3] = {0, 0, 0}, mg[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            me[k] += est[i].p[k];
            mg[k] += truth[i].p[k];
        }
    }
    for (int k = 0; k < 3; ++k) {
        me[k] /= double(n);
        mg[k] /= double(n);
    }
    double sin_sum = 0.0, cos_sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double ex = est[i].p[0] - me[0], ey = est[i].p[1] - me[1];
        const double gx = truth[i].p[0] - mg[0], gy = truth[i].p[1] - mg[1];
        sin_sum += ex * gy - ey * gx;
        cos_sum += ex * gx + ey * gy;
    }
    a.yaw_rad = (sin_sum == 0.0 && cos_sum == 0.0) ? 0.0 : std::atan2(sin_sum, cos_sum);
    const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
    a.t[0] = mg[0] - (c * me[0] - s * me[1]);
    a.t[1] = mg[1] - (s * me[0] + c * me[1]);
    a.t[2] = mg[2] - me[2];
    return a;
}

PosYaw align_pose(const Pose &est, const Pose &truth) {
    double Re[9], Rg[9], M[9];
    rotation_of(est.q, Re);
    rotation_of(truth.q, Rg);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double v = 0.0;
            for (int k = 0; k < 3; ++k) v += Rg[3 * r + k] * Re[3 * c + k];  // R_g R_eᵀ
            M[3 * r + c] = v;
        }
    }
    PosYaw a;
    a.yaw_rad = std::atan2(M[3] - M[1], M[0] + M[4]);
    double r[3];
    a.apply(est.p, r);  // t = 0 so far: the estimate's position rotated
    for (int k = 0; k < 3; ++k) a.t[k] = truth.p[k] - r[k];
    return a;
}

TrajectoryErrors evaluate_trajectory(const std::vector<Pose> &est, const std::vector<Pose> &truth) {
    TrajectoryErrors e;
    const size_t n = std::min(est.size(), truth.size());
    e.frames = long(n);
    if (n == 0) return e;
    // Path length from the first frame (prefix sums) and the raw and aligned errors.
    std::vector<double> path(n, 0.0);
    for (size_t i = 1; i < n; ++i) {
        const double d[3] = {truth[i].p[0] - truth[i - 1].p[0], truth[i].p[1] - truth[i - 1].p[1],
                             truth[i].p[2] - truth[i - 1].p[2]};
        path[i] = path[i - 1] + norm3(d);
    }
    e.distance_m = path[n - 1];
    e.alignment = align_posyaw(est, truth);
    double se_raw = 0.0, se_ate = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double r[3];
        e.alignment.apply(est[i].p, r);
        for (int k = 0; k < 3; ++k) {
            const double d_raw = est[i].p[k] - truth[i].p[k], d = r[k] - truth[i].p[k];
            se_raw += d_raw * d_raw;
            se_ate += d * d;
        }
    }
    e.rmse_raw_m = std::sqrt(se_raw / double(n));
    e.ate_m = std::sqrt(se_ate / double(n));

    // Final drift, aligned at the first pose.
    const PosYaw first = align_pose(est[0], truth[0]);
    double last[3];
    first.apply(est[n - 1].p, last);
    const double dl[3] = {last[0] - truth[n - 1].p[0], last[1] - truth[n - 1].p[1],
                          last[2] - truth[n - 1].p[2]};
    e.final_error_m = norm3(dl);
    if (e.distance_m >= 1.0) e.drift_percent = 100.0 * e.final_error_m / e.distance_m;

    // Relative errors: 1 s and 10 m segments from every start frame.
    std::vector<double> err_t, err_d, len_d;
    size_t jt = 0, jd = 0;
    for (size_t i = 0; i < n; ++i) {
        jt = std::max(jt, i);
        while (jt < n && est[jt].t_us - est[i].t_us < 1000000) ++jt;
        if (jt < n) err_t.push_back(segment_error(est[i], est[jt], truth[i], truth[jt]));
        jd = std::max(jd, i);
        while (jd < n && path[jd] - path[i] < 10.0) ++jd;
        if (jd < n) {
            err_d.push_back(segment_error(est[i], est[jd], truth[i], truth[jd]));
            len_d.push_back(path[jd] - path[i]);
        }
    }
    finish_segments(err_t, {}, &e.rpe_1s);
    finish_segments(err_d, len_d, &e.rpe_10m);

    // NEES of the position in the estimate's frame (the inverse of the first-pose alignment).
    const double c = std::cos(first.yaw_rad), s = std::sin(first.yaw_rad);
    double nees_sum = 0.0;
    long in_band = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!est[i].has_var || !(est[i].var[0] > 0) || !(est[i].var[1] > 0) ||
            !(est[i].var[2] > 0)) {
            continue;
        }
        const double g[3] = {truth[i].p[0] - first.t[0], truth[i].p[1] - first.t[1],
                             truth[i].p[2] - first.t[2]};
        const double g_est[3] = {c * g[0] + s * g[1], -s * g[0] + c * g[1], g[2]};  // R_zᵀ g
        double eps = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double d = est[i].p[k] - g_est[k];
            eps += d * d / est[i].var[k];
        }
        nees_sum += eps;
        in_band += eps >= kChi2_3_lo && eps <= kChi2_3_hi;
        ++e.nees_frames;
    }
    if (e.nees_frames > 0) {
        e.nees_mean = nees_sum / double(e.nees_frames);
        e.nees_in_band_95 = double(in_band) / double(e.nees_frames);
    }
    return e;
}

}  // namespace sfdeval
