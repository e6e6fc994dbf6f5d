// The candidate readings of DIAG.json (formats::ReadDiagnosisReadings): what `ema diagnose --json`
// writes (formats::DiagnosisJson) comes back with every effect whole, laws parsed by the model
// file's own law parser; bad files are InputErrors naming the file and the candidate's rank.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/diagnosis_readings.hpp"
#include "ema/formats/json_codecs.hpp"
#include "ema/formats/model_file.hpp"
#include "tmp_file.hpp"

namespace ema::formats {
namespace {

namespace fs = std::filesystem;

fs::path WriteDiagText(const std::string& name, const std::string& text) {
  const fs::path path = test::TmpFile(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

model::Law HertzInSeries() {
  model::HertzLaw hertz;
  hertz.modulus = 1.1e11 / 3.0;
  hertz.radius = 0.0125;
  hertz.offset = 1e-7;
  hertz.operating_force = 350.5;
  model::SeriesLaw series;
  series.elements = {hertz, model::LinearLaw{2.0e8 / 7.0}};
  series.setting = 0.0;
  series.force = 123.0;
  return series;
}

diagnose::Diagnosis SmallDiagnosis() {
  diagnose::Diagnosis d;
  diagnose::Candidate linear;  // rank 1: one effect with a linear law
  linear.rank = 1;
  linear.kind = "series_compliance";
  linear.target = "joints/J3";
  linear.probability = 0.625;
  model::Effect compliance;
  compliance.kind = model::EffectKind::kSeriesCompliance;
  compliance.target = model::EffectTarget::MemberOf("joints", "J3");
  compliance.parameters["k"] = 6.5e6;
  compliance.law = model::LinearLaw{6.5e6};
  linear.effects = {compliance};

  diagnose::Candidate none;  // rank 2: the model as given
  none.rank = 2;
  none.kind = "none";
  none.probability = 0.25;

  diagnose::Candidate two;  // rank 3: two effects, one with a series/hertz law
  two.rank = 3;
  two.kind = "series_compliance+stiffness_scale";
  two.target = "bearings+mounts";
  two.probability = 0.125;
  model::Effect contact;
  contact.kind = model::EffectKind::kSeriesCompliance;
  contact.target = model::EffectTarget::Named("bearings");
  contact.law = HertzInSeries();
  model::Effect scale;
  scale.kind = model::EffectKind::kStiffnessScale;
  scale.target = model::EffectTarget::Named("mounts");
  scale.parameters["factor"] = 1.0 / 3.0;
  two.effects = {contact, scale};

  d.candidates = {linear, none, two};
  d.baseline = none;
  return d;
}

TEST(DiagnosisReadings, ReadsWhatDiagnoseJsonWrites) {
  const diagnose::Diagnosis d = SmallDiagnosis();
  const fs::path path =
      WriteDiagText("readings-diag.json", DiagnosisJson(d, diagnose::DiagnoseOptions{}).dump(2));
  const std::vector<DiagnosisReading> r = ReadDiagnosisReadings(path);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].rank, 1);
  EXPECT_EQ(r[1].rank, 2);
  EXPECT_EQ(r[2].rank, 3);
  EXPECT_EQ(r[0].probability, 0.625);
  EXPECT_EQ(r[1].probability, 0.25);
  EXPECT_EQ(r[2].probability, 0.125);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(r[i].kind, d.candidates[i].kind);
    EXPECT_EQ(r[i].target, d.candidates[i].target);
    ASSERT_EQ(r[i].effects.size(), d.candidates[i].effects.size()) << "rank " << r[i].rank;
    for (std::size_t e = 0; e < r[i].effects.size(); ++e) {
      const model::Effect& got = r[i].effects[e];
      const model::Effect& want = d.candidates[i].effects[e];
      EXPECT_EQ(got.kind, want.kind);
      EXPECT_EQ(got.target, want.target);
      EXPECT_EQ(got.parameters, want.parameters);  // exact: every digit
      ASSERT_EQ(got.law.has_value(), want.law.has_value());
      if (want.law) {
        EXPECT_EQ(LawToToml(*got.law), LawToToml(*want.law));
      }
    }
  }
  EXPECT_EQ(r[1].kind, "none");
  EXPECT_TRUE(r[1].effects.empty());
  // The laws' kinds and values, not only their text.
  ASSERT_TRUE(r[0].effects[0].law);
  EXPECT_EQ(std::get<model::LinearLaw>(r[0].effects[0].law->value).k, 6.5e6);
  const auto& series = std::get<model::SeriesLaw>(r[2].effects[0].law->value);
  ASSERT_EQ(series.elements.size(), 2u);
  const auto& hertz = std::get<model::HertzLaw>(series.elements[0].value);
  EXPECT_EQ(hertz.modulus, 1.1e11 / 3.0);
  EXPECT_EQ(hertz.radius, 0.0125);
  EXPECT_EQ(hertz.offset, 1e-7);
  EXPECT_EQ(hertz.operating_force, 350.5);
  EXPECT_EQ(std::get<model::LinearLaw>(series.elements[1].value).k, 2.0e8 / 7.0);
  EXPECT_EQ(series.force, 123.0);
  EXPECT_FALSE(r[2].effects[1].law);
}

TEST(DiagnosisReadings, LiteralJsonSortedByRankWithLawTextAndCurveFile) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "readings-literal";
  fs::create_directories(dir);
  std::ofstream(dir / "curve.csv") << "deflection,force\n0,0\n1e-6,10\n2e-6,30\n";
  const std::string law_text = "{ linear = { k = 6.5e6 } }";
  const std::string text = R"({"candidates": [
    {"rank": 2, "kind": "none", "target": "", "probability": null, "effects": []},
    {"rank": 1, "kind": "series_compliance", "target": "joints", "probability": 0.9,
     "parameters": {"k": 6.5e6}, "effects": [
       {"kind": "series_compliance", "target": "joints", "parameters": {"k": 6.5e6}, "law": ")" + law_text + R"("}]},
    {"rank": 3, "kind": "series_compliance", "target": "pads",
     "effects": [{"kind": "series_compliance", "target": "pads", "parameters": {},
                  "law": "{ table = { file = \"curve.csv\", deflection = 1.5e-6 } }"}]},
    {"rank": 4, "kind": "added_mass", "target": "points:101", "effects": [
       {"kind": "added_mass", "target": "points:101", "parameters": {"mass": 3}}]}
  ]})";
  std::ofstream(dir / "DIAG.json") << text;
  const std::vector<DiagnosisReading> r = ReadDiagnosisReadings(dir / "DIAG.json");
  ASSERT_EQ(r.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r[i].rank, i + 1);
  EXPECT_EQ(r[0].kind, "series_compliance");
  EXPECT_EQ(r[0].probability, 0.9);
  EXPECT_TRUE(std::isnan(r[1].probability));
  EXPECT_EQ(r[1].kind, "none");
  EXPECT_EQ(r[1].target, "");
  EXPECT_TRUE(r[1].effects.empty());
  ASSERT_EQ(r[0].effects.size(), 1u);
  EXPECT_EQ(r[0].effects[0].target, model::EffectTarget::Named("joints"));
  EXPECT_EQ(r[0].effects[0].parameters, (std::map<std::string, double>{{"k", 6.5e6}}));
  ASSERT_TRUE(r[0].effects[0].law);
  EXPECT_EQ(LawToToml(*r[0].effects[0].law), LawToToml(model::LinearLaw{6.5e6}));
  // The curve file resolves against the DIAG.json's folder.
  ASSERT_TRUE(r[2].effects[0].law);
  const auto& table = std::get<model::TableLaw>(r[2].effects[0].law->value);
  EXPECT_EQ(table.deflection, (std::vector<double>{0.0, 1e-6, 2e-6}));
  EXPECT_EQ(table.force, (std::vector<double>{0.0, 10.0, 30.0}));
  EXPECT_EQ(table.operating_deflection, 1.5e-6);
  EXPECT_EQ(r[3].effects[0].target, model::EffectTarget::Points({101}));
  EXPECT_EQ(r[3].effects[0].parameters.at("mass"), 3.0);  // a JSON integer
}

