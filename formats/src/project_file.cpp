#include "ema/formats/project_file.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <toml++/toml.h>

#include "ema/core/error.hpp"
#include "ema/formats/toml_fields.hpp"

namespace ema::formats {

namespace fs = std::filesystem;

namespace {

std::string Where(const fs::path& file, const toml::node& node) { return TomlFields(file.string()).At(node); }

void CheckKeys(const fs::path& file, const toml::table& table, const std::set<std::string>& allowed,
               const std::string& context) {
  TomlFields(file.string()).CheckKeys(table, allowed, context);
}

std::string String(const fs::path& file, const toml::node& node, const std::string& key) {
  if (auto v = node.value<std::string>()) return *v;
  throw InputError(Where(file, node), "'" + key + "' must be a string");
}

fs::path Resolve(const fs::path& file, const std::string& relative) {
  const fs::path p(relative);
  return fs::absolute(p.is_absolute() ? p : file.parent_path() / p).lexically_normal();
}

fs::path ExistingFile(const fs::path& file, const toml::node& node, const std::string& key) {
  const fs::path p = Resolve(file, String(file, node, key));
  std::error_code ec;  // an unusable name (too long, ...) is "no such file", not a filesystem_error
  if (!fs::is_regular_file(p, ec)) throw InputError(Where(file, node), "'" + key + "': no such file " + p.string());
  return p;
}

std::vector<std::string> Strings(const fs::path& file, const toml::node& node, const std::string& key) {
  std::vector<std::string> out;
  if (const toml::array* a = node.as_array()) {
    for (const toml::node& item : *a) out.push_back(String(file, item, key));
    return out;
  }
  throw InputError(Where(file, node), "'" + key + "' must be an array of strings");
}

// A selection as `ema fit --select` takes it: "auto" (an empty list) or positive frequencies in Hz,
// comma-separated.
std::vector<double> Selection(const fs::path& file, const toml::node& node) {
  const std::string text = String(file, node, "select");
  std::vector<double> hz;
  if (text == "auto") return hz;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    size_t used = 0;
    double f = 0.0;
    try {
      f = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !(f > 0.0) || !std::isfinite(f))
      throw InputError(Where(file, node), "'select' must be \"auto\" or positive frequencies in Hz, comma-separated "
                                          "(\"196.4,266.7\"); got '" + item + "'");
    hz.push_back(f);
  }
  if (hz.empty()) throw InputError(Where(file, node), "'select' must be \"auto\" or F1,F2,... in Hz");
  return hz;
}

// ---- The typed options of [frf], [fit] and [diagnose] -----------------------------------------

// One key's value in an options table, with the messages of its line: "file:line: [fit] key: what".
class KeyValue {
 public:
  KeyValue(const fs::path& file, const std::string& table, const char* key, const toml::node& node)
      : file_(file), table_(table), key_(key), node_(node) {}

  const fs::path& file() const { return file_; }
  const toml::node& node() const { return node_; }

  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(Where(file_, node_), table_ + " " + key_ + ": " + what);
  }
  double Number() const {
    const std::optional<double> v = node_.is_number() ? node_.value<double>() : std::nullopt;
    if (!v || !std::isfinite(*v)) Fail("expected a number");
    return *v;
  }
  int Integer() const {
    const std::optional<int> v = IntValue(node_);
    if (!v) Fail("expected an integer");
    return *v;
  }
  bool Bool() const {
    const toml::value<bool>* v = node_.as_boolean();
    if (!v) Fail("expected true or false");
    return v->get();
  }
  std::string Text() const {
    const toml::value<std::string>* v = node_.as_string();
    if (!v) Fail("expected a string");
    return v->get();
  }
  /// One name of the option's name table (`ema <command> --option` takes the same names).
  template <class Enum, std::size_t N>
  Enum Choice(const EnumName<Enum> (&names)[N]) const {
    Enum value{};
    const std::string text = node_.is_string() ? Text() : std::string();
    if (!node_.is_string() || !FromName(names, text, &value))
      Fail("expected " + NameList(names) + (node_.is_string() ? ", got '" + text + "'" : std::string()));
    return value;
  }
  /// [low_hz, high_hz] with 0 <= low < high (`--band LO:HI`).
  std::pair<double, double> Band() const {
    const toml::array* a = node_.as_array();
    if (!a || a->size() != 2 || !a->get(0)->is_number() || !a->get(1)->is_number())
      Fail("expected [low_hz, high_hz]");
    const double lo = a->get(0)->value<double>().value_or(kNaN), hi = a->get(1)->value<double>().value_or(kNaN);
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo >= 0.0 && hi > lo)) Fail("expected [low_hz, high_hz] with 0 <= low < high");
    return {lo, hi};
  }

 private:
  const fs::path& file_;
  const std::string& table_;
  std::string key_;
  const toml::node& node_;
};

