// Helpers of the simulated hammer-test chains (simulate → frf → fit → diagnose through the `ema`
// executable), shared by real_chain_test.cpp and acceptance_test.cpp.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "diagnose/article_models.hpp"
#include "test_files.hpp"

namespace ema::test_chain {

namespace fs = std::filesystem;
using nlohmann::json;

inline bool HaveExecutable() { return fs::exists(EMA_EXECUTABLE); }

/// Runs `ema ARGS` with stdout and stderr in dir/log; returns the exit code.
inline int RunEma(const fs::path& dir, const std::string& args, const std::string& log) {
  const std::string cmd =
      std::string("\"") + EMA_EXECUTABLE + "\" " + args + " > \"" + (dir / log).string() + "\" 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

using ema::test::Slurp;

/// A hammer plan: references, sensor sets (each a list of DOFs), 3 impacts each, 0.2 % force and
/// 0.5 % response noise, no sensor mass.
inline std::string Plan(unsigned seed, const std::vector<std::string>& references,
                        const std::vector<std::vector<std::string>>& sets) {
  std::ostringstream p;
  p << "[plan]\nreferences = [";
  for (size_t i = 0; i < references.size(); ++i) p << (i ? ", " : "") << '"' << references[i] << '"';
  p << "]\nsample_rate_hz = 4096.0\nsamples = 4096\nimpacts = 3\nforce_peak_n = 100.0\npulse_duration_s = 0.4e-3\n"
    << "force_noise = 0.002\nresponse_noise = 0.005\nsensor_mass = 0.0\nseed = " << seed << "\n\n";
  int n = 0;
  for (const auto& set : sets) {
    p << "[[set]]\nname = \"set " << ++n << "\"\nsensors = [";
    for (size_t i = 0; i < set.size(); ++i) p << (i ? ", " : "") << '"' << set[i] << '"';
    p << "]\n\n";
  }
  return p.str();
}

/// simulate → frf → fit of `model` with `plan_text`; returns the modes file (dir/tag-modes.unv).
inline fs::path Chain(const fs::path& dir, const fs::path& model, const std::string& setup, const std::string& tag,
                      const std::string& plan_text, const std::string& band = "40:1000") {
  const fs::path plan = dir / (tag + "-plan.toml");
  Write(plan, plan_text);
  const fs::path time = dir / (tag + ".unv"), frf = dir / (tag + "-frf.unv"), modes = dir / (tag + "-modes.unv");
  const std::string s = setup.empty() ? "" : " --setup " + setup;
  EXPECT_EQ(RunEma(dir,
                   "simulate \"" + model.string() + "\" --plan \"" + plan.string() + "\" -o \"" + time.string() + "\"" +
                       s + " --binary",
                   tag + "-simulate.log"),
            0)
      << Slurp(dir / (tag + "-simulate.log"));
  EXPECT_EQ(RunEma(dir, "frf \"" + time.string() + "\" -o \"" + frf.string() + "\"", tag + "-frf.log"), 0)
      << Slurp(dir / (tag + "-frf.log"));
  EXPECT_EQ(RunEma(dir, "fit \"" + frf.string() + "\" -o \"" + modes.string() + "\" --band " + band, tag + "-fit.log"), 0)
      << Slurp(dir / (tag + "-fit.log"));
  return modes;
}

/// `ema diagnose` with --json dir/tag-diag.json and -o `updated` (default dir/tag-updated.toml).
inline json Diagnose(const fs::path& dir, const fs::path& model,
                     const std::vector<std::pair<std::string, fs::path>>& tests, const std::string& tag,
                     const std::string& extra = "", fs::path updated = {}) {
  std::string args = "diagnose \"" + model.string() + "\"";
  for (const auto& [setup, modes] : tests)
    args += " --test \"" + (setup.empty() ? "" : setup + "=") + modes.string() + "\"";
  const fs::path out = dir / (tag + "-diag.json");
  if (updated.empty()) updated = dir / (tag + "-updated.toml");
  args += " --json \"" + out.string() + "\" -o \"" + updated.string() + "\" " + extra;
  EXPECT_EQ(RunEma(dir, args, tag + "-diagnose.log"), 0) << Slurp(dir / (tag + "-diagnose.log"));
  return json::parse(Slurp(out));
}

}  // namespace ema::test_chain
