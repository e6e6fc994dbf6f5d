// The words the terminal and the HTML report both use for the same numbers: a fitted parameter
// in engineering units with its σ, what rank 1's effect does to a spring group's stiffness, a
// probability. One function each, so a value reads the same wherever it is shown.
#pragma once

#include <string>
#include <vector>

#include "ema/diagnose/diagnose.hpp"
#include "ema/formats/project_file.hpp"
#include "ema/pipeline/findings.hpp"

namespace ema::report {

/// printf "%.*g": the significant digits a reader needs.
std::string Significant(double value, int digits = 3);

/// "auto" (none) or the frequencies as `ema fit --select` takes them, each exactly (ExactNumberText).
std::string SelectText(const std::vector<double>& frequencies_hz);

/// A project test simulated from a plan (`plan =`): "simulated from plan.toml on variant.toml (a
/// rehearsal, not a measurement)"; "" for a measured test.
std::string RehearsalWords(const formats::ProjectTest& test);

/// What the agreement / MAC columns of a run's headline compare when its tests carried sensors
/// (`[[test]] sensor_mass`, kg per measured node; the largest of the run's): the model as stated,
/// without them, as a validation table does — while the diagnosis carries them, so its frequency
/// errors are smaller (the guideway sample: 99.1 % agreement beside a 0.0004 % error). A whole
/// sentence, "Agreement / MAC: …"; "" for 0.
std::string AgreementBasisWords(double sensor_mass_kg);

/// Whether `modes` (a candidate's, one per test mode) hold two tests of one setup, whose modes
/// must then be told apart by their test.
bool SeveralTestsOfOneSetup(const std::vector<diagnose::ModeComparison>& modes);

/// "mode 3", "mode 3 of stud-5um", with `name_test` "mode 3 of test 2" / "mode 3 of test 2
/// (stud-5um)".
std::string TestModeWords(const diagnose::ModeComparison& mode, bool name_test);

/// "12.3 %" of a probability in [0, 1].
std::string Percent(double probability);

/// A fitted parameter in engineering units with its 1σ: "Hertz contact E' = 168 ± 0.37 GPa
/// (R' = 1 mm)", "k = 2.8 ± 0.1 N/µm", "10.9 ± 2.6 g per point", "factor 0.31 ± 0.02",
/// "value = 5.1 ± 0.2 µm". `effect`: the effect it belongs to (a Hertz law's radius), or null.
std::string ParameterWords(const diagnose::FittedParameter& parameter, const model::Effect* effect);

/// An effect's fitted values and, for a spring target, its springs' stiffness per setup:
/// "k = 6.4 ± 0.3 N/µm; per spring of 'mounts' now: 2.80 N/µm at stud-5um (the element in series
/// alone: 21.8 N/µm at stud-5um)".
std::string EffectValuesWords(const pipeline::EffectFinding& finding);

/// Rank 1 the model as given and a reading its own error also explains
/// (pipeline::Findings::model_error_lookalike): "…, but the next reading, an added mass of 57.6 g
/// per point at all_points (13.9 %), brings the mean frequency error from 4.32 % to 0.92 %: these
/// data cannot tell it from an error of the model's own (3.5 % shared by all its frequencies), and
/// the priors order the two. If the model is known to be right overall … take that reading." The
/// sentence after "Diagnosis: no effect the model can try explains the mismatch beyond the
/// model's own error (the model as given ranks first, probability P)"; "" without such a reading.
std::string ModelErrorLookAlikeWords(const pipeline::Findings& findings);

}  // namespace ema::report
