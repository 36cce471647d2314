// SPDX-License-Identifier: MIT
// The parity-space detector: sliding window of tracked features, deterministic grouping, group
// tests, isolation inside failing groups, verdicts (sfd/sfd_parity.h, core/docs/parity_space.md).
#include "float_round.h"
#include "core_private.hpp"
#include "parity_space.hpp"
#include "rotation.hpp"
#include "small_linalg.hpp"
#include "sfd/sfd_camera.h"
#include "sfd/sfd_parity.h"
#include "track_index.h"

namespace sfd {
namespace parity {
namespace {

constexpr uint32_t kMagic = 0x53464450u;  // "SFDP"
constexpr int kSlots = SFD_PARITY_HASH_SLOTS;
// The ring holds the newest SFD_MAX_WINDOW frames whatever L is: the parity window is the newest
// L of them, the evidence test (window-limited GLR) may reach back further.
constexpr int kRing = SFD_MAX_WINDOW;

// sfd_parity_obs_t.dir: no direction.
constexpr int8_t kNoDirection = INT8_MIN;

// The direction of (x, y) in one byte (parity_space.md "Directional hold"): the diamond angle
// a = t for x >= 0 and 2 - t, -2 - t for x < 0 and t >= 0, t < 0, with t = y / (|x| + |y|),
// a in [-2, 2] and monotonic in the angle, rounded to steps of 1 / 63.5 (-127..127).
// Arithmetic only (no trigonometry), so every target stores the same bits; the angle is kept
// to within half a degree. kNoDirection for a zero or non-finite vector.
int8_t encode_direction(double x, double y) {
    const double s = std::fabs(x) + std::fabs(y);
    if (!(s > 0.0) || !std::isfinite(s)) return kNoDirection;
    const double t = y / s;
    const double a = (x >= 0.0) ? t : ((t >= 0.0) ? 2.0 - t : -2.0 - t);
    const long q = std::lround(a * 63.5);
    return static_cast<int8_t>(q > 127 ? 127 : (q < -127 ? -127 : q));
}

// The direction encode_direction() stored, as a vector on the diamond |x| + |y| = 1 (its length
// does not matter to the one-sided statistic). False for kNoDirection.
bool decode_direction(int8_t q, double d[2]) {
    if (q == kNoDirection) return false;
    const double a = static_cast<double>(q) / 63.5;
    const double t = (a > 1.0) ? 2.0 - a : ((a < -1.0) ? -2.0 - a : a);
    d[0] = (a > 1.0 || a < -1.0) ? -(1.0 - std::fabs(t)) : 1.0 - std::fabs(t);
    d[1] = t;
    return true;
}

// Ring slot of the frame `back` frames before the newest (0 = newest), back < det.count.
int ring_index(const sfd_parity_t &det, int back) {
    return (det.head - back + kRing) % kRing;
}

// Index stored for `id` in table (over the n track ids of its frame), or -1 (track_index.h).
int hash_find(const int16_t *table, const int64_t *ids, int n, int64_t id) {
    const sfd_track_index_t t = sfd_track_index_view_i16(table, kSlots, ids, sizeof ids[0], n);
    return sfd_track_index_find(&t, id);
}

// The table has more than twice as many slots as a frame has features: never full.
void hash_insert(int16_t *table, int64_t id, int16_t index) {
    const sfd_track_index_t t = sfd_track_index_i16(table, kSlots, nullptr, 0, 0);
    (void)sfd_track_index_insert(&t, id, index);
}

// Spread-out ordering key: Morton (Z-order) code of the pixel position in 16-px cells. Walking
// the Z-curve visits the image region by region, so taking every G-th feature of that walk puts
// features of different regions into one group.
uint32_t morton_key(double u_px, double v_px) {
    // the raw pixels clamped into float's range, then rounded to float, as they were stored
    const float uv[2] = {clamp_to_float(u_px), clamp_to_float(v_px)};
    uint32_t c[2];
    for (int k = 0; k < 2; ++k) {
        double v = static_cast<double>(uv[k]) / 16.0;
        v = (v < 0.0) ? 0.0 : ((v > 65535.0) ? 65535.0 : v);
        c[k] = static_cast<uint32_t>(v);
    }
    uint32_t key = 0;
    for (int b = 0; b < 16; ++b) {
        key |= ((c[0] >> b) & 1u) << (2 * b);
        key |= ((c[1] >> b) & 1u) << (2 * b + 1);
    }
    return key;
}

// Heap sort of idx[0..n) by (key, track id): no recursion, O(n log n), deterministic.
struct SortView {
    const uint32_t *key;
    const int64_t *track_id;
    bool less(int16_t a, int16_t b) const {
        if (key[a] != key[b]) return key[a] < key[b];
        return track_id[a] < track_id[b];
    }
};

void sift_down(int16_t *idx, int start, int end, const SortView &v) {
    int root = start;
    for (int guard = 0; guard < 32 && 2 * root + 1 < end; ++guard) {
        int child = 2 * root + 1;
        if (child + 1 < end && v.less(idx[child], idx[child + 1])) ++child;
        if (!v.less(idx[root], idx[child])) return;
        const int16_t t = idx[root];
        idx[root] = idx[child];
        idx[child] = t;
        root = child;
    }
}

void heap_sort(int16_t *idx, int n, const SortView &v) {
    for (int start = n / 2 - 1; start >= 0; --start) sift_down(idx, start, n, v);
    for (int end = n - 1; end > 0; --end) {
        const int16_t t = idx[0];
        idx[0] = idx[end];
        idx[end] = t;
        sift_down(idx, 0, end, v);
    }
}

struct Window {
    int L = 0;
    bool translation_known = false;
    int fidx[kMaxL] = {};  // ring index of window frame t (0 = oldest)
    double R_C0toCt[kMaxL][9] = {};
    double p_CtInC0[kMaxL][3] = {};
    WindowBasis wb;
};

// Builds feature `i` (index in the newest frame)'s window data: follows the prev links back to
// the oldest frame. y_dir is the predicted direction of eq. (22) (frame-0 observation, its depth
// prior, transported with R_t and, when known, p_t) or the measured y of eq. (28).
void load_window_feature(const sfd_parity_t &det, const Window &w, int i, FeatureWindow *fw) {
    const int L = w.L;
    int index[kMaxL];
    index[L - 1] = i;
    for (int t = L - 1; t > 0; --t) index[t - 1] = det.frames[w.fidx[t]].obs[index[t]].prev;
    const sfd_parity_obs_t &o0 = det.frames[w.fidx[0]].obs[index[0]];
    const double s2 = det.params.pixel_sigma_px * det.params.pixel_sigma_px;
    const double d0 = static_cast<double>(o0.depth_m);
    const double m0[3] = {d0 * static_cast<double>(o0.xn[0]), d0 * static_cast<double>(o0.xn[1]),
                          d0};
    for (int t = 0; t < L; ++t) {
        const sfd_parity_obs_t &o = det.frames[w.fidx[t]].obs[index[t]];
        fw->y[t][0] = static_cast<double>(o.xn[0]);
        fw->y[t][1] = static_cast<double>(o.xn[1]);
        for (int c = 0; c < 3; ++c) fw->cov_y[t][c] = s2 * static_cast<double>(o.jjt_px2[c]);
        fw->depth[t] = static_cast<double>(o.depth_m);
        fw->depth_var[t] = static_cast<double>(o.depth_var_m2);
        fw->y_dir[t][0] = static_cast<double>(o.xn[0]);
        fw->y_dir[t][1] = static_cast<double>(o.xn[1]);
        if (det.params.exact_depth_covariance) {
            double m[3];
            for (int r = 0; r < 3; ++r) {
                m[r] = 0.0;
                for (int k = 0; k < 3; ++k) {
                    const double p = w.translation_known ? w.p_CtInC0[t][k] : 0.0;
                    m[r] += w.R_C0toCt[t][3 * r + k] * (m0[k] - p);
                }
            }
            if (m[2] > 1e-6) {
                fw->y_dir[t][0] = m[0] / m[2];
                fw->y_dir[t][1] = m[1] / m[2];
            }
        }
    }
}

bool reduce(const sfd_parity_t &det, const Window &w, int i, FeatureReduced *out) {
    FeatureWindow fw{};
    load_window_feature(det, w, i, &fw);
    return reduce_feature(w.wb, fw, w.R_C0toCt, w.p_CtInC0, w.translation_known, out);
}

void set_verdict(sfd_feature_result_t *v, int8_t status, int8_t reason, int nu, double T,
                 double thr) {
    v->status = status;
    v->stage = SFD_STAGE_PARITY;
    v->reason = reason;
    v->dof = static_cast<int16_t>(nu);
    v->statistic = (thr > 0.0) ? T / thr : 0.0;
}

void classify_fault(const GroupStats &gs, int j, int L, sfd_feature_result_t *v) {
    if (L < 3) {
        v->fault_kind = SFD_FAULT_UNKNOWN;  // a jump and a drift look alike over two frames
        return;
    }
    v->fault_kind = (gs.jump_glr[j] >= gs.drift_glr[j]) ? SFD_FAULT_JUMP : SFD_FAULT_DRIFT;
}

// Work lists of one frame (kept off the stack: they live in the caller's verdict, see below).
struct Lists {
    int16_t testable[SFD_MAX_FEATURES];
    int n_testable;
    int8_t suspect[SFD_MAX_FEATURES];    // by index in the newest frame
    float group_stat[SFD_MAX_FEATURES];  // normalized statistic of the passing group, by index
};

// Tests the groups; returns the number of groups tested.
__attribute__((noinline)) void test_groups(sfd_parity_t *det, const Window &w, Lists *lists,
                                           sfd_verdict_t *out) {
    const int n = det->params.group_size;
    const int d = w.wb.d;
    const int G = lists->n_testable / n;
    for (int g = 0; g < G; ++g) {
        FeatureReduced fr[kMaxN];
        const FeatureReduced *ptr[kMaxN];
        int members[kMaxN];
        bool ok = true;
        for (int k = 0; k < n; ++k) {
            members[k] = lists->testable[g + k * G];
            ok = ok && reduce(*det, w, members[k], &fr[k]);
            ptr[k] = &fr[k];
        }
        GroupStats gs;
        if (ok) ok = group_stats(ptr, n, d, w.translation_known, false, &gs);
        if (!ok) {
            for (int k = 0; k < n; ++k) out->features[members[k]].reason = SFD_REASON_NUMERIC;
            continue;
        }
        if (gs.nu <= 0) {
            for (int k = 0; k < n; ++k) out->features[members[k]].reason = SFD_REASON_RANK;
            continue;
        }
        out->groups_tested++;
        const double thr = det->chi2.threshold[gs.nu];
        if (gs.glr <= thr) {
            for (int k = 0; k < n; ++k) {
                set_verdict(&out->features[members[k]], SFD_VERDICT_CONSISTENT, SFD_REASON_NONE,
                            gs.nu, gs.glr, thr);
                lists->group_stat[members[k]] = static_cast<float>(gs.glr / thr);
            }
            continue;
        }
        out->groups_failed++;
        out->flags |= SFD_FLAG_PARITY_ALARM;
        if (!det->params.parity_isolation) {
            GroupStats sig;
            const bool have_sig = group_stats(ptr, n, d, w.translation_known, true, &sig);
            for (int k = 0; k < n; ++k) {
                sfd_feature_result_t *v = &out->features[members[k]];
                set_verdict(v, SFD_VERDICT_SPURIOUS, SFD_REASON_GROUP_FAILED, gs.nu, gs.glr, thr);
                if (have_sig) classify_fault(sig, k, w.L, v);
            }
            continue;
        }
        for (int k = 0; k < n; ++k) {
            lists->suspect[members[k]] = 1;
            set_verdict(&out->features[members[k]], SFD_VERDICT_SPURIOUS, SFD_REASON_INCONCLUSIVE,
                        gs.nu, gs.glr, thr);
        }
    }
}

// Isolation with a reference set of consistent features: candidate j is tested together with
// the references (the features of the most consistent passing groups). Under H0 for j the
// statistic is chi2 with |R| d dof (unknown translation) or d (known: references add nothing, the
// features are independent, so j is tested alone).
__attribute__((noinline)) void isolate_with_references(sfd_parity_t *det, const Window &w,
                                                       Lists *lists, const int16_t *candidates,
                                                       int n_candidates, sfd_verdict_t *out) {
    const int d = w.wb.d;
    const int n = det->params.group_size;
    const int want_refs = w.translation_known ? 0 : n - 1;
    FeatureReduced fr[kMaxN];
    const FeatureReduced *ptr[kMaxN];
    // Pick references: smallest passing-group statistic first (ties: grouping order).
    int refs = 0;
    for (int r = 0; r < want_refs; ++r) {
        int best = -1;
        for (int a = 0; a < lists->n_testable; ++a) {
            const int i = lists->testable[a];
            if (out->features[i].status != SFD_VERDICT_CONSISTENT ||
                out->features[i].reason != SFD_REASON_NONE) {
                continue;
            }
            if (lists->suspect[i] == 2) continue;  // already a reference
            if (best < 0 || lists->group_stat[i] < lists->group_stat[best]) best = i;
        }
        if (best < 0) break;
        lists->suspect[best] = 2;
        if (!reduce(*det, w, best, &fr[1 + refs])) {
            out->features[best].reason = SFD_REASON_NUMERIC;  // keeps its CONSISTENT verdict
            continue;
        }
        ptr[1 + refs] = &fr[1 + refs];
        ++refs;
    }
    if (!w.translation_known && refs == 0) {
        out->flags |= SFD_FLAG_NO_REFERENCE;
        return;
    }
    const int m = 1 + refs;
    for (int c = 0; c < n_candidates; ++c) {
        const int j = candidates[c];
        sfd_feature_result_t *v = &out->features[j];
        if (!reduce(*det, w, j, &fr[0])) {
            v->status = SFD_VERDICT_UNTESTED;
            v->stage = SFD_STAGE_NONE;
            v->reason = SFD_REASON_NUMERIC;
            v->statistic = 0.0;
            continue;
        }
        ptr[0] = &fr[0];
        GroupStats gs;
        if (!group_stats(ptr, m, d, w.translation_known, false, &gs)) {
            v->status = SFD_VERDICT_UNTESTED;
            v->stage = SFD_STAGE_NONE;
            v->reason = SFD_REASON_NUMERIC;
            v->statistic = 0.0;
            continue;
        }
        // Known translation: the candidate's own statistic; unknown: the re-test group's.
        const double T = w.translation_known ? gs.feature_glr[0] : gs.glr;
        const int nu = w.translation_known ? gs.feature_dof[0] : gs.nu;
        const double thr = det->chi2.threshold[nu];
        if (T <= thr) {
            set_verdict(v, SFD_VERDICT_CONSISTENT, SFD_REASON_ISOLATED, nu, T, thr);
        } else {
            set_verdict(v, SFD_VERDICT_SPURIOUS, SFD_REASON_ISOLATED, nu, T, thr);
            GroupStats sig;  // signatures only for the features found spurious
            if (group_stats(ptr, m, d, w.translation_known, true, &sig)) {
                classify_fault(sig, 0, w.L, v);
            }
        }
        lists->suspect[j] = 0;
    }
}

// Without references (no passing group): peel a failing group by its per-feature GLRs, the
// largest first, re-testing the rest each time; bounded by n - 1 rounds.
__attribute__((noinline)) void isolate_within_group(sfd_parity_t *det, const Window &w,
                                                    int *members, int n, sfd_verdict_t *out) {
    const int d = w.wb.d;
    FeatureReduced fr[kMaxN];
    const FeatureReduced *ptr[kMaxN];
    for (int k = 0; k < n; ++k) {
        if (!reduce(*det, w, members[k], &fr[k])) return;  // stays SPURIOUS/INCONCLUSIVE
        ptr[k] = &fr[k];
    }
    int m = n;
    for (int round = 0; round < n - 1 && m >= 2; ++round) {
        GroupStats gs;
        if (!group_stats(ptr, m, d, w.translation_known, true, &gs)) return;
        int worst = 0;
        for (int k = 1; k < m; ++k) {
            if (gs.feature_glr[k] > gs.feature_glr[worst]) worst = k;
        }
        sfd_feature_result_t *v = &out->features[members[worst]];
        const int nu_j = gs.feature_dof[worst] > 0 ? gs.feature_dof[worst] : gs.nu;
        set_verdict(v, SFD_VERDICT_SPURIOUS, SFD_REASON_ISOLATED, nu_j, gs.feature_glr[worst],
                    det->chi2.threshold[nu_j]);
        classify_fault(gs, worst, w.L, v);
        // Remove it and re-test the rest.
        members[worst] = members[m - 1];
        ptr[worst] = ptr[m - 1];
        --m;
        GroupStats rest;
        if (!group_stats(ptr, m, d, w.translation_known, false, &rest)) return;
        if (rest.nu <= 0) return;  // what is left cannot be tested: stays INCONCLUSIVE
        const double thr = det->chi2.threshold[rest.nu];
        if (rest.glr <= thr) {
            for (int k = 0; k < m; ++k) {
                set_verdict(&out->features[members[k]], SFD_VERDICT_CONSISTENT, SFD_REASON_ISOLATED,
                            rest.nu, rest.glr, thr);
            }
            return;
        }
    }
}

__attribute__((noinline)) bool build_window(const sfd_parity_t &det, Window *w) {
    const int L = det.params.window_frames;
    w->L = L;
    bool known = det.params.translation_known != 0;
    Mat3 R_CttoC0 = Mat3::Identity();
    Vec3 p = Vec3::Zero();
    for (int t = 0; t < L; ++t) {
        w->fidx[t] = ring_index(det, L - 1 - t);
        const sfd_parity_frame_t &fr = det.frames[w->fidx[t]];
        if (t > 0) {
            const Mat3 R_step = Eigen::Map<const Mat3>(fr.R_CtoCprev);
            // p_CtInC0 = p_C(t-1)InC0 + R_C(t-1)toC0 p_CtInC(t-1)
            p += R_CttoC0 * Vec3(fr.p_CinCprev_m[0], fr.p_CinCprev_m[1], fr.p_CinCprev_m[2]);
            R_CttoC0 = R_CttoC0 * R_step;
            known = known && fr.translation_known != 0;
        }
        Eigen::Map<Mat3>(w->R_C0toCt[t]) = R_CttoC0.transpose();
        w->p_CtInC0[t][0] = p.x();
        w->p_CtInC0[t][1] = p.y();
        w->p_CtInC0[t][2] = p.z();
    }
    w->translation_known = known;
    return window_basis(w->R_C0toCt, L, &w->wb);
}

// Stores the new frame's observations and links them to the previous frame.
__attribute__((noinline)) void ingest(sfd_parity_t *det, const sfd_frame_t *frame,
                                      const sfd_frame_motion_t *motion, int slot,
                                      sfd_verdict_t *out) {
    sfd_parity_frame_t &nf = det->frames[slot];
    const bool have_prev = det->count > 0;
    const int16_t *old_table = det->hash[det->hash_cur];
    int16_t *new_table = det->hash[1 - det->hash_cur];
    const int64_t *old_ids = det->track_id[det->hash_cur];
    int64_t *new_ids = det->track_id[1 - det->hash_cur];
    for (int s = 0; s < kSlots; ++s) new_table[s] = -1;
    const sfd_parity_frame_t &pf = det->frames[det->head];
    nf.utime = frame->utime;
    nf.num = frame->num_features;
    nf.translation_known = (motion != nullptr && have_prev) ? motion->translation_known : 0;
    // The gyro's rotation is kept at rest too: the rest test assumes none, but when the features
    // refuse rest the group test judges the frame with it. The translation is zero at rest.
    for (int k = 0; k < 9; ++k) {
        nf.R_CtoCprev[k] = (motion != nullptr && have_prev) ? motion->R_CcurToCprev[k]
                                                            : ((k % 4 == 0) ? 1.0 : 0.0);
    }
    for (int k = 0; k < 3; ++k) {
        nf.p_CinCprev_m[k] = (motion != nullptr && have_prev && motion->translation_known == 1)
                                 ? motion->p_CcurInCprev_m[k]
                                 : 0.0;
    }
    for (int i = 0; i < frame->num_features; ++i) {
        const sfd_feature_t &f = frame->features[i];
        sfd_parity_obs_t &o = nf.obs[i];
        sfd_feature_result_t &v = out->features[i];
        // Zero the padding too, so verdicts are byte-deterministic (IEEE 754 zero is all-bits-0).
        // cppcheck-suppress memsetClassFloat
        std::memset(&v, 0, sizeof v);
        v.track_id = f.track_id;
        v.status = SFD_VERDICT_UNTESTED;
        v.stage = SFD_STAGE_NONE;
        v.reason = SFD_REASON_SHORT_TRACK;
        v.fault_kind = SFD_FAULT_NONE;
        v.dof = 0;
        v.statistic = 0.0;
        new_ids[i] = f.track_id;
        o.prev = -1;
        o.run = 0;
        o.valid = 0;
        o.prior = 0;
        o.dir = kNoDirection;
        o.segment = 0;
        o.alarm = 0;
        const double uv[2] = {f.u_px, f.v_px};
        double J[4];
        double xn[2];
        bool ok = all_finite(uv, 2) && sfd_camera_undistort(&det->camera, uv, xn, J) == SFD_OK &&
                  fits_float(xn, 2) && hash_find(new_table, new_ids, nf.num, f.track_id) < 0;
        if (!ok) {
            v.reason = SFD_REASON_BAD_INPUT;
            out->flags |= SFD_FLAG_BAD_FEATURES;
            continue;
        }
        // Cov(xn) = sigma^2 J J^T with J = d xn / d uv; J J^T is stored (float: a relative
        // 6e-8 of the covariance, far below what the tests resolve) and sigma^2 applied on load.
        // A J J^T beyond float's range (a distortion model near its fold) is bad input.
        const double jjt[3] = {J[0] * J[0] + J[1] * J[1], J[0] * J[2] + J[1] * J[3],
                               J[2] * J[2] + J[3] * J[3]};
        if (!fits_float(jjt, 3)) {
            v.reason = SFD_REASON_BAD_INPUT;
            out->flags |= SFD_FLAG_BAD_FEATURES;
            continue;
        }
        o.xn[0] = static_cast<float>(xn[0]);
        o.xn[1] = static_cast<float>(xn[1]);
        for (int c = 0; c < 3; ++c) o.jjt_px2[c] = static_cast<float>(jjt[c]);
        // and still positive definite once stored (float rounding of a near-singular J J^T;
        // sfd_float_round_trip: the compiler may not skip the rounding)
        const double s0 = sfd_float_round_trip(jjt[0]), s1 = sfd_float_round_trip(jjt[1]),
                     s2 = sfd_float_round_trip(jjt[2]);
        if (!(s0 > 0.0 && s2 > 0.0 && s0 * s2 - s1 * s1 > 0.0)) {
            v.reason = SFD_REASON_BAD_INPUT;
            out->flags |= SFD_FLAG_BAD_FEATURES;
            continue;
        }
        o.cell_key = morton_key(f.u_px, f.v_px);
        // The wire's depth prior where it is one float can hold (a depth normal in float, a
        // finite variance); otherwise the configured default (sfd_params_validate holds it to
        // the same range), as for a feature that carries none.
        const bool prior = depth_prior_fits_float(f.depth_m, f.depth_var_m2);
        o.depth_m = static_cast<float>(prior ? f.depth_m : det->params.default_depth_m);
        o.depth_var_m2 =
            static_cast<float>(prior ? f.depth_var_m2 : det->params.default_depth_var_m2);
        o.prior = prior ? 1 : 0;
        o.valid = 1;
        o.run = 1;
        o.segment = 1;
        hash_insert(new_table, f.track_id, static_cast<int16_t>(i));
        if (have_prev) {
            const int p = hash_find(old_table, old_ids, pf.num, f.track_id);
            if (p >= 0 && pf.obs[p].valid) {
                o.prev = static_cast<int16_t>(p);
                o.run = static_cast<int8_t>(pf.obs[p].run >= SFD_MAX_WINDOW ? SFD_MAX_WINDOW
                                                                            : pf.obs[p].run + 1);
                o.segment = static_cast<int8_t>(
                    pf.obs[p].segment >= SFD_MAX_WINDOW ? SFD_MAX_WINDOW : pf.obs[p].segment + 1);
            }
        }
    }
    det->hash_cur = 1 - det->hash_cur;
}

// Pixel noise scale (core/docs/parity_space.md "Pixel noise scale"): the frame's median of
// gamma / median(chi2(dof)) is 1 when the pixel noise variance is right; the scale moves a fifth
// of the way (in log) toward the value that makes it so, from frames with at least 16 tests, and
// stays within [1/25, 25].
void update_noise_scale(sfd_parity_t &det, float *u, int n) {
    if (!det.params.pixel_noise_adapt || n < 16) return;
    const double m = median_in_place(u, n);
    if (!(m > 0.0) || !std::isfinite(m)) return;
    double s = det.noise_scale * std::pow(m, 0.2);
    s = s < 0.04 ? 0.04 : (s > 25.0 ? 25.0 : s);
    det.noise_scale = s;
}

// The rest test (core/docs/parity_space.md "At rest"). The newest frame's motion is
// SFD_MOTION_AT_REST: the IMU showed the camera still since the previous frame, so the paper's
// known-translation case (Section III-A) holds with R = I and p = 0 between the frames: a static
// point's undistorted normalized coordinates do not change, and the parity residual of a track
// over the window is its observations' deviation from their weighted mean. For each feature
// seen in the previous frame, over its newest m = min(L, run) observations back to the first
// frame whose interval was not at rest (m >= 2), with Cov(x_k) = s C_k (C_k the stored J J^T, s
// the pixel variance times the noise scale):
//   xbar = (sum C_k^-1)^-1 sum C_k^-1 x_k,  gamma = sum (x_k - xbar)^T C_k^-1 (x_k - xbar) / s,
// chi2(2 (m - 1)) for a static point (the depth is not observable at rest and needs no prior).
// Flagged at chi2(2 (m - 1), 1 - alpha): no other test shares this frame. Over the same L frames
// as the window test, so a step is flagged in the frames whose window holds both sides of it, as
// the label windows count (apps/sim/SIMULATION.md); an alarm starts the track's segment again,
// as the window test's does.
// The IMU's rest detector tests the scatter of block means and |a| = g: it cannot tell rest from
// a constant velocity, a small constant acceleration or a constant rotation (taken for a gyro
// bias), so the features must agree. The gate uses the configured pixel noise, not the adapted
// scale, so that the scale, which accepted frames update, cannot grow behind a slowly growing
// motion: the median over the tested features of gamma over its chi2 median, times the noise
// scale (gamma with the configured noise), must be at most kRestMedianRatio, with at least
// kRestMinFeatures tested. A still scene exceeds it with probability 0.01-0.03 at 16 features on
// the second frame (2 dof), 0.001 from the third (4 dof), 1e-10 at 150 features (binomial counts
// of chi2 tails). Otherwise the frame is not judged here (false: its motion becomes unknown
// translation and the group test judges it, as without the rest test). While rest is accepted the
// scale therefore stays below kRestMedianRatio / median, and the statistics update it
// (update_noise_scale), which the filter's test then starts from. A feature that has earlier
// observations but no statistic (a singular weight sum, a statistic that is not finite) is
// UNTESTED with SFD_REASON_NUMERIC.
constexpr int kRestMinFeatures = 16;
constexpr double kRestMedianRatio = 2.0;
static_assert(2 * (SFD_MAX_WINDOW - 1) <= SFD_CHI2_MAX_DOF,
              "the rest test's dof 2 (m - 1) must index the chi-square tables");

__attribute__((noinline)) bool test_at_rest(sfd_parity_t &det, sfd_verdict_t *out) {
    sfd_parity_frame_t &nf = det.frames[det.head];
    if (nf.translation_known != SFD_MOTION_AT_REST || det.count < 2 ||
        det.params.translation_known == 0) {
        return false;
    }
    const int L = det.params.window_frames;
    const int m_max = L < det.count ? L : det.count;
    const double scale = det.params.pixel_noise_adapt ? det.noise_scale : 1.0;
    const double s = scale * det.params.pixel_sigma_px * det.params.pixel_sigma_px;
    float *u = det.stat_scratch;
    int n_u = 0;
    for (int i = 0; i < nf.num; ++i) {
        const sfd_parity_obs_t &o = nf.obs[i];
        if (!o.valid || o.prev < 0) continue;
        // the track's observations, newest first, with their weights W_k = C_k^-1
        double x[SFD_MAX_WINDOW][2];
        double W[SFD_MAX_WINDOW][3];
        int m = 0;
        int index = i;
        for (int back = 0; back < m_max && index >= 0; ++back) {
            if (back > 0 &&
                det.frames[ring_index(det, back - 1)].translation_known != SFD_MOTION_AT_REST) {
                break;
            }
            const sfd_parity_obs_t &q = det.frames[ring_index(det, back)].obs[index];
            if (!q.valid) break;
            const double c0 = static_cast<double>(q.jjt_px2[0]);
            const double c1 = static_cast<double>(q.jjt_px2[1]);
            const double c2 = static_cast<double>(q.jjt_px2[2]);
            // positive: ingest checked it
            const Mat2 Wk = la::inverse_2x2(c0, c1, c1, c2, la::det_2x2(c0, c1, c1, c2));
            W[m][0] = Wk(0, 0);
            W[m][1] = Wk(0, 1);
            W[m][2] = Wk(1, 1);
            x[m][0] = static_cast<double>(q.xn[0]);
            x[m][1] = static_cast<double>(q.xn[1]);
            ++m;
            index = q.prev;
        }
        if (m < 2) continue;
        sfd_feature_result_t &v = out->features[i];
        v.dof = -1;  // earlier observations, no statistic yet (NUMERIC if it stays so)
        double A[3] = {0.0, 0.0, 0.0};
        double b[2] = {0.0, 0.0};
        for (int k = 0; k < m; ++k) {
            for (int c = 0; c < 3; ++c) A[c] += W[k][c];
            b[0] += W[k][0] * x[k][0] + W[k][1] * x[k][1];
            b[1] += W[k][1] * x[k][0] + W[k][2] * x[k][1];
        }
        const double dA = la::det_2x2(A[0], A[1], A[1], A[2]);
        if (!(dA > 0.0)) continue;
        const double xbar0 = (A[2] * b[0] - A[1] * b[1]) / dA;
        const double xbar1 = (A[0] * b[1] - A[1] * b[0]) / dA;
        double g = 0.0;
        for (int k = 0; k < m; ++k) {
            const double d0 = x[k][0] - xbar0, d1 = x[k][1] - xbar1;
            g += W[k][0] * d0 * d0 + 2.0 * W[k][1] * d0 * d1 + W[k][2] * d1 * d1;
        }
        const double gamma = g / s;
        if (!std::isfinite(gamma)) continue;
        const int dof = 2 * (m - 1);
        // held in the verdict until the frame is confirmed at rest
        v.statistic = gamma;
        v.dof = static_cast<int16_t>(dof);
        u[n_u++] = static_cast<float>(gamma / det.chi2_median.threshold[dof]);
    }
    const bool still =
        n_u >= kRestMinFeatures && scale * median_in_place(u, n_u) <= kRestMedianRatio;
    if (!still) {
        nf.translation_known = 0;  // the camera moved: unknown translation for every test
        for (int i = 0; i < nf.num; ++i) {
            out->features[i].statistic = 0.0;
            out->features[i].dof = 0;
        }
        return false;
    }
    for (int i = 0; i < nf.num; ++i) {
        sfd_feature_result_t &v = out->features[i];
        if (v.dof == -1) {
            v.dof = 0;
            v.reason = SFD_REASON_NUMERIC;
        }
        if (v.dof < 2) continue;
        const double gamma = v.statistic;
        const double thr = det.chi2.threshold[v.dof];
        if (gamma > thr) {
            set_verdict(&v, SFD_VERDICT_SPURIOUS, SFD_REASON_AT_REST, v.dof, gamma, thr);
            v.fault_kind = SFD_FAULT_UNKNOWN;
            out->flags |= SFD_FLAG_PARITY_ALARM;
            nf.obs[i].segment = 1;
        } else {
            set_verdict(&v, SFD_VERDICT_CONSISTENT, SFD_REASON_AT_REST, v.dof, gamma, thr);
        }
    }
    update_noise_scale(det, u, n_u);  // u was reordered by the median; its median is unchanged
    return true;
}

// Loads feature i of the newest frame over its newest m frames into obs (oldest first), with the
// pixel noise variance scaled by `scale`; the depth prior is the newest observation's.
void load_track(const sfd_parity_t &det, int i, int m, double scale, sfd_window_test_obs_t *obs) {
    const double scale_px2 = scale * det.params.pixel_sigma_px * det.params.pixel_sigma_px;
    obs->frames = m;
    int index = i;
    for (int t = m - 1; t >= 0; --t) {
        const sfd_parity_frame_t &fr = det.frames[ring_index(det, m - 1 - t)];
        const sfd_parity_obs_t &o = fr.obs[index];
        obs->utime[t] = fr.utime;
        obs->xn[t][0] = static_cast<double>(o.xn[0]);
        obs->xn[t][1] = static_cast<double>(o.xn[1]);
        for (int c = 0; c < 3; ++c)
            obs->cov_xn[t][c] = scale_px2 * static_cast<double>(o.jjt_px2[c]);
        index = o.prev;
    }
    const sfd_parity_obs_t &newest = det.frames[det.head].obs[i];
    obs->depth_m = newest.prior ? static_cast<double>(newest.depth_m) : 0.0;
    obs->depth_var_m2 = newest.prior ? static_cast<double>(newest.depth_var_m2) : 0.0;
}

// Known translation from the window filter (sfd_parity_push_frame_filter; core/docs/
// parity_space.md "Known translation from the window filter"). Every feature tracked through the
// L frames is tested alone with the filter's poses and covariance (sfd_window_test_track). Then
// the evidence test: a feature whose window passed and whose segment (its observations since
// its last alarm at the full threshold) is longer than L is tested again over min(segment,
// evidence_frames) frames, a window-limited GLR that sees a slow drift or a moving point the
// L-frame window absorbs, and beside it the ramp test over the same frames (parity_space.md
// "Ramp"). With it each of the window and the evidence test runs at alpha / 2 (the window test at
// alarm_hold_alpha_scale of that with the hold on; the evidence test's alpha / 2 split with the
// ramp test by evidence_ramp_share), so a clean feature is flagged with probability <= alpha. False
// when the filter does not hold the window's frames (nothing written: the caller falls back to the
// group test). The alarm hold (parity_space.md "Alarm hold"): a track whose last alarm_hold_frames
// observations this test flagged is tested against alarm_hold_ratio times the window test's
// threshold. A moving point is inconsistent over its whole life, while its 3-frame window alone
// passes in a fraction of frames; a clean track pays the lower threshold only after that many
// false alarms in a row. Consecutive windows share L - 1 frames, so a clean track's false alarm
// is often repeated under the lower threshold: with the hold on, the window test runs at
// alarm_hold_alpha_scale times its share of alpha (det.chi2_window), a factor measured on clean
// logs (parity_space.md "Alarm hold"), not derived. The evidence test (with its ramp test) keeps
// alpha / 2 and their alarms neither start nor continue the hold (their repeats would not be
// paid for), except with the directional hold. A held alarm continues the hold only at or above
// alarm_hold_min_statistic times the full threshold, and does not start the track's segment
// again (the segment runs from the last alarm at the full threshold). The directional hold
// (parity_space.md "Directional hold"; alarm_hold_direction_alpha > 0): every test also fits a
// ramp beside the point over the window test's frames and stores its direction; a held track
// with a direction stored at its previous observation is tested one-sided along it instead of
// against the lowered threshold, and an evidence or ramp alarm with a direction starts a run.
__attribute__((noinline)) bool test_with_filter(sfd_parity_t &det, sfd_window_t *filter,
                                                sfd_window_scratch_t *scratch,
                                                const sfd_extrinsics_t &ext, sfd_verdict_t *out) {
    const int L = det.params.window_frames;
    // The filter must hold the window: its newest L - 1 clones at the window's older frames and
    // its state at the newest frame's time (sfd_window_test_track checks every test's frames).
    if (!filter->started || filter->num_clones < L - 1) return false;
    for (int back = 0; back < L; ++back) {
        const int64_t ft = det.frames[ring_index(det, back)].utime;
        const int64_t wt =
            (back == 0) ? filter->utime : filter->clones[filter->num_clones - back].utime;
        if (ft != wt) return false;
    }
    // How far back the filter's clones match the ring (the evidence test's longest window).
    int m_max = L;
    const int want = det.params.evidence_frames;
    while (m_max < want && m_max < det.count && m_max <= filter->num_clones &&
           det.frames[ring_index(det, m_max)].utime ==
               filter->clones[filter->num_clones - m_max].utime) {
        ++m_max;
    }
    const bool evidence = want > L;
    const bool ramp_on = evidence && det.ramp_threshold > 0.0;
    const bool omnibus_on = !ramp_on || det.params.evidence_ramp_share < 1.0;
    const sfd_chi2_table_t &tab = det.chi2_window;  // the evidence test's is det.chi2_half
    sfd_parity_frame_t &nf = det.frames[det.head];
    // the previous frame (newest.prev indexes it; the window check above means L >= 2 frames)
    const sfd_parity_frame_t &pf = det.frames[ring_index(det, 1)];
    const double hold = det.params.alarm_hold_ratio;
    const int hold_after = det.params.alarm_hold_frames;
    const double step_stat = det.params.alarm_hold_max_statistic;
    const double hold_min = det.params.alarm_hold_min_statistic;
    const double scale = det.params.pixel_noise_adapt ? det.noise_scale : 1.0;
    float *u = det.stat_scratch;  // gamma over the median of chi2(dof), per tested feature
    int n_u = 0;
    sfd_window_test_obs_t obs;
    for (int i = 0; i < nf.num; ++i) {
        sfd_parity_obs_t &newest = nf.obs[i];
        // A track seen in fewer than L frames is tested over the frames it has (at least 2):
        // with the poses known, two frames already leave a residual.
        const int m_short = newest.run < L ? newest.run : L;
        if (!newest.valid || m_short < 2) continue;
        // The evidence window: the segment since the last alarm at the full threshold, as far
        // back as the clones reach.
        // When it is longer than L, both tests come from one linearization over it (the L-frame
        // test is the statistic of its newest L frames' rows; sfd_window_test_track_nested);
        // when that fails (e.g. an old observation puts the point behind a camera), or there is
        // no evidence window, the L-frame test alone.
        const int m_ev = newest.segment < m_max ? newest.segment : m_max;
        // gam[0] the L-frame (or m_short-frame) test, gam[1] the evidence test, gam[2] the ramp's
        // GLR; the motion fitted over the L-frame test's frames (the directional hold's)
        double gam[3] = {0.0, 0.0, 0.0};
        int32_t dofs[3] = {0, 0, 0};
        // (fitted only with the directional hold on: without it the tests alone, bit for bit)
        sfd_window_motion_t motion{};
        sfd_window_motion_t *fit = det.hold_direction_z > 0.0 ? &motion : nullptr;
        sfd_status_t st = SFD_ERR_STATE;
        if (evidence && m_ev > L && m_short == L) {
            load_track(det, i, m_ev, scale, &obs);
            st = sfd_window_test_track_motion(filter, &ext, &obs, L, ramp_on ? 1 : 0, scratch, gam,
                                              dofs, fit);
        }
        const bool have_evidence = (st == SFD_OK);
        if (!have_evidence) {
            load_track(det, i, m_short, scale, &obs);
            st = sfd_window_test_track_motion(filter, &ext, &obs, 0, 0, scratch, gam, dofs, fit);
        }
        sfd_feature_result_t *v = &out->features[i];
        if (st != SFD_OK || dofs[0] < 1 || dofs[0] > SFD_PARITY_MAX_RESIDUAL) {
            v->reason = (st == SFD_ERR_NUMERIC) ? SFD_REASON_RANK : SFD_REASON_NUMERIC;
            continue;
        }
        // The motion's direction, v = info^-1 score up to the positive factor det(info), for the
        // next observation's directional hold.
        if (motion.ok != 0) {
            newest.dir = encode_direction(
                motion.info[2] * motion.score[0] - motion.info[1] * motion.score[1],
                motion.info[0] * motion.score[1] - motion.info[1] * motion.score[0]);
        }
        // consecutive alarms of the track before this observation
        const int run_before = newest.prev >= 0 ? pf.obs[newest.prev].alarm : 0;
        const bool held = hold < 1.0 && run_before >= hold_after;
        const int8_t alarm_run = static_cast<int8_t>(
            run_before >= SFD_ALARM_HOLD_MAX_FRAMES ? SFD_ALARM_HOLD_MAX_FRAMES : run_before + 1);
        const double full = tab.threshold[dofs[0]];
        double thr = held ? hold * full : full;  // the threshold that decides
        u[n_u++] = static_cast<float>(gam[0] / det.chi2_median.threshold[dofs[0]]);
        // The directional hold (parity_space.md "Directional hold"): a held track whose previous
        // observation fitted a motion is tested one-sided along that direction d, z =
        // d^T score / sqrt(d^T info d) against hold_direction_z, instead of against the lowered
        // threshold; the full threshold still applies. Its verdicts report the one-sided GLR
        // max(z, 0)^2 over hold_direction_z^2 with dof 1.
        double d[2] = {0.0, 0.0};
        double dd = 0.0;  // d^T info d (held: newest.prev >= 0)
        if (held && det.hold_direction_z > 0.0 && motion.ok != 0 &&
            decode_direction(pf.obs[newest.prev].dir, d)) {
            dd = d[0] * d[0] * motion.info[0] + 2.0 * d[0] * d[1] * motion.info[1] +
                 d[1] * d[1] * motion.info[2];
        }
        const bool directional = dd > 0.0;
        double z_glr = 0.0;  // max(z, 0)^2
        const double z_thr = det.hold_direction_z * det.hold_direction_z;
        if (directional) {
            const double z = (d[0] * motion.score[0] + d[1] * motion.score[1]) / std::sqrt(dd);
            z_glr = z > 0.0 ? z * z : 0.0;
            thr = full;
        }
        if (gam[0] > thr || (directional && z_glr > z_thr)) {
            // ALARM_HOLD only where the hold decided (the full threshold would have passed it)
            const bool by_hold = !(gam[0] > full);
            if (by_hold && directional) {
                set_verdict(v, SFD_VERDICT_SPURIOUS, SFD_REASON_ALARM_HOLD, 1, z_glr, z_thr);
            } else {
                set_verdict(v, SFD_VERDICT_SPURIOUS,
                            by_hold ? SFD_REASON_ALARM_HOLD : SFD_REASON_FEATURE_TEST, dofs[0],
                            gam[0], by_hold ? thr : full);
            }
            v->fault_kind = SFD_FAULT_UNKNOWN;
            out->flags |= SFD_FLAG_PARITY_ALARM;
            // An alarm at the full threshold starts the track's segment again; a held one does
            // not, so the evidence test keeps a moving point's held stretch.
            if (!by_hold) newest.segment = 1;
            // A step's alarm (far above the threshold) breaks the run of alarms: after a jump the
            // track follows another point and its next windows are clean. So does a held alarm
            // below alarm_hold_min_statistic times the full threshold: after a drift the track
            // follows another point too, and its clean windows exceed the lowered threshold with
            // probability P(chi2(dof) > hold * full) (0.27-0.36 at 3-4 dof in the shipped
            // configuration, 0.10-0.14 above 0.4 full), so held false alarms would chain.
            const bool step = !(gam[0] < step_stat * full);
            // (A directional alarm is not weak: its own level bounds a locked track's repeats.)
            const bool weak = by_hold && !directional && gam[0] < hold_min * full;
            newest.alarm = (step || weak) ? 0 : alarm_run;
            continue;
        }
        if (directional) {
            set_verdict(v, SFD_VERDICT_CONSISTENT, SFD_REASON_FEATURE_TEST, 1, z_glr, z_thr);
        } else {
            set_verdict(v, SFD_VERDICT_CONSISTENT, SFD_REASON_FEATURE_TEST, dofs[0], gam[0], thr);
        }
        if (!have_evidence || dofs[1] < 1 || dofs[1] > SFD_PARITY_MAX_RESIDUAL) continue;
        thr = det.chi2_half.threshold[dofs[1]];
        // Not window alarms: the run stays 0 (as ingest set it) and the next window test is not
        // held, except with the directional hold on and a direction fitted here: then the alarm
        // is the first of a run (a slide the window absorbs is followed along its direction;
        // a clean track's repeat costs at most alarm_hold_direction_alpha).
        const bool starts_hold = det.hold_direction_z > 0.0 && newest.dir != kNoDirection;
        if (omnibus_on && gam[1] > thr) {
            set_verdict(v, SFD_VERDICT_SPURIOUS, SFD_REASON_EVIDENCE, dofs[1], gam[1], thr);
            v->fault_kind = SFD_FAULT_DRIFT;
            out->flags |= SFD_FLAG_PARITY_ALARM;
            if (starts_hold) newest.alarm = 1;
        } else if (ramp_on && dofs[2] == 2 && gam[2] > det.ramp_threshold) {
            set_verdict(v, SFD_VERDICT_SPURIOUS, SFD_REASON_EVIDENCE_RAMP, 2, gam[2],
                        det.ramp_threshold);
            v->fault_kind = SFD_FAULT_DRIFT;
            out->flags |= SFD_FLAG_PARITY_ALARM;
            if (starts_hold) newest.alarm = 1;
        }
    }
    update_noise_scale(det, u, n_u);
    return true;
}

}  // namespace
}  // namespace parity
}  // namespace sfd

