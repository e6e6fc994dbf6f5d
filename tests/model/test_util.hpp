// Helpers of the model tests: temporary files and a small rigid-body model builder.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "ema/model/model.hpp"

namespace ema::model::testing {

// One folder per test process: ctest runs each test of a fixture as its own process, two at once,
// and a folder shared by name let one test's SetUp rewrite the files another was reading (a
// flaky PartBadInput.NameClashWithASpringGroupOrABody).
inline std::filesystem::path TempDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(EMA_TEST_TMP_DIR) / "model" / (name + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::filesystem::path WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

inline Body MakeBody(const std::string& name, double mass, Eigen::Vector3d inertia,
                     Eigen::Vector3d centre = Eigen::Vector3d::Zero()) {
  Body b;
  b.name = name;
  b.mass = mass;
  b.inertia = inertia;
  b.centre = centre;
  return b;
}

inline Spring MakeSpring(const std::string& name, const std::string& group, const std::string& body,
                         Eigen::Vector3d at, Eigen::Vector3d direction, Law law) {
  Spring s;
  s.name = name;
  s.group = group;
  s.a.body = body;
  s.a.at = at;
  s.a.has_at = true;
  s.b.body = kGround;
  s.direction = direction;
  s.law = std::move(law);
  return s;
}

}  // namespace ema::model::testing
