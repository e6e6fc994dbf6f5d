"""ema.plan against `ema plan` (issue 40, docs/plan.md): the same plan for the same options, PLAN.json's
numbers to the last bit, the plan file's text, the look-alike readings of a diagnosis (a DIAG.json path
or a dict) and an extended plan (keep); bad input named as the other bindings name it."""
import json
import math

import pytest

import ema
from conftest import SOURCE, load_json, run_ema

GUIDEWAY = SOURCE / "samples" / "guideway" / "model.toml"
# The guideway sample's hardware: four triaxial accelerometers roved over four sets, three hammer DOFs.
HARDWARE = dict(setup="stud-5um", sensors=4, sets=4, triaxial=True, references=3)
HARDWARE_CLI = ["--setup", "stud-5um", "--sensors", "4", "--sets", "4", "--triaxial", "--references", "3"]


def plan_lines(text):
    """The plan file without its comment (which names the program that wrote it)."""
    return [line for line in text.splitlines() if not line.startswith("#")]


def cli_plan(tmp, name, *args):
    """`ema plan` with --json: (PLAN.json as a dict, the plan file's text)."""
    run_ema("plan", *args, "-o", tmp / f"{name}.toml", "--json", tmp / f"{name}.json")
    return load_json(tmp / f"{name}.json"), (tmp / f"{name}.toml").read_text()


def candidate(rank, target, probability, mass=0.05):
    """One candidate of DIAG.json as `ema diagnose --json` writes it (the keys ema plan reads)."""
    return {"rank": rank, "kind": "added_mass", "target": target, "probability": probability,
            "effects": [{"kind": "added_mass", "target": target, "parameters": {"mass": mass}}]}


# Rank 1 and its mirror look-alike (a mass at point 101 or at 103, across the carriage); a far reading
# at 1 % (beyond a factor 20 of rank 1: left out) and "none" (never a reading to separate).
DIAGNOSIS = {"candidates": [candidate(1, "points:101", 0.50), candidate(2, "points:103", 0.45),
                            candidate(3, "points:102", 0.01),
                            {"rank": 4, "kind": "none", "target": "", "probability": 0.04, "effects": []}]}


def without_toml(result):
    plain = dict(result)
    del plain["plan_toml"]
    return plain


def test_guideway_plan_sees_every_mode_and_matches_the_cli(tmp):
    py = ema.plan(GUIDEWAY, **HARDWARE)
    assert isinstance(py, ema.Result)
    assert len(py["sensors"]) == 48 and len(set(py["sensors"])) == 48  # 16 points x X, Y, Z
    assert [s["name"] for s in py["sets"]] == ["set 1", "set 2", "set 3", "set 4"]
    assert all(len(s["sensors"]) == 12 for s in py["sets"])
    assert len(py["references"]) == 3
    assert len(py["modes"]) == 5 and all(m["excited"] for m in py["modes"])
    assert py["automac_max_offdiagonal"] <= 0.1
    assert py["notes"] == []
    assert "separations" not in py  # no candidates
    assert py["acquisition"]["impacts"] == 5 and py["acquisition"]["sensor_mass_kg"] == 0.0

    cli, toml = cli_plan(tmp, "cli", GUIDEWAY, *HARDWARE_CLI)
    assert without_toml(py) == cli  # every number to the last bit
    assert plan_lines(py["plan_toml"]) == plan_lines(toml)
    assert py["plan_toml"].startswith(f"# Test plan of {GUIDEWAY} made by ema.plan")

    # output=: the plan file written is the text returned; a str path or an os.PathLike alike.
    written = ema.plan(str(GUIDEWAY), **HARDWARE, output=str(tmp / "py.toml"))
    assert (tmp / "py.toml").read_text() == written["plan_toml"] == py["plan_toml"]
    assert ema.results.tables(py)[:2] == ["modes", "sets"]


def test_options_reach_the_plan_as_the_cli_options_do(tmp):
    options = dict(band=(500.0, 950.0), sensors=5, sets=2, references=2, sensor_mass=0.0112, impacts=8)
    py = ema.plan(GUIDEWAY, setup="stud-5um", **options)
    cli, toml = cli_plan(tmp, "cli", GUIDEWAY, "--setup", "stud-5um", "--band", "500:950", "--sensors", "5", "--sets", "2",
                         "--references", "2", "--sensor-mass", "0.0112", "--impacts", "8")
    assert without_toml(py) == cli
    assert plan_lines(py["plan_toml"]) == plan_lines(toml)
    assert py["band_hz"] == [500.0, 950.0]
    assert [round(m["frequency_hz"], 1) for m in py["modes"]] == [566.8, 773.5, 899.4, 931.2]
    assert len(py["sensors"]) == 10 and len(py["references"]) == 2  # DOFs, not points
    assert py["acquisition"]["impacts"] == 8 and py["acquisition"]["sensor_mass_kg"] == 0.0112
    assert "sensor_mass = 0.0112" in py["plan_toml"]


