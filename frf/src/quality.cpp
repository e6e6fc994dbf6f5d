#include "ema/frf/quality.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include "ema/core/error.hpp"

namespace ema::frf {

std::string VerdictToString(Verdict verdict) { return verdict == Verdict::kPass ? "pass" : "warn"; }

bool QualityOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (!(band_lo_hz >= 0.0)) return fail("band_lo_hz must be >= 0");
  if (band_hi_hz > 0.0 && !(band_hi_hz > band_lo_hz)) return fail("band_hi_hz must be > band_lo_hz (or <= 0 for all lines)");
  if (!(reciprocity_tolerance > 0.0)) return fail("reciprocity_tolerance must be > 0");
  if (!(resonance_level > 0.0 && resonance_level < 1.0)) return fail("resonance_level must be in (0, 1)");
  if (!(coherence_min > 0.0 && coherence_min <= 1.0)) return fail("coherence_min must be in (0, 1]");
  if (!(coherence_max_low_fraction >= 0.0 && coherence_max_low_fraction <= 1.0))
    return fail("coherence_max_low_fraction must be in [0, 1]");
  if (!(scatter_max > 0.0)) return fail("scatter_max must be > 0");
  return true;
}

Verdict FrfQualityReport::Overall() const { return WarningCount() > 0 ? Verdict::kWarn : Verdict::kPass; }

int FrfQualityReport::WarningCount() const {
  int n = 0;
  for (const auto& c : reciprocity) n += c.verdict == Verdict::kWarn;
  for (const auto& c : driving_points) n += c.verdict == Verdict::kWarn;
  for (const auto& c : frfs) n += (c.coherence_verdict == Verdict::kWarn) + (c.scatter_verdict == Verdict::kWarn);
  return n;
}

double RandomErrorOfMagnitude(double coherence, int averages) {
  if (!(coherence > 0.0) || averages < 1) return kNaN;
  const double g2 = std::min(coherence, 1.0);
  return std::sqrt(1.0 - g2) / (std::sqrt(g2) * std::sqrt(2.0 * averages));
}

namespace {

/// One measured FRF on the band lines, DOFs turned positive (sign folded into h).
struct Entry {
  Dof response, reference;
  Eigen::VectorXcd h;
  Eigen::VectorXd coherence;  // empty when unknown
  int averages = 0;
  Quantity quantity = Quantity::kAcceleration;
};

Dof Positive(Dof dof, double* sign) {
  if (dof.direction < 0) {
    dof.direction = -dof.direction;
    *sign = -*sign;
  }
  return dof;
}

std::string Hz(double f) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", f);
  return buf;
}

std::string Percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * x);
  return buf;
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  return m;
}

/// The part of H whose sign a passive driving point fixes, made positive-when-right:
/// Im(accelerance), Re(mobility), -Im(receptance).
double SignedPart(std::complex<double> h, Quantity q) {
  switch (FrfTypeOf(q)) {
    case FrfType::kReceptance: return -h.imag();
    case FrfType::kMobility: return h.real();
    default: return h.imag();
  }
}

const char* SignedPartName(Quantity q) {
  switch (FrfTypeOf(q)) {
    case FrfType::kReceptance: return "Im of the receptance";
    case FrfType::kMobility: return "Re of the mobility";
    default: return "Im of the accelerance";
  }
}

ReciprocityCheck CompareReciprocal(const Entry& a, const Entry& b, double tolerance) {
  ReciprocityCheck c;
  c.dof_i = a.response;
  c.dof_j = a.reference;
  double diff = 0.0, na = 0.0, nb = 0.0;
  for (int k = 0; k < a.h.size(); ++k) {
    if (!std::isfinite(a.h[k].real()) || !std::isfinite(b.h[k].real())) continue;
    diff += std::norm(a.h[k] - b.h[k]);
    na += std::norm(a.h[k]);
    nb += std::norm(b.h[k]);
  }
  na = std::sqrt(na);
  nb = std::sqrt(nb);
  const std::string pair = "H(" + DofName(a.response) + "/" + DofName(a.reference) + ") vs H(" +
                           DofName(b.response) + "/" + DofName(b.reference) + ")";
  if (na + nb == 0.0) {
    c.verdict = Verdict::kWarn;
    c.reason = pair + ": no common measured lines";
    return c;
  }
  c.relative_difference = std::sqrt(diff) / (0.5 * (na + nb));
  c.amplitude_ratio = nb > 0.0 ? na / nb : kNaN;
  if (c.relative_difference <= tolerance) {
    c.reason = pair + " differ by " + Percent(c.relative_difference) + " (<= " + Percent(tolerance) + ")";
  } else {
    c.verdict = Verdict::kWarn;
    c.reason = pair + " differ by " + Percent(c.relative_difference) + " (> " + Percent(tolerance) +
               "): amplitude ratio " + Percent(c.amplitude_ratio) +
               "; check sensor/hammer calibration, DOF labels, or nonlinearity";
  }
  return c;
}