// One key of an options table: the TOML form of one command-line option of the subcommand
// (`options`: that option's name, and any other option that sets the same field) and how its
// value is read into the subcommand's options struct.
template <class Options>
struct OptionKey {
  const char* key;
  std::vector<std::string> options;
  std::function<void(const KeyValue&, Options&)> read;
};

// Keys whose value goes into one field: `field(options)` is that field.
template <class Options, class Field>
OptionKey<Options> NumberKey(const char* key, std::string option, Field field) {
  return {key, {std::move(option)}, [field](const KeyValue& v, Options& o) { field(o) = v.Number(); }};
}
template <class Options, class Field>
OptionKey<Options> IntegerKey(const char* key, std::string option, Field field) {
  return {key, {std::move(option)}, [field](const KeyValue& v, Options& o) { field(o) = v.Integer(); }};
}
template <class Options, class Field, class Enum, std::size_t N>
OptionKey<Options> ChoiceKey(const char* key, std::string option, const EnumName<Enum> (&names)[N], Field field) {
  return {key, {std::move(option)}, [field, &names](const KeyValue& v, Options& o) { field(o) = v.Choice(names); }};
}

// `ema frf` (app/cmd_frf.cpp ParseFrfArgs). Not here: the inputs and outputs, --binary ([output]
// binary), --force-bins / --force-bin-edges (one FRF file per test in `ema run`).
const std::vector<OptionKey<frf::FrfOptions>>& FrfKeys() {
  using O = frf::FrfOptions;
  static const std::vector<OptionKey<O>> keys = {
      {"estimator", {"estimator"},
       [](const KeyValue& v, O& o) {
         try {
           o.estimator = frf::ParseEstimator(v.Text());
         } catch (const std::invalid_argument& e) {
           v.Fail(e.what());
         }
       }},
      {"band", {"band"}, [](const KeyValue& v, O& o) { std::tie(o.band_lo_hz, o.band_hi_hz) = v.Band(); }},
      {"exp_window", {"exp-window"},
       [](const KeyValue& v, O& o) {
         // A mode's name (frf::kExpWindowNames), else a fixed decay rate in 1/s, as --exp-window.
         acquisition::ImpactOptions& imp = o.impact;
         if (v.node().is_number()) {
           imp.exp_window = acquisition::ExpWindowMode::kFixed;
           imp.exp_decay_rate = v.Number();
         } else if (!v.node().is_string() || !FromName(frf::kExpWindowNames, v.Text(), &imp.exp_window)) {
           v.Fail("expected \"auto\", \"none\" or a decay rate 1/tau in 1/s");
         }
       }},
      NumberKey<O>("exp_end_level", "exp-end-level", [](auto& o) -> auto& { return o.impact.exp_end_level; }),
      ChoiceKey<O>("quantity", "quantity", frf::kOutputQuantityNames, [](auto& o) -> auto& { return o.output_quantity; }),
      NumberKey<O>("trigger_level", "trigger-level", [](auto& o) -> auto& { return o.impact.trigger_level; }),
      NumberKey<O>("force_window", "force-window", [](auto& o) -> auto& { return o.impact.force_window_pulses; }),
      {"double_hit_ratio", {"double-hit-ratio"},
       [](const KeyValue& v, O& o) {
         o.impact.double_hit_high = v.Number();
         o.impact.double_hit_low = std::min(o.impact.double_hit_low, 0.5 * o.impact.double_hit_high);  // as ParseFrfArgs
       }},
      NumberKey<O>("double_hit_autocorrelation", "double-hit-autocorrelation",
                   [](auto& o) -> auto& { return o.impact.double_hit_autocorrelation; }),
      {"accept_double_hits", {"accept-double-hits"}, [](const KeyValue& v, O& o) { o.impact.reject_double_hits = !v.Bool(); }},
      NumberKey<O>("overload_fraction", "overload-fraction", [](auto& o) -> auto& { return o.impact.overload_fraction; }),
      NumberKey<O>("level_tolerance", "level-tolerance", [](auto& o) -> auto& { return o.impact.level_tolerance; }),
      IntegerKey<O>("threads", "threads", [](auto& o) -> auto& { return o.threads; }),
  };
  return keys;
}

