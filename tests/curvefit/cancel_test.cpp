// Cancellation (issue 41, Ctrl-C in ema.fit): a progress callback that throws ema::Cancelled from a
// worker thread stops curvefit::Fit promptly, and the exception reaches the caller.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "curvefit/synthetic.hpp"
#include "ema/core/parallel.hpp"
#include "ema/core/progress.hpp"
#include "ema/curvefit/fit.hpp"

namespace ema::curvefit {
namespace {

// Six modes over 8 outputs, 1 % noise: a fit with a PolyMAX stage of many orders and an ML
// refinement of several iterations.
FrfSet CancelTestFrfs() {
  const test::Truth truth = test::MakeTruth({13.0, 38.1, 58.8, 78.2, 96.1, 111.5},
                                            {0.0065, 0.0072, 0.0084, 0.0070, 0.0078, 0.0081}, 8);
  return test::MakeFrfSet(truth, {0}, 128.0, 0.0625, 0.01, 41);
}

FitOptions CancelTestOptions() {
  FitOptions options;
  options.data.band_lo_hz = 5.0;
  options.data.band_hi_hz = 125.0;
  options.polymax.order_max = 60;
  options.polymax.threads = 3;  // worker threads beside the calling one, whatever the machine
  return options;
}

TEST(Cancel, ThrownFromAPolymaxWorkerStopsTheFitAndReachesTheCaller) {
  const FrfSet frfs = CancelTestFrfs();
  const FitOptions options = CancelTestOptions();
  const std::thread::id caller = std::this_thread::get_id();
  std::mutex mutex;
  int orders_done = 0, orders_after = 0;
  bool thrown = false;
  const ProgressCallback progress = [&](double fraction, std::string_view stage) {
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_EQ(stage, "poles");  // never the refinement: the fit stopped in the PolyMAX stage
    if (fraction == 0.0) return;  // the normal equations' steps, before the first order
    if (thrown) {
      ++orders_after;
      return;
    }
    ++orders_done;
    if (std::this_thread::get_id() != caller) {  // a worker thread's order
      thrown = true;
      throw Cancelled{};
    }
  };
  EXPECT_THROW(Fit(frfs, options, "cancel", progress), Cancelled);
  EXPECT_TRUE(thrown);
  // The other threads each finish the order they are in and stop without reporting it: the
  // cancellation is seen under the progress lock, whatever the scheduling (a loaded machine once
  // let them report 6 more orders while the thrower was descheduled).
  EXPECT_EQ(orders_after, 0);
  EXPECT_LT(orders_done + orders_after, 20);
}

TEST(Cancel, ThrownDuringTheRefinementStopsTheFit) {
  const FrfSet frfs = CancelTestFrfs();
  const FitOptions options = CancelTestOptions();
  // The control: the whole fit reports every order and then refinement iterations.
  int iterations = 0;
  const FitResult full = Fit(frfs, options, "cancel", [&](double fraction, std::string_view stage) {
    if (stage == "ML refinement" && fraction > 0.0) ++iterations;
  });
  ASSERT_GE(full.modes.modes.size(), 5u);
  ASSERT_GE(iterations, 2);
  // Thrown at the first refinement iteration (from inside Ceres' iteration callback): the solver
  // stops and the exception comes out of Fit, not a "refinement failed" warning.
  bool poles_done = false;
  int refinement_steps = 0;
  const ProgressCallback progress = [&](double fraction, std::string_view stage) {
    if (stage == "poles" && fraction == 1.0) poles_done = true;
    if (stage == "ML refinement" && fraction > 0.0) {
      ++refinement_steps;
      throw Cancelled{};
    }
  };
  EXPECT_THROW(Fit(frfs, options, "cancel", progress), Cancelled);
  EXPECT_TRUE(poles_done);
  EXPECT_EQ(refinement_steps, 1);
}

TEST(Cancel, AFlagRaisedFromAnotherThreadStopsAFitInProgress) {
  // What the Python binding does on Ctrl-C: another thread raises the flag while the fit runs; the
  // flag's callback throws at the fit's next step. The same fit uncancelled gives the same modes
  // as one without any callback (the callback changes nothing but where the fit may stop).
  const FrfSet frfs = CancelTestFrfs();
  FitOptions options = CancelTestOptions();
  const FitResult plain = Fit(frfs, options, "cancel");
  CancelFlag idle;
  const FitResult with_callback = Fit(frfs, options, "cancel", idle.Callback());
  ASSERT_EQ(plain.modes.modes.size(), with_callback.modes.modes.size());
  for (size_t k = 0; k < plain.modes.modes.size(); ++k) {
    EXPECT_EQ(plain.modes.modes[k].frequency_hz, with_callback.modes.modes[k].frequency_hz);
    EXPECT_EQ(plain.modes.modes[k].damping_ratio, with_callback.modes.modes[k].damping_ratio);
    EXPECT_EQ(plain.modes.modes[k].frequency_std_hz, with_callback.modes.modes[k].frequency_std_hz);
  }
  // Raised (from a thread of its own) when half the orders are done: every later step throws before
  // it reports, and the fit never reaches the refinement.
  CancelFlag flag;
  bool raised = false;
  int reported_after = 0;
  const ProgressCallback progress = flag.Callback([&](double fraction, std::string_view stage) {
    if (raised) ++reported_after;
    EXPECT_EQ(stage, "poles");
    if (!raised && fraction >= 0.5) {
      std::thread([&flag] { flag.Cancel(); }).join();
      raised = true;
    }
  });
  EXPECT_THROW(Fit(frfs, options, "cancel", progress), Cancelled);
  EXPECT_TRUE(raised);
  EXPECT_EQ(reported_after, 0);
}

TEST(Cancel, RunOnThreadsCarriesTheFirstExceptionAndStopsTheOthers) {
  // Worker 2 throws at its 5th step; the others see `stop` at their next step. Every thread is
  // joined before the exception reaches the caller (no std::terminate), and no worker runs its
  // loop to the end.
  std::atomic<int> steps_after_throw{0};
  std::atomic<bool> thrown{false};
  std::vector<int> finished(4, 0);
  EXPECT_THROW(RunOnThreads(4,
                            [&](int t, const std::atomic<bool>& stop) {
                              for (int step = 0; step < 1000000; ++step) {
                                if (stop.load()) return;
                                if (thrown.load()) ++steps_after_throw;
                                if (t == 2 && step == 5) {
                                  thrown = true;
                                  throw std::runtime_error("worker 2");
                                }
                                std::this_thread::yield();
                              }
                              finished[static_cast<size_t>(t)] = 1;
                            }),
               std::runtime_error);
  EXPECT_EQ(finished, std::vector<int>(4, 0));
  EXPECT_LT(steps_after_throw.load(), 1000);
  // One thread: the worker runs on the caller's, its exception passes unchanged.
  EXPECT_THROW(RunOnThreads(1, [](int, const std::atomic<bool>&) { throw Cancelled{}; }), Cancelled);
}

}  // namespace
}  // namespace ema::curvefit