using namespace sfd;
using namespace sfd::parity;

extern "C" sfd_status_t sfd_parity_init(sfd_parity_t *det, const sfd_params_t *params,
                                        const sfd_camera_t *camera) {
    if (det == nullptr || params == nullptr || camera == nullptr) return SFD_ERR_INVAL;
    det->magic_ = 0;
    const sfd_status_t v = sfd_params_validate(params);
    if (v != SFD_OK) return v;
    // A camera passes through sfd_camera_init's validation again (fields may be hand-filled).
    sfd_camera_t cam;
    const sfd_status_t c =
        sfd_camera_init(&cam, camera->model, camera->width_px, camera->height_px, camera->fx_px,
                        camera->fy_px, camera->cx_px, camera->cy_px, camera->dist);
    if (c != SFD_OK) return c;
    const sfd_status_t t = sfd_chi2_table_init(&det->chi2, params->false_alarm_rate);
    if (t != SFD_OK) return t;
    const sfd_status_t tm = sfd_chi2_table_init(&det->chi2_median, 0.5);
    if (tm != SFD_OK) return tm;
    // The tests with the filter's translation (test_with_filter): alpha / 2 each for the window
    // and the evidence test, alpha for the window test alone; with the alarm hold on, the window
    // test gets a share alarm_hold_alpha_scale of its part (its held repeats take the rest).
    const bool evidence = params->evidence_frames > params->window_frames;
    const double alpha_window =
        (evidence ? 0.5 : 1.0) * params->false_alarm_rate *
        (params->alarm_hold_ratio < 1.0 ? params->alarm_hold_alpha_scale : 1.0);
    const sfd_status_t tw = sfd_chi2_table_init(&det->chi2_window, alpha_window);
    if (tw != SFD_OK) return tw;
    // The ramp test takes evidence_ramp_share of the evidence test's alpha / 2 (a Bonferroni
    // split; chi2(2) has the closed-form quantile -2 ln(alpha)); the omnibus keeps the rest.
    const double ramp = evidence ? params->evidence_ramp_share : 0.0;
    const double alpha_ev = 0.5 * params->false_alarm_rate;
    const sfd_status_t th =
        sfd_chi2_table_init(&det->chi2_half, ramp < 1.0 ? (1.0 - ramp) * alpha_ev : alpha_ev);
    if (th != SFD_OK) return th;
    det->ramp_threshold = ramp > 0.0 ? -2.0 * std::log(ramp * alpha_ev) : 0.0;
    // The directional hold's one-sided threshold z with P(N(0, 1) > z) = a: z^2 is chi2(1)'s
    // upper 2a quantile (a < 0.5, so z > 0).
    det->hold_direction_z = 0.0;
    const double a_dir = params->alarm_hold_direction_alpha;
    if (a_dir > 0.0) {
        double z2 = 0.0;
        const sfd_status_t tz = sfd_chi2_quantile_upper(2.0 * a_dir, 1, &z2);
        if (tz != SFD_OK) return tz;
        det->hold_direction_z = std::sqrt(z2);
    }
    det->noise_scale = 1.0;
    det->params = *params;
    det->camera = cam;
    det->head = 0;
    det->count = 0;
    det->hash_cur = 0;
    for (int s = 0; s < kSlots; ++s) {
        det->hash[0][s] = -1;
        det->hash[1][s] = -1;
    }
    det->magic_ = kMagic;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_parity_reset(sfd_parity_t *det) {
    if (det == nullptr) return SFD_ERR_INVAL;
    if (det->magic_ != kMagic) return SFD_ERR_STATE;
    det->count = 0;
    det->head = 0;
    for (int s = 0; s < kSlots; ++s) det->hash[det->hash_cur][s] = -1;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_parity_newest_xn(const sfd_parity_t *det, int64_t utime, int32_t index,
                                             double xn[2]) {
    if (det == nullptr || xn == nullptr) return SFD_ERR_INVAL;
    if (det->magic_ != kMagic) return SFD_ERR_STATE;
    if (det->count == 0) return SFD_ERR_INVAL;
    const sfd_parity_frame_t &fr = det->frames[det->head];
    if (fr.utime != utime || index < 0 || index >= fr.num || !fr.obs[index].valid) {
        return SFD_ERR_INVAL;
    }
    xn[0] = static_cast<double>(fr.obs[index].xn[0]);
    xn[1] = static_cast<double>(fr.obs[index].xn[1]);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_parity_push_frame(sfd_parity_t *det, const sfd_frame_t *frame,
                                              const sfd_frame_motion_t *motion,
                                              sfd_verdict_t *out) {
    return sfd_parity_push_frame_filter(det, frame, motion, nullptr, nullptr, nullptr, out);
}

extern "C" sfd_status_t sfd_parity_push_frame_filter(sfd_parity_t *det, const sfd_frame_t *frame,
                                                     const sfd_frame_motion_t *motion,
                                                     sfd_window_t *filter,
                                                     sfd_window_scratch_t *scratch,
                                                     const sfd_extrinsics_t *ext,
                                                     sfd_verdict_t *out) {
    if (det == nullptr || frame == nullptr || out == nullptr) return SFD_ERR_INVAL;
    if (filter != nullptr && (ext == nullptr || scratch == nullptr)) return SFD_ERR_INVAL;
    if (det->magic_ != kMagic) return SFD_ERR_STATE;
    if (frame->num_features < 0 || frame->num_features > SFD_MAX_FEATURES) {
        return SFD_ERR_CAPACITY;
    }
    const int L = det->params.window_frames;
    if (det->count > 0) {
        if (frame->utime <= det->frames[det->head].utime) return SFD_ERR_ORDER;
        if (motion == nullptr) return SFD_ERR_INVAL;
        if (motion->translation_known != 0 && motion->translation_known != 1 &&
            motion->translation_known != SFD_MOTION_AT_REST) {
            return SFD_ERR_INVAL;
        }
        if (!is_rotation(Eigen::Map<const Mat3>(motion->R_CcurToCprev), 1e-6)) {
            return SFD_ERR_INVAL;
        }
        if (motion->translation_known == 1 && !all_finite(motion->p_CcurInCprev_m, 3)) {
            return SFD_ERR_INVAL;
        }
    }
    out->utime = frame->utime;
    out->flags = 0;
    out->num_features = frame->num_features;
    out->num_consistent = out->num_spurious = out->num_untested = 0;
    out->groups_tested = out->groups_failed = 0;

    const int slot = (det->count == 0) ? 0 : (det->head + 1) % kRing;
    ingest(det, frame, motion, slot, out);
    det->head = slot;
    if (det->count < kRing) det->count++;

    const bool want_filter = det->params.translation_known != 0 && filter != nullptr;
    if (test_at_rest(*det, out)) {
        out->flags |= SFD_FLAG_AT_REST;  // every feature seen before tested against its own past
    } else if (det->count < L) {
        out->flags |= SFD_FLAG_WINDOW_FILLING;
    } else if (want_filter && test_with_filter(*det, filter, scratch, *ext, out)) {
        // every feature of the window tested alone (known translation from the filter)
    } else {
        if (want_filter) out->flags |= SFD_FLAG_TRANSLATION_UNKNOWN;
        Window w;
        if (!build_window(*det, &w)) {
            for (int i = 0; i < frame->num_features; ++i) {
                if (out->features[i].reason != SFD_REASON_BAD_INPUT) {
                    out->features[i].reason = SFD_REASON_NUMERIC;
                }
            }
        } else {
            if (w.wb.rank < 3) out->flags |= SFD_FLAG_RANK_DEFICIENT;
            // Work lists live in a static-size struct on the stack (1.8 KiB at 256 features).
            Lists lists{};  // zeroed: ~1.8 KiB per frame, keeps every entry defined
            const sfd_parity_frame_t &nf = det->frames[slot];
            uint32_t key[SFD_MAX_FEATURES];
            for (int i = 0; i < nf.num; ++i) {
                lists.suspect[i] = 0;
                lists.group_stat[i] = 0.0f;
                if (nf.obs[i].valid && nf.obs[i].run >= L) {
                    lists.testable[lists.n_testable++] = static_cast<int16_t>(i);
                    key[i] = nf.obs[i].cell_key;
                }
            }
            const SortView view{key, det->track_id[det->hash_cur]};
            heap_sort(lists.testable, lists.n_testable, view);
            test_groups(det, w, &lists, out);
            const int n = det->params.group_size;
            const int grouped = (lists.n_testable / n) * n;
            // Candidates for isolation: suspects of failing groups, then the leftovers.
            int16_t cand[SFD_MAX_FEATURES];
            int n_cand = 0;
            for (int a = 0; a < grouped; ++a) {
                if (lists.suspect[lists.testable[a]] == 1) cand[n_cand++] = lists.testable[a];
            }
            for (int a = grouped; a < lists.n_testable; ++a) {
                const int i = lists.testable[a];
                out->features[i].reason = SFD_REASON_NO_GROUP;
                if (det->params.parity_isolation) cand[n_cand++] = static_cast<int16_t>(i);
            }
            if (det->params.parity_isolation && n_cand > 0) {
                isolate_with_references(det, w, &lists, cand, n_cand, out);
                if (out->flags & SFD_FLAG_NO_REFERENCE) {
                    // No consistent reference anywhere: peel each failing group on its own.
                    const int G = lists.n_testable / n;
                    for (int g = 0; g < G; ++g) {
                        int members[kMaxN];
                        if (lists.suspect[lists.testable[g]] != 1) continue;
                        for (int k = 0; k < n; ++k) members[k] = lists.testable[g + k * G];
                        isolate_within_group(det, w, members, n, out);
                    }
                }
            }
        }
    }
    for (int i = 0; i < frame->num_features; ++i) {
        const int8_t s = out->features[i].status;
        if (s == SFD_VERDICT_CONSISTENT) {
            out->num_consistent++;
        } else if (s == SFD_VERDICT_SPURIOUS) {
            out->num_spurious++;
        } else {
            out->num_untested++;
        }
    }
    return SFD_OK;
}
