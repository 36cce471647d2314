// SPDX-License-Identifier: MIT
// Unit tests of the OpenCV feature tracker (drivers/opencv/sfd_feature_tracker.hpp) on synthetic
// images: a smooth random texture (seeded sfd_prng, Gaussian-blurred) moved by known sub-pixel
// translations (cv::warpAffine, bilinear), so the true position of every corner is known.
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "sfd/sfd_prng.h"
#include "sfd_feature_tracker.hpp"

// cmocka last: its macros (fail, ...) clash with the C++ standard headers.
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

extern "C" {
#include <cmocka.h>
}

namespace {

constexpr int kW = 400, kH = 300, kMargin = 40;

// Smooth random texture, (kW + 2 kMargin) x (kH + 2 kMargin), 8 bit.
cv::Mat texture(uint64_t seed) {
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed);
    cv::Mat f(kH + 2 * kMargin, kW + 2 * kMargin, CV_32FC1);
    for (int r = 0; r < f.rows; ++r)
        for (int c = 0; c < f.cols; ++c) f.at<float>(r, c) = float(sfd_prng_uniform(&rng));
    cv::GaussianBlur(f, f, cv::Size(0, 0), 2.0);
    cv::Mat out;
    cv::normalize(f, f, 0.0, 255.0, cv::NORM_MINMAX);
    f.convertTo(out, CV_8UC1);
    return out;
}

