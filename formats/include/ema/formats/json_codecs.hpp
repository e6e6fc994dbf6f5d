// One JSON codec per core result type, used by every command that writes it (cli.md layouts):
// the mode set (`ema fit --json`, `ema model --json`), the FRF summary (`ema frf --json`), the
// stabilisation diagram (`ema fit --stabilisation`), the correlation (`ema correlate --json`) and
// the diagnosis (`ema diagnose --json`). The report and the run summary draw from the same JSON.
// JSON numbers cannot be NaN: a value that is not finite is written as null.
// JSON text is UTF-8: every string and key the codecs write passes through JsonText (a label or
// file name in another encoding is read as Latin-1, as the readers do), so dump() never throws.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "ema/core/types.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/curvefit/fit.hpp"
#include "ema/diagnose/diagnose.hpp"
#include "ema/frf/hammer_frf.hpp"
#include "ema/model/solve.hpp"

namespace ema::formats {

/// `value` as a JSON number, or null when it is not finite.
nlohmann::json NumberOrNull(double value);

/// [re, im].
nlohmann::json ComplexJson(std::complex<double> value);

/// `text` as JSON can carry it: unchanged when it is valid UTF-8 (RFC 3629, what nlohmann's
/// dump() checks: no overlong forms, no surrogates, nothing above U+10FFFF), else every byte
/// read as Latin-1 and converted (what the UFF reader does with "m/s\xB2"); NUL stays (\u0000).
std::string JsonText(std::string_view text);

/// `j` with every string value and object key passed through JsonText. Each codec below that
/// writes text returns its JSON through it, so `dump()` of any codec's result never throws
/// nlohmann's type_error 316 (invalid UTF-8), whatever bytes the labels hold.
nlohmann::json ValidUtf8(nlohmann::json j);

/// The FRF summary of `ema frf --json`: {"frfs": [{response/reference node and dir, averages,
/// rejected}], estimator, window_decay_rate, roving_hammer, impacts, rejected_impacts, lines,
/// frequency_min_hz, frequency_max_hz, notes}.
nlohmann::json FrfSummaryJson(const frf::FrfResult& result);

/// One mode of a mode set, every field either writer gives (the union, so every consumer of
/// `ema fit --json` and `ema model --json` finds its keys): frequency_hz, damping_ratio, their
/// σ, mpc, mpd_deg, mcf, pole, spreads, unit_modal_mass, participation and the shape as
/// [{"node", "dir", "value", "std"?}].
nlohmann::json ModeJson(const ModeSet& set, std::size_t mode);

/// {"modes": [ModeJson...]} of a whole set.
nlohmann::json ModeSetJson(const ModeSet& set);

/// `ema fit --json`: ModeSetJson of the fitted modes plus the fit's own keys (order,
/// cluster_orders per mode, synthesis_error, reciprocity_transposed, dropped, refinement,
/// modal_model).
nlohmann::json FitModesJson(const curvefit::FitResult& fit, curvefit::RefineMethod refine);

/// The fitted modal model (curvefit.md "modal_model"): poles, residues per FRF in the measured
/// orientation, residual terms, FRF type and band.
/// The roving sets of a test as `ema fit --json` records them beside its modes: {"roving_sets":
/// [[node, ...] per set], "reference": {"node", "dir"}} (each key only when known) — what the
/// diagnosis needs to load each set's sensors where and while it was measured (cli.md, added turn 3).
nlohmann::json TestSetsJson(const FrfSet& frfs);

/// Reads what TestSetsJson wrote from a modes JSON (`ema fit --json` or another tool's file in its
/// layout); false (outputs untouched) when it holds no roving sets.
bool ReadTestSets(const nlohmann::json& modes_json, std::vector<std::vector<int>>* roving_sets, Dof* reference);

nlohmann::json ModalModelJson(const curvefit::ModalModel& model);

/// `ema fit --stabilisation` (without the CMIF/MMIF keys).
nlohmann::json StabilisationJson(const curvefit::FitResult& fit, const curvefit::StabilityOptions& stability);

/// `ema correlate --json`: pairs, unpaired modes, summary, COMAC and the MAC matrix (rows: test
/// modes, columns: model modes).
nlohmann::json CorrelationJson(const correlation::CorrelationResult& result, const ModeSet& test, const ModeSet& model);

/// `ema model --json`: the model's name, the setup, ModeSetJson of its modes, rigid-body
/// frequencies, the springs' operating states and the energy shares.
nlohmann::json ModelSolutionJson(const model::Model& model, const model::Solution& solution, const std::string& setup);

/// One [[effect]] of a candidate: kind, target, parameters, law (TOML inline table).
nlohmann::json EffectJson(const model::Effect& effect);

/// The model's own error inferred with a reading (cli.md "added turn 4" `model_error`):
/// frequency_rel, shape, frequency_common_rel, dominates.
nlohmann::json ModelErrorJson(const diagnose::ModelError& error);

/// `ema diagnose --json` without "modes" and "nonlinearity" (DiagnosisModeRows; the amplitude
/// analysis): baseline, candidates, criterion, the effective options, counts, explanation,
/// effect probabilities and the steps.
nlohmann::json DiagnosisJson(const diagnose::Diagnosis& diagnosis, const diagnose::DiagnoseOptions& options);

/// The "modes" rows of `ema diagnose --json`: every test mode against the baseline and rank 1.
nlohmann::json DiagnosisModeRows(const diagnose::Candidate& before, const diagnose::Candidate& after);

}  // namespace ema::formats
