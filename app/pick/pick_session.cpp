// `ema pick`'s session: the picks as fits, their JSON for the page, Save through RunFitStage.
#include "pick_session.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <ostream>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/correlation/mac.hpp"
#include "ema/curvefit/stabilisation.hpp"
#include "ema/formats/mode_indicators_json.hpp"

namespace ema::app {

namespace {

using json = nlohmann::json;

json NumberOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// Five significant digits: what a curve on screen needs, and it keeps the page's data small.
json Rounded(double v) {
  if (!std::isfinite(v)) return nullptr;
  char text[32];
  std::snprintf(text, sizeof text, "%.5g", v);
  return std::strtod(text, nullptr);
}

// A pole is named by its order and its exact frequency (both fixed once the diagram is built).
bool SamePole(const curvefit::Pole& a, const curvefit::Pole& b) {
  return a.order == b.order && a.frequency_hz == b.frequency_hz;
}

// The diagram's pole behind a selected pole. The refinement moves the selected copy (frequency,
// damping, participation); its order, label and distance to its previous-order match stay, and
// name it. This is the pole `--select` chose for the clicked frequency (the highest stable order
// of its column, curvefit::SelectPolesNear), not always the one clicked: the page rings it, and
// removes the mode by it.
const curvefit::Pole* DiagramPole(const curvefit::StabilisationDiagram& diagram, const curvefit::Pole& selected) {
  const curvefit::Pole* best = nullptr;
  auto same_match = [&](const curvefit::Pole& q) {
    return q.match_distance == selected.match_distance ||
           (std::isnan(q.match_distance) && std::isnan(selected.match_distance));
  };
  for (const auto& order : diagram.orders)
    for (const curvefit::Pole& q : order) {
      if (q.order != selected.order || q.label != selected.label) continue;
      if (!best || (same_match(q) && !same_match(*best)) ||
          (same_match(q) == same_match(*best) &&
           std::abs(q.frequency_hz - selected.frequency_hz) < std::abs(best->frequency_hz - selected.frequency_hz)))
        best = &q;
    }
  return best;
}

std::string Hz(double f) {
  std::ostringstream text;
  text << std::setprecision(6) << f << " Hz";
  return text.str();
}

// The lines drawn: the fit band widened by 10 % (as the report draws it), strided to `max_points`.
std::vector<int> DisplayLines(const FrfSet& frfs, double lo, double hi, int max_points) {
  std::vector<int> lines;
  const double margin = hi > lo ? 0.1 * (hi - lo) : 0.0;
  for (int i = 0; i < frfs.LineCount(); ++i) {
    const double f = frfs.frequency_hz[i];
    if (f > 0.0 && (!(hi > lo) || (f >= lo - margin && f <= hi + margin))) lines.push_back(i);
  }
  const int stride = static_cast<int>(lines.size()) / max_points + 1;
  if (stride > 1) {
    std::vector<int> kept;
    for (size_t i = 0; i < lines.size(); i += stride) kept.push_back(lines[i]);
    lines.swap(kept);
  }
  return lines;
}

// A driving point: the response at the reference's node and axis (the sign may differ: 101+Z / 101-Z).
bool IsDrivingPoint(const Dof& response, const Dof& reference) {
  return response.node == reference.node && std::abs(response.direction) == std::abs(reference.direction);
}

}  // namespace

PickSession::PickSession(FitConfig config, FrfSet frfs, PickOptions options)
    : config_(std::move(config)), frfs_(std::move(frfs)), options_(options) {
  if (config_.options.method != curvefit::FitMethod::kPolymax)
    throw UsageError("ema pick needs --method polymax: picking is done on the stabilisation diagram");
  const std::vector<double>& first = config_.options.select_frequencies_hz;
  pick_ = FitPick(first.empty(), first);  // curvefit::Fit's errors name the FRF file
  diagram_ = pick_.fit->diagram;
  for (const auto& w : pick_.fit->warnings) std::cerr << "warning: " << w << "\n";
  display_lines_ = DisplayLines(frfs_, diagram_.band_lo_hz, diagram_.band_hi_hz, options_.max_display_lines);
  std::vector<std::pair<int, int>> driving, others;
  for (int r = 0; r < frfs_.ReferenceCount(); ++r)
    for (int o = 0; o < frfs_.OutputCount(); ++o) {
      if (!(frfs_.h[r].col(o).array() == frfs_.h[r].col(o).array()).any()) continue;  // never measured (all NaN)
      (IsDrivingPoint(frfs_.outputs[o], frfs_.references[r]) ? driving : others).emplace_back(r, o);
    }
  display_frfs_ = driving;
  display_frfs_.insert(display_frfs_.end(), others.begin(), others.end());
  if (static_cast<int>(display_frfs_.size()) > options_.max_display_frfs) display_frfs_.resize(options_.max_display_frfs);
}

PickSession::Pick PickSession::FitPick(bool automatic, std::vector<double> requested_hz) const {
  Pick pick;
  pick.automatic = automatic;
  pick.requested_hz = std::move(requested_hz);
  std::sort(pick.requested_hz.begin(), pick.requested_hz.end());
  if (!automatic && pick.requested_hz.empty()) return pick;  // nothing picked: no fit to run
  curvefit::FitOptions options = config_.options;
  options.select_frequencies_hz = automatic ? std::vector<double>() : pick.requested_hz;
  const auto t0 = std::chrono::steady_clock::now();
  pick.fit = curvefit::Fit(frfs_, options, config_.input);
  pick.fit->modes.source = config_.input;
  pick.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return pick;
}

json PickSession::Select(const json& request) {
  // One pick at a time, in the order they came. Everything is checked before anything changes:
  // a refused pick leaves the session as it was.
  std::lock_guard<std::mutex> lock(mutex_);
  if (!request.is_object()) throw PickRequestError("expected a JSON object {\"frequencies_hz\": [...]} or {\"selection\": \"auto\"}");
  for (auto it = request.begin(); it != request.end(); ++it)
    if (it.key() != "frequencies_hz" && it.key() != "selection")
      throw PickRequestError("unknown key '" + it.key() + "': expected \"frequencies_hz\" or \"selection\"");
  bool automatic = false;
  std::vector<double> requested;
  if (request.contains("selection")) {
    if (request["selection"] != "auto" || request.contains("frequencies_hz"))
      throw PickRequestError("\"selection\": only \"auto\" (automatic selection, without frequencies) is known");
    automatic = true;
  } else {
    if (!request.contains("frequencies_hz") || !request["frequencies_hz"].is_array())
      throw PickRequestError("\"frequencies_hz\": expected an array of frequencies in Hz");
    const json& list = request["frequencies_hz"];
    if (list.size() > options_.max_picked)
      throw PickRequestError("\"frequencies_hz\": " + std::to_string(list.size()) + " frequencies, at most " +
                             std::to_string(options_.max_picked) + " are accepted");
    const double lo = diagram_.band_lo_hz, hi = diagram_.band_hi_hz;
    for (size_t k = 0; k < list.size(); ++k) {
      const std::string where = "\"frequencies_hz\"[" + std::to_string(k) + "]";
      if (!list[k].is_number()) throw PickRequestError(where + ": expected a number (Hz), got " + list[k].dump());
      const double f = list[k].get<double>();
      if (!std::isfinite(f) || !(f > 0.0)) throw PickRequestError(where + ": expected a positive frequency, got " + list[k].dump());
      if (f < lo || f > hi)
        throw PickRequestError(where + " = " + Hz(f) + ": outside the fit band " + ExactNumberText(lo) + ".." +
                               ExactNumberText(hi) + " Hz");
      requested.push_back(f);
    }
    std::sort(requested.begin(), requested.end());
    // Two frequencies that `--select` would map to one pole would fit one mode twice.
    std::vector<curvefit::SelectedPole> poles;
    try {
      poles = curvefit::SelectPolesNear(diagram_, requested);
    } catch (const InputError& e) {
      throw PickRequestError(e.what());
    }
    for (size_t a = 0; a < poles.size(); ++a)
      for (size_t b = a + 1; b < poles.size(); ++b)
        if (SamePole(poles[a].pole, poles[b].pole))
          throw PickRequestError(Hz(requested[a]) + " and " + Hz(requested[b]) + " both pick the pole at " +
                                 Hz(poles[a].pole.frequency_hz) + " (order " + std::to_string(poles[a].pole.order) +
                                 "): keep one of them");
  }
  Pick pick;
  try {
    pick = FitPick(automatic, requested);
  } catch (const std::exception& e) {
    throw PickRequestError(std::string("the fit failed: ") + e.what());
  }
  pick_ = std::move(pick);
  return StateJsonLocked();
}

json PickSession::DataJson() const {
  std::lock_guard<std::mutex> lock(mutex_);
  json diagram = {{"order", json::array()}, {"frequency_hz", json::array()}, {"damping_ratio", json::array()}};
  std::string labels;  // one letter per pole: o f d v s, x for a non-physical pole
  for (const auto& order : diagram_.orders)
    for (const curvefit::Pole& p : order) {
      diagram["order"].push_back(p.order);
      diagram["frequency_hz"].push_back(p.frequency_hz);  // exact: a click sends it back as the pick
      diagram["damping_ratio"].push_back(Rounded(p.damping_ratio));
      labels += p.physical ? p.label : 'x';
    }
  diagram["label"] = labels;

  json indicator = {{"frequency_hz", json::array()}, {"sum_frf", json::array()}};
  for (Eigen::Index k = 0; k < diagram_.frequency_hz.size(); ++k) {
    indicator["frequency_hz"].push_back(Rounded(diagram_.frequency_hz[k]));
    indicator["sum_frf"].push_back(Rounded(k < diagram_.sum_frf.size() ? diagram_.sum_frf[k] : kNaN));
  }
  try {  // CMIF: the first two singular values (a close mode the sum hides shows in the second)
    json mi;
    formats::AddModeIndicatorsJson(&mi, frfs_, config_.options.data, config_.input);
    indicator["cmif_frequency_hz"] = json::array();
    for (const json& f : mi["cmif"]["frequency_hz"]) indicator["cmif_frequency_hz"].push_back(Rounded(f.get<double>()));
    indicator["cmif"] = json::array();
    for (size_t c = 0; c < std::min<size_t>(2, mi["cmif"]["values"].size()); ++c) {
      json column = json::array();
      for (const json& v : mi["cmif"]["values"][c]) column.push_back(v.is_number() ? Rounded(v.get<double>()) : json(nullptr));
      indicator["cmif"].push_back(std::move(column));
    }
  } catch (const std::exception&) {
    // Without CMIF the sum of |H| still shows the resonances.
  }

  json frfs = {{"frequency_hz", json::array()}, {"items", json::array()},
               {"unit", frfs_.response_unit + "/" + frfs_.force_unit}};
  for (int i : display_lines_) frfs["frequency_hz"].push_back(Rounded(frfs_.frequency_hz[i]));
  for (const auto& [r, o] : display_frfs_) {
    json magnitude = json::array(), phase = json::array();
    for (int i : display_lines_) {
      const std::complex<double> v = frfs_.h[r](i, o);
      magnitude.push_back(Rounded(std::abs(v)));
      phase.push_back(Rounded(std::arg(v) * 180.0 / M_PI));
    }
    frfs["items"].push_back({{"label", DofName(frfs_.outputs[o]) + " / " + DofName(frfs_.references[r])},
                             {"driving", IsDrivingPoint(frfs_.outputs[o], frfs_.references[r])},
                             {"magnitude", std::move(magnitude)},
                             {"phase_deg", std::move(phase)}});
  }
  const json no_path = nullptr;
  json fixed = {{"input", config_.input},
                {"band_hz", {diagram_.band_lo_hz, diagram_.band_hi_hz}},
                {"orders", {diagram_.order_min, diagram_.order_max}},
                {"references", diagram_.references},
                {"diagram", std::move(diagram)},
                {"indicator", std::move(indicator)},
                {"frfs", std::move(frfs)},
                {"max_picked", options_.max_picked},
                {"outputs", {{"modes", config_.output.empty() ? no_path : json(config_.output)},
                             {"json", config_.json_path.empty() ? no_path : json(config_.json_path)}}}};
  return {{"fixed", std::move(fixed)}, {"state", StateJsonLocked()}};
}

json PickSession::StateJson() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return StateJsonLocked();
}

