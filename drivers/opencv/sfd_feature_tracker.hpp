// SPDX-License-Identifier: MIT
/**
 * @file sfd_feature_tracker.hpp
 * @brief Feature tracker for 8-bit grayscale frames with OpenCV (host driver, not core):
 *        Shi-Tomasi corners (cv::goodFeaturesToTrack, refined with cv::cornerSubPix), pyramidal
 *        Lucas-Kanade tracking (cv::calcOpticalFlowPyrLK, Bouguet 2000) with an optional
 *        forward-backward check (Kalal et al. 2010: track the result back to the previous frame and
 *        reject the track when it does not return within fb_threshold_px), and replenishment to
 *        max_features with a minimum spacing of min_distance_px.
 *
 * Units: pixels of the raw (distorted) image, origin at the centre of the top-left pixel (OpenCV's
 * convention, as FEATURES' u, v expect).
 *
 * Capacity: at most TrackerConfig::max_features tracks per frame, itself at most
 * kTrackerMaxFeatures = min(SFD_MAX_FEATURES, FEATURES wire capacity 512), so every frame fits a
 * FEATURES message the node accepts.
 *
 * Track ids: 1, 2, 3, ... in order of creation, monotonically increasing and never reused (int64).
 * A track keeps its id while LK follows it; a lost track is never revived.
 *
 * Spacing: after tracking, a track closer than min_distance_px to an older (longer-tracked)
 * surviving track is dropped (the older one is kept), and new corners are detected only farther
 * than min_distance_px from every track; so all pairwise distances are >= min_distance_px.
 *
 * Determinism: the output depends only on the sequence of images and the configuration (OpenCV's
 * corner detection sorts by response with a position tie-break; LK is per point); no clock, no
 * random numbers. Heap: OpenCV and std::vector allocate (host driver). Not thread-safe: one
 * tracker per image stream.
 */
#ifndef SFD_FEATURE_TRACKER_HPP
#define SFD_FEATURE_TRACKER_HPP

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "sfd/sfd_config.h"

namespace sfd {

/// Largest max_features: the core's capacity and FEATURES' wire capacity (512).
constexpr int kTrackerMaxFeatures = SFD_MAX_FEATURES < 512 ? SFD_MAX_FEATURES : 512;

struct TrackerConfig {
    int max_features = 150;  ///< target (and bound) of tracks per frame, 1..kTrackerMaxFeatures
    double min_distance_px = 20.0;  ///< minimum distance between two tracks (px), >= 0
    double quality_level = 0.01;    ///< Shi-Tomasi: min eigenvalue relative to the best, (0, 1)
    int block_size_px = 3;          ///< Shi-Tomasi: derivative covariation window (px), >= 1
    int border_px = 8;              ///< no corners and no tracks closer than this to the edge (px)
    int lk_window_px = 21;          ///< LK search window side (px), odd, >= 5
    int lk_pyramid_levels = 3;      ///< LK pyramid levels above the full image, 0..8
    int lk_max_iterations = 30;     ///< LK iterations per level, >= 1
    double lk_epsilon_px = 0.01;    ///< LK stops when the update is below this (px), > 0
    double lk_min_eig = 1e-4;       ///< LK: reject a point whose gradient matrix is weaker, >= 0
    bool fb_check = true;           ///< forward-backward check on (false: plain LK)
    double fb_threshold_px = 1.0;   ///< forward-backward: max round-trip error (px), > 0
};

/// One tracked feature in the current frame.
struct Track {
    int64_t id;   ///< stable track id (see file comment)
    double u_px;  ///< column of the feature (px)
    double v_px;  ///< row of the feature (px)
    int32_t age;  ///< frames this track has been seen in, 1 for a new one
};

/// What one call of track() did (counts of tracks).
struct TrackerStats {
    int tracked = 0;       ///< tracks carried over from the previous frame
    int lost_lk = 0;       ///< LK failed (status 0, small eigenvalue, left the image border)
    int lost_fb = 0;       ///< rejected by the forward-backward check
    int lost_spacing = 0;  ///< dropped for being closer than min_distance_px to an older track
    int added = 0;         ///< new corners
};

class FeatureTracker {
  public:
    /// The configuration must pass validate(); an invalid one is replaced by the defaults
    /// (check with validate() first; the constructor does not throw).
    explicit FeatureTracker(const TrackerConfig &cfg);

    /// True when cfg is usable; otherwise false and a one-line reason naming the field.
    static bool validate(const TrackerConfig &cfg, std::string *error);

    /**
     * @brief Tracks the previous frame's features into `gray` and replenishes.
     * @param gray  8-bit single-channel image (CV_8UC1), not empty, of the same size as the first
     *              frame, larger than 2 * border_px + 1 in both directions.
     * @return true; false with a reason in *error (image rejected; the tracker is unchanged).
     */
    bool track(const cv::Mat &gray, std::string *error);

    /// Tracks of the last accepted frame, older tracks first (ascending id).
    const std::vector<Track> &tracks() const { return m_tracks; }
    /// Counts of the last call.
    const TrackerStats &stats() const { return m_stats; }
    const TrackerConfig &config() const { return m_cfg; }
    /// Next id to be given (ids given so far are 1 .. next_id() - 1).
    int64_t next_id() const { return m_next_id; }

  private:
    void replenish(const cv::Mat &gray);
    void enforce_spacing();

    TrackerConfig m_cfg;
    cv::Size m_size;
    std::vector<cv::Mat> m_prev_pyramid;
    std::vector<Track> m_tracks;
    TrackerStats m_stats;
    int64_t m_next_id = 1;
};

}  // namespace sfd

#endif  // SFD_FEATURE_TRACKER_HPP