// `ema fit` (app/cmd_fit.cpp ParseFitArgs). Not here: the input and the outputs (--json,
// --stabilisation, --plot), which `ema run` names.
const std::vector<OptionKey<curvefit::FitOptions>>& FitKeys() {
  using O = curvefit::FitOptions;
  static const std::vector<OptionKey<O>> keys = {
      {"band", {"band"}, [](const KeyValue& v, O& o) { std::tie(o.data.band_lo_hz, o.data.band_hi_hz) = v.Band(); }},
      {"order_max", {"order-max"},
       [](const KeyValue& v, O& o) {
         const std::optional<int> order = IntValue(v.node());
         if (!order || *order < 1) v.Fail("expected a positive integer (the highest PolyMAX order)");
         o.polymax.order_max = *order;
       }},
      {"select", {"select"}, [](const KeyValue& v, O& o) { o.select_frequencies_hz = Selection(v.file(), v.node()); }},
      ChoiceKey<O>("method", "method", curvefit::kFitMethodNames, [](auto& o) -> auto& { return o.method; }),
      ChoiceKey<O>("refine", "refine", curvefit::kRefineMethodNames, [](auto& o) -> auto& { return o.refine; }),
      NumberKey<O>("freq_tol", "freq-tol", [](auto& o) -> auto& { return o.stability.frequency_tol; }),
      NumberKey<O>("damping_tol", "damping-tol", [](auto& o) -> auto& { return o.stability.damping_tol; }),
      NumberKey<O>("mac_min", "mac-min", [](auto& o) -> auto& { return o.stability.mac_min; }),
      IntegerKey<O>("threads", "threads", [](auto& o) -> auto& { return o.polymax.threads; }),
  };
  return keys;
}

// `ema diagnose` (app/cmd_diagnose.cpp ParseDiagnoseArgs). Not here: the model, the tests and the
// outputs, which `ema run` names; --sensor-mass ([[test]] sensor_mass); --bundle (`ema run
// --bundle`); --force-level.
const std::vector<OptionKey<diagnose::DiagnoseOptions>>& DiagnoseKeys() {
  using O = diagnose::DiagnoseOptions;
  static const std::vector<OptionKey<O>> keys = {
      ChoiceKey<O>("criterion", "criterion", diagnose::kCriterionNames, [](auto& o) -> auto& { return o.criterion; }),
      {"max_effects", {"max-effects", "no-pairs"}, [](const KeyValue& v, O& o) { o.max_effects = v.Integer(); }},
      {"pairs", {"no-pairs", "max-effects"},
       [](const KeyValue& v, O& o) {
         if (!v.Bool()) o.max_effects = 1;  // --no-pairs; pairs = true leaves max_effects as it is
       }},
      {"members", {"no-members"}, [](const KeyValue& v, O& o) { o.members = v.Bool(); }},
      NumberKey<O>("frequency_floor", "frequency-floor", [](auto& o) -> auto& { return o.frequency_floor; }),
      {"shape_sigma", {"shape-sigma", "shape-weight"}, [](const KeyValue& v, O& o) { o.shape_sigma = v.Number(); }},
      ChoiceKey<O>("shape_residual", "shape-residual", diagnose::kShapeResidualNames,
                   [](auto& o) -> auto& { return o.shape_residual; }),
      NumberKey<O>("shape_dof_sigma", "shape-dof-sigma", [](auto& o) -> auto& { return o.shape_dof_sigma; }),
      {"exact_form", {"exact-form"}, [](const KeyValue& v, O& o) { o.model_error = !v.Bool(); }},
      NumberKey<O>("effect_prior_odds", "effect-prior-odds", [](auto& o) -> auto& { return o.effect_prior_odds; }),
      NumberKey<O>("mac_min", "mac-min", [](auto& o) -> auto& { return o.pairing.mac_min; }),
  };
  return keys;
}