// The message of the InputError reading `text` throws ("" when none).
std::string ReadingsErrorOf(const std::string& name, const std::string& text) {
  try {
    ReadDiagnosisReadings(WriteDiagText(name, text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DiagnosisReadings, BadFilesNameTheFileAndTheRank) {
  auto expect = [](const std::string& message, const std::string& file, const std::vector<std::string>& parts) {
    ASSERT_FALSE(message.empty()) << file << " accepted";
    EXPECT_NE(message.find(file), std::string::npos) << message;
    for (const std::string& p : parts) EXPECT_NE(message.find(p), std::string::npos) << p << " not in: " << message;
  };
  expect(ReadingsErrorOf("readings-not-json.json", "{\"candidates\": [\n"), "readings-not-json.json", {"JSON"});
  expect(ReadingsErrorOf("readings-no-candidates.json", "{\"baseline\": {}}"), "readings-no-candidates.json",
         {"candidates"});
  expect(ReadingsErrorOf("readings-candidates-object.json", "{\"candidates\": {}}"),
         "readings-candidates-object.json", {"candidates"});
  expect(ReadingsErrorOf("readings-no-rank.json", R"({"candidates": [{"kind": "none", "target": "", "effects": []}]})"),
         "readings-no-rank.json", {"candidates[0]", "rank"});
  expect(ReadingsErrorOf("readings-no-target.json", R"({"candidates": [{"rank": 4, "kind": "none", "effects": []}]})"),
         "readings-no-target.json", {"rank 4", "target"});
  expect(ReadingsErrorOf("readings-no-effects.json", R"({"candidates": [{"rank": 5, "kind": "none", "target": ""}]})"),
         "readings-no-effects.json", {"rank 5", "effects"});
  expect(ReadingsErrorOf("readings-effect-no-kind.json",
                         R"({"candidates": [{"rank": 1, "kind": "none", "target": "", "effects": []},
                             {"rank": 2, "kind": "stiffness_scale", "target": "mounts",
                              "effects": [{"target": "mounts", "parameters": {"factor": 2.0}}]}]})"),
         "readings-effect-no-kind.json", {"rank 2", "effect 1", "kind"});
  expect(ReadingsErrorOf("readings-bad-law.json",
                         R"({"candidates": [{"rank": 3, "kind": "series_compliance", "target": "joints",
                              "effects": [{"kind": "series_compliance", "target": "joints", "parameters": {},
                                           "law": "{ linear = { stiffness = 1e6 } }"}]}]})"),
         "readings-bad-law.json", {"rank 3", "effect 1", "stiffness", "law linear"});
  expect(ReadingsErrorOf("readings-law-not-toml.json",
                         R"({"candidates": [{"rank": 7, "kind": "series_compliance", "target": "joints",
                              "effects": [{"kind": "series_compliance", "target": "joints", "parameters": {},
                                           "law": "{ linear = { k = "}]}]})"),
         "readings-law-not-toml.json", {"rank 7", "effect 1", "key 'law'", "{ linear = { k = "});
  expect(ReadingsErrorOf("readings-unknown-law.json",
                         R"({"candidates": [{"rank": 8, "kind": "series_compliance", "target": "joints",
                              "effects": [{"kind": "series_compliance", "target": "joints", "parameters": {},
                                           "law": "{ cubic = { k = 1.0 } }"}]}]})"),
         "readings-unknown-law.json", {"rank 8", "cubic"});
  expect(ReadingsErrorOf("readings-law-injection.json",
                         R"({"candidates": [{"rank": 9, "kind": "series_compliance", "target": "joints",
                              "effects": [{"kind": "series_compliance", "target": "joints", "parameters": {},
                                           "law": "{ linear = { k = 1.0 } }\nfactor = 2.0"}]}]})"),
         "readings-law-injection.json", {"rank 9", "law"});
  expect(ReadingsErrorOf("readings-bad-parameter.json",
                         R"({"candidates": [{"rank": 6, "kind": "stiffness_scale", "target": "mounts",
                              "effects": [{"kind": "stiffness_scale", "target": "mounts",
                                           "parameters": {"factor": null}}]}]})"),
         "readings-bad-parameter.json", {"rank 6", "factor"});
  expect(ReadingsErrorOf("readings-unknown-parameter.json",
                         R"({"candidates": [{"rank": 6, "kind": "stiffness_scale", "target": "mounts",
                              "effects": [{"kind": "stiffness_scale", "target": "mounts",
                                           "parameters": {"gain": 2.0}}]}]})"),
         "readings-unknown-parameter.json", {"rank 6", "gain"});
  // An effect's kind is parsed where it enters: one outside the vocabulary is said at its candidate.
  expect(ReadingsErrorOf("readings-unknown-kind.json",
                         R"({"candidates": [{"rank": 2, "kind": "glue", "target": "joints",
                              "effects": [{"kind": "glue", "target": "joints", "parameters": {}}]}]})"),
         "readings-unknown-kind.json",
         {"candidate rank 2: effect 1: effect glue 'joints': unknown effect kind (allowed: series_compliance, "
          "stiffness_scale, operating_point, added_mass, mass_scale, ground_spring)"});
  // The line numbers of the TOML built inside are not shown: they are in no file.
  const std::string law_message = ReadingsErrorOf("readings-bad-law2.json",
                         R"({"candidates": [{"rank": 3, "kind": "series_compliance", "target": "joints",
                              "effects": [{"kind": "series_compliance", "target": "joints", "parameters": {},
                                           "law": "{ linear = { stiffness = 1e6 } }"}]}]})");
  const auto at = law_message.find("candidate rank 3: effect 1:");
  ASSERT_NE(at, std::string::npos) << law_message;
  EXPECT_EQ(law_message.substr(at + 27, 2), " u") << law_message;  // ": unknown key ...", no ":LINE:"
  EXPECT_THROW(ReadDiagnosisReadings(test::TmpFile("readings-missing.json")), InputError);
}

