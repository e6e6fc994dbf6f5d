#include "ema/pipeline/stages.hpp"

#include <utility>

#include "ema/acquisition/hammer_measurement.hpp"
#include "ema/core/error.hpp"
#include "ema/formats/io.hpp"

namespace ema::pipeline {

namespace {

// Why a fit found no mode (exit 1, nothing written): said in terms of the options to change.
std::string NoModeReason(const curvefit::FitResult& fit, const curvefit::FitOptions& options) {
  if (options.method == curvefit::FitMethod::kPeak) return "no mode found: no resonance peak in the band (try --band)";
  const int orders = fit.diagram.order_max;
  std::string why = "no mode found: no pole stayed stable over the PolyMAX orders " + std::to_string(fit.diagram.order_min) +
                    ".." + std::to_string(orders);
  if (orders < 4) why += " (--order-max " + std::to_string(orders) + " is too low: a stable pole must repeat over several orders)";
  return why + "; try a higher --order-max, another --band" + (options.select_frequencies_hz.empty() ? " or --select F1,F2,..." : "");
}

}  // namespace

FrfStage EstimateFrfs(const std::vector<std::string>& time_files, const frf::FrfOptions& options, bool binary,
                      const ProgressCallback& progress) {
  std::vector<acquisition::RecordSet> sets;
  for (const std::string& path : time_files) {
    for (const auto& s : sets)
      if (s.name == path) throw UsageError("file given twice: " + path);
    sets.push_back({path, formats::ReadTimeRecords(path)});
  }
  return EstimateFrfs(std::move(sets), options, binary, progress);
}

FrfStage EstimateFrfs(std::vector<acquisition::RecordSet> sets, const frf::FrfOptions& options, bool binary,
                      const ProgressCallback& progress) {
  FrfStage stage;
  stage.file_count = static_cast<int>(sets.size());
  const acquisition::HammerMeasurement test = acquisition::AssembleHammerMeasurement(std::move(sets));
  stage.result = frf::EstimateFrfs(test, options, progress);
  formats::WriteOptions stored_as;
  stored_as.binary = binary;
  stage.stored = formats::StoredFrfSet(stage.result.frfs, stored_as);
  return stage;
}

FitStage FitModes(const FrfSet& frfs, const curvefit::FitOptions& options, const std::string& source,
                  const std::string& modes_path, const ProgressCallback& progress) {
  FitStage stage;
  stage.options = options;
  stage.fit = curvefit::Fit(frfs, options, source, progress);  // its errors name `source`
  if (stage.fit.modes.modes.empty()) throw InputError(source, NoModeReason(stage.fit, options));
  stage.fit.modes.source = source;
  stage.stored_modes = formats::StoredModeSet(stage.fit.modes, modes_path);
  return stage;
}

DiagnoseStage DiagnoseModel(const model::Model& model, const std::vector<diagnose::SetupModes>& tests,
                            const diagnose::DiagnoseOptions& options, std::vector<correlation::AmplitudeLevel> force_levels,
                            const ProgressCallback& progress) {
  DiagnoseStage stage;
  stage.options = options;
  diagnose::DiagnoseOptions with_progress = options;
  if (progress) with_progress.progress = progress;
  stage.diagnosis = diagnose::Diagnose(model, tests, with_progress);
  stage.findings = FindingsOf(stage.diagnosis, model);
  const diagnose::Candidate& first = stage.diagnosis.candidates.front();
  stage.updated = model;
  stage.updated.effects.insert(stage.updated.effects.end(), first.effects.begin(), first.effects.end());
  if (!force_levels.empty())
    stage.nonlinearity = correlation::AnalyseAmplitude(std::move(force_levels), correlation::LevelKind::kPeakForce);
  return stage;
}

}  // namespace ema::pipeline
