#!/usr/bin/env python3
"""The diagnosis benchmark: how often is `ema diagnose` right? (docs/diagnosis-benchmark.md)

  bench.py run    --ema EMA --cases 0:200 [--jobs N] [--seed S] [--work DIR]
  bench.py gather --work DIR [--doc docs/diagnosis-benchmark.md --svg docs/img/diagnosis-calibration.svg]
  bench.py check  --ema EMA --cases 0:21 --floor 0.9 [--work DIR]      (the CI test)
  bench.py run    --ema EMA --family form --cases 0:60 [--jobs N]       (the model-form family)
  bench.py run    --ema EMA --family form-rich --cases 0:120              (the same cases, errors no effect can say)
  bench.py run    --ema EMA --cases 0:200 --replan                        (look-alikes: the follow-up test ema plan makes)
  bench.py run    --ema EMA --family lookalike --cases 0:10 --replan      (mirror pairs tied by the first test)
  bench.py run    --ema EMA --keep ... then --reuse --diagnose-arg=--shape-residual --diagnose-arg=mac
                  (the same simulated tests diagnosed with other options)

`run` generates each case (cases.py), puts it through the real chain with the built `ema`
(simulate -> frf -> fit -> diagnose -> correlate) and writes WORK/scores/case-NNNN.json; cases
are independent, so one index range per scheduler task works as well as --jobs on one machine.
`gather` merges the per-case score files into WORK/scores.json, prints the tables and, with
--doc, replaces the generated section of the markdown page and writes the calibration SVG.
Standard library only.
"""

import argparse
import concurrent.futures
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import tomllib
import zlib

sys.dont_write_bytecode = True  # no __pycache__ in the source tree (CI runs it from there)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases  # noqa: E402
import report  # noqa: E402

DEFAULT_SEED = 2026
PARAMETER_TOLERANCE = 0.10   # the "parameters within 10 %"
AGREEMENT_GOAL = 99.0        # mean agreement (%) of the updated model, as in the acceptance tests


class StepFailed(Exception):
    pass


def run_ema(ema, args, folder, log):
    """Runs `ema ARGS` in folder; stdout+stderr to folder/log. Raises StepFailed on exit != 0."""
    start = time.monotonic()
    with open(os.path.join(folder, log), "w") as out:
        rc = subprocess.call([ema] + args, cwd=folder, stdout=out, stderr=subprocess.STDOUT)
    if rc != 0:
        with open(os.path.join(folder, log)) as f:
            tail = f.read()[-800:]
        raise StepFailed(f"ema {args[0]} exited {rc}: {tail.strip()}")
    return time.monotonic() - start


def read_json(path):
    with open(path) as f:
        return json.load(f)


VISIBLE_SHIFT_PCT = 0.5
MAX_ATTEMPTS = 8


def choose_band(frequencies, family, damping, single_setup=True):
    """Band, sample rate and record length of the test from the truth's modes: the modes a
    hammer test of this article would be fitted over (rigid articles: below 2 kHz; the beam: its
    first six), the band edges half-way to the next mode, and a frequency line spacing of at
    most the lowest mode's damping times its frequency (two lines in its half-power band).

    The upper edge ends in a quiet stretch of the spectrum, as an engineer would put it: while
    the next mode lies less than 15 % above the last one, the last one is left out too (one
    setup; two setups' modes interleave and keep the plain rule). A band cut half-way between
    two modes 6 % apart leaves the outside one's peak three half-power bandwidths from the edge;
    its residue then leaks into the last fitted mode's shape (MPC 0.5), which pairs with the
    wrong model mode (case 87 of seed 2026 before this rule).

    The sample rate is the lowest power of two from 256 Hz above 2.6 times the band's top, and the
    hammer tip is matched to the band: a half-sine contact time of 0.25 / top (at least 0.3 ms),
    whose force spectrum falls by 0.5 dB at the top and has its first zero at six times it. A hard
    0.3 ms tip on a 100 Hz footbridge band spends most of the response's rms on modes far above the
    band, and noise set against that rms buried the two lowest modes (cases 139 and 199 of seed
    2026 before 2026-11-26: both missed by the fit, reduced chi-square 46).
    Returns (lo, hi, sample rate, samples, modes in the band, contact time)."""
    f = sorted(x for x in frequencies if x > 1.0)
    keep = ([x for x in f if x < 2000.0] if family not in ("fe", "parts", cases.LOOKALIKE_FAMILY) + cases.FORM_FAMILIES
            else [x for x in f if x < 2500.0][:8 if family in ("parts", cases.LOOKALIKE_FAMILY) else 6])
    if len(keep) < 2:
        keep = f[:2]
    lo = 0.75 * keep[0]
    while single_setup and len(keep) > 2:
        above = [x for x in f if x > keep[-1]]
        if not above or above[0] >= 1.15 * keep[-1]:
            break
        keep.pop()
    nxt = [x for x in f if x > keep[-1]]
    hi = min(1.1 * keep[-1], 0.5 * (keep[-1] + nxt[0])) if nxt else 1.15 * keep[-1]
    fs = 256
    while fs < 2.6 * hi:
        fs *= 2
    spacing = damping * keep[0]
    samples = 4096
    while fs / samples > spacing and samples < 32768:
        samples *= 2
    pulse = max(0.3e-3, 0.25 / hi)
    return lo, hi, fs, samples, len(keep), pulse


