"""The README's "guideway story in ten lines of Python" runs as written, and ema.diagnose agrees
with `ema diagnose` on the same mode files to the last digit."""
import os
import re
import subprocess
import sys

import ema
from conftest import SOURCE, load_json, run_ema


def readme_story():
    text = (SOURCE / "README.md").read_text()
    section = text.split("## Python: the guideway story in ten lines", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_story_runs_and_finds_the_mount_compliance():
    code = readme_story()
    assert len([l for l in code.splitlines() if l.strip()]) <= 10
    env = dict(os.environ)
    result = subprocess.run([sys.executable, "-c", code], cwd=SOURCE, env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    out = result.stdout
    # The air-film-only model agrees to ~34 % and ~70 % (samples/guideway/README.md) ...
    agreements = [float(x) for x in re.findall(r"agrees to ([0-9.]+) %", out)]
    assert len(agreements) == 2 and 30 < agreements[0] < 40 and 65 < agreements[1] < 75, out
    # ... and the missing physics sits in series with the bearings (the ball-joint mounts: a
    # compliance, a Hertz contact, as the diagnosis words it).
    assert "in series with group 'bearings'" in out, out
    # The roving sensors' own mass is modelled (sensor_mass): nothing else is added to explain it.
    assert "added mass" not in out, out


def test_diagnose_matches_cli(tmp):
    data = SOURCE / "samples" / "guideway"
    tests = {}
    for setup in ["stud-5um", "stud-9um"]:
        run_ema("frf", data / "data" / f"{setup}.unv", "-o", tmp / f"{setup}-frf.unv")
        # The `ema fit --json` file beside the modes carries each mode's σ: both read it.
        run_ema("fit", tmp / f"{setup}-frf.unv", "-o", tmp / f"{setup}.unv", "--json", tmp / f"{setup}.json",
                "--band", "100:450")
        tests[setup] = str(tmp / f"{setup}.unv")
    run_ema("diagnose", data / "model.toml", *[a for s, p in tests.items() for a in ("--test", f"{s}={p}")],
            "--json", tmp / "diag.json")
    cli = load_json(tmp / "diag.json")
    py = ema.diagnose(str(data / "model.toml"), tests)
    assert len(py["candidates"]) == len(cli["candidates"])
    for p, c in zip(py["candidates"], cli["candidates"]):
        for key in ["rank", "kind", "target", "parameters", "mean_abs_frequency_error_pct", "mean_mac", "score"]:
            assert p[key] == c[key], (key, p[key], c[key])
        assert p["description"] == c["description"]
    # The whole of DIAG.json, rank 1's findings included: the same stage, the same codec, the same
    # σ per mode (pipeline::DiagnoseModel, pipeline::DiagnosisJson).
    assert set(cli) == set(py)
    for key in py:
        assert py[key] == cli[key], key
    sigmas = [m["frequency_std_hz"] for s in tests for m in load_json(tmp / f"{s}.json")["modes"]]
    assert [r["sigma_hz"] for r in py["modes"]] == [max(s, 1e-3 * r["test_frequency_hz"])
                                                   for s, r in zip(sigmas, py["modes"])]
