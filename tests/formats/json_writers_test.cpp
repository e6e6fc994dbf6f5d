// The JSON writers of the result types (formats/json_codecs.hpp) write valid JSON whatever their
// input holds: labels, file names and messages in another encoding than UTF-8 (Latin-1 "m/s²",
// broken or overlong sequences, NUL), NaN and ±Inf, empty sets. nlohmann's dump() throws
// type_error 316 on a string that is not UTF-8; the codecs pass every text through JsonText
// (Latin-1 read as such, as the UFF reader does), and write a non-finite number as null.
// The fuzz targets fuzz_json_results and fuzz_json_modes_roundtrip try the same at random.
#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"
#include "ema/formats/json_codecs.hpp"
#include "tmp_file.hpp"

namespace ema::formats::json_writers_test {
namespace {

using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();
const std::string kLatin1 = "m/s\xB2";             // "m/s²" as Latin-1
const std::string kLatin1AsUtf8 = "m/s\xC2\xB2";   // the same as UTF-8
// Not UTF-8 for nlohmann (RFC 3629), though a lax check passes it: overlong NUL, a surrogate.
const std::string kOverlong = "\xC0\x80\xED\xA0\x80";
const std::string kNul = std::string("a\0b", 3);

// dump() succeeds and its text parses back; the parsed JSON is returned.
json DumpAndParse(const json& j) {
  std::string text;
  EXPECT_NO_THROW(text = j.dump(2)) << "dump() threw";
  json back;
  EXPECT_NO_THROW(back = json::parse(text)) << text;
  return back;
}

ModeSet NonFiniteModes() {
  ModeSet set;
  set.dofs = {{101, 3}, {102, -1}};
  Mode m;
  m.frequency_hz = kNaN;
  m.damping_ratio = kInf;
  m.pole = {-kInf, kNaN};
  m.shape = Eigen::VectorXcd(2);
  m.shape << std::complex<double>(kNaN, 1.0), std::complex<double>(-kInf, 0.0);
  m.shape_std = Eigen::VectorXd::Constant(2, kInf);
  m.frequency_std_hz = -kInf;
  m.set_frequency_hz = {kNaN};
  set.modes = {m};
  set.source = kLatin1;
  return set;
}

curvefit::FitResult LabelledFit() {
  curvefit::FitResult fit;
  fit.modes = NonFiniteModes();
  curvefit::SelectedPole s;
  s.pole.frequency_hz = kInf;
  s.frequency_spread_hz = kNaN;
  fit.selected = {s};
  fit.selection_rule = kLatin1;
  fit.refine.message = kOverlong;
  fit.dropped = {{kNaN, kInf, kNaN, kLatin1}};
  fit.diagram.orders = {{curvefit::Pole{}}};
  fit.diagram.orders[0][0].label = '\xB2';  // a label byte that is not ASCII
  fit.diagram.orders[0][0].frequency_hz = kNaN;
  fit.diagram.frequency_hz = Eigen::VectorXd::Constant(2, kInf);
  fit.diagram.sum_frf = Eigen::VectorXd::Constant(2, kNaN);
  fit.model.outputs = {{101, 3}};
  fit.model.references = {{1, 3}};
  fit.model.poles_fitted = {{kNaN, kInf}};
  fit.model.residues = Eigen::MatrixXcd::Constant(1, 1, {kInf, kNaN});
  return fit;
}

diagnose::Candidate LabelledCandidate() {
  diagnose::Candidate c;
  model::Effect e;
  e.kind = model::EffectKind::kStiffnessScale;  // typed: written by its name from the table
  e.target = model::EffectTarget::Named(kOverlong);
  e.parameters[kLatin1] = kNaN;
  e.law = model::LinearLaw{kInf};
  c.effects = {e};
  diagnose::FittedParameter p;
  p.effect_kind = model::EffectKind::kStiffnessScale;
  p.name = kLatin1;  // a JSON key
  p.value = kInf;
  p.at_bound = true;
  c.parameters = {p};
  c.kind = kLatin1;
  c.target = kNul;
  c.flags = {kOverlong};
  c.tied_with = {kLatin1};
  c.error = kLatin1;
  c.score = kNaN;
  diagnose::ModeComparison m;
  m.setup = kLatin1;
  m.test_mode = 0;
  m.model_frequency_hz = -kInf;
  c.modes = {m};
  return c;
}

TEST(JsonWriters, TextIsKeptWhenUtf8AndReadAsLatin1Otherwise) {
  EXPECT_EQ(JsonText(kLatin1AsUtf8), kLatin1AsUtf8);
  EXPECT_EQ(JsonText("\xE2\x82\xAC 101+Z"), "\xE2\x82\xAC 101+Z");  // € stays
  EXPECT_EQ(JsonText(kLatin1), kLatin1AsUtf8);
  EXPECT_EQ(JsonText(kNul), kNul);
  EXPECT_EQ(JsonText("\xC0\x80"), "\xC3\x80\xC2\x80");  // overlong: not UTF-8, each byte Latin-1
  EXPECT_EQ(JsonText("\xE2\x82"), "\xC3\xA2\xC2\x82");  // cut sequence
  EXPECT_EQ(JsonText("\xF4\x90\x80\x80"), "\xC3\xB4\xC2\x90\xC2\x80\xC2\x80");  // above U+10FFFF
  // Keys too.
  const json j = ValidUtf8({{kLatin1, {kOverlong, 1.0}}, {"ok", kNul}});
  EXPECT_EQ(DumpAndParse(j), json::parse("{\"m/s\xC2\xB2\": [\"\xC3\x80\xC2\x80\xC3\xAD\xC2\xA0\xC2\x80\", 1.0], "
                                         "\"ok\": \"a\\u0000b\"}"));
}

TEST(JsonWriters, EveryCodecWritesValidJsonForNonUtf8LabelsAndNonFiniteNumbers) {
  frf::FrfResult frf;
  frf.summary.frfs = {{{101, 3}, {1, 3}, 2, {{4, kLatin1, kOverlong}}}};
  frf.summary.notes = {kLatin1, kNul};
  frf.summary.window_decay_rate = kNaN;
  frf.frfs.frequency_hz = Eigen::VectorXd::Constant(3, kInf);
  const json summary = DumpAndParse(FrfSummaryJson(frf));
  EXPECT_EQ(summary["notes"][0], kLatin1AsUtf8);
  EXPECT_EQ(summary["frfs"][0]["rejected"][0]["file"], kLatin1AsUtf8);
  EXPECT_TRUE(summary["window_decay_rate"].is_null());
  EXPECT_TRUE(summary["frequency_max_hz"].is_null());

  const json modes = DumpAndParse(ModeSetJson(NonFiniteModes()));
  EXPECT_TRUE(modes["modes"][0]["frequency_hz"].is_null());
  EXPECT_TRUE(modes["modes"][0]["shape"][1]["value"][0].is_null());

  const curvefit::FitResult fit = LabelledFit();
  const json fitted = DumpAndParse(FitModesJson(fit, curvefit::RefineMethod::kMl));
  EXPECT_EQ(fitted["polymax"]["selection"], kLatin1AsUtf8);
  EXPECT_EQ(fitted["dropped"][0]["reason"], kLatin1AsUtf8);
  const json stab = DumpAndParse(StabilisationJson(fit, {}));
  EXPECT_EQ(stab["orders"][0]["poles"][0]["label"], "\xC2\xB2");
  DumpAndParse(ModalModelJson(fit.model));

  correlation::CorrelationResult corr;
  correlation::CorrelationRow row;
  row.test_mode = 0;
  row.model_mode = 0;
  row.remark = kLatin1;
  corr.rows = {row};
  corr.pairing.unpaired_test = {0};
  corr.comac = {{{101, 3}, kNaN}};
  corr.mac = Eigen::MatrixXd::Constant(1, 1, kInf);
  const ModeSet set = NonFiniteModes();
  EXPECT_EQ(DumpAndParse(CorrelationJson(corr, set, set))["pairs"][0]["remark"], kLatin1AsUtf8);

  model::Model model;
  model.name = kLatin1;
  model::Solution solution;
  solution.modes = set;
  model::SpringState spring;
  spring.name = kLatin1;
  spring.group = kOverlong;
  spring.force = kNaN;
  solution.springs = {spring};
  solution.energy = {{kNul, {kInf}}};
  const json solved = DumpAndParse(ModelSolutionJson(model, solution, kLatin1));
  EXPECT_EQ(solved["model"], kLatin1AsUtf8);
  EXPECT_EQ(solved["setup"], kLatin1AsUtf8);

  const diagnose::Candidate candidate = LabelledCandidate();
  const json effect = DumpAndParse(EffectJson(candidate.effects[0]));
  EXPECT_TRUE(effect["parameters"][kLatin1AsUtf8].is_null());
  diagnose::Diagnosis d;
  d.baseline = candidate;
  d.candidates = {candidate, candidate};
  d.steps = {{kLatin1, kNaN, kInf, -kInf}};
  d.effect_probabilities = {{model::EffectKind::kStiffnessScale, model::EffectTarget::Named(kOverlong), kNaN}};
  d.groups = {{kLatin1, kNul, {1, 2}, kInf}};
  d.explanation = kLatin1;
  const json diagnosis = DumpAndParse(DiagnosisJson(d, {}));
  EXPECT_EQ(diagnosis["explanation"], kLatin1AsUtf8);
  EXPECT_TRUE(diagnosis["candidates"][0]["parameters"].contains(kLatin1AsUtf8));
  DumpAndParse(DiagnosisModeRows(candidate, candidate));
}

TEST(JsonWriters, EveryCodecWritesValidJsonForEmptySets) {
  DumpAndParse(FrfSummaryJson({}));
  DumpAndParse(ModeSetJson({}));
  DumpAndParse(FitModesJson({}, curvefit::RefineMethod::kNone));
  DumpAndParse(TestSetsJson({}));
  DumpAndParse(ModalModelJson({}));
  DumpAndParse(StabilisationJson({}, {}));
  DumpAndParse(CorrelationJson({}, {}, {}));
  DumpAndParse(ModelSolutionJson({}, {}, ""));
  DumpAndParse(EffectJson({}));
  DumpAndParse(DiagnosisJson({}, {}));
  DumpAndParse(DiagnosisModeRows({}, {}));
}

// MODES.json written with non-finite optional values reads back as the convention says: null
// for the writer, NaN for the reader (a non-finite damping ratio: 0); finite values exactly.
TEST(JsonWriters, ModesRoundTripKeepsFiniteValuesAndReadsNullAsNaN) {
  ModeSet set;
  set.dofs = {{7, 1}, {8, -6}};
  Mode m;
  m.frequency_hz = 0.1 + 0.2;  // not a short decimal
  m.damping_ratio = kInf;
  m.frequency_std_hz = kNaN;
  m.mpc = 5e-324;  // denormal
  m.mpd = -kInf;
  m.shape = Eigen::VectorXcd(2);
  m.shape << std::complex<double>(1e308, -0.0), std::complex<double>(1.0 / 3.0, 2.5e-310);
  m.set_frequency_hz = {1e-300};
  m.set_damping_ratio = {kNaN};
  set.modes = {m};
  set.source = kLatin1;
  const auto path = test::TmpFile("json-writers-modes.json");
  std::ofstream(path) << ModeSetJson(set).dump(2);
  const ModeSet back = ReadModeSet(path);  // MODES.json: the file starts with {
  ASSERT_EQ(back.modes.size(), 1u);
  EXPECT_EQ(back.dofs, set.dofs);
  const Mode& b = back.modes[0];
  EXPECT_EQ(b.frequency_hz, m.frequency_hz);
  EXPECT_EQ(b.damping_ratio, 0.0);
  EXPECT_TRUE(std::isnan(b.frequency_std_hz));
  EXPECT_EQ(b.mpc, 5e-324);
  EXPECT_TRUE(std::isnan(b.mpd));
  EXPECT_EQ(b.shape[0], m.shape[0]);
  EXPECT_EQ(b.shape[1], m.shape[1]);
  ASSERT_EQ(b.set_frequency_hz.size(), 1u);
  EXPECT_EQ(b.set_frequency_hz[0], 1e-300);
  EXPECT_TRUE(std::isnan(b.set_damping_ratio[0]));
  EXPECT_TRUE(std::isnan(b.set_frequency_std_hz[0]));
}

}  // namespace
}  // namespace ema::formats::json_writers_test