def effect_set(candidate):
    return sorted((e["kind"], e["target"]) for e in candidate.get("effects", []))


def fitted_value(candidate, kind, target, name):
    """The fitted parameter `name` of the effect (kind, target) of a candidate."""
    for e in candidate.get("effects", []):
        if e["kind"] == kind and e["target"] == target:
            if kind == "series_compliance":
                # The law as TOML text: a linear layer's k; a Hertz contact has none to compare.
                found = re.search(r"linear\s*=\s*\{\s*k\s*=\s*([-+0-9.eE]+)", str(e.get("law", "")))
                return float(found.group(1)) if found else None
            return e.get("parameters", {}).get(name, e.get(name))
    return None


def score(case, diag, corr_after, corr_before, times):
    truth = sorted((e["kind"], e["target"]) for e in case["truth"])
    cands = diag["candidates"]
    first = cands[0]
    rank1 = effect_set(first)
    right = rank1 == truth
    truth_rank, p_truth = None, 0.0
    for c in cands:
        if effect_set(c) == truth:
            truth_rank, p_truth = c["rank"], c.get("probability", 0.0)
            break
    # The diagnosis itself says which candidates the data cannot tell apart from rank 1 (residuals
    # nearly parallel, costs within 2): rank 1 "tied with the truth" when the truth is one of them.
    tied = False
    for label in first.get("tied_with", []):
        parts = []
        for part in label.split(" + "):
            m = re.match(r"^(\w+)(?: \([^)]*\))? of '(.*)'$", part)
            parts.append((m.group(1), m.group(2)) if m else (part, ""))
        tied = tied or sorted(parts) == truth
    params = []
    for e in case["truth"]:
        for name, value in e["parameters"].items():
            got = fitted_value(first, e["kind"], e["target"], name) if right else None
            params.append({"effect": f'{e["kind"]}:{e["target"]}', "name": name, "truth": value, "fitted": got,
                           "rel_error": (abs(got / value - 1.0) if got else None)})
    params_ok = right and all(p["rel_error"] is not None and p["rel_error"] <= PARAMETER_TOLERANCE for p in params)
    agreement = sum(c["summary"]["mean_agreement_pct"] for c in corr_after) / len(corr_after)
    before = sum(c["summary"]["mean_agreement_pct"] for c in corr_before) / len(corr_before)
    return {
        "index": case["index"], "seed": case["seed"], "family": case["family"], "noise": case["noise"],
        "truth": case["truth"], "n_effects": len(case["truth"]),
        "kinds": sorted({e["kind"] for e in case["truth"]}) or ["none"],
        "member": any("/" in e["target"] or e["target"].startswith("points:") for e in case["truth"]),
        "rank1": {"kind": first["kind"], "target": first["target"], "probability": first.get("probability"),
                  "parameters": first.get("parameters", {})},
        "right": right, "right_or_tied": right or tied, "parameters": params, "parameters_ok": params_ok,
        "truth_rank": truth_rank, "p_truth": p_truth, "p_rank1": first.get("probability", 0.0),
        "agreement_before_pct": before, "agreement_after_pct": agreement,
        "agreement_ok": agreement >= AGREEMENT_GOAL,
        "test_modes": diag.get("test_modes"), "baseline_error_pct": diag["baseline"]["mean_abs_frequency_error_pct"],
        "explanation": diag.get("explanation", ""), "seconds": times,
        "runner_up": ({"kind": cands[1]["kind"], "target": cands[1]["target"],
                       "probability": cands[1].get("probability")} if len(cands) > 1 else None),
    }