DrivingPointCheck CheckDrivingPoint(const Entry& e, const Eigen::VectorXd& f, double level) {
  DrivingPointCheck c;
  c.dof = e.response;
  const int n = static_cast<int>(e.h.size());
  Eigen::VectorXd mag(n);
  double top = 0.0, num = 0.0, den = 0.0;
  for (int k = 0; k < n; ++k) {
    mag[k] = std::isfinite(e.h[k].real()) ? std::abs(e.h[k]) : 0.0;
    top = std::max(top, mag[k]);
    if (mag[k] > 0.0) {
      const double p = SignedPart(e.h[k], e.quantity);
      num += p * std::abs(p);
      den += p * p;
    }
  }
  c.sign_consistency = den > 0.0 ? num / den : kNaN;
  for (int k = 1; k + 1 < n; ++k) {
    if (!(mag[k] > mag[k - 1] && mag[k] >= mag[k + 1] && mag[k] >= level * top)) continue;
    // A resonance peak is in quadrature (|signed part| ~ |H|, either sign); noise peaks with a
    // random phase are not resonances and are not judged.
    const double p = SignedPart(e.h[k], e.quantity);
    if (std::abs(p) < 0.7 * mag[k]) continue;
    ++c.resonances;
    if (p < 0.0) {
      ++c.flipped;
      c.flipped_frequencies_hz.push_back(f[k]);
    }
  }
  const std::string name = "driving point " + DofName(e.response) + ": " + SignedPartName(e.quantity);
  if (c.resonances == 0) {
    c.reason = name + ": no resonance peak in the band";
  } else if (c.flipped == 0) {
    c.reason = name + " has the passive sign at all " + std::to_string(c.resonances) + " resonance(s)";
  } else {
    c.verdict = Verdict::kWarn;
    std::string at;
    for (size_t i = 0; i < c.flipped_frequencies_hz.size() && i < 6; ++i)
      at += (i ? ", " : "") + Hz(c.flipped_frequencies_hz[i]);
    c.reason = name + " has the wrong sign at " + std::to_string(c.flipped) + " of " + std::to_string(c.resonances) +
               " resonance(s) (" + at + " Hz): " +
               (c.flipped == c.resonances ? "inverted sensor or hammer (sign or direction code)"
                                          : "a sign change between resonances: check the sensor mounting");
  }
  return c;
}

}  // namespace