json PickSession::StateJsonLocked() const {
  json state = {{"selection", pick_.automatic ? "automatic" : pick_.fit ? "given frequencies" : "none"},
                {"modes", json::array()},
                {"mac", json::array()},
                {"synthesised", json::array()},
                {"dropped", json::array()},
                {"warnings", json::array()},
                {"refinement", ""},
                {"fit_seconds", pick_.fit_seconds},
                {"saves", saves_},
                {"command", EquivalentCommandLocked()},
                {"can_save", !config_.output.empty() && pick_.fit && !pick_.fit->modes.modes.empty()}};
  if (!pick_.fit) {
    state["picked_hz"] = json::array();
    return state;
  }
  const curvefit::FitResult& fit = *pick_.fit;
  // The picked frequencies: as given, or for the automatic selection the diagram poles it chose
  // (what a hand pick starting from it sends).
  json picked = json::array();
  if (!pick_.automatic)
    for (double f : pick_.requested_hz) picked.push_back(f);
  // Which requested frequency gave each mode (the page removes a mode by removing it).
  std::vector<curvefit::Pole> requested_poles;
  if (!pick_.automatic)
    for (const auto& s : curvefit::SelectPolesNear(diagram_, pick_.requested_hz)) requested_poles.push_back(s.pole);
  const size_t n = fit.modes.modes.size();
  Eigen::MatrixXcd shapes(fit.modes.dofs.size(), static_cast<Eigen::Index>(n));
  for (size_t k = 0; k < n; ++k) {
    const Mode& m = fit.modes.modes[k];
    if (m.shape.size() == shapes.rows()) shapes.col(static_cast<Eigen::Index>(k)) = m.shape;
    else shapes.col(static_cast<Eigen::Index>(k)).setZero();
    json mode = {{"frequency_hz", m.frequency_hz},
                 {"frequency_std_hz", NumberOrNull(m.frequency_std_hz)},
                 {"damping_ratio", m.damping_ratio},
                 {"damping_ratio_std", NumberOrNull(m.damping_ratio_std)},
                 {"mpc", NumberOrNull(m.mpc)},
                 {"mpd_deg", NumberOrNull(m.mpd)}};
    if (k < fit.selected.size()) {
      const curvefit::Pole* p = DiagramPole(diagram_, fit.selected[k].pole);
      if (p) {
        mode["pole"] = {{"order", p->order}, {"frequency_hz", p->frequency_hz}, {"damping_ratio", p->damping_ratio},
                        {"label", std::string(1, p->label)}};
        for (size_t j = 0; j < requested_poles.size(); ++j)
          if (SamePole(requested_poles[j], *p)) mode["requested_hz"] = pick_.requested_hz[j];
        if (pick_.automatic) {
          mode["requested_hz"] = p->frequency_hz;
          picked.push_back(p->frequency_hz);
        }
      }
    }
    state["modes"].push_back(std::move(mode));
  }
  state["picked_hz"] = std::move(picked);
  const Eigen::MatrixXd mac = n ? correlation::AutoMac(shapes) : Eigen::MatrixXd();
  for (Eigen::Index i = 0; i < mac.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < mac.cols(); ++j) row.push_back(Rounded(mac(i, j)));
    state["mac"].push_back(std::move(row));
  }
  // The fit's own modal model at the drawn lines (what the report draws over the measured FRFs).
  Eigen::VectorXd f(static_cast<Eigen::Index>(display_lines_.size()));
  for (size_t i = 0; i < display_lines_.size(); ++i) f[static_cast<Eigen::Index>(i)] = frfs_.frequency_hz[display_lines_[i]];
  for (const auto& [r, o] : display_frfs_) {
    json magnitude = json::array(), phase = json::array();
    if (n) {
      const Eigen::VectorXcd h = curvefit::SynthesiseMeasuredFrf(fit.model, frfs_.outputs[o], frfs_.references[r], f);
      for (Eigen::Index i = 0; i < h.size(); ++i) {
        magnitude.push_back(Rounded(std::abs(h[i])));
        phase.push_back(Rounded(std::arg(h[i]) * 180.0 / M_PI));
      }
    }
    state["synthesised"].push_back({{"magnitude", std::move(magnitude)}, {"phase_deg", std::move(phase)}});
  }
  for (const auto& d : fit.dropped) state["dropped"].push_back({{"frequency_hz", d.frequency_hz}, {"reason", d.reason}});
  for (const auto& w : fit.warnings) state["warnings"].push_back(w);
  const bool any_std = std::any_of(fit.modes.modes.begin(), fit.modes.modes.end(),
                                   [](const Mode& m) { return std::isfinite(m.frequency_std_hz); });
  if (any_std) state["refinement"] = fit.refine.BriefReport();
  return state;
}

