#include "ema/curvefit/fit_data.hpp"

#include <map>

#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>
#include <thread>
#include <vector>

#include "ema/core/error.hpp"
#include "ema/core/parallel.hpp"

namespace ema::curvefit {

namespace {

std::string Hz(double f) {
  std::ostringstream s;
  s << f << " Hz";
  return s.str();
}

}  // namespace

FitData PrepareFitData(const FrfSet& frfs, const FitDataOptions& options, const std::string& source) {
  const int n_lines = frfs.LineCount();
  const int n_out = frfs.OutputCount();
  const int n_ref = frfs.ReferenceCount();
  if (n_out == 0 || n_ref == 0 || n_lines == 0) throw InputError(source, "no FRFs to fit");
  if (static_cast<int>(frfs.h.size()) != n_ref)
    throw InputError(source, "inconsistent references: " + std::to_string(n_ref) + " reference DOFs but " +
                                 std::to_string(frfs.h.size()) + " FRF blocks");
  for (int r = 0; r < n_ref; ++r)
    if (frfs.h[r].rows() != n_lines || frfs.h[r].cols() != n_out)
      throw InputError(source, "inconsistent references: FRFs of reference " + DofName(frfs.references[r]) +
                                   " are " + std::to_string(frfs.h[r].rows()) + " lines x " +
                                   std::to_string(frfs.h[r].cols()) + " outputs, expected " +
                                   std::to_string(n_lines) + " x " + std::to_string(n_out));
  for (int a = 0; a < n_ref; ++a)
    for (int b = a + 1; b < n_ref; ++b)
      if (frfs.references[a] == frfs.references[b])
        throw InputError(source, "inconsistent references: reference " + DofName(frfs.references[a]) +
                                     " appears twice");

  // Uniform grid: the Toeplitz/FFT assembly relies on it.
  if (n_lines < 2) throw InputError(source, "only one frequency line");
  const double df = (frfs.frequency_hz[n_lines - 1] - frfs.frequency_hz[0]) / (n_lines - 1);
  if (!(df > 0.0)) throw InputError(source, "frequency axis is not increasing");
  for (int k = 1; k < n_lines; ++k)
    if (std::abs(frfs.frequency_hz[k] - frfs.frequency_hz[k - 1] - df) > 1e-6 * df)
      throw InputError(source, "frequency lines are not uniformly spaced (line " + std::to_string(k) + ")");

  const double lo = std::max(options.band_lo_hz, 0.0);
  const double hi = options.band_hi_hz > 0.0 ? options.band_hi_hz : frfs.frequency_hz[n_lines - 1];
  if (!(hi > lo)) throw InputError(source, "empty band " + Hz(lo) + " to " + Hz(hi));
  int first = -1, last = -1;
  for (int k = 0; k < n_lines; ++k) {
    const double f = frfs.frequency_hz[k];
    if (f <= 0.0 || f < lo - 1e-9 * df || f > hi + 1e-9 * df) continue;
    if (first < 0) first = k;
    last = k;
  }
  if (first < 0)
    throw InputError(source, "no FRF lines in the band " + Hz(lo) + " to " + Hz(hi) + " (data cover " +
                                 Hz(frfs.frequency_hz[0]) + " to " + Hz(frfs.frequency_hz[n_lines - 1]) + ")");

  FitData d;
  d.transposed = frfs.roving_hammer || (options.auto_transpose && n_ref > n_out);
  d.outputs = d.transposed ? frfs.references : frfs.outputs;
  d.references = d.transposed ? frfs.outputs : frfs.references;
  if (!d.transposed && frfs.output_sets.size() == frfs.outputs.size()) d.output_set = frfs.output_sets;
  d.frf_type = FrfTypeOf(frfs.output_quantity);
  d.window_decay_rate = frfs.window_decay_rate;
  d.line_spacing_hz = df;
  const int n = last - first + 1;
  const int l = d.OutputCount(), m = d.ReferenceCount();
  d.frequency_hz = frfs.frequency_hz.segment(first, n);
  d.h.resize(n, l * m);
  // One pass per column: copy H_oi of the fitting orientation (reciprocity makes H(a,b) = H(b,a))
  // and note which lines are finite (NaN screening: an FRF that is NaN everywhere was not
  // measured; scattered NaN lines are skipped). On a big set the columns are split over threads:
  // the pass is page faults and memory traffic, which scale with the cores (a 3000-FRF x
  // 4000-line set: 192 MB).
  const int columns = l * m;
  std::vector<char> column_finite(static_cast<size_t>(columns), 0);
  auto copy_columns = [&](int c0, int c1, std::vector<char>* line_finite) {
    for (int c = c0; c < c1; ++c) {
      const int o = c / m, i = c % m;
      const int ref = d.transposed ? o : i, out = d.transposed ? i : o;
      const std::complex<double>* src = frfs.h[ref].col(out).data() + first;
      std::complex<double>* dst = d.h.col(c).data();
      bool any = false;
      for (int k = 0; k < n; ++k) {
        dst[k] = src[k];
        const bool finite = std::isfinite(src[k].real()) && std::isfinite(src[k].imag());
        any = any || finite;
        if (!finite) (*line_finite)[k] = 0;
      }
      column_finite[c] = any;
    }
  };
  const bool big = static_cast<double>(n) * columns >= double{1 << 22};
  const int threads = big ? std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, 4) : 1;
  std::vector<std::vector<char>> line_finite_of(static_cast<size_t>(threads), std::vector<char>(static_cast<size_t>(n), 1));
  RunOnThreads(threads, [&](int t, const std::atomic<bool>&) {
    copy_columns(columns * t / threads, columns * (t + 1) / threads, &line_finite_of[t]);
  });
  for (int c = 0; c < columns; ++c) {
    if (!column_finite[c]) {
      const int o = c / m, i = c % m;
      throw InputError(source, "inconsistent references: no FRF from reference " + DofName(d.references[i]) +
                                   " to output " + DofName(d.outputs[o]) +
                                   " in the band (polyreference fitting needs every output from every reference)");
    }
  }
  std::vector<char>& line_finite = line_finite_of[0];
  for (int t = 1; t < threads; ++t)
    for (int k = 0; k < n; ++k) line_finite[k] = static_cast<char>(line_finite[k] && line_finite_of[t][k]);
  d.line_weight = Eigen::VectorXd::Ones(n);
  int bad = 0, run = 0, longest = 0, first_bad = -1;
  for (int k = 0; k < n; ++k) {
    const bool finite = line_finite[k] != 0;
    if (!finite) {
      d.line_weight[k] = 0.0;
      d.h.row(k).setZero();
      ++bad;
      longest = std::max(longest, ++run);
      if (first_bad < 0) first_bad = k;
    } else {
      run = 0;
    }
  }
  if (bad > 0) {
    std::ostringstream msg;
    msg << bad << " of " << n << " lines in the band hold NaN or Inf (first at " << d.frequency_hz[first_bad]
        << " Hz, longest run " << longest << " lines)";
    if (bad > options.max_nan_fraction * n || longest > options.max_nan_run)
      throw InputError(source, msg.str() + ": too many to skip; clean the data or narrow the band");
    d.warnings.push_back(source + ": " + msg.str() + "; those lines are skipped");
  }