def model_frequencies(ema, folder, model, setup, name):
    """The model's frequencies (ema model) for one setup, ascending."""
    tag = setup or "test"
    run_ema(ema, ["model", model, "-o", f"{name}-{tag}.unv", "--json", f"{name}-{tag}.json"]
            + (["--setup", setup] if setup else []), folder, f"model-{name}-{tag}.log")
    return sorted(m["frequency_hz"] for m in read_json(os.path.join(folder, f"{name}-{tag}.json"))["modes"])


def effect_shifts(ema, case, folder, lo, hi):
    """Per hidden effect: the largest relative shift (%) it alone gives a mode of the test band,
    against the nominal model (modes paired in frequency order, as small changes keep it)."""
    nominal = {s: model_frequencies(ema, folder, "nominal.toml", s, "nominal") for s in case["setups"]}
    shifts = []
    for k, block in enumerate(case["effect_blocks"]):
        with open(os.path.join(folder, f"effect-{k}.toml"), "w") as f:
            f.write(case["files"]["nominal.toml"] + "\n" + block)
        worst = 0.0
        for s in case["setups"]:
            alone = model_frequencies(ema, folder, f"effect-{k}.toml", s, f"effect-{k}")
            worst = max([worst] + [100.0 * abs(a / b - 1.0) for a, b in zip(alone, nominal[s]) if lo <= b <= hi])
        shifts.append(worst)
    return shifts


def draw_visible_case(ema, index, seed, folder, family=None):
    """The case, drawn again (attempt 1, 2, ...) while one of its hidden effects moves no mode of
    the test band by VISIBLE_SHIFT_PCT: such an effect is below what the test's frequencies show
    (five times the diagnosis' frequency floor of 0.1 %), and no diagnosis can be scored on it.
    Returns the case, the band and the draws that were set aside."""
    set_aside = []
    # --reuse: the kept tests (modes-*.unv/.json) survive the case being written afresh.
    kept = {}
    if REUSE_TESTS and os.path.isdir(folder):
        for name in os.listdir(folder):
            if name.startswith("modes-") and name.endswith((".unv", ".json")):
                with open(os.path.join(folder, name), "rb") as f:
                    kept[name] = f.read()
    for attempt in range(MAX_ATTEMPTS):
        case = cases.make_case(index, seed, attempt, family)
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        for name, data in kept.items():
            with open(os.path.join(folder, name), "wb") as f:
                f.write(data)
        cases.write_case(case, folder)
        # The test's band from the truth's own modes (an engineer picks it from the FRFs).
        freqs = []
        for s in case["setups"]:
            freqs += model_frequencies(ema, folder, "truth.toml", s, "truth")
        damping = float(case["files"]["nominal.toml"].split("ratio = ", 1)[1].split("\n", 1)[0])
        band = choose_band(freqs, case["family"], damping, len(case["setups"]) == 1)
        shifts = effect_shifts(ema, case, folder, band[0], band[1])
        with open(os.path.join(folder, "case.json"), "w") as f:
            json.dump({"attempt": attempt, "truth": case["truth"]}, f)
        if all(x >= VISIBLE_SHIFT_PCT for x in shifts) or attempt == MAX_ATTEMPTS - 1:
            return case, band, shifts, set_aside
        set_aside.append({"attempt": attempt, "truth": [f"{e['kind']} {e['target']}" for e in case["truth"]],
                          "max_shift_pct": [round(x, 3) for x in shifts]})


def all_points_mass(candidate):
    """The mass per point of a candidate's added mass on all points (kg), or None."""
    for e in candidate.get("effects", []):
        if e["kind"] == "added_mass" and e["target"] == "all_points":
            return e.get("parameters", {}).get("mass")
    return None


# A spread mass named by rank 1 is that spread when its size is within this factor of the truth's
# (the element mass scatter, half the stiffness scatter, moves it a little either way).
SPREAD_FACTOR = 2.0


