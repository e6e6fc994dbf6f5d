// The test plan of `ema simulate --plan` (formats::ReadPlanFile, docs/plan-format.md) written by
// formats::PlanToToml / WritePlanFile: every field the reader reads comes back exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "ema/core/error.hpp"
#include "ema/formats/plan_file.hpp"
#include "tmp_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

// Bit-for-bit equal numbers (NaN equals NaN).
void ExpectSamePlanNumber(double a, double b, const char* what) {
  if (std::isnan(a) || std::isnan(b)) {
    EXPECT_TRUE(std::isnan(a) && std::isnan(b)) << what << ": " << a << " vs " << b;
    return;
  }
  EXPECT_EQ(a, b) << what;
  EXPECT_EQ(std::signbit(a), std::signbit(b)) << what;
}

void ExpectSamePlan(const Plan& a, const Plan& b) {
  const acquisition::HammerTestPlan& x = a.hammer;
  const acquisition::HammerTestPlan& y = b.hammer;
  ExpectSamePlanNumber(x.sample_rate_hz, y.sample_rate_hz, "sample_rate_hz");
  EXPECT_EQ(x.samples_per_record, y.samples_per_record);
  ExpectSamePlanNumber(x.pre_trigger_fraction, y.pre_trigger_fraction, "pre_trigger");
  EXPECT_EQ(x.references, y.references);
  EXPECT_EQ(x.roving_sets, y.roving_sets);
  EXPECT_EQ(x.impacts_per_reference, y.impacts_per_reference);
  ExpectSamePlanNumber(x.force_peak_n, y.force_peak_n, "force_peak_n");
  ExpectSamePlanNumber(x.force_spread, y.force_spread, "force_spread");
  ExpectSamePlanNumber(x.pulse_duration_s, y.pulse_duration_s, "pulse_duration_s");
  ExpectSamePlanNumber(x.force_noise, y.force_noise, "force_noise");
  ExpectSamePlanNumber(x.response_noise, y.response_noise, "response_noise");
  EXPECT_EQ(x.noise_relative_to_peak, y.noise_relative_to_peak);
  EXPECT_EQ(x.response_quantity, y.response_quantity);
  ExpectSamePlanNumber(x.response_full_scale, y.response_full_scale, "response_full_scale");
  ExpectSamePlanNumber(x.force_full_scale, y.force_full_scale, "force_full_scale");
  EXPECT_EQ(x.trigger_jitter, y.trigger_jitter);
  EXPECT_EQ(x.oversampling, y.oversampling);
  EXPECT_EQ(x.seed, y.seed);
  EXPECT_EQ(x.number_impacts_across_sets, y.number_impacts_across_sets);
  ASSERT_EQ(x.force_levels_n.size(), y.force_levels_n.size());
  for (std::size_t i = 0; i < x.force_levels_n.size(); ++i)
    ExpectSamePlanNumber(x.force_levels_n[i], y.force_levels_n[i], "force_levels_n");
  ASSERT_EQ(x.double_hits.size(), y.double_hits.size());
  for (std::size_t i = 0; i < x.double_hits.size(); ++i) {
    EXPECT_EQ(x.double_hits[i].set, y.double_hits[i].set);
    EXPECT_EQ(x.double_hits[i].reference, y.double_hits[i].reference);
    EXPECT_EQ(x.double_hits[i].impact, y.double_hits[i].impact);
    ExpectSamePlanNumber(x.double_hits[i].delay_s, y.double_hits[i].delay_s, "delay_s");
    ExpectSamePlanNumber(x.double_hits[i].ratio, y.double_hits[i].ratio, "ratio");
  }
  ASSERT_EQ(x.clipping.size(), y.clipping.size());
  for (std::size_t i = 0; i < x.clipping.size(); ++i) {
    EXPECT_EQ(x.clipping[i].set, y.clipping[i].set);
    EXPECT_EQ(x.clipping[i].reference, y.clipping[i].reference);
    EXPECT_EQ(x.clipping[i].impact, y.clipping[i].impact);
    EXPECT_EQ(x.clipping[i].channel, y.clipping[i].channel);
    EXPECT_EQ(x.clipping[i].force, y.clipping[i].force);
    ExpectSamePlanNumber(x.clipping[i].full_scale, y.clipping[i].full_scale, "full_scale");
  }
  ASSERT_EQ(a.sets.size(), b.sets.size());
  for (std::size_t i = 0; i < a.sets.size(); ++i) {
    EXPECT_EQ(a.sets[i].name, b.sets[i].name);
    EXPECT_EQ(a.sets[i].sensors, b.sets[i].sensors);
    ASSERT_EQ(a.sets[i].masses.size(), b.sets[i].masses.size()) << "set " << i;
    for (const auto& [point, mass] : a.sets[i].masses) {
      ASSERT_TRUE(b.sets[i].masses.count(point)) << "set " << i << " point " << point;
      ExpectSamePlanNumber(mass, b.sets[i].masses.at(point), "mass");
    }
  }
  EXPECT_EQ(a.setup, b.setup);
  EXPECT_EQ(a.time_integration, b.time_integration);
}

