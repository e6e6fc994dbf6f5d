// The JSON of the pipeline's results, shared by `ema diagnose --json`, `ema run`'s diagnosis.json
// and the Python package (one codec per result; the formats/ codecs of the numerical results
// underneath). Each returns its JSON through formats::ValidUtf8: `dump()` never throws on a label,
// a target or a file name that is not UTF-8 (fuzz_json_results, docs/reliability.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "ema/pipeline/findings.hpp"
#include "ema/pipeline/run.hpp"
#include "ema/pipeline/stages.hpp"

namespace ema::pipeline {

/// `ema fit --json` (cli.md): formats::FitModesJson with the roving sets and hammer DOF of `frfs`.
nlohmann::json FitModesJson(const FitStage& stage, const FrfSet& frfs);

/// `ema fit --stabilisation`: formats::StabilisationJson with CMIF and MMIF of `frfs` (named
/// `source`) on the fit's band and lines.
nlohmann::json FitStabilisationJson(const FitStage& stage, const FrfSet& frfs, const std::string& source);

/// DIAG.json (cli.md "ema diagnose"): formats::DiagnosisJson, "modes" (the evidence per test mode
/// before and after, formats::DiagnosisModeRows), "findings" (FindingsJson) and, with force
/// levels, "nonlinearity" (`ema amplitude`'s JSON + "flagged").
nlohmann::json DiagnosisJson(const DiagnoseStage& stage);

/// Rank 1's effects as numbers: [{"kind", "target", "description" (diagnose::DescribeCandidate of
/// the effect alone, without a law's constants), "probability", "any": {"target", "probability"}
/// (the same kind on any member or point, when it has such a wildcard), "parameters": [{"name",
/// "value", "sigma"}] (SI units), "springs": [{"setup", "per_spring_n_per_m", "element_n_per_m"}]}].
nlohmann::json FindingsJson(const Findings& findings);

/// A run as JSON (Python's `ema.run`): {"project", "model", "tests": [{"name", "setup", "simulated"
/// (a planned test: {"plan", "truth", "records", "sets", "references", "impacts_per_reference",
/// "in_time", "undamped"}, else null), "frf"
/// (`ema frf --json`, null when the project gives FRFs), "modes" (`ema fit --json`), "select_hz",
/// "picked_by_hand", "correlation_before", "correlation_after" (`ema correlate --json`)}],
/// "diagnosis" (DIAG.json), "steps": [{"step", "test", "status" (done, failed, skipped, given),
/// "error"}], "problems": [{"test", "what", "error"}], "mean_agreement_pct_before", "mean_mac_before",
/// "mean_agreement_pct_after", "mean_mac_after"}; null where a stage gave nothing.
nlohmann::json RunResultJson(const RunResult& run);

}  // namespace ema::pipeline