  // Noise variance of H1 from coherence (Bendat & Piersol, algorithms.md §1.8):
  // var|dH|^2 ~ |H|^2 (1 - coh) / (n_avg coh). Needs n_avg >= 2 (one impact gives coh = 1).
  const bool have_coherence = static_cast<int>(frfs.coherence.size()) == n_ref;
  bool coherence_shapes_ok = have_coherence;
  for (int r = 0; r < n_ref && coherence_shapes_ok; ++r)
    coherence_shapes_ok = frfs.coherence[r].rows() == n_lines && frfs.coherence[r].cols() == n_out;
  if (coherence_shapes_ok) {
    const bool have_averages = frfs.averages.rows() == n_ref && frfs.averages.cols() == n_out;
    d.noise_variance = Eigen::MatrixXd::Constant(n, l * m, kNaN);
    for (int o = 0; o < l; ++o)
      for (int i = 0; i < m; ++i) {
        const int ref = d.transposed ? o : i, out = d.transposed ? i : o;
        const int n_avg = have_averages ? frfs.averages(ref, out) : 0;
        if (n_avg < 2) continue;
        for (int k = 0; k < n; ++k) {
          const double coh = frfs.coherence[ref](first + k, out);
          const std::complex<double> h = d.h(k, o * m + i);
          if (!(coh > 0.0 && coh <= 1.0) || d.line_weight[k] == 0.0) continue;
          d.noise_variance(k, o * m + i) = std::norm(h) * (1.0 - coh) / (n_avg * coh);
        }
      }
  }

  // Per-output 1/RMS weight (algorithms.md §2.2): a few large FRFs must not dominate.
  d.output_weight.resize(l);
  const double used = std::max(1.0, d.line_weight.sum());
  for (int o = 0; o < l; ++o) {
    const double ss = d.h.middleCols(o * m, m).squaredNorm() / (used * m);
    d.output_weight[o] = ss > 0.0 ? 1.0 / std::sqrt(ss) : 0.0;
    if (ss <= 0.0) d.warnings.push_back(source + ": output " + DofName(d.outputs[o]) + " is zero in the band");
  }
  return d;
}

std::vector<std::vector<int>> FitData::SetOutputs() const {
  std::map<int, std::vector<int>> sets;
  if (output_set.size() != outputs.size()) return {};
  for (size_t o = 0; o < outputs.size(); ++o) sets[output_set[o]].push_back(static_cast<int>(o));
  std::vector<std::vector<int>> out;
  for (auto& [id, list] : sets) out.push_back(std::move(list));
  return out;
}

FitData SubsetOutputs(const FitData& data, const std::vector<int>& outputs) {
  FitData d = data;
  const int m = data.ReferenceCount(), l = static_cast<int>(outputs.size());
  d.outputs.clear();
  d.output_set.clear();
  d.output_weight.resize(l);
  d.h.resize(data.LineCount(), l * m);
  if (data.noise_variance.size() > 0) d.noise_variance.resize(data.LineCount(), l * m);
  for (int k = 0; k < l; ++k) {
    const int o = outputs[static_cast<size_t>(k)];
    d.outputs.push_back(data.outputs[static_cast<size_t>(o)]);
    if (!data.output_set.empty()) d.output_set.push_back(data.output_set[static_cast<size_t>(o)]);
    d.output_weight[k] = data.output_weight[o];
    d.h.middleCols(k * m, m) = data.h.middleCols(o * m, m);
    if (data.noise_variance.size() > 0) d.noise_variance.middleCols(k * m, m) = data.noise_variance.middleCols(o * m, m);
  }
  return d;
}

}  // namespace ema::curvefit