// One candidate (rank 1, kind and target as its one effect's) around `effect`, the JSON of one effect.
nlohmann::json OneEffectDiagnosis(const nlohmann::json& effect) {
  return {{"candidates",
           {{{"rank", 1}, {"kind", effect.value("kind", "")}, {"target", effect.value("target", "")},
             {"effects", nlohmann::json::array({effect})}}}}};
}

// The message of the InputError reading the JSON `diagnosis` throws ("" when none).
std::string ReadingsErrorOf(const nlohmann::json& diagnosis) {
  try {
    ReadDiagnosisReadings(diagnosis, "DIAG.json", EMA_TEST_TMP_DIR);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The values of an effect are values: names and texts holding TOML syntax are taken verbatim
// (nothing is written out as TOML and read again), so they name what they are, never act as TOML.
TEST(DiagnosisReadings, ParameterNamesAndTargetsAreValuesNotToml) {
  const std::string allowed = "(allowed: factor, k, mass, value)";
  EXPECT_EQ(ReadingsErrorOf(OneEffectDiagnosis(
                {{"kind", "stiffness_scale"}, {"target", "mounts"}, {"parameters", {{"factor\" = 3 #", 2.0}}}})),
            "DIAG.json: candidate rank 1: effect 1: effect stiffness_scale 'mounts': unknown parameter "
            "'factor\" = 3 #' " + allowed);
  EXPECT_EQ(ReadingsErrorOf(OneEffectDiagnosis(
                {{"kind", "stiffness_scale"}, {"target", "mounts"}, {"parameters", {{"x\nfactor", 2.0}}}})),
            "DIAG.json: candidate rank 1: effect 1: effect stiffness_scale 'mounts': unknown parameter "
            "'x\nfactor' " + allowed);
  // A key a model file takes, but no parameter of an effect.
  EXPECT_EQ(ReadingsErrorOf(OneEffectDiagnosis(
                {{"kind", "stiffness_scale"}, {"target", "mounts"}, {"parameters", {{"target", 2.0}}}})),
            "DIAG.json: candidate rank 1: effect 1: effect stiffness_scale 'mounts': unknown parameter "
            "'target' " + allowed);
  // A points target with TOML in it is a bad point id, said at its candidate.
  const std::string points = "points:101\"\nmass = 5.0\n#";
  EXPECT_EQ(ReadingsErrorOf(OneEffectDiagnosis(
                {{"kind", "added_mass"}, {"target", points}, {"parameters", {{"mass", 0.1}}}})),
            "DIAG.json: candidate rank 1: effect 1: effect added_mass '" + points +
                "': bad point id '101\"\nmass = 5.0\n#': expected 'all_points' or 'points:101,102' (test point "
                "ids separated by commas)");
  // A name target is any text (the model says whether it names something): it stays that text,
  // and the parameters stay those given.
  const std::string name = "mounts\"\nfactor = 9.0\n[[effect]]";
  const std::vector<DiagnosisReading> r = ReadDiagnosisReadings(
      OneEffectDiagnosis({{"kind", "stiffness_scale"}, {"target", name}, {"parameters", {{"factor", 2.0}}}}),
      "DIAG.json", EMA_TEST_TMP_DIR);
  ASSERT_EQ(r.size(), 1u);
  ASSERT_EQ(r[0].effects.size(), 1u);
  EXPECT_EQ(r[0].effects[0].target, model::EffectTarget::Named(name));
  EXPECT_EQ(r[0].effects[0].parameters, (std::map<std::string, double>{{"factor", 2.0}}));
}

TEST(DiagnosisReadings, ParametersKeepEveryBit) {
  const std::vector<double> values = {0.1 + 0.2, 1.0 / 3.0, 5e-324, 1.7976931348623157e308, -0.0, 9007199254740993.0};
  for (const double v : values) {
    const nlohmann::json diagnosis =
        OneEffectDiagnosis({{"kind", "stiffness_scale"}, {"target", "mounts"}, {"parameters", {{"factor", v}}}});
    // From the JSON itself and from its text in a file.
    const std::vector<DiagnosisReading> direct = ReadDiagnosisReadings(diagnosis, "DIAG.json", EMA_TEST_TMP_DIR);
    const std::vector<DiagnosisReading> file = ReadDiagnosisReadings(WriteDiagText("readings-bits.json", diagnosis.dump()));
    for (const auto* r : {&direct, &file}) {
      const double got = (*r)[0].effects[0].parameters.at("factor");
      EXPECT_EQ(std::memcmp(&got, &v, sizeof v), 0) << got << " != " << v;
    }
  }
}

TEST(DiagnosisReadings, LawFieldIsOneInlineTomlValue) {
  auto law_effect = [](const std::string& law) {
    return OneEffectDiagnosis({{"kind", "series_compliance"}, {"target", "joints"}, {"law", law}});
  };
  // A comment after the value is still the one value.
  const std::vector<DiagnosisReading> r =
      ReadDiagnosisReadings(law_effect("{ linear = { k = 6.5e6 } }  # a comment"), "DIAG.json", EMA_TEST_TMP_DIR);
  ASSERT_TRUE(r[0].effects[0].law);
  EXPECT_EQ(std::get<model::LinearLaw>(r[0].effects[0].law->value).k, 6.5e6);
  // Anything after the value on its line is not TOML; a second line is refused as such.
  EXPECT_NE(ReadingsErrorOf(law_effect("{ linear = { k = 1.0 } }, factor = 2.0"))
                .find("DIAG.json: candidate rank 1: effect 1: key 'law': '{ linear = { k = 1.0 } }, factor = 2.0' is "
                      "not the inline TOML of a law"),
            std::string::npos);
  EXPECT_EQ(ReadingsErrorOf(law_effect("{ linear = { k = 1.0 } }\nfactor = 2.0")),
            "DIAG.json: candidate rank 1: effect 1: key 'law': expected the inline TOML of one law on one line, such "
            "as \"{ linear = { k = 6.5e6 } }\"");
  // The law parser's own messages, said at the candidate (the law's TOML has no line in any file).
  EXPECT_EQ(ReadingsErrorOf(law_effect("5.0")),
            "DIAG.json: candidate rank 1: effect 1: key 'effect series_compliance': expected a table");
  EXPECT_EQ(ReadingsErrorOf(law_effect("{ linear = { k = 1.0, c = 2.0 } }")),
            "DIAG.json: candidate rank 1: effect 1: unknown key 'c' in effect series_compliance law linear (allowed: k)");
}

// A curve file a law names keeps its own place (file and line), after the candidate that names it.
TEST(DiagnosisReadings, CurveFileErrorsKeepTheirPlace) {
  const fs::path dir = fs::path(EMA_TEST_TMP_DIR) / "readings-bad-curve";
  fs::create_directories(dir);
  std::ofstream(dir / "curve.csv") << "deflection,force\n0,0\n1e-6,ten\n";
  const nlohmann::json diagnosis = OneEffectDiagnosis(
      {{"kind", "series_compliance"}, {"target", "pads"}, {"law", "{ table = { file = \"curve.csv\" } }"}});
  std::ofstream(dir / "DIAG.json") << diagnosis.dump();
  try {
    ReadDiagnosisReadings(dir / "DIAG.json");
    FAIL() << "a bad curve file was read";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "DIAG.json").string() + ": candidate rank 1: effect 1: " +
                                         (dir / "curve.csv").string() + ":3: expected two numbers 'x,y'");
  }
  const nlohmann::json missing = OneEffectDiagnosis(
      {{"kind", "series_compliance"}, {"target", "pads"}, {"law", "{ table = { file = \"no-such.csv\" } }"}});
  EXPECT_EQ(ReadingsErrorOf(missing), "DIAG.json: candidate rank 1: effect 1: cannot open curve file '" +
                                          (fs::path(EMA_TEST_TMP_DIR) / "no-such.csv").string() + "'");
}

}  // namespace
}  // namespace ema::formats
