#include "ema/acquisition/simulator.hpp"

#include "antialias.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>

namespace ema::acquisition {

namespace {

using cd = std::complex<double>;
using internal::DesignAntiAlias;
using internal::FilterDecimate;
using internal::kPi;

std::string Where(const Dof& dof) { return DofName(dof); }

}  // namespace

cd ModalTruth::ModalA(int r) const {
  if (!modal_a.empty()) return modal_a[r];
  return {0.0, 2.0 * poles[r].imag()};
}

int ModalTruth::IndexOf(const Dof& dof) const {
  for (size_t i = 0; i < dofs.size(); ++i)
    if (dofs[i] == dof) return static_cast<int>(i);
  throw std::invalid_argument("ModalTruth: DOF " + Where(dof) + " is not among the truth's DOFs");
}

ModalTruth ModalTruthFromRealModes(const std::vector<Dof>& dofs, const Eigen::MatrixXd& phi,
                                   const std::vector<double>& frequency_hz, const std::vector<double>& damping_ratio) {
  if (phi.rows() != static_cast<Eigen::Index>(dofs.size()) || phi.cols() != static_cast<Eigen::Index>(frequency_hz.size()) ||
      damping_ratio.size() != frequency_hz.size())
    throw std::invalid_argument("ModalTruthFromRealModes: inconsistent sizes");
  ModalTruth truth;
  truth.dofs = dofs;
  for (size_t r = 0; r < frequency_hz.size(); ++r) {
    truth.poles.push_back(FrequencyAndDampingToPole(frequency_hz[r], damping_ratio[r]));
    truth.shapes.push_back(phi.col(static_cast<Eigen::Index>(r)).cast<cd>());
  }
  return truth;
}

Eigen::MatrixXcd ReceptanceMatrix(const ModalTruth& truth, double w) {
  const int n = static_cast<int>(truth.dofs.size());
  Eigen::MatrixXcd alpha = Eigen::MatrixXcd::Zero(n, n);
  const cd jw(0.0, w);
  for (size_t r = 0; r < truth.poles.size(); ++r) {
    const cd a = truth.ModalA(static_cast<int>(r));
    const cd lambda = truth.poles[r];
    const Eigen::VectorXcd& psi = truth.shapes[r];
    const Eigen::MatrixXcd rr = psi * psi.transpose() / a;
    alpha += rr / (jw - lambda) + rr.conjugate() / (jw - std::conj(lambda));
  }
  return alpha;
}

Eigen::VectorXcd AnalyticFrfShifted(const ModalTruth& truth, const Dof& out, const Dof& ref,
                                    const Eigen::VectorXd& frequency_hz, double decay_rate, Quantity quantity) {
  const int i = truth.IndexOf(out);
  const int j = truth.IndexOf(ref);
  const int k = quantity == Quantity::kDisplacement ? 0 : quantity == Quantity::kVelocity ? 1 : 2;
  Eigen::VectorXcd h(frequency_hz.size());
  for (Eigen::Index f = 0; f < frequency_hz.size(); ++f) {
    // The windowed FRF is the FRF evaluated at s = jw + decay_rate: poles shifted left, and the
    // (jw)^k of a velocity/acceleration FRF becomes (jw + decay_rate)^k as well.
    const cd s(decay_rate, kTwoPi * frequency_hz[f]);
    cd alpha = 0.0;
    for (size_t r = 0; r < truth.poles.size(); ++r) {
      const cd a = truth.ModalA(static_cast<int>(r));
      const cd lambda = truth.poles[r];
      const cd res = truth.shapes[r][i] * truth.shapes[r][j] / a;
      alpha += res / (s - lambda) + std::conj(res) / (s - std::conj(lambda));
    }
    h[f] = alpha * std::pow(s, k);
  }
  return h;
}

Eigen::VectorXcd AnalyticFrf(const ModalTruth& truth, const Dof& out, const Dof& ref,
                             const Eigen::VectorXd& frequency_hz, Quantity quantity) {
  return AnalyticFrfShifted(truth, out, ref, frequency_hz, 0.0, quantity);
}

double ShortestSimulatedPulse(double sample_rate_hz) {
  return kFineStepsPerPulse / (sample_rate_hz * kMaxOversampling);
}

int EffectiveOversampling(double pulse_duration_s, double sample_rate_hz, int oversampling) {
  if (sample_rate_hz <= 0.0 || pulse_duration_s <= 0.0 || oversampling < 1)
    throw std::invalid_argument("the sample rate, the pulse duration and the oversampling must be > 0");
  const double needed = std::ceil(kFineStepsPerPulse / (pulse_duration_s * sample_rate_hz) - 1e-9);
  if (needed > kMaxOversampling) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "a hammer pulse of %.3g s is shorter than the simulator resolves at %.6g Hz: the shortest is %.3g s "
                  "(%d steps of a grid %d times finer than the samples)",
                  pulse_duration_s, sample_rate_hz, ShortestSimulatedPulse(sample_rate_hz), kFineStepsPerPulse,
                  kMaxOversampling);
    throw std::invalid_argument(text);
  }
  return std::max(oversampling, static_cast<int>(needed));
}