template <class Options>
std::set<std::string> KeyNames(const std::vector<OptionKey<Options>>& keys, bool with_args) {
  std::set<std::string> names;
  for (const OptionKey<Options>& k : keys) names.insert(k.key);
  if (with_args) names.insert("args");
  return names;
}

// Reads the keys `table` gives into *options (over what it holds: the struct's defaults) and
// lists them in *given. `valid` is the struct's own check: run after each key, so that a value
// out of range is reported at its key's line, and once more over the whole table.
template <class Options>
void ReadOptionKeys(const fs::path& file, const toml::table& table, const std::string& name,
                    const std::vector<OptionKey<Options>>& keys, const std::function<bool(const Options&, std::string*)>& valid,
                    Options* options, std::vector<std::string>* given) {
  for (const OptionKey<Options>& k : keys) {
    const toml::node* node = table.get(k.key);
    if (!node) continue;
    const KeyValue value(file, name, k.key, *node);
    k.read(value, *options);
    given->push_back(k.key);
    if (std::string why; !valid(*options, &why)) value.Fail(why);
  }
  if (std::string why; !valid(*options, &why)) throw InputError(Where(file, table), name + ": " + why);
}

// The option of `options` a command-line token sets as Boost's parser reads it (cli::Parse, its
// default style): --name or --name=value, and a prefix of one name only standing for that name.
// "" for anything else (a value, a short option, an option no key has). A prefix shared with an
// option no key has (`ema fit --s`: --select, --stabilisation) counts as the key's option here;
// the parser would refuse it as ambiguous anyway.
std::string OptionOfToken(const std::string& token, const std::set<std::string>& options) {
  if (token.size() < 3 || token.compare(0, 2, "--") != 0) return "";
  const std::string name = token.substr(2, token.find('=') == std::string::npos ? std::string::npos : token.find('=') - 2);
  if (name.empty()) return "";
  if (options.count(name)) return name;
  std::string match;
  for (const std::string& option : options) {
    if (option.compare(0, name.size(), name) != 0) continue;
    if (!match.empty()) return "";  // ambiguous: the parser refuses it when the run parses args
    match = option;
  }
  return match;
}

// A key and the same option in the table's args (the old form): refused, naming both.
template <class Options>
void RefuseKeysInArgs(const fs::path& file, const toml::table& table, const std::string& name,
                      const std::vector<OptionKey<Options>>& keys, const std::vector<std::string>& args) {
  std::set<std::string> all;
  for (const OptionKey<Options>& k : keys) all.insert(k.options.begin(), k.options.end());
  for (const std::string& token : args) {
    const std::string option = OptionOfToken(token, all);
    if (option.empty()) continue;
    for (const OptionKey<Options>& k : keys) {
      const toml::node* node = table.get(k.key);
      if (!node || std::find(k.options.begin(), k.options.end(), option) == k.options.end()) continue;
      const std::string written = token.substr(0, token.find('='));
      throw InputError(Where(file, *node), name + " " + k.key + " and args " + written +
                                               (written == "--" + option ? "" : " (--" + option + ")") + ": give one");
    }
  }
}

}  // namespace