// Writes `plan` with WritePlanFile and reads it back.
Plan PlanRoundTrip(const Plan& plan, const std::string& name, const std::string& comment = "") {
  const fs::path out = test::TmpFile(name);
  WritePlanFile(out, plan, comment);
  return ReadPlanFile(out);
}

TEST(PlanFileWriter, GuidewaySamplePlanRoundTrips) {
  const Plan original =
      ReadPlanFile(fs::path(EMA_SOURCE_DIR) / "samples" / "guideway" / "truth" / "plan-stud-5um.toml");
  // What the sample holds, so that the round trip below is not of an empty plan.
  ASSERT_EQ(original.sets.size(), 4u);
  ASSERT_EQ(original.hammer.references.size(), 3u);
  EXPECT_EQ(original.hammer.references[2], (Dof{101, -3}));
  ASSERT_EQ(original.hammer.double_hits.size(), 1u);
  EXPECT_EQ(original.sets[1].masses.at(105), 0.0112);
  EXPECT_EQ(original.setup, "stud-5um");

  const Plan back = PlanRoundTrip(original, "plan-roundtrip-guideway.toml");
  ExpectSamePlan(original, back);
  // The shared sensor mass is written once, as the sample does.
  const std::string text = PlanToToml(original);
  EXPECT_NE(text.find("sensor_mass = 0.0112\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\"101-Z\""), std::string::npos) << text;
  EXPECT_EQ(text.find("masses"), std::string::npos) << text;
  // Writing the read-back plan gives the same text again.
  EXPECT_EQ(PlanToToml(back), text);
}

// A plan with every optional field set, per-set and per-point masses, both fault kinds and
// numbers that need all 17 digits.
Plan FullPlan() {
  Plan p;
  auto& h = p.hammer;
  h.references = {{101, 3}, {7, -1}, {0, 2}};
  h.sample_rate_hz = 2560.0 / 3.0;
  h.samples_per_record = 1000;
  h.pre_trigger_fraction = 0.1;
  h.impacts_per_reference = 3;
  h.force_peak_n = 123.456789012345678;
  h.force_spread = 0.0;
  h.pulse_duration_s = 1.7e-3;
  h.force_noise = 1e-7;
  h.response_noise = 0.3;
  h.noise_relative_to_peak = true;
  h.response_quantity = Quantity::kVelocity;
  h.response_full_scale = 512.25;
  h.force_full_scale = 2.0e3;
  h.trigger_jitter = false;
  h.oversampling = 12;
  h.force_levels_n = {2.0, 5.5, 1.0 / 3.0};
  h.seed = 2147483647;
  p.setup = "stud \"5\" µm\\x";
  p.time_integration = true;
  RovingSet a;
  a.name = "set \"A\"";
  a.sensors = {{101, 1}, {101, 2}, {101, -3}, {102, 3}};
  a.masses = {{101, 0.0112}, {102, 0.004}, {999, 0.25}};  // 999: a mass where no sensor measures
  RovingSet b;
  b.name = "";
  b.sensors = {{103, -2}};
  b.masses = {{103, 0.0}};
  RovingSet c;
  c.name = "third";
  c.sensors = {{104, 3}, {105, 3}};
  c.masses = {{104, 1.0 / 7.0}, {105, 1.0 / 7.0}};
  p.sets = {a, b, c};
  for (const RovingSet& s : p.sets) h.roving_sets.push_back(s.sensors);
  h.double_hits.push_back({0, 1, 2, 0.0025, 0.45});
  h.double_hits.push_back({2, 0, 1, 1.0 / 3000.0, 1.0});
  acquisition::Clipping response;
  response.set = 1;
  response.reference = 2;
  response.impact = 3;
  response.channel = {103, -2};
  response.full_scale = 50.5;
  acquisition::Clipping force;
  force.set = 0;
  force.reference = 1;
  force.impact = 2;
  force.force = true;
  force.channel = h.references[1];
  force.full_scale = 1000.0 / 3.0;
  h.clipping = {response, force};
  return p;
}