def form_scores(ema, case, folder, diag, lo, hi, shifts):
    """The model-form family's own scores (docs/diagnosis-benchmark.md "Model-form error"): the
    model error's size (rms relative frequency error of the form-only truth against the nominal
    model over the band), whether the hidden effects stand clearly above it (each moves a mode of
    the band by ≥ 3× that rms), whether a discrete effect was invented (none hidden, rank 1 holds
    one), and whether "not adequate" was said where the model error exceeds the test's noise
    (rms ≥ 3× the diagnosis' 0.1 % frequency floor).

    The form truth's non-structural mass spread is the one part of its error the vocabulary can
    say: an added mass on all points (the FE beam has a test point at every node) is that spread,
    lumped. Rank 1 naming it at its size (the all-points mass beyond any hidden one, within
    SPREAD_FACTOR of the spread's kg) is no invention: `right_spread` counts rank 1 right when it
    is the truth plus that named spread, and the model error it must call inadequate is then what
    it leaves — the form-only truth against the nominal model with the named spread added."""
    s = case["setups"][0]
    nominal = model_frequencies(ema, folder, "nominal.toml", s, "nominal")
    form_only = model_frequencies(ema, folder, "form-only.toml", s, "form-only")

    def rms_against(reference):
        pairs = [(a, b) for a, b in zip(form_only, reference) if lo <= b <= hi]
        return math.sqrt(sum((a / b - 1.0) ** 2 for a, b in pairs) / max(1, len(pairs)))

    rms = rms_against(nominal)
    first = diag["candidates"][0]
    clear = bool(case["truth"]) and all(x >= 3.0 * 100.0 * rms for x in shifts)
    truth = sorted((e["kind"], e["target"]) for e in case["truth"])
    # The spread rank 1 names: its all-points mass beyond the hidden one, in kg over every point.
    with open(os.path.join(folder, "nominal.toml"), "rb") as f:
        points = len(tomllib.load(f).get("point", []))
    hidden_per_point = sum(e["parameters"]["mass"] for e in case["truth"]
                           if e["kind"] == "added_mass" and e["target"] == "all_points")
    per_point = all_points_mass(first)
    spread_kg = case["form_error"]["nonstructural_mass_kg"]
    named_kg = (per_point - hidden_per_point) * points if per_point is not None else None
    spread_named = (named_kg is not None and spread_kg > 0.0 and named_kg > 0.0
                    and 1.0 / SPREAD_FACTOR <= named_kg / spread_kg <= SPREAD_FACTOR)
    with_spread = sorted(set(truth) | {("added_mass", "all_points")})
    right_spread = effect_set(first) == truth or (spread_named and effect_set(first) == with_spread)
    left = rms
    if spread_named:
        with open(os.path.join(folder, "spread-named.toml"), "w") as f:
            f.write(case["files"]["nominal.toml"] + "\n[[effect]]\nkind = \"added_mass\"\n"
                    f"target = \"all_points\"\nmass = {named_kg / points!r}\n")
        left = rms_against(model_frequencies(ema, folder, "spread-named.toml", s, "spread-named"))
    discrete = [e for e in first.get("effects", []) if e["target"] != "all_points" or not spread_named]
    return {"form_error": case["form_error"], "form_error_rms_pct": 100.0 * rms,
            "effects_clear": clear, "invented": (not case["truth"]) and first["kind"] != "none",
            "form_exceeds_noise": rms >= 3.0 * 1e-3, "said_inadequate": not first.get("noise_consistent", True),
            "model_error_rank1": first.get("model_error"),
            # Rank 1 naming the spread at its size: scored as the truth where the rest is, the error left
            # then the one "not adequate" is owed for (see the docstring).
            "spread_named": spread_named, "spread_named_kg": named_kg, "spread_kg": spread_kg,
            "right_spread": right_spread,
            "invented_spread": (not case["truth"]) and bool(discrete) and first["kind"] != "none",
            "form_left_rms_pct": 100.0 * left, "form_left_exceeds_noise": left >= 3.0 * 1e-3}