Project ReadProjectFile(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path.string(), "no such project file");
  toml::table root;
  try {
    root = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw InputError(path.string() + ":" + std::to_string(e.source().begin.line),
                     "not a valid TOML project file: " + std::string(e.description()));
  }
  Project project;
  project.file = fs::absolute(path).lexically_normal();
  const fs::path& file = project.file;
  CheckKeys(file, root, {"project", "test", "frf", "fit", "diagnose", "report", "output"}, "the project file");

  const toml::table* head = root["project"].as_table();
  if (!head) throw InputError(file.string(), "missing [project] table (with model = \"MODEL.toml\")");
  CheckKeys(file, *head, {"name", "model"}, "[project]");
  project.name = (*head)["name"] ? String(file, *(*head)["name"].node(), "name") : file.stem().string();
  if (!(*head)["model"]) throw InputError(Where(file, *head), "[project] needs model = \"MODEL.toml\"");
  project.model = ExistingFile(file, *(*head)["model"].node(), "model");

  const toml::array* tests = root["test"].as_array();
  if (!tests || tests->empty())
    throw InputError(file.string(), "no [[test]] (each names a setup and its time data files)");
  std::set<std::string> names;
  for (const toml::node& node : *tests) {
    const toml::table* t = node.as_table();
    if (!t) throw InputError(Where(file, node), "[[test]] must be a table");
    CheckKeys(file, *t, {"setup", "name", "time", "frf", "plan", "truth", "sensor_mass", "select", "pick"}, "[[test]]");
    ProjectTest test;
    if ((*t)["setup"]) test.setup = String(file, *(*t)["setup"].node(), "setup");
    test.name = (*t)["name"] ? String(file, *(*t)["name"].node(), "name") : test.setup;
    if (test.name.empty()) test.name = "test" + std::to_string(project.tests.size() + 1);
    if (test.name.find_first_of("/\\") != std::string::npos || test.name == "." || test.name == "..")
      throw InputError(Where(file, *t), "test name '" + test.name + "' must be a plain folder name");
    if (!names.insert(test.name).second)
      throw InputError(Where(file, *t), "two tests named '" + test.name + "' (give each a distinct name or setup)");
    if (const toml::node* time = (*t)["time"].node()) {
      if (time->is_string()) {
        test.time.push_back(ExistingFile(file, *time, "time"));
      } else if (const toml::array* a = time->as_array()) {
        for (const toml::node& item : *a) test.time.push_back(ExistingFile(file, item, "time"));
      } else {
        throw InputError(Where(file, *time), "'time' must be a file name or an array of file names");
      }
    }
    if (const toml::node* frf = (*t)["frf"].node()) test.frf = ExistingFile(file, *frf, "frf");
    if (const toml::node* plan = (*t)["plan"].node()) test.plan = ExistingFile(file, *plan, "plan");
    if (const toml::node* truth = (*t)["truth"].node()) {
      if (!test.plan)
        throw InputError(Where(file, *truth), "'truth' is the model a planned test is simulated on: give plan = \"PLAN.toml\" too");
      test.truth = ExistingFile(file, *truth, "truth");
    }
    if (const toml::node* m = (*t)["sensor_mass"].node()) {
      const std::optional<double> v = m->value<double>();
      if (!v || !(m->is_floating_point() || m->is_integer()) || !(*v >= 0.0) || !std::isfinite(*v) || *v > 1e3)
        throw InputError(Where(file, *m), "sensor_mass must be a mass in kg per measured node, >= 0 (0.0112 for an "
                                          "11.2 g accelerometer)");
      test.sensor_mass = *v;
    }
    if (const toml::node* select = (*t)["select"].node()) {
      test.select_hz = Selection(file, *select);
      test.select = String(file, *select, "select");
    }
    if (const toml::node* pick = (*t)["pick"].node()) {
      const auto v = pick->value<bool>();
      if (!v) throw InputError(Where(file, *pick), "'pick' must be true or false");
      test.pick = *v;
    }
    const int sources = (test.time.empty() ? 0 : 1) + (test.frf ? 1 : 0) + (test.plan ? 1 : 0);
    if (sources == 0)
      throw InputError(Where(file, *t), "[[test]] '" + test.name +
                                            "' needs time = [files] (or frf = \"FRF.unv\", or plan = \"PLAN.toml\" to simulate it)");
    if (sources > 1)
      throw InputError(Where(file, *t), "[[test]] '" + test.name + "' gives more than one of time, frf and plan; keep one");
    project.tests.push_back(std::move(test));
  }

  if (const toml::table* frf = root["frf"].as_table()) {
    CheckKeys(file, *frf, KeyNames(FrfKeys(), false), "[frf]");
    ReadOptionKeys<frf::FrfOptions>(
        file, *frf, "[frf]", FrfKeys(), [](const frf::FrfOptions& o, std::string* why) { return o.IsValid(why); },
        &project.frf, &project.frf_keys);
  }
  project.estimator = frf::EstimatorName(project.frf.estimator);
  if (const toml::table* fit = root["fit"].as_table()) {
    CheckKeys(file, *fit, KeyNames(FitKeys(), true), "[fit]");
    ReadOptionKeys<curvefit::FitOptions>(
        file, *fit, "[fit]", FitKeys(), [](const curvefit::FitOptions& o, std::string* why) { return o.IsValid(why); },
        &project.fit, &project.fit_keys);
    if (const toml::node* select = (*fit)["select"].node()) project.select = String(file, *select, "select");
    project.select_hz = project.fit.select_frequencies_hz;
    if (std::count(project.fit_keys.begin(), project.fit_keys.end(), "band"))
      project.band_hz = std::make_pair(project.fit.data.band_lo_hz, project.fit.data.band_hi_hz);
    if (std::count(project.fit_keys.begin(), project.fit_keys.end(), "order_max")) project.order_max = project.fit.polymax.order_max;
    if ((*fit)["args"]) project.fit_extra = Strings(file, *(*fit)["args"].node(), "args");
    RefuseKeysInArgs(file, *fit, "[fit]", FitKeys(), project.fit_extra);
  }
  if (const toml::table* diagnose = root["diagnose"].as_table()) {
    CheckKeys(file, *diagnose, KeyNames(DiagnoseKeys(), true), "[diagnose]");
    const toml::node* pairs = (*diagnose)["pairs"].node();
    const toml::node* max_effects = (*diagnose)["max_effects"].node();
    if (pairs && max_effects && pairs->value<bool>() == false && IntValue(*max_effects).value_or(1) != 1)
      throw InputError(Where(file, *pairs), "[diagnose] pairs = false and max_effects = " +
                                                std::to_string(*IntValue(*max_effects)) + ": give one");
    ReadOptionKeys<diagnose::DiagnoseOptions>(
        file, *diagnose, "[diagnose]", DiagnoseKeys(),
        [](const diagnose::DiagnoseOptions& o, std::string* why) { return o.IsValid(why) && o.pairing.IsValid(why); },
        &project.diagnose, &project.diagnose_keys);
    if ((*diagnose)["args"]) project.diagnose_extra = Strings(file, *(*diagnose)["args"].node(), "args");
    RefuseKeysInArgs(file, *diagnose, "[diagnose]", DiagnoseKeys(), project.diagnose_extra);
  }
  project.title = project.name;
  if (const toml::table* report = root["report"].as_table()) {
    CheckKeys(file, *report, {"title", "lines"}, "[report]");
    if ((*report)["title"]) project.title = String(file, *(*report)["title"].node(), "title");
    if (const toml::node* lines = (*report)["lines"].node()) {
      const toml::array* a = lines->as_array();
      if (!a) throw InputError(Where(file, *lines), "'lines' must be an array of [node, node] pairs");
      for (const toml::node& pair : *a) {
        const toml::array* p = pair.as_array();
        const auto first = p && p->size() == 2 ? IntValue(*p->get(0)) : std::nullopt;
        const auto second = p && p->size() == 2 ? IntValue(*p->get(1)) : std::nullopt;
        if (!first || !second) throw InputError(Where(file, pair), "each entry of 'lines' must be [node, node]");
        project.lines.emplace_back(*first, *second);
      }
    }
  }
  if (const toml::table* output = root["output"].as_table()) {
    CheckKeys(file, *output, {"binary"}, "[output]");
    if (const toml::node* binary = (*output)["binary"].node()) {
      auto v = binary->value<bool>();
      if (!v) throw InputError(Where(file, *binary), "'binary' must be true or false");
      project.binary = *v;
    }
  }
  return project;
}

}  // namespace ema::formats
