// SPDX-License-Identifier: MIT
// Feature tracker (see sfd_feature_tracker.hpp): Shi-Tomasi + pyramidal LK + forward-backward.
#include "sfd_feature_tracker.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>

namespace sfd {
namespace {

bool inside(const cv::Point2f &p, const cv::Size &size, int border_px) {
    return std::isfinite(p.x) && std::isfinite(p.y) && p.x >= float(border_px) &&
           p.y >= float(border_px) && p.x <= float(size.width - 1 - border_px) &&
           p.y <= float(size.height - 1 - border_px);
}

double dist2_px2(double u0, double v0, double u1, double v1) {
    return (u0 - u1) * (u0 - u1) + (v0 - v1) * (v0 - v1);
}

}  // namespace

FeatureTracker::FeatureTracker(const TrackerConfig &cfg) : m_cfg(cfg) {
    std::string ignored;
    if (!validate(cfg, &ignored)) m_cfg = TrackerConfig{};
}

bool FeatureTracker::validate(const TrackerConfig &c, std::string *error) {
    const auto fail = [error](const char *why) {
        if (error != nullptr) *error = why;
        return false;
    };
    if (c.max_features < 1 || c.max_features > kTrackerMaxFeatures)
        return fail("max_features must be 1..kTrackerMaxFeatures (SFD_MAX_FEATURES, <= 512)");
    if (!(c.min_distance_px >= 0.0 && c.min_distance_px <= 1000.0))
        return fail("min_distance_px must be in [0, 1000]");
    if (!(c.quality_level > 0.0 && c.quality_level < 1.0))
        return fail("quality_level must be in (0, 1)");
    if (c.block_size_px < 1 || c.block_size_px > 31) return fail("block_size_px must be 1..31");
    if (c.border_px < 0 || c.border_px > 1000) return fail("border_px must be 0..1000");
    if (c.lk_window_px < 5 || c.lk_window_px > 101 || c.lk_window_px % 2 == 0)
        return fail("lk_window_px must be odd, 5..101");
    if (c.lk_pyramid_levels < 0 || c.lk_pyramid_levels > 8)
        return fail("lk_pyramid_levels must be 0..8");
    if (c.lk_max_iterations < 1 || c.lk_max_iterations > 1000)
        return fail("lk_max_iterations must be 1..1000");
    if (!(c.lk_epsilon_px > 0.0 && c.lk_epsilon_px < 10.0))
        return fail("lk_epsilon_px must be in (0, 10)");
    if (!(c.lk_min_eig >= 0.0 && c.lk_min_eig < 1.0)) return fail("lk_min_eig must be in [0, 1)");
    if (!(c.fb_threshold_px > 0.0 && c.fb_threshold_px <= 1000.0))
        return fail("fb_threshold_px must be in (0, 1000]");
    return true;
}

bool FeatureTracker::track(const cv::Mat &gray, std::string *error) {
    const auto fail = [error](const std::string &why) {
        if (error != nullptr) *error = why;
        return false;
    };
    if (gray.empty()) return fail("empty image");
    if (gray.type() != CV_8UC1) return fail("image is not 8-bit single-channel (CV_8UC1)");
    if (gray.cols <= 2 * m_cfg.border_px + 1 || gray.rows <= 2 * m_cfg.border_px + 1)
        return fail("image smaller than twice the border");
    if (!m_prev_pyramid.empty() && gray.size() != m_size) {
        return fail("image size " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                    " differs from the first frame's " + std::to_string(m_size.width) + "x" +
                    std::to_string(m_size.height));
    }
    m_stats = TrackerStats{};
    const cv::Size win(m_cfg.lk_window_px, m_cfg.lk_window_px);
    std::vector<cv::Mat> pyramid;
    const int levels = cv::buildOpticalFlowPyramid(gray, pyramid, win, m_cfg.lk_pyramid_levels);

    if (!m_tracks.empty() && !m_prev_pyramid.empty()) {
        const size_t n = m_tracks.size();
        std::vector<cv::Point2f> prev(n), next(n), back;
        for (size_t i = 0; i < n; ++i) {
            prev[i] = cv::Point2f(float(m_tracks[i].u_px), float(m_tracks[i].v_px));
        }
        std::vector<uint8_t> status, status_back;
        std::vector<float> err;
        const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                    m_cfg.lk_max_iterations, m_cfg.lk_epsilon_px);
        cv::calcOpticalFlowPyrLK(m_prev_pyramid, pyramid, prev, next, status, err, win, levels,
                                 crit, 0, m_cfg.lk_min_eig);
        if (m_cfg.fb_check) {
            back = prev;  // initial guess: where the point was
            cv::calcOpticalFlowPyrLK(pyramid, m_prev_pyramid, next, back, status_back, err, win,
                                     levels, crit, cv::OPTFLOW_USE_INITIAL_FLOW, m_cfg.lk_min_eig);
        }
        const double fb2 = m_cfg.fb_threshold_px * m_cfg.fb_threshold_px;
        std::vector<Track> kept;
        kept.reserve(n);
        for (size_t i = 0; i < n; ++i) {
            if (status[i] == 0 || !inside(next[i], gray.size(), m_cfg.border_px)) {
                ++m_stats.lost_lk;
                continue;
            }
            if (m_cfg.fb_check &&
                (status_back[i] == 0 ||
                 !(dist2_px2(back[i].x, back[i].y, prev[i].x, prev[i].y) <= fb2))) {
                ++m_stats.lost_fb;
                continue;
            }
            Track t = m_tracks[i];
            t.u_px = double(next[i].x);
            t.v_px = double(next[i].y);
            ++t.age;
            kept.push_back(t);
        }
        m_tracks.swap(kept);
        enforce_spacing();
        m_stats.tracked = int(m_tracks.size());
    } else {
        m_tracks.clear();
    }
    replenish(gray);
    m_size = gray.size();
    m_prev_pyramid.swap(pyramid);
    return true;
}

