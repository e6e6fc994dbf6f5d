#include "ema/correlation/correlate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/correlation/mac.hpp"

namespace ema::correlation {
namespace {

std::string SourceName(const ModeSet& set, const char* fallback) { return set.source.empty() ? fallback : set.source; }

void CheckModeSet(const ModeSet& set, const char* role) {
  const std::string where = SourceName(set, role);
  if (set.modes.empty()) throw InputError(where, std::string("no modes found; expected at least one ") + role + " mode");
  for (size_t m = 0; m < set.modes.size(); ++m)
    if (set.modes[m].shape.size() != static_cast<Eigen::Index>(set.dofs.size()))
      throw InputError(where, std::string("mode ") + std::to_string(m + 1) + " has " + std::to_string(set.modes[m].shape.size()) +
                                  " shape values, expected one per DOF (" + std::to_string(set.dofs.size()) + ")");
}

std::string Fixed(double value, int digits) {
  if (std::isnan(value)) return "";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string HtmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace

CorrelationResult Correlate(const ModeSet& test, const ModeSet& model, const CorrelationOptions& options) {
  CheckModeSet(test, "test");
  CheckModeSet(model, "model");
  CorrelationResult result;
  result.dof_match = MatchDofs(test, model, options.dofs);
  result.shared_dof_count = result.dof_match.Count();
  result.test_dof_count = static_cast<int>(test.dofs.size());
  if (result.shared_dof_count == 0) {
    std::string example = test.dofs.empty() ? "none" : DofName(test.dofs.front());
    std::string model_example = model.dofs.empty() ? "none" : DofName(model.dofs.front());
    throw InputError(SourceName(test, "test"),
                     std::string("no DOF shared with the model ") + SourceName(model, "model") + " (test has " +
                         std::to_string(test.dofs.size()) + " DOFs, e.g. " + example + "; model has " +
                         std::to_string(model.dofs.size()) + ", e.g. " + model_example +
                         "); expected test nodes that the model defines (same id, an id map, or a node within "
                         "the matching tolerance)");
  }
  const Eigen::MatrixXcd test_shapes = result.dof_match.TestShapes(test);
  const Eigen::MatrixXcd model_shapes = result.dof_match.ModelShapes(model);
  result.mac = MacMatrix(test_shapes, model_shapes);
  result.automac_test = AutoMac(test_shapes);
  result.automac_model = AutoMac(model_shapes);

  Eigen::VectorXd test_hz(test.modes.size()), model_hz(model.modes.size());
  for (size_t i = 0; i < test.modes.size(); ++i) test_hz(i) = test.modes[i].frequency_hz;
  for (size_t j = 0; j < model.modes.size(); ++j) model_hz(j) = model.modes[j].frequency_hz;
  result.pairing = PairModes(result.mac, test_hz, model_hz, options.pairing);

  // Rows: every model mode in frequency order (paired or model-only), then test-only modes.
  std::vector<int> model_order(model.modes.size());
  for (size_t j = 0; j < model_order.size(); ++j) model_order[j] = static_cast<int>(j);
  std::stable_sort(model_order.begin(), model_order.end(), [&](int a, int b) { return model_hz(a) < model_hz(b); });
  std::vector<int> test_of_model(model.modes.size(), -1);
  for (const ModePair& p : result.pairing.pairs) test_of_model[p.model] = p.test;
  // Order swap: the paired test modes, read in model order, are not in ascending test frequency.
  double last_test_hz = -1.0;
  double sum_agreement = 0.0, sum_mac = 0.0, sum_abs_error = 0.0;
  result.min_agreement_pct = kNaN;
  for (int j : model_order) {
    CorrelationRow row;
    row.model_mode = j;
    row.model_frequency_hz = model_hz(j);
    const int i = test_of_model[j];
    if (i >= 0) {
      row.test_mode = i;
      row.test_frequency_hz = test_hz(i);
      row.test_damping_ratio = test.modes[i].damping_ratio;
      row.agreement_pct = AgreementPct(model_hz(j), test_hz(i));
      row.frequency_error_pct = FrequencyErrorPct(model_hz(j), test_hz(i));
      row.mac = result.mac(i, j);
      row.remark = "paired";
      if (test_hz(i) < last_test_hz) row.remark += "; order swap";
      last_test_hz = std::max(last_test_hz, test_hz(i));
      if (row.test_damping_ratio > options.interface_damping_ratio) row.remark += "; interface-dominated";
      sum_agreement += row.agreement_pct;
      sum_mac += row.mac;
      sum_abs_error += std::abs(row.frequency_error_pct);
      if (std::isnan(result.min_agreement_pct) || row.agreement_pct < result.min_agreement_pct)
        result.min_agreement_pct = row.agreement_pct;
    } else {
      row.remark = "model-only";
    }
    result.rows.push_back(row);
  }
  for (int i : result.pairing.unpaired_test) {
    CorrelationRow row;
    row.test_mode = i;
    row.test_frequency_hz = test_hz(i);
    row.test_damping_ratio = test.modes[i].damping_ratio;
    row.remark = "test-only";
    if (row.test_damping_ratio > options.interface_damping_ratio) row.remark += "; interface-dominated";
    result.rows.push_back(row);
  }
  const double n_pairs = static_cast<double>(result.pairing.pairs.size());
  if (n_pairs > 0) {
    result.mean_agreement_pct = sum_agreement / n_pairs;
    result.mean_mac = sum_mac / n_pairs;
    result.mean_abs_frequency_error_pct = sum_abs_error / n_pairs;
    Eigen::MatrixXcd paired_test(test_shapes.rows(), result.pairing.pairs.size());
    Eigen::MatrixXcd paired_model(model_shapes.rows(), result.pairing.pairs.size());
    for (size_t r = 0; r < result.pairing.pairs.size(); ++r) {
      paired_test.col(r) = test_shapes.col(result.pairing.pairs[r].test);
      paired_model.col(r) = model_shapes.col(result.pairing.pairs[r].model);
    }
    const Eigen::VectorXd comac = Comac(paired_test, paired_model);
    for (int k = 0; k < result.shared_dof_count; ++k)
      result.comac.push_back({result.dof_match.shared[k].test_dof, comac(k)});
    std::stable_sort(result.comac.begin(), result.comac.end(),
                     [](const ComacEntry& a, const ComacEntry& b) { return a.comac < b.comac; });
  }
  return result;
}

std::string FormatCorrelationTable(const CorrelationResult& result, TableFormat format) {
  const std::vector<std::string> header = {"Mode",      "Model f [Hz]", "Test f [Hz]", "Test damping [%]",
                                           "Agreement [%]", "Δf [%]",   "MAC",         "Remark"};
  std::vector<std::vector<std::string>> body;
  int number = 0;
  for (const CorrelationRow& row : result.rows) {
    ++number;
    body.push_back({std::to_string(number), Fixed(row.model_frequency_hz, 1), Fixed(row.test_frequency_hz, 1),
                    Fixed(100.0 * row.test_damping_ratio, 2), Fixed(row.agreement_pct, 1),
                    Fixed(row.frequency_error_pct, 1), Fixed(row.mac, 3), row.remark});
  }
  std::ostringstream out;
  const std::string summary = std::string("Shared DOFs: ") + std::to_string(result.shared_dof_count) + " of " +
                              std::to_string(result.test_dof_count) + " test DOFs; " +
                              std::to_string(result.pairing.pairs.size()) + " pairs, mean agreement " +
                              Fixed(result.mean_agreement_pct, 1) + " %, min " + Fixed(result.min_agreement_pct, 1) +
                              " %, mean MAC " + Fixed(result.mean_mac, 3);
  switch (format) {
    case TableFormat::kMarkdown: {
      out << "# Validation table\n\n" << summary << "\n\n|";
      for (const auto& h : header) out << ' ' << h << " |";
      out << "\n|";
      for (size_t k = 0; k < header.size(); ++k) out << (k == 0 || k == header.size() - 1 ? "---|" : "---:|");
      out << '\n';
      for (const auto& r : body) {
        out << '|';
        for (const auto& cell : r) out << ' ' << (cell.empty() ? "–" : cell) << " |";
        out << '\n';
      }
      out << "\n## COMAC (worst first)\n\n| DOF | COMAC |\n|---|---:|\n";
      for (const ComacEntry& c : result.comac) out << "| " << DofName(c.dof) << " | " << Fixed(c.comac, 3) << " |\n";
      break;
    }
    case TableFormat::kCsv: {
      // Plain ASCII headers for spreadsheets.
      out << "mode,model_frequency_hz,test_frequency_hz,test_damping_pct,agreement_pct,frequency_error_pct,mac,remark\n";
      for (const auto& r : body) {
        for (size_t k = 0; k < r.size(); ++k) {
          if (k) out << ',';
          if (k + 1 == r.size()) {
            out << '"' << r[k] << '"';  // the remark may hold commas
          } else {
            out << r[k];
          }
        }
        out << '\n';
      }
      out << "\ndof,comac\n";
      for (const ComacEntry& c : result.comac) out << DofName(c.dof) << ',' << Fixed(c.comac, 4) << '\n';
      break;
    }
    case TableFormat::kHtml: {
      out << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Validation table</title>\n"
             "<style>table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px}"
             "td{text-align:right}td:last-child,td:first-child{text-align:left}</style></head><body>\n"
          << "<h1>Validation table</h1>\n<p>" << HtmlEscape(summary) << "</p>\n<table>\n<tr>";
      for (const auto& h : header) out << "<th>" << HtmlEscape(h) << "</th>";
      out << "</tr>\n";
      for (const auto& r : body) {
        out << "<tr>";
        for (const auto& cell : r) out << "<td>" << HtmlEscape(cell) << "</td>";
        out << "</tr>\n";
      }
      out << "</table>\n<h2>COMAC (worst first)</h2>\n<table>\n<tr><th>DOF</th><th>COMAC</th></tr>\n";
      for (const ComacEntry& c : result.comac)
        out << "<tr><td>" << DofName(c.dof) << "</td><td>" << Fixed(c.comac, 3) << "</td></tr>\n";
      out << "</table>\n</body></html>\n";
      break;
    }
  }
  return out.str();
}

}  // namespace ema::correlation