TEST(PlanFileWriter, EveryOptionalFieldRoundTrips) {
  const Plan original = FullPlan();
  const Plan back = PlanRoundTrip(original, "plan-roundtrip-full.toml", "ema plan\ntwo lines\n");
  ExpectSamePlan(original, back);
  const std::string text = PlanToToml(original, "ema plan\ntwo lines\n");
  EXPECT_EQ(text.rfind("# ema plan\n# two lines\n\n[plan]\n", 0), 0u) << text;
  EXPECT_NE(text.find("integration = \"time\"\n"), std::string::npos) << text;
  EXPECT_NE(text.find("response = \"velocity\"\n"), std::string::npos) << text;
  EXPECT_EQ(PlanToToml(back, "ema plan\ntwo lines\n"), text);
}

TEST(PlanFileWriter, DefaultsAndNegativeSeedRoundTrip) {
  Plan p;
  p.hammer.references = {{1, 3}};
  RovingSet s;
  s.name = "set 1";
  s.sensors = {{2, 3}};
  p.sets = {s};  // no masses given: read back as 0 kg at the sensor point
  p.hammer.roving_sets = {s.sensors};
  p.hammer.seed = static_cast<std::uint64_t>(-5);  // what `seed = -5` reads as
  const Plan back = PlanRoundTrip(p, "plan-roundtrip-defaults.toml");
  EXPECT_EQ(back.hammer.seed, p.hammer.seed);
  ASSERT_EQ(back.sets.size(), 1u);
  EXPECT_EQ(back.sets[0].masses, (std::map<int, double>{{2, 0.0}}));
  p.sets[0].masses = {{2, 0.0}};
  ExpectSamePlan(p, back);
  EXPECT_TRUE(std::isnan(back.hammer.response_full_scale));
  const std::string text = PlanToToml(p);
  EXPECT_EQ(text.find("full_scale"), std::string::npos) << text;
  EXPECT_EQ(text.find("setup"), std::string::npos) << text;
  EXPECT_EQ(text.find("force_levels_n"), std::string::npos) << text;
  EXPECT_EQ(text.find("integration"), std::string::npos) << text;
  EXPECT_EQ(text.find("sensor_mass"), std::string::npos) << text;
}

TEST(PlanFileWriter, WrittenFileIsAcceptedAndMissingMassesMeanNoMass) {
  // Sets with different base masses and a sensor point with no mass entry.
  Plan p = FullPlan();
  p.sets[2].masses.erase(105);  // absent: no sensor mass, written as 0 kg (the set's own mass is 1/7)
  const fs::path out = test::TmpFile("plan-accepted.toml");
  WritePlanFile(out, p);
  Plan back;
  ASSERT_NO_THROW(back = ReadPlanFile(out));
  EXPECT_EQ(back.sets[2].masses.at(105), 0.0);
  EXPECT_EQ(back.sets[2].masses.at(104), 1.0 / 7.0);
  p.sets[2].masses[105] = 0.0;
  ExpectSamePlan(p, back);
}

TEST(PlanFileWriter, RefusesWhatTheFormatCannotSay) {
  Plan p = FullPlan();
  p.hammer.references[0] = {101, 4};  // a rotation
  EXPECT_THROW(PlanToToml(p), std::invalid_argument);
  p = FullPlan();
  p.hammer.seed = 1ull << 40;
  EXPECT_THROW(PlanToToml(p), std::invalid_argument);
  p = FullPlan();
  p.hammer.response_quantity = Quantity::kUnknown;
  EXPECT_THROW(PlanToToml(p), std::invalid_argument);
  p = FullPlan();
  p.hammer.double_hits[0].set = 3;
  EXPECT_THROW(PlanToToml(p), std::invalid_argument);
  p = FullPlan();
  p.hammer.clipping[0].reference = 3;
  EXPECT_THROW(PlanToToml(p), std::invalid_argument);
  p = FullPlan();
  p.sets[0].masses[-3] = 0.1;
  EXPECT_THROW(PlanToToml(p), std::invalid_argument);
}

}  // namespace
}  // namespace ema::formats