// Drops every track closer than min_distance_px to an older surviving one. m_tracks is in
// ascending id order, i.e. oldest first, so a greedy pass keeps the older track of each pair.
// O(n^2) with n <= kTrackerMaxFeatures.
void FeatureTracker::enforce_spacing() {
    const double d2 = m_cfg.min_distance_px * m_cfg.min_distance_px;
    std::vector<Track> kept;
    kept.reserve(m_tracks.size());
    for (const Track &t : m_tracks) {
        bool ok = true;
        for (const Track &k : kept) {
            if (dist2_px2(t.u_px, t.v_px, k.u_px, k.v_px) < d2) {
                ok = false;
                break;
            }
        }
        if (ok) {
            kept.push_back(t);
        } else {
            ++m_stats.lost_spacing;
        }
    }
    m_tracks.swap(kept);
}

// Detects Shi-Tomasi corners (Shi & Tomasi 1994, min eigenvalue of the gradient covariance)
// outside discs of radius min_distance_px around the tracks and inside the border, refines them
// to sub-pixel, and appends up to max_features - tracks of them with new ids.
void FeatureTracker::replenish(const cv::Mat &gray) {
    const int want = m_cfg.max_features - int(m_tracks.size());
    if (want <= 0) return;
    cv::Mat mask(gray.size(), CV_8UC1, cv::Scalar(0));
    const int b = m_cfg.border_px;
    mask(cv::Rect(b, b, gray.cols - 2 * b, gray.rows - 2 * b)).setTo(cv::Scalar(255));
    const int radius = int(std::ceil(m_cfg.min_distance_px));
    for (const Track &t : m_tracks) {
        cv::circle(mask, cv::Point(int(std::lround(t.u_px)), int(std::lround(t.v_px))), radius,
                   cv::Scalar(0), cv::FILLED);
    }
    std::vector<cv::Point2f> corners;
    cv::goodFeaturesToTrack(gray, corners, want, m_cfg.quality_level, m_cfg.min_distance_px, mask,
                            m_cfg.block_size_px);
    if (corners.empty()) return;
    cv::cornerSubPix(gray, corners, cv::Size(3, 3), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.01));
    // The refinement moves a corner by up to the window: re-check the border and the spacing
    // (against the tracks and the corners accepted before it, strongest first).
    const double d2 = m_cfg.min_distance_px * m_cfg.min_distance_px;
    for (const cv::Point2f &c : corners) {
        if (int(m_tracks.size()) >= m_cfg.max_features) break;
        if (!inside(c, gray.size(), b)) continue;
        bool ok = true;
        for (const Track &t : m_tracks) {
            if (dist2_px2(c.x, c.y, t.u_px, t.v_px) < d2) {
                ok = false;
                break;
            }
        }
        if (!ok) continue;
        m_tracks.push_back(Track{m_next_id++, double(c.x), double(c.y), 1});
        ++m_stats.added;
    }
}

}  // namespace sfd