FrfQualityReport CheckFrfQuality(const std::vector<FrfSet>& sets, const QualityOptions& options,
                                 const std::vector<std::string>& sources) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("quality options", error);
  auto source = [&](size_t s) { return s < sources.size() ? sources[s] : "FRF set " + std::to_string(s + 1); };
  FrfQualityReport report;
  if (sets.empty()) return report;

  // Band lines of the first set; the others must share the grid.
  const Eigen::VectorXd& grid = sets.front().frequency_hz;
  std::vector<int> lines;
  for (int k = 0; k < grid.size(); ++k) {
    const double f = grid[k];
    if (f <= 0.0 || f < options.band_lo_hz || (options.band_hi_hz > 0.0 && f > options.band_hi_hz)) continue;
    lines.push_back(k);
  }
  if (lines.size() < 3) throw InputError(source(0), "fewer than 3 frequency lines in the quality band");
  for (size_t s = 1; s < sets.size(); ++s) {
    const auto& g = sets[s].frequency_hz;
    const double tol = 1e-6 * std::max(1.0, std::abs(grid[grid.size() - 1]));
    if (g.size() != grid.size() || (g - grid).cwiseAbs().maxCoeff() > tol)
      throw InputError(source(s), "frequency lines differ from " + source(0) + " (" + std::to_string(g.size()) +
                                      " lines vs " + std::to_string(grid.size()) + "); the quality checks compare line by line");
  }
  const int nb = static_cast<int>(lines.size());
  Eigen::VectorXd band_f(nb);
  for (int k = 0; k < nb; ++k) band_f[k] = grid[lines[k]];

  // Every measured FRF once, keyed by (response, reference).
  std::map<std::pair<Dof, Dof>, Entry> entries;
  std::vector<std::pair<Dof, Dof>> order;  // first-seen order, for stable output
  for (size_t s = 0; s < sets.size(); ++s) {
    const FrfSet& set = sets[s];
    if (static_cast<int>(set.h.size()) != set.ReferenceCount())
      throw InputError(source(s), "FRF set has " + std::to_string(set.h.size()) + " FRF blocks for " +
                                      std::to_string(set.ReferenceCount()) + " references");
    report.has_averages = report.has_averages || set.averages.size() > 0;
    for (int r = 0; r < set.ReferenceCount(); ++r) {
      const bool coh = r < static_cast<int>(set.coherence.size()) && set.coherence[r].rows() == set.h[r].rows() &&
                       set.coherence[r].cols() == set.h[r].cols();
      for (int o = 0; o < set.OutputCount(); ++o) {
        double sign = 1.0;
        const Dof resp = Positive(set.outputs[o], &sign);
        const Dof ref = Positive(set.references[r], &sign);
        Entry e{resp, ref, Eigen::VectorXcd(nb), Eigen::VectorXd(), 0, set.output_quantity};
        bool measured = false;
        for (int k = 0; k < nb; ++k) {
          e.h[k] = sign * set.h[r](lines[k], o);
          measured = measured || std::isfinite(e.h[k].real());
        }
        if (!measured) continue;
        if (coh) {
          e.coherence.resize(nb);
          for (int k = 0; k < nb; ++k) e.coherence[k] = set.coherence[r](lines[k], o);
          report.has_coherence = true;
        }
        if (r < set.averages.rows() && o < set.averages.cols()) e.averages = set.averages(r, o);
        const auto key = std::make_pair(resp, ref);
        if (entries.count(key)) continue;
        entries.emplace(key, std::move(e));
        order.push_back(key);
      }
    }
  }

  for (const auto& key : order) {
    const Entry& e = entries.at(key);
    if (e.response == e.reference) {
      report.driving_points.push_back(CheckDrivingPoint(e, band_f, options.resonance_level));
      continue;
    }
    if (!(e.response < e.reference)) continue;  // each pair once
    const auto other = entries.find({e.reference, e.response});
    if (other != entries.end())
      report.reciprocity.push_back(CompareReciprocal(e, other->second, options.reciprocity_tolerance));
  }
  if (report.reciprocity.empty())
    report.notes.push_back("reciprocity: no FRF was measured both ways (H_ij and H_ji); give several references, "
                           "or a roving-hammer file beside a roving-sensor file");
  if (report.driving_points.empty())
    report.notes.push_back("driving point: no FRF with the response at its reference DOF");

  // Coherence and scatter per FRF, and the coherence map.
  if (report.has_coherence) {
    report.coherence_map.frequency_hz = band_f;
    report.coherence_map.coherence.setConstant(static_cast<int>(order.size()), nb, kNaN);
  }
  int row = 0;
  for (const auto& key : order) {
    const Entry& e = entries.at(key);
    FrfStatistics st;
    st.response = e.response;
    st.reference = e.reference;
    st.averages = e.averages;
    if (e.coherence.size() == nb) {
      std::vector<double> eps;
      double sum = 0.0, max_eps = 0.0;
      int count = 0, low = 0;
      for (int k = 0; k < nb; ++k) {
        const double g = e.coherence[k];
        if (!std::isfinite(g)) continue;
        sum += g;
        ++count;
        low += g < options.coherence_min;
        const double x = RandomErrorOfMagnitude(g, e.averages);
        if (std::isfinite(x)) {
          eps.push_back(x);
          max_eps = std::max(max_eps, x);
        }
      }
      if (count > 0) {
        st.mean_coherence = sum / count;
        st.low_coherence_fraction = static_cast<double>(low) / count;
      }
      if (!eps.empty()) {
        st.median_random_error = Median(eps);
        st.max_random_error = max_eps;
      }
      report.coherence_map.coherence.row(row) = e.coherence.transpose();
    }
    std::string reason;
    if (std::isfinite(st.low_coherence_fraction) && st.low_coherence_fraction > options.coherence_max_low_fraction) {
      st.coherence_verdict = Verdict::kWarn;
      reason = "coherence below " + std::to_string(options.coherence_min).substr(0, 4) + " on " +
               Percent(st.low_coherence_fraction) + " of the band (> " + Percent(options.coherence_max_low_fraction) + ")";
    }
    if (std::isfinite(st.median_random_error) && st.median_random_error > options.scatter_max) {
      st.scatter_verdict = Verdict::kWarn;
      reason += (reason.empty() ? "" : "; ") + std::string("impact-to-impact scatter of |H| ") +
                Percent(st.median_random_error) + " (median, > " + Percent(options.scatter_max) + ")";
    }
    st.reason = reason;
    report.frfs.push_back(st);
    if (report.has_coherence) report.coherence_map.labels.push_back(DofName(e.response) + "/" + DofName(e.reference));
    ++row;
  }
  if (!report.has_coherence)
    report.notes.push_back("coherence: the FRF files carry no coherence (UFF 58 function type 6); no coherence map");
  if (!report.has_averages)
    report.notes.push_back("scatter: the number of averaged impacts is unknown (not recorded in the file); "
                           "no impact-to-impact scatter");
  return report;
}

}  // namespace ema::frf