def look_alikes(diag):
    """Rank 1 and the readings within a factor 20 of its probability (the first screen's rule,
    docs/plan.md): what `ema plan --candidates` separates. "none" left out."""
    cands = diag["candidates"]
    p1 = cands[0].get("probability") or 0.0
    return [c for c in cands if c["kind"] != "none" and c.get("effects")
            and (c["rank"] == 1 or (c.get("probability") or 0.0) >= max(0.05 * p1, 0.001))]


def test_dof_count(folder):
    """The test DOFs nominal.toml offers a plan: three per point of a body, and per point on an FE
    node the translations (ux, uy, uz or 1, 2, 3) the FE model has there — one on the FE beams,
    whose nodes carry uz and ry (counting three there asked `ema plan` for DOFs the model does not
    have), three on the look-alike family's frames (six DOFs per node, numbered)."""
    with open(os.path.join(folder, "nominal.toml"), "rb") as f:
        model = tomllib.load(f)
    translations = {}
    dofs_file = model.get("fe", {}).get("dofs")
    if dofs_file:
        with open(os.path.join(folder, dofs_file)) as f:
            for line in f.read().splitlines()[1:]:
                node, dof = (x.strip() for x in line.split(",")[:2])
                if dof in ("ux", "uy", "uz", "1", "2", "3"):  # the model file's names or numbers 1..6
                    translations[int(node)] = translations.get(int(node), 0) + 1
    return sum(translations.get(p["node"], 0) if "node" in p else 3 for p in model.get("point", []))


def replan(ema, case, folder, tests, lo, hi, times, index):
    """The follow-up test of a diagnosis that left look-alikes (issue 40): `ema plan --candidates
    diag.json --keep <the plan>` adds one roving set where the readings differ most, the truth is
    tested again with the extended plan (a new noise seed), fitted and diagnosed. Single-setup
    cases only. Returns what the replanned diagnosis says, or None when rank 1 had no look-alike."""
    diag = read_json(os.path.join(folder, "diag.json"))
    readings = look_alikes(diag)
    if len(case["setups"]) != 1 or len(readings) < 2:
        return None
    s, _ = tests[0]
    tag = s or "test"
    kept = f"plan-{tag}.toml"
    with open(os.path.join(folder, kept), "rb") as f:
        kept_plan = tomllib.load(f)
    sets = [st["sensors"] for st in kept_plan["set"]]
    # The follow-up set uses the first test's sensors: `ema plan` gives a set it adds --sensor-mass
    # (default 0), not the kept plan's.
    sensor_mass = kept_plan.get("plan", {}).get("sensor_mass", 0.0)
    candidates = test_dof_count(folder)
    free = candidates - len({x for st in sets for x in st})
    per_set = min(REPLAN_SENSORS or (len(sets[0]) if sets else 8), free)
    if per_set < 1:
        return {"readings": [f"{c['kind']} on {c['target']}" for c in readings], "skipped": "every DOF already measured"}
    args = ["plan", "nominal.toml", "--candidates", "diag.json", "--keep", kept, "--sensors", str(per_set),
            "--band", f"{lo:.3f}:{hi:.3f}", "--sensor-mass", repr(sensor_mass), "-o", "replan.toml", "--json", "replan.json"]
    times["replan"] = run_ema(ema, args, folder, "replan.log")
    with open(os.path.join(folder, "replan.toml")) as f:
        text = f.read()
    text = re.sub(r"(?m)^seed = .*$", f"seed = {1000 * index + 77}", text)
    with open(os.path.join(folder, "replan.toml"), "w") as f:
        f.write(text)
    sflag = ["--setup", s] if s else []
    # --replan-together: the first test and the follow-up diagnosed as two tests of the one setup.
    diagnosed = ([tests[0][1]] if REPLAN_TOGETHER else []) + ["modes-replan.unv"]
    test_args = [a for modes in diagnosed for a in ("--test", f"{s}={modes}" if s else modes)]
    for step, args in (("simulate", ["simulate", "simulate.toml", "--plan", "replan.toml", "-o", "time-replan.unv",
                                     "--binary"] + sflag),
                       ("frf", ["frf", "time-replan.unv", "-o", "frf-replan.unv"]),
                       ("fit", ["fit", "frf-replan.unv", "-o", "modes-replan.unv", "--band", f"{lo:.3f}:{hi:.3f}",
                                "--json", "modes-replan.json"]),
                       ("diagnose", ["diagnose", "nominal.toml"] + test_args + ["--json", "diag-replan.json"])):
        times[step + "_replan"] = run_ema(ema, args, folder, f"{step}-replan.log")
    after = read_json(os.path.join(folder, "diag-replan.json"))
    plan = read_json(os.path.join(folder, "replan.json"))
    truth = sorted((e["kind"], e["target"]) for e in case["truth"])
    first = after["candidates"][0]
    return {"readings": [f"{c['kind']} on {c['target']}" for c in readings],
            "truth_among_readings": any(effect_set(c) == truth for c in readings),
            "separations": plan.get("separations", []),
            "right_before": effect_set(diag["candidates"][0]) == truth,
            "p_rank1_before": diag["candidates"][0].get("probability"),
            "right_after": effect_set(first) == truth, "p_rank1_after": first.get("probability"),
            "rank1_after": {"kind": first["kind"], "target": first["target"]}}


