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

inline std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void Write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

inline std::string Vec(double x, double y, double z) {
  std::ostringstream s;
  s << "[" << x << ", " << y << ", " << z << "]";
  return s.str();
}

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

// Air-film load-lift table of one pad: exponential (vertical) or inverse-square (lateral).
inline std::string FilmArrays(bool exponential, bool csv = false) {
  std::ostringstream gap, load;
  for (int i = 0; i <= 80; ++i) {
    const double h = (0.5 + 0.75 * i) * 1e-6;
    const double w = exponential ? 300.0 * std::exp(-h / 6e-6) : 80.0 * std::pow(5e-6 / h, 2.0);
    if (csv) {
      gap << h << "," << w << "\n";
      continue;
    }
    gap << (i ? ", " : "") << h;
    load << (i ? ", " : "") << w;
  }
  if (csv) return "gap,load\n" + gap.str();
  return "gap = [" + gap.str() + "], load = [" + load.str() + "]";
}

/// The two-body guideway of the real-chain tests: carriage on 4 vertical (exponential W(h)) and 4
/// lateral (inverse-square W(h)) air-film pads over a base on 12 mount springs, 8 test points,
/// setups stud-5um / stud-9um. `lateral_file` non-empty: the lateral curve is read from that CSV
/// (written by the caller with FilmArrays(false, true)), relative to the model's folder.
inline std::string ModelToml(const std::string& lateral_group = "bearings", const std::string& lateral_file = "") {
  std::ostringstream m;
  m.precision(10);
  m << "[model]\nname = \"two-body guideway (test)\"\n\n"
    << "[[body]]\nname = \"carriage\"\nmass = 2.88\ninertia = [0.0117763, 0.0151621, 0.0104617]\ncentre = [0.0, 0.0, 0.0]\n\n"
    << "[[body]]\nname = \"base\"\nmass = 12.0\ninertia = [0.08, 0.10, 0.15]\ncentre = [0.0, 0.0, -0.08]\n\n"
    << "[damping]\nratio = 0.01\n\n";
  int n = 0;
  const std::string vertical = FilmArrays(true);
  const std::string lateral = lateral_file.empty() ? FilmArrays(false) : "file = \"" + lateral_file + "\"";
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03})
      m << "[[spring]]\nname = \"V" << ++n << "\"\ngroup = \"bearings\"\na = { body = \"carriage\", at = "
        << Vec(x, y, -0.03) << " }\nb = { body = \"base\" }\ndirection = [0, 0, 1]\n"
        << "law = { series = { setting = 5.0e-6, elements = [ { air_film = { " << vertical << " } } ] } }\n\n";
  for (double x : {-0.06, 0.06})
    for (double y : {-0.045, 0.045})
      m << "[[spring]]\nname = \"L" << ++n << "\"\ngroup = \"" << lateral_group
        << "\"\na = { body = \"carriage\", at = " << Vec(x, y, 0.0) << " }\nb = { body = \"base\" }\ndirection = "
        << Vec(0, y > 0 ? -1.0 : 1.0, 0) << "\n"
        << "law = { series = { setting = 5.0e-6, elements = [ { air_film = { " << lateral << " } } ] } }\n\n";
  m << "[[spring]]\nname = \"drive\"\ngroup = \"drive\"\na = { body = \"carriage\", at = [0, 0, 0] }\n"
       "b = { body = \"base\" }\ndirection = [1, 0, 0]\nlaw = { linear = { k = 3.0e6 } }\n\n";
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08}) {
      const std::string at = Vec(x, y, -0.1);
      ++n;
      m << "[[spring]]\nname = \"MZ" << n << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = " << at
        << " }\nb = { body = \"ground\" }\ndirection = [0, 0, 1]\nlaw = { linear = { k = 8.0e6 } }\n\n"
        << "[[spring]]\nname = \"MX" << n << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = " << at
        << " }\nb = { body = \"ground\" }\ndirection = [1, 0, 0]\nlaw = { linear = { k = " << (x > 0 ? 3.0e6 : 2.0e6)
        << " } }\n\n"
        << "[[spring]]\nname = \"MY" << n << "\"\ngroup = \"mounts\"\na = { body = \"base\", at = " << at
        << " }\nb = { body = \"ground\" }\ndirection = [0, 1, 0]\nlaw = { linear = { k = 3.0e6 } }\n\n";
    }
  int id = 101;
  for (double x : {-0.06, 0.06})
    for (double y : {-0.03, 0.03})
      m << "[[point]]\nid = " << id++ << "\nbody = \"carriage\"\nat = " << Vec(x, y, 0.03) << "\n\n";
  id = 201;
  for (double x : {-0.1, 0.1})
    for (double y : {-0.08, 0.08})
      m << "[[point]]\nid = " << id++ << "\nbody = \"base\"\nat = " << Vec(x, y, -0.06) << "\n\n";
  m << "[[setup]]\nname = \"stud-5um\"\noperating = { bearings = 5.0e-6 }\n\n"
    << "[[setup]]\nname = \"stud-9um\"\noperating = { bearings = 9.0e-6 }\n";
  return m.str();
}

}  // namespace ema::test_chain