ImpactSignals SimulateImpact(const ModalTruth& truth, const Dof& ref, const std::vector<Dof>& responses,
                             const std::vector<std::pair<double, double>>& pulses, double pulse_duration_s,
                             double sample_rate_hz, int samples, Quantity quantity, int requested_oversampling) {
  if (sample_rate_hz <= 0.0 || samples <= 0 || pulse_duration_s <= 0.0 || requested_oversampling < 1)
    throw std::invalid_argument("SimulateImpact: sample rate, samples, pulse duration and oversampling must be > 0");
  // A pulse shorter than a few fine steps would be sampled at zero or one point: refine the grid.
  const int oversampling = EffectiveOversampling(pulse_duration_s, sample_rate_hz, requested_oversampling);
  const int iref = truth.IndexOf(ref);
  const std::vector<double> fir = DesignAntiAlias(oversampling);
  const int half = static_cast<int>(fir.size() / 2);
  const int n_fine = (samples - 1) * oversampling + 2 * half + 1;
  const double dtf = 1.0 / (sample_rate_hz * oversampling);
  auto fine_time = [&](int i) { return (i - half) * dtf; };
  const int order = quantity == Quantity::kDisplacement ? 0 : quantity == Quantity::kVelocity ? 1 : 2;
  const double tc = pulse_duration_s;
  const double omega_c = kPi / tc;

  // Force u(t) and its derivative on the fine grid.
  std::vector<double> u(n_fine, 0.0), du(n_fine, 0.0);
  for (const auto& [t0, peak] : pulses) {
    const int i_begin = std::max(0, static_cast<int>(std::ceil((t0) / dtf)) + half);
    for (int i = i_begin; i < n_fine; ++i) {
      const double tau = fine_time(i) - t0;
      if (tau > tc) break;
      if (tau < 0.0) continue;
      u[i] += peak * std::sin(omega_c * tau);
      du[i] += peak * omega_c * std::cos(omega_c * tau);
    }
  }

  // Per mode: G_r(t) = lambda^k q_r(t) (+ lambda u for acceleration); q_r in closed form (§7.3).
  const size_t n_modes = truth.poles.size();
  std::vector<std::vector<cd>> modal(n_modes);
  for (size_t r = 0; r < n_modes; ++r) {
    const cd lambda = truth.poles[r];
    std::vector<cd> q(n_fine, cd(0.0));
    const cd denom = lambda * lambda + omega_c * omega_c;
    const cd step = std::exp(lambda * dtf);
    for (const auto& [t0, peak] : pulses) {
      const cd k_after = peak * (std::exp(-lambda * tc) * omega_c + omega_c) / denom;  // sin(pi)=0, cos(pi)=-1
      int i = std::max(0, static_cast<int>(std::floor(t0 / dtf)) + half);
      for (; i < n_fine; ++i) {
        const double tau = fine_time(i) - t0;
        if (tau < 0.0) continue;
        if (tau > tc) break;
        q[i] += peak * (omega_c * std::exp(lambda * tau) - (lambda * std::sin(omega_c * tau) + omega_c * std::cos(omega_c * tau))) / denom;
      }
      // Free decay: recurrence on e^{lambda dtf}, re-anchored every 1024 steps against drift.
      cd z;
      for (int m = 0; i < n_fine; ++i, ++m) {
        if (m % 1024 == 0) z = k_after * std::exp(lambda * (fine_time(i) - t0));
        q[i] += z;
        z *= step;
      }
    }
    std::vector<cd>& g = modal[r];
    g.resize(n_fine);
    for (int i = 0; i < n_fine; ++i) {
      if (order == 0) g[i] = q[i];
      else if (order == 1) g[i] = lambda * q[i];
      else g[i] = lambda * lambda * q[i] + lambda * u[i];
    }
  }

  // The same FIR on every series (filtering is linear, so filtering modal series = filtering channels).
  ImpactSignals out;
  out.force = FilterDecimate(u, fir, oversampling, samples);
  std::vector<double> direct_dec;
  if (order == 1) direct_dec = FilterDecimate(u, fir, oversampling, samples);
  if (order == 2) direct_dec = FilterDecimate(du, fir, oversampling, samples);
  std::vector<std::vector<cd>> modal_dec(n_modes);
  for (size_t r = 0; r < n_modes; ++r) modal_dec[r] = FilterDecimate(modal[r], fir, oversampling, samples);

  for (const Dof& dof : responses) {
    const int io = truth.IndexOf(dof);
    std::vector<double> y(samples, 0.0);
    double direct = 0.0;  // sum over the pair of c_r: 0 for a complete real-mode set, kept for exactness
    for (size_t r = 0; r < n_modes; ++r) {
      const cd c = truth.shapes[r][io] * truth.shapes[r][iref] / truth.ModalA(static_cast<int>(r));
      direct += 2.0 * c.real();
      const std::vector<cd>& g = modal_dec[r];
      for (int n = 0; n < samples; ++n) y[n] += 2.0 * (c * g[n]).real();
    }
    if (order > 0)
      for (int n = 0; n < samples; ++n) y[n] += direct * direct_dec[n];
    out.responses.push_back(std::move(y));
  }
  return out;
}

