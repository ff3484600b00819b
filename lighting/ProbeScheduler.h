// ProbeScheduler.h — v1 planner: where to capture the next probe (thesis 8.1, 8.4, appendix B).
//
// [SECTION] Motion model   observe(): the camera's position and velocity history; the velocity
//                          is low-pass filtered (inertia, thesis 8.1: the camera keeps roughly
//                          its direction for several frames). predictedPath(): samples of the
//                          future ground track — a straight line along the filtered velocity, or,
//                          on a road and moving along it, the road ahead. After a teleport
//                          (CaptureCore.h) the owner calls reset(): the history and the
//                          prediction restart at the new place.
// [SECTION] Resolution     finestLevel(): the finest lattice level worth capturing at the current
//                          speed. Keeping a corridor `corridorCells` cells wide along the track
//                          populated at spacing s costs speed x corridorCells / s probes per
//                          second; the finest level is the finest whose spacing keeps this within
//                          the probe rate (thesis 8.4: resolution falls as speed rises).
// [SECTION] Choice         choose(): candidate lattice points around the predicted path (the
//                          finest level within a narrow corridor, coarser levels further out),
//                          ranked by cost in seconds, lowest first:
//                            cost = time until the camera comes nearest the point
//                                   (min over path samples of tau + distance / max(speed, v_min))
//                                 - gapBonus_s        if no anchor of its level is near it
//                                 - coarseFirst_s x s_L / s_0   for a new point of level L
//                                 + staleBias_s x (1 - urgency)  if an anchor is there but asks
//                                                     for regeneration (urgency 0 when it asks,
//                                                     1 when it expires)
//                          Points with a fresh anchor are skipped. When none is left, the
//                          corridor widens (up to maxWiden doublings), then the scheduler idles.
//                          The candidates and their time to reach depend only on the motion
//                          observed and the lattice: they are found once a frame (between two
//                          observe calls) and kept for the frame's other choices, so a budget of
//                          many probes a frame does not search the rings again for each.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/AnchorStore.h"

namespace amb {

class RoadNetwork;

struct ProbeSchedulerSettings {
    // Motion model.
    double velocityTimeConstant_s = 0.3;  // inertia of the velocity filter
    double horizon_s = 3.0;               // how far ahead the path is predicted
    double pathStep_s = 0.25;             // spacing of the path samples
    double historyLength_s = 2.0;         // position history kept
    double roadSnap_m = 6.0;     // within halfWidth + this of a road's centre the camera is on it
    double roadAlignment = 0.7;  // |cos| between motion and road direction needed to follow it
    // Resolution against speed.
    // Width of the finest-level corridor along the path, in cells.
    // (why this value: docs/TUNING.md "Scheduler")
    double corridorCells = 4.0;
    // Never capture finer than this lattice level (0: the coarsest; level 2 is 27 m with the
    // default lattice). (why this value: docs/TUNING.md "Scheduler")
    int maxLevel = 2;
    // Candidates and priority.
    double finestRingCells = 1.0;     // finest-level candidates within this x s_L of the path
    double coarseRingCells = 2.0;     // coarser-level candidates within this x s_L of the path
    // Doublings of the rings when every point in them is fresh; 0: idle instead (why this value:
    // docs/TUNING.md "Scheduler").
    int maxWiden = 0;
    double minReachSpeed_mps = 10.0;  // speed assumed for time-to-reach when slower
    double gapBonus_s = 0.5;
    // A new point of level L is ranked this x s_L / s_0 seconds earlier: at a cold start (the
    // first frames, after a teleport) the coarse lattice, whose anchors reach furthest, is
    // captured before the fine corridor near the camera. 0: off. (why this value:
    // docs/TUNING.md "Scheduler")
    double coarseFirst_s = 0.0;
    double staleBias_s = 1.0;
    // Adaptive density (thesis appendix B, "colour difference to neighbours"): a new point of a
    // level L >= 1 is skipped when the four anchors of the level L - 1 cell around it are all
    // there and none differs from their mean by more than this relative irradiance distance
    // (lighting/Metrics.h): the coarse cell already says the field is uniform there, so a finer
    // probe would change little. 0: off (every point of the finest level is taken).
    double adaptiveThreshold = 0.0;
};

struct ProbeChoice {
    LatticeKey key;
    double cost_s = 0.0;         // see ProbeScheduler.h "Choice"
    double timeToReach_s = 0.0;  // first term of the cost
    bool refresh = false;        // an anchor exists there and asked for regeneration
};

class ProbeScheduler {
  public:
    explicit ProbeScheduler(const ProbeSchedulerSettings& settings = {});

