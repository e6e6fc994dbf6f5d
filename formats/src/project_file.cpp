#include "ema/formats/project_file.hpp"

#include <cmath>
#include <set>
#include <sstream>
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

double Number(const fs::path& file, const toml::node& node, const std::string& key) {
  if (auto v = node.value<double>()) return *v;
  throw InputError(Where(file, node), "'" + key + "' must be a number");
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

// A selection as `ema fit --select` takes it: "auto" or positive frequencies in Hz, comma-separated.
std::string Selection(const fs::path& file, const toml::node& node) {
  const std::string text = String(file, node, "select");
  if (text == "auto") return text;
  std::stringstream items(text);
  std::string item;
  int count = 0;
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
    ++count;
  }
  if (count == 0) throw InputError(Where(file, node), "'select' must be \"auto\" or F1,F2,... in Hz");
  return text;
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
    CheckKeys(file, *t, {"setup", "name", "time", "frf", "sensor_mass", "select", "pick"}, "[[test]]");
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
    if (const toml::node* m = (*t)["sensor_mass"].node()) {
      const std::optional<double> v = m->value<double>();
      if (!v || !(m->is_floating_point() || m->is_integer()) || !(*v >= 0.0) || !std::isfinite(*v) || *v > 1e3)
        throw InputError(Where(file, *m), "sensor_mass must be a mass in kg per measured node, >= 0 (0.0112 for an "
                                          "11.2 g accelerometer)");
      test.sensor_mass = *v;
    }
    if (const toml::node* select = (*t)["select"].node()) test.select = Selection(file, *select);
    if (const toml::node* pick = (*t)["pick"].node()) {
      const auto v = pick->value<bool>();
      if (!v) throw InputError(Where(file, *pick), "'pick' must be true or false");
      test.pick = *v;
    }
    if (test.time.empty() && !test.frf)
      throw InputError(Where(file, *t), "[[test]] '" + test.name + "' needs time = [files] (or frf = \"FRF.unv\")");
    if (!test.time.empty() && test.frf)
      throw InputError(Where(file, *t), "[[test]] '" + test.name + "' gives both time and frf; keep one");
    project.tests.push_back(std::move(test));
  }

  if (const toml::table* frf = root["frf"].as_table()) {
    CheckKeys(file, *frf, {"estimator"}, "[frf]");
    if ((*frf)["estimator"]) project.estimator = String(file, *(*frf)["estimator"].node(), "estimator");
  }
  if (const toml::table* fit = root["fit"].as_table()) {
    CheckKeys(file, *fit, {"band", "order_max", "select", "args"}, "[fit]");
    if (const toml::node* band = (*fit)["band"].node()) {
      const toml::array* a = band->as_array();
      if (!a || a->size() != 2) throw InputError(Where(file, *band), "'band' must be [low_hz, high_hz]");
      const double lo = Number(file, *a->get(0), "band"), hi = Number(file, *a->get(1), "band");
      if (!(lo >= 0.0 && hi > lo)) throw InputError(Where(file, *band), "'band' must satisfy 0 <= low < high");
      project.band_hz = std::make_pair(lo, hi);
    }
    if (const toml::node* order = (*fit)["order_max"].node()) {
      const auto v = IntValue(*order);
      if (!v || *v < 1) throw InputError(Where(file, *order), "'order_max' must be a positive integer");
      project.order_max = *v;
    }
    if ((*fit)["select"]) project.select = Selection(file, *(*fit)["select"].node());
    if ((*fit)["args"]) project.fit_extra = Strings(file, *(*fit)["args"].node(), "args");
  }
  if (const toml::table* diagnose = root["diagnose"].as_table()) {
    CheckKeys(file, *diagnose, {"args"}, "[diagnose]");
    if ((*diagnose)["args"]) project.diagnose_extra = Strings(file, *(*diagnose)["args"].node(), "args");
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
