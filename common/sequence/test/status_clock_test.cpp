// The elapsed time a sequence's status reports stops when the sequence ends: a status
// heard long after a completion still says how long the sequence ran.
#include "sequence/executor.hpp"

#include <gtest/gtest.h>

using namespace rover::sequence;

TEST(SequenceStatusClock, ElapsedStopsWhenTheSequenceEnds) {
  ExecutorOptions options;
  options.required_processes = {"state_estimator"};
  SequenceExecutor ex(options);
  std::int64_t utime = 1'000'000;
  double wall = 10.0;
  auto tick = [&](double seconds) {
    for (int i = 0; i < static_cast<int>(seconds * 10); ++i) {
      utime += 100'000;
      wall += 0.1;
      ex.OnHeartbeat("state_estimator", wall);
      PoseEstimate p;
      p.utime = utime;
      ex.OnPose(p);
      ex.Tick(utime, wall);
      ex.TakeOutputs();
    }
  };
  tick(1.0);
  // Settings only: no motion, so it completes as soon as it starts.
  ex.SubmitText("slip limit 40 %\nlimit time 600 s\n", 3, "settings.seq");
  tick(2.0);
  ASSERT_EQ(ex.state(), SequenceState::kCompleted) << ex.CurrentStatus().detail;
  const double at_end = ex.CurrentStatus().elapsed_s;
  EXPECT_LT(at_end, 2.0);
  tick(300.0);  // five minutes later the executor is still publishing statuses
  EXPECT_DOUBLE_EQ(ex.CurrentStatus().elapsed_s, at_end);
}