std::string PickSession::EquivalentCommand() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return EquivalentCommandLocked();
}

std::string PickSession::SelectText() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return SelectTextLocked();
}

std::optional<std::vector<double>> PickSession::Selection() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (pick_.automatic) return std::vector<double>();
  if (pick_.requested_hz.empty()) return std::nullopt;
  return pick_.requested_hz;
}

std::string PickSession::SelectTextLocked() const {
  if (pick_.automatic) return "auto";
  std::string list;
  for (double f : pick_.requested_hz) {
    if (!list.empty()) list += ',';
    list += ExactNumberText(f);
  }
  return list;
}

std::string PickSession::EquivalentCommandLocked() const {
  FitConfig config = config_;
  config.options.select_frequencies_hz = pick_.automatic ? std::vector<double>() : pick_.requested_hz;
  if (config.output.empty()) config.output = "MODES.unv";
  return "ema " + CommandLine(config);
}

json PickSession::Save(std::ostream& out) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string command = EquivalentCommandLocked();
  if (config_.output.empty())
    throw PickRequestError("no -o MODES.unv was given to ema pick, so Save writes nothing; the equivalent command is: " +
                           command);
  if (!pick_.fit || pick_.fit->modes.modes.empty()) throw PickRequestError("nothing is picked: click a pole first");
  FitConfig config = config_;
  config.options.select_frequencies_hz = pick_.automatic ? std::vector<double>() : pick_.requested_hz;
  std::ostringstream text;
  try {
    RunFitStage(config, frfs_, text);  // `ema fit` itself: the same fit, the same writers
  } catch (const std::exception& e) {
    throw PickRequestError(std::string("saving failed: ") + e.what());
  }
  ++saves_;
  json written = json::array();
  for (const std::string* path : {&config.output, &config.json_path, &config.stabilisation_path, &config.plot_path})
    if (!path->empty()) written.push_back(*path);
  std::string files;
  for (const json& w : written) files += (files.empty() ? "" : ", ") + w.get<std::string>();
  out << text.str() << "wrote " << files << "\nequivalent: " << command << std::endl;
  return {{"written", std::move(written)}, {"command", command}, {"text", text.str()}};
}

std::string PickSession::Summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::ostringstream out;
  const curvefit::FitResult* fit = pick_.fit ? &*pick_.fit : nullptr;
  const size_t n = fit ? fit->modes.modes.size() : 0;
  out << n << " mode(s) from " << config_.input << " (PolyMAX";
  if (fit && fit->transposed) out << ", roving hammer fitted by reciprocity";
  out << "), orders " << diagram_.order_min << ".." << diagram_.order_max << ", selection "
      << (fit ? fit->selection_rule : "none") << ", fitted in " << std::fixed << std::setprecision(2)
      << pick_.fit_seconds << " s\n";
  for (size_t k = 0; k < n; ++k) {
    const Mode& m = fit->modes.modes[k];
    out << "  " << std::setw(2) << k + 1 << "  f " << std::setprecision(3) << m.frequency_hz << " Hz  zeta "
        << 100.0 * m.damping_ratio << " %  MPC " << m.mpc << "\n";
  }
  return out.str();
}

}  // namespace ema::app