// The texture moved by (dx, dy) px (a point at p appears at p + d), central kW x kH crop.
cv::Mat shifted(const cv::Mat &tex, double dx, double dy) {
    const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
    cv::Mat w;
    cv::warpAffine(tex, w, M, tex.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    return w(cv::Rect(kMargin, kMargin, kW, kH)).clone();
}

std::map<int64_t, sfd::Track> by_id(const std::vector<sfd::Track> &v) {
    std::map<int64_t, sfd::Track> m;
    for (const auto &t : v) m[t.id] = t;
    return m;
}

void test_follows_known_shift(void **state) {
    (void)state;
    const cv::Mat tex = texture(1);
    sfd::TrackerConfig cfg;
    cfg.max_features = 80;
    sfd::FeatureTracker tr(cfg);
    std::string err;
    assert_true(tr.track(shifted(tex, 0, 0), &err));
    const auto first = by_id(tr.tracks());
    assert_true(first.size() >= 40);
    const double dx = 3.3, dy = -2.7;
    assert_true(tr.track(shifted(tex, dx, dy), &err));
    int carried = 0, interior = 0;
    double worst_px = 0.0;
    for (const auto &t : tr.tracks()) {
        const auto it = first.find(t.id);
        if (it == first.end()) continue;  // a new corner
        ++carried;
        assert_int_equal(t.age, 2);
        const double e =
            std::hypot(t.u_px - (it->second.u_px + dx), t.v_px - (it->second.v_px + dy));
        // Near the edge the LK window leaves the image and the estimate degrades (0.15 px
        // measured at 8 px from the edge); the 0.1 px bound holds where the window fits.
        const double edge = 0.5 * cfg.lk_window_px + 4.0;
        if (t.u_px < edge || t.v_px < edge || t.u_px > kW - 1 - edge || t.v_px > kH - 1 - edge)
            continue;
        ++interior;
        if (e > worst_px) worst_px = e;
    }
    // Every track whose point stays inside the image is kept with its id (at most 4 lost at
    // the edge), and away from the edge it is within 0.1 px of the true shift.
    assert_true(carried >= int(first.size()) - 4);
    assert_true(interior >= 30);
    assert_true(worst_px < 0.1);
    assert_int_equal(tr.stats().tracked, carried);
}

void test_ids_monotonic_never_reused(void **state) {
    (void)state;
    const cv::Mat tex = texture(2);
    sfd::TrackerConfig cfg;
    cfg.max_features = 60;
    sfd::FeatureTracker tr(cfg);
    std::string err;
    std::set<int64_t> seen, lost;
    std::set<int64_t> prev;
    int64_t max_id = 0;
    for (int f = 0; f < 12; ++f) {  // drifts right: tracks leave at the edge, new ones come in
        assert_true(tr.track(shifted(tex, 2.5 * f, 0.7 * f), &err));
        std::set<int64_t> now;
        int64_t last = 0;
        for (const auto &t : tr.tracks()) {
            assert_true(t.id > last);  // ascending order
            last = t.id;
            now.insert(t.id);
            assert_true(lost.count(t.id) == 0);                     // a lost id never comes back
            if (seen.count(t.id) == 0) assert_true(t.id > max_id);  // new ids above all earlier
        }
        for (const int64_t id : prev)
            if (now.count(id) == 0) lost.insert(id);
        for (const auto &t : tr.tracks()) {
            seen.insert(t.id);
            if (t.id > max_id) max_id = t.id;
        }
        prev = now;
    }
    assert_true(!lost.empty());  // the drift did remove tracks, so the check above was exercised
    assert_int_equal(tr.next_id(), max_id + 1);
}

// A track's patch replaced by texture from elsewhere: LK converges somewhere, but tracking back
// does not return to the start, so the forward-backward check drops it; plain LK keeps a track
// with that id (a real tracker error the detectors must meet).
void test_fb_check_rejects_altered_patch(void **state) {
    (void)state;
    const cv::Mat tex = texture(3), other = texture(33);
    for (int fb = 1; fb >= 0; --fb) {
        sfd::TrackerConfig cfg;
        cfg.max_features = 40;
        cfg.fb_check = fb != 0;
        sfd::FeatureTracker tr(cfg);
        std::string err;
        assert_true(tr.track(shifted(tex, 0, 0), &err));
        const size_t first_count = tr.tracks().size();
        // The track nearest to the image centre.
        sfd::Track victim = tr.tracks().front();
        double best = 1e9;
        for (const auto &t : tr.tracks()) {
            const double d = std::hypot(t.u_px - kW / 2.0, t.v_px - kH / 2.0);
            if (d < best) {
                best = d;
                victim = t;
            }
        }
        cv::Mat next = shifted(tex, 1.0, 0.5);
        const int half = 12;
        const cv::Rect box(int(victim.u_px) - half, int(victim.v_px) - half, 2 * half + 1,
                           2 * half + 1);
        other(box).copyTo(next(box));
        assert_true(tr.track(next, &err));
        const auto now = by_id(tr.tracks());
        if (fb) {
            assert_true(now.count(victim.id) == 0);
            assert_true(tr.stats().lost_fb >= 1);
        } else {
            assert_int_equal(tr.stats().lost_fb, 0);
            assert_true(now.count(victim.id) == 1);  // plain LK follows the wrong texture
        }
        // Only the altered track (and at most one neighbour whose window overlaps the patch)
        // is lost: the check does not reject correctly tracked features.
        assert_true(tr.stats().tracked >= int(first_count) - 2);
    }
}

double min_pair_distance_px(const std::vector<sfd::Track> &v) {
    double m = 1e9;
    for (size_t i = 0; i < v.size(); ++i)
        for (size_t j = i + 1; j < v.size(); ++j)
            m = std::min(m, std::hypot(v[i].u_px - v[j].u_px, v[i].v_px - v[j].v_px));
    return m;
}

// Zooming out (scale 0.8 per frame about the centre) pulls tracks together: the spacing rule
// must drop the younger of close pairs, and replenishment must keep the distance too.
void test_bound_and_spacing(void **state) {
    (void)state;
    const cv::Mat tex = texture(4);
    for (const int cap : {25, sfd::kTrackerMaxFeatures}) {
        sfd::TrackerConfig cfg;
        cfg.max_features = cap;
        cfg.min_distance_px = 15.0;
        sfd::FeatureTracker tr(cfg);
        std::string err;
        int spacing_drops = 0;
        for (int f = 0; f < 6; ++f) {
            const double s = std::pow(0.85, f);
            const cv::Point2f c(float(tex.cols) / 2.0f, float(tex.rows) / 2.0f);
            cv::Mat M = cv::getRotationMatrix2D(c, 0.0, s), w;
            cv::warpAffine(tex, w, M, tex.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
            assert_true(tr.track(w(cv::Rect(kMargin, kMargin, kW, kH)).clone(), &err));
            assert_true(int(tr.tracks().size()) <= cap);
            assert_true(min_pair_distance_px(tr.tracks()) >= 15.0);
            spacing_drops += tr.stats().lost_spacing;
            for (const auto &t : tr.tracks()) {
                assert_true(t.u_px >= cfg.border_px && t.u_px <= kW - 1 - cfg.border_px);
                assert_true(t.v_px >= cfg.border_px && t.v_px <= kH - 1 - cfg.border_px);
            }
        }
        if (cap == 25) assert_int_equal(int(tr.tracks().size()), 25);  // replenished to target
        assert_true(spacing_drops > 0);  // the zoom did bring tracks closer than the spacing
    }
}

void test_deterministic(void **state) {
    (void)state;
    const cv::Mat tex = texture(5);
    std::vector<std::vector<sfd::Track>> runs[2];
    for (auto &run : runs) {
        sfd::TrackerConfig cfg;
        sfd::FeatureTracker tr(cfg);
        std::string err;
        for (int f = 0; f < 5; ++f) {
            assert_true(tr.track(shifted(tex, 1.7 * f, -0.9 * f), &err));
            run.push_back(tr.tracks());
        }
    }
    for (size_t f = 0; f < runs[0].size(); ++f) {
        assert_int_equal(runs[0][f].size(), runs[1][f].size());
        for (size_t i = 0; i < runs[0][f].size(); ++i) {
            assert_true(runs[0][f][i].id == runs[1][f][i].id);
            assert_true(runs[0][f][i].u_px == runs[1][f][i].u_px);  // bit-identical
            assert_true(runs[0][f][i].v_px == runs[1][f][i].v_px);
        }
    }
}

void test_rejects_bad_images_and_configs(void **state) {
    (void)state;
    sfd::TrackerConfig cfg;
    sfd::FeatureTracker tr(cfg);
    std::string err;
    assert_false(tr.track(cv::Mat(), &err));
    assert_true(err.find("empty") != std::string::npos);
    assert_false(tr.track(cv::Mat(100, 100, CV_8UC3, cv::Scalar(0)), &err));
    assert_false(tr.track(cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)), &err));
    const cv::Mat tex = texture(6);
    assert_true(tr.track(shifted(tex, 0, 0), &err));
    const auto before = tr.tracks();
    assert_false(tr.track(cv::Mat(kH + 2, kW, CV_8UC1, cv::Scalar(7)), &err));
    assert_true(err.find("differs") != std::string::npos);
    assert_int_equal(tr.tracks().size(), before.size());  // unchanged
    // A flat image: no corners, no crash, nothing tracked.
    sfd::FeatureTracker flat(cfg);
    assert_true(flat.track(cv::Mat(kH, kW, CV_8UC1, cv::Scalar(90)), &err));
    assert_int_equal(flat.tracks().size(), 0);

    sfd::TrackerConfig bad = cfg;
    bad.max_features = sfd::kTrackerMaxFeatures + 1;
    assert_false(sfd::FeatureTracker::validate(bad, &err));
    bad = cfg;
    bad.max_features = 0;
    assert_false(sfd::FeatureTracker::validate(bad, &err));
    bad = cfg;
    bad.lk_window_px = 20;
    assert_false(sfd::FeatureTracker::validate(bad, &err));
    bad = cfg;
    bad.fb_threshold_px = 0.0;
    assert_false(sfd::FeatureTracker::validate(bad, &err));
    bad = cfg;
    bad.min_distance_px = std::nan("");
    assert_false(sfd::FeatureTracker::validate(bad, &err));
    assert_true(sfd::FeatureTracker::validate(cfg, &err));
}

}  // namespace

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_follows_known_shift),
        cmocka_unit_test(test_ids_monotonic_never_reused),
        cmocka_unit_test(test_fb_check_rejects_altered_patch),
        cmocka_unit_test(test_bound_and_spacing),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_rejects_bad_images_and_configs),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