def closed_loop_right(result):
    """Issue 40's score of a case run with --replan: the truth at rank 1 with probability >= 0.9
    after the follow-up test, or from the first test when it left no look-alike."""
    r = result.get("replan")
    if r and "right_after" in r:
        return r["right_after"] and (r["p_rank1_after"] or 0.0) >= 0.9
    return result["right"] and (result.get("p_rank1") or 0.0) >= 0.9


def run_case(ema, index, seed, work, keep, family=None, replan_lookalikes=False):
    folder = os.path.join(work, "cases", f"{index:04d}")
    times = {}
    t0 = time.monotonic()
    case, (lo, hi, fs, samples, n_modes, pulse), shifts, set_aside = draw_visible_case(ema, index, seed, folder, family)
    setups = case["setups"]
    sflag = lambda s: ["--setup", s] if s else []
    tag = lambda s: s or "test"
    times["model"] = time.monotonic() - t0
    tests = []
    for k, s in enumerate(setups):
        plan = (case["files"]["plan.toml"].replace("{fs}", f"{fs}.0").replace("{samples}", str(samples))
                .replace("{plan_seed}", str(1000 * index + k + 1)).replace("{pulse}", f"{pulse:.6g}"))
        with open(os.path.join(folder, f"plan-{tag(s)}.toml"), "w") as f:
            f.write(plan)
        if REUSE_TESTS and os.path.isfile(os.path.join(folder, f"modes-{tag(s)}.unv")):
            tests.append((s, f"modes-{tag(s)}.unv"))  # --reuse: the kept test of an earlier --keep run
            continue
        for step, args in (("simulate", ["simulate", "simulate.toml", "--plan", f"plan-{tag(s)}.toml",
                                         "-o", f"time-{tag(s)}.unv", "--binary"] + sflag(s)),
                           ("frf", ["frf", f"time-{tag(s)}.unv", "-o", f"frf-{tag(s)}.unv"]),
                           ("fit", ["fit", f"frf-{tag(s)}.unv", "-o", f"modes-{tag(s)}.unv", "--band",
                                    f"{lo:.3f}:{hi:.3f}", "--json", f"modes-{tag(s)}.json"])):
            times[step] = times.get(step, 0.0) + run_ema(ema, args, folder, f"{step}-{tag(s)}.log")
        tests.append((s, f"modes-{tag(s)}.unv"))
    args = ["diagnose", "nominal.toml"]
    for s, modes in tests:
        args += ["--test", f"{s}={modes}" if s else modes]
    times["diagnose"] = run_ema(ema, args + ["--json", "diag.json", "-o", "updated.toml"] + DIAGNOSE_ARGS, folder,
                                "diagnose.log")
    corr_after, corr_before = [], []
    t1 = time.monotonic()
    for s, modes in tests:
        for model, out in (("updated.toml", corr_after), ("nominal.toml", corr_before)):
            name = f"corr-{model.split('.')[0]}-{tag(s)}.json"
            run_ema(ema, ["correlate", modes, model, "--json", name] + sflag(s), folder, f"correlate-{tag(s)}.log")
            out.append(read_json(os.path.join(folder, name)))
    times["correlate"] = time.monotonic() - t1
    times["total"] = time.monotonic() - t0
    diag = read_json(os.path.join(folder, "diag.json"))
    result = score(case, diag, corr_after, corr_before, times)
    if case["family"] in cases.FORM_FAMILIES:
        result.update(form_scores(ema, case, folder, diag, lo, hi, shifts))
    if replan_lookalikes:
        result["replan"] = replan(ema, case, folder, tests, lo, hi, times, index)
    result.update({"attempt": case["attempt"], "set_aside": set_aside, "effect_shift_pct": shifts,
                   "band_hz": [lo, hi], "sample_rate_hz": fs, "samples": samples, "pulse_duration_s": pulse,
                   "truth_modes_in_band": n_modes,
                   "references": case["references"], "sensor_points": len(case["sensor_points"]),
                   "sensor_mass_kg": case["sensor_mass"]})
    if not keep:
        shutil.rmtree(folder, ignore_errors=True)
    return result


