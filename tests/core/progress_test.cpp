// ema/core/progress.hpp: the cancellation flag and the shared, throttled progress of a stage.
#include "ema/core/progress.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "ema/core/parallel.hpp"

namespace ema {
namespace {

TEST(Progress, CancelFlagThrowsFromTheNextStepOnly) {
  CancelFlag flag;
  int passed = 0;
  const ProgressCallback progress = flag.Callback([&](double, std::string_view) { ++passed; });
  progress(0.1, "a");
  EXPECT_EQ(passed, 1);
  std::thread([&flag] { flag.Cancel(); }).join();  // raised from another thread
  EXPECT_TRUE(flag.IsCancelled());
  EXPECT_THROW(progress(0.2, "a"), Cancelled);
  EXPECT_EQ(passed, 1);
  // Without an inner callback: only the check.
  const ProgressCallback check = flag.Callback();
  EXPECT_THROW(check(0.0, ""), Cancelled);
}

TEST(Progress, StepProgressReportsAboutAThousandTimesOneAtATimeAndEndsAtItsEnd) {
  // 100 000 steps from four threads: at most ~1000 reports, never two at once, never backwards,
  // the last one exactly `to`.
  std::atomic<int> inside{0};
  int reports = 0;
  double last = -1.0;
  bool overlapped = false, backwards = false;
  const ProgressCallback progress = [&](double fraction, std::string_view stage) {
    if (inside.fetch_add(1) != 0) overlapped = true;
    ++reports;
    if (fraction < last) backwards = true;
    last = fraction;
    EXPECT_EQ(stage, "spectra");
    inside.fetch_sub(1);
  };
  StepProgress steps(progress, "spectra", 100000, 0.5, 0.95);
  RunOnThreads(4, [&](int, const std::atomic<bool>&) {
    for (int k = 0; k < 25000; ++k) steps.Step();
  });
  EXPECT_LE(reports, 1001);
  EXPECT_GE(reports, 1000);
  EXPECT_FALSE(overlapped);
  EXPECT_FALSE(backwards);
  EXPECT_DOUBLE_EQ(last, 0.95);
  // Fewer steps than a thousand: every one reported. An empty callback: nothing to do.
  int few = 0;
  StepProgress small([&](double, std::string_view) { ++few; }, "x", 7);  // the callback copied: a temporary is fine
  for (int k = 0; k < 7; ++k) small.Step();
  EXPECT_EQ(few, 7);
  const ProgressCallback empty;
  StepProgress quiet(empty, "x", 3);
  quiet.Step();
}

TEST(Progress, StepProgressPassesWhatTheCallbackThrows) {
  CancelFlag flag;
  flag.Cancel();
  const ProgressCallback progress = flag.Callback();
  StepProgress steps(progress, "x", 10);
  EXPECT_THROW(steps.Step(), Cancelled);
}

}  // namespace
}  // namespace ema