    const ProbeSchedulerSettings& settings() const { return settings_; }
    // Every setting is read where it is used, so new ones apply from the next observe/choose.
    void setSettings(const ProbeSchedulerSettings& settings) {
        settings_ = settings;
        ++motion_;
    }
    // Roads to follow when the camera drives on one (may be null; must outlive the scheduler).
    void setRoads(const RoadNetwork* roads) {
        roads_ = roads;
        ++motion_;
    }

    // Feeds the camera at simulation time now_s. A non-finite velocity is replaced by the one
    // from the position history.
    void observe(const glm::dvec3& position_m, const glm::dvec3& velocity_mps, double now_s);
    // Forgets the motion (after a teleport, CaptureCore.h: the old prediction says nothing
    // about the new place).
    void reset();

    glm::dvec3 position_m() const { return position_; }
    glm::dvec3 velocity_mps() const { return velocity_; }  // filtered
    double speed_mps() const;                              // horizontal, filtered
    bool onRoad() const { return onRoad_; }

    // Ground-track samples (y = camera height) at tau = 0, pathStep_s, ..., horizon_s.
    struct PathSample {
        double tau_s;
        glm::dvec3 position_m;
    };
    std::vector<PathSample> predictedPath() const;
    glm::dvec3 predict(double ahead_s) const;

    // Finest level worth capturing at the current speed, given the probe rate (probes per
    // second the capture budget allows), within [0, min(store levels, maxLevel + 1) - 1].
    int finestLevel(const AnchorStore& store, double probesPerSecond) const;

    // The best point to capture next, or nothing when every candidate is fresh. `busy` lists
    // points already being captured.
    std::optional<ProbeChoice> choose(const AnchorStore& store, double probesPerSecond,
                                      const std::vector<LatticeKey>& busy = {}) const;

  private:
    // True when adaptive density leaves the new point `key` out (see adaptiveThreshold).
    bool coarseIsUniform(const AnchorStore& store, const LatticeKey& key) const;
    // The lattice points of every level up to `finest` within the level's ring (widened
    // `widen` times) around the path, and each one's time to reach (NaN until asked), as of the
    // motion last observed.
    struct Candidates {
        std::uint64_t motion = 0;
        const AnchorStore* store = nullptr;
        double coarsestSpacing_m = 0.0;
        int levels = 0, finest = -1, widen = -1;
        double reachSpeed = 0.0;
        std::vector<PathSample> path;
        std::vector<LatticeKey> keys;
        std::vector<double> reach_s;
    };
    Candidates& candidates(const AnchorStore& store, int finest, double reachSpeed,
                           int widen) const;
    double timeToReach(Candidates& c, std::size_t index, const AnchorStore& store) const;
    ProbeSchedulerSettings settings_;
    const RoadNetwork* roads_ = nullptr;
    struct Observation {
        double t_s;
        glm::dvec3 position_m;
    };
    std::deque<Observation> history_;
    glm::dvec3 position_{0.0};
    glm::dvec3 velocity_{0.0};
    double now_ = 0.0;
    bool initialised_ = false;
    bool onRoad_ = false;
    int roadIndex_ = -1;
    double roadAlong_m_ = 0.0;
    double roadDirection_ = 1.0;  // +1 along increasing arc length, -1 against
    std::uint64_t motion_ = 0;    // counts changes of the motion (observe, reset, settings, roads)
    mutable std::vector<Candidates> candidates_;  // by widen: this frame's
};

}  // namespace amb