def run_one(ema, index, seed, work, keep, family=None, replan_lookalikes=False):
    """One case, never raising: a failed step is a scored failure with its message."""
    out = os.path.join(work, "scores", f"case-{index:04d}.json")
    try:
        result = run_case(ema, index, seed, work, keep, family, replan_lookalikes)
    except Exception as e:  # noqa: BLE001 — any failure of one case is that case's score, never the run's end
        case = cases.make_case(index, seed, 0, family)
        drawn = os.path.join(work, "cases", f"{index:04d}", "case.json")
        if os.path.isfile(drawn):  # the truth of the draw that failed (a redrawn case's own)
            case.update(read_json(drawn))
        result = {"index": index, "seed": seed, "family": case["family"], "noise": case["noise"],
                  "truth": case["truth"], "n_effects": len(case["truth"]),
                  "kinds": sorted({e["kind"] for e in case["truth"]}) or ["none"],
                  "member": any("/" in e["target"] or e["target"].startswith("points:") for e in case["truth"]),
                  "right": False, "parameters_ok": False, "agreement_ok": False, "p_truth": 0.0, "p_rank1": None,
                  "error": f"{type(e).__name__}: {e}"}
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, out)
    return result


def parse_range(text):
    """Case indices: "0:200" (200 excluded), "0:200:8" (every 8th), "7", or a comma list of these."""
    out = []
    for part in text.split(","):
        fields = [int(f) for f in part.split(":")]
        if len(fields) == 1:
            out.append(fields[0])
        elif len(fields) in (2, 3):
            out += list(range(*fields))
        else:
            raise SystemExit(f"bench.py: --cases {text!r}: expected A:B, A:B:STEP or an index")
    if not out or min(out) < 0:
        raise SystemExit(f"bench.py: --cases {text!r} selects no case")
    return sorted(set(out))


# Extra `ema diagnose` arguments (--diagnose-arg) and whether kept tests are reused (--reuse): to
# compare diagnosis options on the same simulated tests.
DIAGNOSE_ARGS = []
REUSE_TESTS = False
REPLAN_SENSORS = 0  # --replan-sensors: the follow-up set's DOFs (0: as many as the first set)
REPLAN_TOGETHER = False  # --replan-together: diagnose the first test and the follow-up together


