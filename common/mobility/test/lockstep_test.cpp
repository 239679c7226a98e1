#include "mobility/lockstep.hpp"

#include <gtest/gtest.h>

using rover::mobility::EstimatorLockstep;

TEST(EstimatorLockstep, WaitsOnlyForALiveEstimatorThatHasPosedSinceItStarted) {
  EstimatorLockstep lock(0.5, 2.0);
  EXPECT_FALSE(lock.ShouldWait(10'000'000, 0.0)) << "nothing posed yet: run so that it can";
  lock.OnHeartbeat("state_estimator", 0, 0.0);
  lock.OnPose(1'000'000);
  EXPECT_FALSE(lock.ShouldWait(1'400'000, 0.5)) << "within the lead";
  EXPECT_TRUE(lock.ShouldWait(1'600'000, 0.5)) << "past the lead, estimator alive";
  lock.OnHeartbeat("hazard_monitor", 0, 3.0);
  EXPECT_FALSE(lock.ShouldWait(1'600'000, 3.0)) << "no estimator heartbeat for 3 s: dead, run on";
  // Restarted: its heartbeat count begins again; the clock runs until it poses.
  lock.OnHeartbeat("state_estimator", 0, 3.5);
  lock.OnHeartbeat("state_estimator", 5, 3.6);
  lock.OnHeartbeat("state_estimator", 0, 4.0);
  EXPECT_FALSE(lock.ShouldWait(9'000'000, 4.0));
  lock.OnPose(8'000'000);
  EXPECT_TRUE(lock.ShouldWait(9'000'000, 4.1));
  lock.OnPose(8'800'000);
  EXPECT_FALSE(lock.ShouldWait(9'000'000, 4.2));
}