std::vector<SimulatedSet> SimulateHammerTestSets(const std::vector<ModalTruth>& truth_per_set,
                                                 const HammerTestPlan& plan) {
  if (truth_per_set.empty()) throw std::invalid_argument("SimulateHammerTest: no modal truth");
  if (truth_per_set.size() != 1 && truth_per_set.size() != plan.roving_sets.size())
    throw std::invalid_argument("SimulateHammerTest: give one truth, or one per roving set");
  std::vector<ImpactFunction> impact;
  for (const ModalTruth& truth : truth_per_set)
    impact.push_back([&truth, &plan](const Dof& ref, const std::vector<Dof>& responses,
                                     const std::vector<std::pair<double, double>>& pulses) {
      return SimulateImpact(truth, ref, responses, pulses, plan.pulse_duration_s, plan.sample_rate_hz,
                            plan.samples_per_record, plan.response_quantity, plan.oversampling);
    });
  return SimulateHammerTestSetsWith(impact, plan);
}

std::vector<SimulatedSet> SimulateHammerTestSetsWith(const std::vector<ImpactFunction>& impact_per_set,
                                                     const HammerTestPlan& plan) {
  if (impact_per_set.empty()) throw std::invalid_argument("SimulateHammerTest: no structure to simulate");
  if (impact_per_set.size() != 1 && impact_per_set.size() != plan.roving_sets.size())
    throw std::invalid_argument("SimulateHammerTest: give one truth, or one per roving set");
  if (plan.references.empty() || plan.roving_sets.empty() || plan.impacts_per_reference < 1)
    throw std::invalid_argument("SimulateHammerTest: references, roving sets and impacts are required");
  std::mt19937_64 rng(plan.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double dt = 1.0 / plan.sample_rate_hz;
  const int n = plan.samples_per_record;
  const int pre = static_cast<int>(std::lround(plan.pre_trigger_fraction * n));
  // Place the pulse so its rising edge crosses 10 % of the peak near the pre-trigger sample.
  const double rise_to_trigger = plan.pulse_duration_s * std::asin(0.1) / kPi;

  auto add_noise = [&](std::vector<double>& x, double relative) {
    if (relative <= 0.0) return;
    double level = 0.0;
    if (plan.noise_relative_to_peak) {
      for (double v : x) level = std::max(level, std::abs(v));
    } else {
      double ss = 0.0;
      for (double v : x) ss += v * v;
      level = std::sqrt(ss / x.size());
    }
    const double sigma = relative * level;
    for (double& v : x) v += sigma * normal(rng);
  };
  auto clip = [](std::vector<double>& x, double fs) {
    for (double& v : x) v = std::clamp(v, -fs, fs);
  };

  const std::vector<double> levels = plan.force_levels_n.empty() ? std::vector<double>{plan.force_peak_n}
                                                                  : plan.force_levels_n;
  const int impacts = plan.impacts_per_reference * static_cast<int>(levels.size());
  std::vector<SimulatedSet> sets(plan.roving_sets.size());
  for (size_t s = 0; s < plan.roving_sets.size(); ++s) {
    const ImpactFunction& simulate = impact_per_set.size() == 1 ? impact_per_set[0] : impact_per_set[s];
    const std::vector<Dof>& responses = plan.roving_sets[s];
    for (size_t ir = 0; ir < plan.references.size(); ++ir) {
      const Dof& ref = plan.references[ir];
      for (int k = 1; k <= impacts; ++k) {
        const double level = levels[static_cast<size_t>((k - 1) / plan.impacts_per_reference)];
        const double peak = level * (1.0 + plan.force_spread * uniform(rng));
        const double jitter = plan.trigger_jitter ? unit(rng) * dt : 0.0;
        const double t0 = pre * dt - rise_to_trigger + jitter;
        std::vector<std::pair<double, double>> pulses{{t0, peak}};
        for (const DoubleHit& d : plan.double_hits)
          if (d.set == static_cast<int>(s) && d.reference == static_cast<int>(ir) && d.impact == k)
            pulses.push_back({t0 + d.delay_s, peak * d.ratio});
        ImpactSignals sig = simulate(ref, responses, pulses);
        const std::string where = "simulated set " + std::to_string(s + 1) + ", reference " + DofName(ref) +
                                  ", impact " + std::to_string(k);
        TimeRecord force;
        force.channel = ref;
        force.reference = ref;
        force.impact = k;
        force.quantity = Quantity::kForce;
        force.sample_interval_s = dt;
        force.samples = std::move(sig.force);
        force.full_scale = plan.force_full_scale;
        force.unit = "N";
        add_noise(force.samples, plan.force_noise);
        for (const Clipping& c : plan.clipping)
          if (c.force && c.set == static_cast<int>(s) && c.reference == static_cast<int>(ir) && c.impact == k) {
            clip(force.samples, c.full_scale);
            force.full_scale = c.full_scale;
          }
        force.origin = where + ", force " + DofName(ref);
        sets[s].records.push_back(std::move(force));
        for (size_t o = 0; o < responses.size(); ++o) {
          TimeRecord rec;
          rec.channel = responses[o];
          rec.reference = ref;
          rec.impact = k;
          rec.quantity = plan.response_quantity;
          rec.sample_interval_s = dt;
          rec.samples = std::move(sig.responses[o]);
          rec.full_scale = plan.response_full_scale;
          rec.unit = plan.response_quantity == Quantity::kDisplacement ? "m"
                     : plan.response_quantity == Quantity::kVelocity ? "m/s"
                                                                      : "m/s^2";
          add_noise(rec.samples, plan.response_noise);
          for (const Clipping& c : plan.clipping)
            if (!c.force && c.set == static_cast<int>(s) && c.reference == static_cast<int>(ir) && c.impact == k &&
                c.channel == responses[o]) {
              clip(rec.samples, c.full_scale);
              rec.full_scale = c.full_scale;
            }
          rec.origin = where + ", response " + DofName(responses[o]);
          sets[s].records.push_back(std::move(rec));
        }
      }
    }
  }
  return sets;
}

namespace {

std::vector<TimeRecord> Flatten(std::vector<SimulatedSet> sets, const HammerTestPlan& plan) {
  const int impacts = plan.impacts_per_reference * static_cast<int>(std::max<size_t>(1, plan.force_levels_n.size()));
  std::vector<TimeRecord> all;
  for (size_t s = 0; s < sets.size(); ++s)
    for (TimeRecord& r : sets[s].records) {
      if (plan.number_impacts_across_sets) r.impact += static_cast<int>(s) * impacts;
      all.push_back(std::move(r));
    }
  return all;
}

}  // namespace

std::vector<TimeRecord> SimulateHammerTest(const std::vector<ModalTruth>& truth_per_set, const HammerTestPlan& plan) {
  return Flatten(SimulateHammerTestSets(truth_per_set, plan), plan);
}

std::vector<TimeRecord> SimulateHammerTestWith(const std::vector<ImpactFunction>& impact_per_set,
                                               const HammerTestPlan& plan) {
  return Flatten(SimulateHammerTestSetsWith(impact_per_set, plan), plan);
}

}  // namespace ema::acquisition