def run_range(args):
    global REUSE_TESTS, REPLAN_SENSORS, REPLAN_TOGETHER
    DIAGNOSE_ARGS[:] = getattr(args, "diagnose_arg", None) or []
    REUSE_TESTS = getattr(args, "reuse", False)
    REPLAN_SENSORS = getattr(args, "replan_sensors", 0) or 0
    REPLAN_TOGETHER = getattr(args, "replan_together", False)
    if not (os.path.isfile(args.ema) and os.access(args.ema, os.X_OK)):
        print(f"bench.py: the ema executable is missing or not executable: {args.ema}", file=sys.stderr)
        sys.exit(2)
    ema = os.path.abspath(args.ema)
    os.makedirs(os.path.join(args.work, "scores"), exist_ok=True)
    indices = parse_range(args.cases)
    start = time.monotonic()
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = {pool.submit(run_one, ema, i, args.seed, args.work, args.keep, args.family,
                               getattr(args, "replan", False)): i for i in indices}
        for fut in concurrent.futures.as_completed(futures):
            r = fut.result()
            results.append(r)
            status = "right" if r["right"] else ("ERROR " + r["error"][:120] if "error" in r else "wrong")
            print(f"case {r['index']:4d} {r['family']:8s} noise {100 * r['noise']:.1f}% "
                  f"truth {'+'.join(e['kind'] + ':' + e['target'] for e in r['truth']) or 'none'}: {status}"
                  + ("" if r["right"] or "error" in r else f" (rank 1 {r['rank1']['kind']}:{r['rank1']['target']})"),
                  flush=True)
    wall = time.monotonic() - start
    tag = args.cases.replace(':', '-').replace(',', '_')
    if len(tag) > 80:  # a long comma list: a name the file system takes (255 bytes at most), still unique
        tag = f"{indices[0]}-{indices[-1]}-n{len(indices)}-{zlib.crc32(args.cases.encode()):08x}"
    with open(os.path.join(args.work, f"wall-{tag}.json"), "w") as f:
        json.dump({"cases": args.cases, "count": len(indices), "jobs": args.jobs, "wall_seconds": wall}, f)
    print(f"{len(results)} cases in {wall:.0f} s with --jobs {args.jobs}")
    return results


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    for name in ("run", "check"):
        q = sub.add_parser(name)
        q.add_argument("--ema", required=True, help="the built ema executable")
        q.add_argument("--cases", default="0:200",
                       help="case indices: A:B (B excluded), A:B:STEP, one index, or a comma list")
        q.add_argument("--jobs", type=int, default=1, help="cases run at once (default 1)")
        q.add_argument("--seed", type=int, default=DEFAULT_SEED, help=f"benchmark seed (default {DEFAULT_SEED})")
        q.add_argument("--work", default="diagnosis-benchmark-work", help="folder for cases and scores")
        q.add_argument("--keep", action="store_true", help="keep each case's files (default: scores only)")
        q.add_argument("--family", choices=[*cases.FORM_FAMILIES, cases.LOOKALIKE_FAMILY], default=None,
                       help="the model-form family (truth richer than the model), form-rich (its cases with "
                            "shear, rotary inertia and support restraints no effect can say) or the look-alike family "
                            "(mirror pairs a first test at mid-span cannot tell apart; with --replan); "
                            "default: the four families")
        q.add_argument("--replan", action="store_true",
                       help="when rank 1 has look-alikes, plan the follow-up test (ema plan --candidates --keep), "
                            "test again and diagnose (docs/plan.md)")
        q.add_argument("--replan-sensors", type=int, default=0,
                       help="DOFs of the follow-up set (default: as many as the first test's first set)")
        q.add_argument("--replan-together", action="store_true",
                       help="with --replan: diagnose the first test and the follow-up together (two tests of one "
                            "setup) instead of the follow-up alone")
        q.add_argument("--diagnose-arg", action="append", default=[],
                       help="an extra `ema diagnose` argument (repeat for several: --diagnose-arg=--shape-residual "
                            "--diagnose-arg=mac)")
        q.add_argument("--reuse", action="store_true",
                       help="reuse each case's kept test (an earlier run with --keep and the same --work): only "
                            "diagnose and correlate run again, to compare diagnosis options on the same data")
        if name == "check":
            q.add_argument("--floor", type=float, required=True, help="minimum share right at rank 1")
    g = sub.add_parser("gather")
    g.add_argument("--work", default="diagnosis-benchmark-work")
    g.add_argument("--doc", help="markdown page whose generated section is replaced")
    g.add_argument("--svg", help="calibration plot to write")
    args = p.parse_args()
    if args.command == "run":
        run_range(args)
    elif args.command == "gather":
        report.gather(args.work, args.doc, args.svg)
    else:
        results = run_range(args)
        right = sum(1 for r in results if (closed_loop_right(r) if getattr(args, "replan", False) else r["right"]))
        errors = [r for r in results if "error" in r]
        rate = right / len(results)
        what = "right at rank 1 with probability >= 0.9 after the follow-up test" if getattr(args, "replan", False) \
            else "right at rank 1"
        print(f"{what}: {right}/{len(results)} = {100 * rate:.1f} % (floor {100 * args.floor:.1f} %)")
        for r in errors:
            print(f"case {r['index']}: {r['error']}", file=sys.stderr)
        sys.exit(0 if rate >= args.floor and not errors else 1)


if __name__ == "__main__":
    main()