def test_candidates_separate_mirror_readings_as_the_cli_does(tmp):
    diag = tmp / "diag.json"
    diag.write_text(json.dumps(DIAGNOSIS, indent=1))
    by_path = ema.plan(GUIDEWAY, setup="stud-5um", candidates=diag)
    separations = by_path["separations"]
    assert len(separations) == 1  # rank 1 and rank 2; rank 3 beyond a factor 20, "none" left out
    s = separations[0]
    assert (s["a"], s["b"]) == ("added_mass on points:101", "added_mass on points:103")
    assert math.isfinite(s["sigma_before"]) and math.isfinite(s["sigma_after"])
    assert s["sigma_before"] > 0.0 and s["sigma_after"] >= s["sigma_before"]

    cli, toml = cli_plan(tmp, "cli", GUIDEWAY, "--setup", "stud-5um", "--candidates", diag)
    assert without_toml(by_path) == cli
    assert plan_lines(by_path["plan_toml"]) == plan_lines(toml)
    assert f"look-alike readings of {diag}" in by_path["plan_toml"]

    # The dict itself (what ema.diagnose returns; here as it was written): the same plan.
    by_dict = ema.plan(GUIDEWAY, setup="stud-5um", candidates=DIAGNOSIS)
    assert without_toml(by_dict) == cli
    assert "look-alike readings of candidates" in by_dict["plan_toml"]

    # Only rank 1 within a factor 20: nothing to separate, an empty list (not absent).
    alone = {"candidates": [candidate(1, "points:101", 0.9), candidate(2, "points:103", 0.01)]}
    assert ema.plan(GUIDEWAY, setup="stud-5um", candidates=alone)["separations"] == []


def test_keep_extends_a_plan_as_the_cli_does(tmp):
    first = ema.plan(GUIDEWAY, sensors=6, references=2, output=tmp / "first.toml")
    py = ema.plan(GUIDEWAY, sensors=4, keep=tmp / "first.toml", candidates=DIAGNOSIS)
    assert len(py["sets"]) == 2
    assert py["sets"][0] == first["sets"][0]  # the kept set as it was
    assert not set(py["sets"][1]["sensors"]) & set(first["sets"][0]["sensors"])
    assert len(py["separations"]) == 1
    assert py["separations"][0]["sigma_after"] >= py["separations"][0]["sigma_before"]
    # The kept plan's settings stay: its references and sampling, in the plan file.
    assert plan_lines(first["plan_toml"])[:12] == plan_lines(py["plan_toml"])[:12]

    diag = tmp / "diag.json"
    diag.write_text(json.dumps(DIAGNOSIS))
    cli, toml = cli_plan(tmp, "cli", GUIDEWAY, "--sensors", "4", "--keep", tmp / "first.toml", "--candidates", diag)
    assert without_toml(py) == cli
    assert plan_lines(py["plan_toml"]) == plan_lines(toml)


def test_bad_input_is_named(tmp):
    with pytest.raises(ValueError, match="no model mode in the band 5000.0–6000.0 Hz"):
        ema.plan(GUIDEWAY, band=(5000.0, 6000.0))
    with pytest.raises(ValueError, match="20 test points asked, but the model has 16"):
        ema.plan(GUIDEWAY, sensors=4, sets=5, triaxial=True)
    for name in ("sensors", "sets", "references", "impacts"):
        with pytest.raises(ValueError, match=f"^{name}: expected >= 1"):
            ema.plan(GUIDEWAY, **{name: 0})
    with pytest.raises(ValueError, match="sensor_mass"):
        ema.plan(GUIDEWAY, sensor_mass=-0.01)
    with pytest.raises(TypeError, match="band"):
        ema.plan(GUIDEWAY, band="500:950")
    with pytest.raises(TypeError, match="band"):
        ema.plan(GUIDEWAY, band=(500.0, "high"))
    with pytest.raises(ValueError, match="band"):
        ema.plan(GUIDEWAY, band=(950.0, 500.0))
    with pytest.raises(TypeError, match="candidates"):
        ema.plan(GUIDEWAY, candidates=3)
    with pytest.raises(TypeError, match="keep"):
        ema.plan(GUIDEWAY, keep={"sets": []})
    with pytest.raises(TypeError):
        ema.plan(GUIDEWAY, 4)  # the options are keywords

    # A diagnosis of another model, a dict that is no diagnosis, files that are not there.
    other = {"candidates": [candidate(1, "points:999", 0.6), candidate(2, "points:101", 0.3)]}
    with pytest.raises(ema.InputError, match="candidates, candidate rank 1: .*expected a diagnosis of this model"):
        ema.plan(GUIDEWAY, candidates=other)
    with pytest.raises(ema.InputError, match='^candidates: no "candidates" array'):
        ema.plan(GUIDEWAY, candidates={"modes": []})
    with pytest.raises(ema.InputError, match="candidates: candidate rank 1: missing key 'effects'"):
        ema.plan(GUIDEWAY, candidates={"candidates": [{"rank": 1, "kind": "x", "target": "y"}]})
    with pytest.raises(ema.InputError, match="missing.json: diagnosis file not found"):
        ema.plan(GUIDEWAY, candidates=tmp / "missing.json")
    with pytest.raises(ema.InputError, match="missing.toml: plan file not found"):
        ema.plan(GUIDEWAY, keep=tmp / "missing.toml")

    # An output over an input is refused before anything is written.
    diag = tmp / "diag.json"
    diag.write_text(json.dumps(DIAGNOSIS))
    before = GUIDEWAY.read_text()
    ema.plan(GUIDEWAY, output=tmp / "kept.toml")
    kept = (tmp / "kept.toml").read_text()
    for given in (dict(output=GUIDEWAY), dict(candidates=diag, output=diag),
                  dict(keep=tmp / "kept.toml", output=tmp / "kept.toml")):
        with pytest.raises(ema.UsageError, match="^output: .*refused, it would replace the input"):
            ema.plan(GUIDEWAY, **given)
    assert GUIDEWAY.read_text() == before and json.loads(diag.read_text()) == DIAGNOSIS
    assert (tmp / "kept.toml").read_text() == kept
    with pytest.raises(ValueError, match="no model mode"):
        ema.plan(GUIDEWAY, band=(5000.0, 6000.0), output=tmp / "never.toml")
    assert not (tmp / "never.toml").exists()
