"""The ema Python module against the ema CLI on the same files: every number the CLI writes with
full precision (JSON) must come back from Python bit for bit; FRFs written to UFF (13 significant
digits) agree to that last digit."""
import ast
import os
import pathlib
import re

import numpy as np
import pytest

import ema
from conftest import SHARED, SOURCE, load_json, run_ema


def test_module_and_functions_have_docstrings_and_stubs():
    assert "numpy" in ema.__doc__ and "pip install" in ema.__doc__
    functions = [name for name in ema.__all__ if callable(getattr(ema, name)) and not isinstance(getattr(ema, name), type)]
    assert {"read_frfs", "read_modes", "estimate_frfs", "fit", "mode_indicators", "model_modes", "mac", "correlate",
            "diagnose", "quality"} <= set(functions)
    # The compiled core's functions (some wrapped in Python to return an ema.Result, their docstring
    # kept) have stubs in _ema.pyi; the package's own (plots, JSON, tables) are typed in their module.
    compiled = [name for name in functions if hasattr(ema._ema, name)]
    assert {"plot_stabilisation", "plot_frf", "plot_mac", "to_json", "to_jsonable", "to_dataframe"} <= \
        set(functions) - set(compiled)
    # Every function: a docstring beyond pybind11's signature line (or a summary line); the compiled
    # ones a stub with a docstring in _ema.pyi.
    stubs = ast.parse((pathlib.Path(ema.__file__).parent / "_ema.pyi").read_text())
    stubbed = {f.name: ast.get_docstring(f) for f in stubs.body if isinstance(f, ast.FunctionDef)}
    for name in functions:
        assert len(getattr(ema, name).__doc__.strip().splitlines()) > 1, name
    for name in compiled:
        assert stubbed.get(name), f"{name}: no stub with a docstring in _ema.pyi"
    # The stubs' parameters are the module's (pybind11's signature line starts each docstring).
    for f in (f for f in stubs.body if isinstance(f, ast.FunctionDef)):
        line = getattr(ema, f.name).__doc__.splitlines()[0]
        runtime = re.findall(r"(\w+): ", line[line.index("(") + 1:line.rindex(")")])
        assert [a.arg for a in f.args.args + f.args.kwonlyargs] == runtime, f.name
    assert set(stubbed) == set(compiled)
    assert (pathlib.Path(ema.__file__).parent / "py.typed").exists()
    assert ema.__version__.count(".") == 2


def test_fit_matches_cli_bit_for_bit(beam_fit):
    sample, d = beam_fit
    cli = load_json(d / "modes.json")["modes"]
    py = ema.fit(str(sample), band=(30.0, 300.0), order_max=40)
    assert len(py["frequency_hz"]) == len(cli) == 3
    for r, m in enumerate(cli):
        assert py["frequency_hz"][r] == m["frequency_hz"]
        assert py["damping_ratio"][r] == m["damping_ratio"]
        assert py["mpc"][r] == m["mpc"]
        assert py["mpd_deg"][r] == m["mpd_deg"]
        assert py["mcf"][r] == m["mcf"]
        assert py["frequency_std_hz"][r] == m["frequency_std_hz"]
        assert py["damping_ratio_std"][r] == m["damping_ratio_std"]
        assert py["order"][r] == m["order"]
        for i, v in enumerate(m["shape"]):
            assert py["dofs"][i] == (v["node"], v["dir"])
            assert py["shapes"][i, r] == complex(*v["value"])


def test_read_modes_matches_what_fit_wrote(beam_fit):
    _, d = beam_fit
    cli = load_json(d / "modes.json")["modes"]
    modes = ema.read_modes(str(d / "modes.unv"))
    # The UFF 55 ID line carries f with 12 significant digits (%.12g): equal to that last digit.
    np.testing.assert_allclose(modes["frequency_hz"], [m["frequency_hz"] for m in cli], rtol=5e-12, atol=0)
    assert modes["shapes"].shape == (len(cli[0]["shape"]), 3)


def test_mode_indicators_match_the_stabilisation_json(beam_fit):
    sample, d = beam_fit
    stab = load_json(d / "stab.json")
    mi = ema.mode_indicators(str(sample), band=(30.0, 300.0))
    assert mi["frequency_hz"].tolist() == stab["cmif"]["frequency_hz"]
    assert mi["cmif"].shape[1] == len(stab["cmif"]["values"])
    assert mi["cmif"][:, 0].tolist() == stab["cmif"]["values"][0]
    assert mi["mmif"][:, 0].tolist() == stab["mmif"]["values"][0]


def test_fit_returns_the_stabilisation_and_the_modal_model_of_the_cli(beam_fit):
    # issue 41: why a mode is there (or not) and the model behind the shapes, as `ema fit
    # --stabilisation` and `--json` write them: the same poles per order, the same residues.
    sample, d = beam_fit
    stab = load_json(d / "stab.json")
    cli = load_json(d / "modes.json")
    py = ema.fit(str(sample), band=(30.0, 300.0), order_max=40, stabilisation=True)
    plain = {k: v for k, v in stab.items() if k not in ("cmif", "mmif")}  # mode_indicators() gives those
    assert set(plain) <= set(py["stabilisation"])
    for key in plain:
        assert py["stabilisation"][key] == plain[key], key
    assert py["modal_model"] == cli["modal_model"]
    assert len(py["modal_model"]["poles"]) == len(py["frequency_hz"]) == 3
    assert py["dropped"] == cli.get("dropped", [])
    assert "stabilisation" not in ema.fit(str(sample), band=(30.0, 300.0), order_max=40)


def test_correlate_matches_cli(beam_fit, tmp):
    sample, d = beam_fit
    # A second fit (another band and order) against the first: a non-trivial pairing.
    run_ema("fit", sample, "-o", tmp / "other.unv", "--band", "20:400", "--order-max", "30")
    run_ema("correlate", d / "modes.unv", tmp / "other.unv", "--json", tmp / "corr.json")
    cli = load_json(tmp / "corr.json")
    py = ema.correlate(str(d / "modes.unv"), str(tmp / "other.unv"))
    assert len(py["pairs"]) == len(cli["pairs"]) > 0
    for p, c in zip(py["pairs"], cli["pairs"]):
        for key in ["test_mode", "model_mode", "test_frequency_hz", "model_frequency_hz", "agreement_pct", "mac"]:
            assert p[key] == c[key], key
    assert py["mean_mac"] == cli["summary"]["mean_mac"]
    # The MAC matrix holds the paired entries.
    for p in py["pairs"]:
        assert py["mac"][p["test_mode"] - 1, p["model_mode"] - 1] == p["mac"]
    # One convention (issue 41): unpaired modes are mode numbers too, 1-based as the CLI's.
    assert py["unpaired_test"] == [u["test_mode"] for u in cli["unpaired_test"]]
    assert py["unpaired_model"] == [u["model_mode"] for u in cli.get("unpaired_model", [])]
    numbers = sorted([p["model_mode"] for p in py["pairs"]] + py["unpaired_model"])
    assert numbers == list(range(1, py["mac"].shape[1] + 1))
    # The same modes against themselves without their second: test mode 2 is the unpaired one.
    test = ema.read_modes(str(d / "modes.unv"))
    n = len(test["frequency_hz"])
    keep = [i for i in range(n) if i != 1]
    model = {k: (v[..., keep] if isinstance(v, np.ndarray) and v.shape[-1] == n else v) for k, v in test.items()}
    r = ema.correlate(test, model)
    assert r["unpaired_test"] == [2] and r["unpaired_model"] == []
    assert [(p["test_mode"], p["model_mode"]) for p in r["pairs"]] == [(1, 1), (3, 2)]


def test_mac_of_mismatched_shapes_raises():
    # Issue 41: 2x2 against 50000x2 crashed the interpreter (exit 139), 3x2 against 4x2 quietly
    # returned 0.75 everywhere; shapes of different lengths have no MAC.
    for a, b in ((np.ones((2, 2)), np.ones((50000, 2))), (np.ones((3, 2)), np.ones((4, 2)))):
        with pytest.raises(ValueError, match="same DOFs"):
            ema.mac(a, b)


def test_mac_of_known_shapes():
    a = np.array([[1.0, 0.0], [1.0, 1.0]], dtype=complex)
    b = np.array([[2.0j], [2.0j]])
    # MAC(a0, b) = |2j + 2j|^2 / (2 * 8) = 1; MAC(a1, b) = |2j|^2 / (1 * 8) = 0.5.
    np.testing.assert_allclose(ema.mac(a, b)[:, 0], [1.0, 0.5], rtol=1e-15)


def test_quality_matches_cli(beam_fit, tmp):
    sample, d = beam_fit
    run_ema("quality", sample, "--modes", d / "modes.unv", "--json", tmp / "q.json")
    cli = load_json(tmp / "q.json")
    py = ema.quality(str(sample), modes=str(d / "modes.unv"))
    assert py == cli


def test_quality_on_arrays_finds_the_inverted_driving_point():
    # Two-mode accelerance (e^{+jwt}), driving point 1/1 and transfer 2/1; Im(A_11) >= 0 when passive.
    frfs = _two_mode_frfs()
    h = frfs["h"]
    good = ema.quality(frfs)
    assert good["driving_points"][0]["verdict"] == "pass"
    assert good["driving_points"][0]["resonances"] == 2
    frfs["h"] = h * np.array([-1.0, 1.0])  # sensor 1 mounted upside down
    bad = ema.quality(frfs)
    assert bad["driving_points"][0]["verdict"] == "warn"
    assert bad["driving_points"][0]["flipped"] == 2
    assert bad["verdict"] == "warn"


def test_estimate_frfs_matches_cli_to_the_digits_written(tmp):
    data = SHARED / "hammer-pyfrf" / "hammer-5-impacts.unv"
    if not data.exists():
        pytest.skip("shared data not present")
    run_ema("frf", data, "-o", tmp / "frf.unv")
    written = ema.read_frfs(str(tmp / "frf.unv"))
    py = ema.estimate_frfs([str(data)])
    assert py["outputs"] == written["outputs"] and py["references"] == written["references"]
    np.testing.assert_allclose(py["frequency_hz"], written["frequency_hz"], rtol=1e-12, atol=0)
    # UFF 58 FRFs are written with 13 significant digits: agreement to that last digit.
    scale = np.abs(py["h"]).max()
    assert np.abs(py["h"] - written["h"]).max() <= 1e-12 * scale
    np.testing.assert_allclose(py["coherence"], written["coherence"], rtol=1e-11, atol=1e-12)
    assert (py["averages"] == written["averages"]).all()


def test_bad_input_raises_with_the_file_name(tmp):
    missing = tmp / "missing.unv"
    with pytest.raises(ValueError, match="missing.unv"):
        ema.read_modes(str(missing))
    with pytest.raises(ValueError):
        ema.fit({"frequency_hz": [1.0, 2.0], "outputs": [(1, "+Z")], "references": [(1, "+Z")],
                 "h": np.zeros((2, 2, 1), dtype=complex)})


def _two_mode_frfs():
    """Two-mode accelerance at 40 and 120 Hz, driving point 1/1 and transfer 2/1 (analytic)."""
    f = np.arange(0.0, 200.0, 0.5)
    w = 2 * np.pi * f
    h = np.zeros((1, len(f), 2), dtype=complex)
    for fn, zeta, phi in [(40.0, 0.01, (1.0, 0.8)), (120.0, 0.02, (1.0, -0.6))]:
        wn = 2 * np.pi * fn
        rec = 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)
        h[0, :, 0] += -(w**2) * phi[0] * phi[0] * rec
        h[0, :, 1] += -(w**2) * phi[1] * phi[0] * rec
    return {"frequency_hz": f, "outputs": [(1, "+Z"), (2, "+Z")], "references": [(1, "+Z")], "h": h}


def test_fit_finds_the_analytic_poles():
    # The control for the refusals below: the same FRFs fit to their two poles.
    py = ema.fit(_two_mode_frfs(), band=(10.0, 190.0))
    np.testing.assert_allclose(sorted(py["frequency_hz"]), [40.0, 120.0], rtol=1e-3)


def test_synthesize_gives_back_the_analytic_frfs():
    # The fitted modal model of two analytic modes, synthesised on the measured lines, is the
    # analytic FRF again: to 1e-3 of its peak inside the band (the ML-refined poles and the LSFD
    # residues of noise-free data; the residual terms absorb the band's edges), NaN outside it.
    frfs = _two_mode_frfs()
    fit = ema.fit(frfs, band=(10.0, 190.0), stabilisation=True)
    syn = ema.synthesize(fit, frfs["frequency_hz"])
    assert syn["h"].shape == frfs["h"].shape
    assert [tuple(d) for d in syn["outputs"]] == [(1, "+Z"), (2, "+Z")]
    f = frfs["frequency_hz"]
    inside = (f >= 10.0) & (f <= 190.0)
    err = np.abs(syn["h"][:, inside, :] - frfs["h"][:, inside, :]).max()
    assert err < 1e-3 * np.abs(frfs["h"]).max(), err
    assert np.isnan(syn["h"][:, ~inside, :]).all()
    with pytest.raises(ValueError, match="stabilisation=True"):
        ema.synthesize(ema.fit(frfs, band=(10.0, 190.0)), f)
    broken = dict(fit["modal_model"], frfs=[{"response_node": 1}])
    with pytest.raises(ValueError, match="layout"):
        ema.synthesize(broken, f)
    with pytest.raises(TypeError):
        ema.synthesize([1, 2], f)
    # Any Mapping, not only a dict: a read-only view of the fit crashed the interpreter (exit 139).
    import types
    proxied = ema.synthesize(types.MappingProxyType(fit), f)
    np.testing.assert_array_equal(np.nan_to_num(proxied["h"]), np.nan_to_num(syn["h"]))
    with pytest.raises(TypeError, match="modal_model"):
        ema.synthesize({"modal_model": [1, 2]}, f)


def test_fit_that_finds_nothing_raises_as_the_cli_exits():
    # issue 41: these returned zero modes without a word (the CLI exits 1 there).
    frfs = _two_mode_frfs()
    with pytest.raises(ValueError, match="no mode found"):
        ema.fit(frfs, band=(60.0, 61.0))
    with pytest.raises(ValueError, match="no mode found"):
        ema.fit(frfs, band=(10.0, 190.0), order_max=2)
    zero = dict(frfs, h=np.zeros_like(frfs["h"]))
    with pytest.raises(ValueError, match="no mode found"):
        ema.fit(zero, band=(10.0, 190.0))


def test_bindings_refuse_wrong_types_with_the_argument_named():
    frfs = _two_mode_frfs()
    with pytest.raises(ValueError, match="unknown direction"):
        ema.fit(dict(frfs, outputs=[(1, "+Q"), (2, "+Z")]))
    with pytest.raises(ValueError, match="unknown direction"):
        ema.fit(dict(frfs, outputs=[(1, 9), (2, "+Z")]))
    with pytest.raises(ValueError, match="node number"):
        ema.fit(dict(frfs, outputs=["a+Z", "2+Z"]))
    with pytest.raises(TypeError, match=r"frfs\['h'\]: expected a complex array"):
        ema.fit(dict(frfs, h=np.abs(frfs["h"])))
    with pytest.raises(TypeError, match="band"):
        ema.fit(frfs, band=100)
    with pytest.raises(TypeError, match="band"):
        ema.fit(frfs, band=("a", "b"))
    with pytest.raises(ValueError, match="band"):
        ema.fit(frfs, band=(100.0, 50.0))


def test_diagnose_takes_the_model_error_options():
    # --effect-prior-odds and --exact-form as keywords, validated as the CLI validates them.
    model = SOURCE / "samples" / "guideway" / "model.toml"
    modes = {"modes": [{"frequency_hz": 200.0, "frequency_std_hz": 0.2, "damping_ratio": 0.01,
                        "shape": [{"node": 1, "dir": "+Z", "value": 1.0}]}]}
    with pytest.raises(ValueError, match="effect_prior_odds"):
        ema.diagnose(str(model), {"stud-5um": modes}, effect_prior_odds=0.0)


def test_ctrl_c_interrupts_a_diagnosis():
    # issue 41: Ctrl-C waited for the whole call. The 1 000-DOF FE-parts model of the benchmark
    # against its own six lowest modes 1 % low: a diagnosis of a few seconds (the control, timed).
    # SIGINT 0.3 s into the same call ends it with KeyboardInterrupt in well under the control's
    # time (before: the signal was seen only when the call returned, after the whole diagnosis).
    import os
    import signal
    import threading
    import time

    model = str(SOURCE / "tests" / "diagnose" / "data" / "benchmark-parts43" / "model.toml")
    modes = ema.model_modes(model, max_modes=6)
    modes["frequency_hz"] = modes["frequency_hz"] * 0.99
    start = time.monotonic()
    full = ema.diagnose(model, {"": modes}, max_effects=2)
    whole = time.monotonic() - start
    assert full["candidates"] and whole > 1.0, whole
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        ema.diagnose(model, {"": modes}, max_effects=2)
    interrupted = time.monotonic() - start
    timer.join()
    assert interrupted < 0.6 * whole, (whole, interrupted)


def test_write_modes_and_frfs_round_trip_through_the_readers(tmp_path):
    # issue 41: the fit's modes and the FRFs written as the CLI writes them, read back by the
    # readers: UFF 55 and MODES.json give the same frequencies and shapes (to the UFF fields' 1e-6
    # relative precision), UFF 58 and 58b the same FRFs.
    frfs = _two_mode_frfs()
    fit = ema.fit(frfs, band=(10.0, 190.0))
    for name in ("modes.unv", "modes.json"):
        ema.write_modes(fit, tmp_path / name)
        back = ema.read_modes(tmp_path / name)
        np.testing.assert_allclose(back["frequency_hz"], fit["frequency_hz"], rtol=1e-6)
        np.testing.assert_allclose(np.abs(back["shapes"]), np.abs(fit["shapes"]), rtol=1e-5, atol=1e-9)
    for binary in (False, True):
        path = tmp_path / f"frf-{binary}.unv"
        ema.write_frfs(frfs, path, binary=binary)
        back = ema.read_frfs(path)
        np.testing.assert_allclose(back["frequency_hz"], frfs["frequency_hz"], rtol=1e-6)
        np.testing.assert_allclose(back["h"], frfs["h"], rtol=1e-5, atol=1e-9 * np.abs(frfs["h"]).max())
        assert [tuple(d) for d in back["outputs"]] == [(1, "+Z"), (2, "+Z")]
    # An output over the input is refused and leaves the input as it was; a bad path is a TypeError.
    before = (tmp_path / "modes.unv").read_bytes()
    with pytest.raises(ValueError, match="path"):
        ema.write_modes(tmp_path / "modes.unv", tmp_path / "modes.unv")
    assert (tmp_path / "modes.unv").read_bytes() == before
    with pytest.raises(TypeError, match="path"):
        ema.write_frfs(frfs, 42)
    with pytest.raises(TypeError, match="frfs"):
        ema.write_frfs([1, 2], tmp_path / "x.unv")
    assert not (tmp_path / "x.unv").exists()


def test_estimate_frfs_takes_the_cli_options_and_returns_the_rejected_impacts(tmp_path):
    # issue 41: ema frf's options by the same names, a pathlib.Path, and the summary ema frf --json
    # writes (per FRF the rejected impacts with file and reason) — equal to the CLI's files.
    data = pathlib.Path(SOURCE) / "samples" / "guideway" / "data" / "stud-5um.unv"
    run_ema("frf", data, "-o", tmp_path / "frf.unv", "--json", tmp_path / "frf.json", "--exp-window", "none",
            "--trigger-level", "0.2", "--band", "50:600")
    written = ema.read_frfs(str(tmp_path / "frf.unv"))
    py = ema.estimate_frfs(data, exp_window="none", trigger_level=0.2, band=(50.0, 600.0))
    np.testing.assert_allclose(py["frequency_hz"], written["frequency_hz"], rtol=1e-12, atol=0)
    assert np.abs(py["h"] - written["h"]).max() <= 1e-12 * np.abs(py["h"]).max()
    summary = load_json(tmp_path / "frf.json")
    assert py["summary"] == summary
    rejected = [r for f in py["summary"]["frfs"] for r in f["rejected"]]
    assert rejected and all(r["reason"] and r["file"].endswith("stud-5um.unv") for r in rejected)
    # The sample's double hit (set 2, impact 3): rejected by default, kept when asked.
    kept = ema.estimate_frfs([data], exp_window="none", trigger_level=0.2, band=(50.0, 600.0), accept_double_hits=True)
    assert kept["averages"].sum() > py["averages"].sum()
    with pytest.raises(TypeError, match="paths"):
        ema.estimate_frfs(42)
    with pytest.raises(ValueError, match="exp_window"):
        ema.estimate_frfs(data, exp_window="sometimes")
    with pytest.raises(ValueError, match="trigger_level"):
        ema.estimate_frfs(data, trigger_level=1.5)


def test_estimate_frfs_from_arrays_equals_the_same_records_from_a_file(tmp_path):
    # issue 41: numpy arrays in (force=, response=, fs=, dofs=, reference=) give exactly what the same
    # records give from a CSV file (docs/formats.md: impact column, shortest round-trip numbers):
    # a 1-DOF oscillator at 40 Hz hit 4 times by a 2 ms half-sine, two response channels.
    fs, n, impacts = 1024.0, 2048, 4
    t = np.arange(n) / fs
    wn, zeta = 2 * np.pi * 40.0, 0.02
    wd = wn * np.sqrt(1 - zeta**2)
    g = np.exp(-zeta * wn * t) * np.sin(wd * t) / wd  # impulse response of x'' + 2ζωx' + ω²x = f (unit mass)
    rng = np.random.default_rng(41)
    force = np.zeros((impacts, n))
    response = np.zeros((impacts, 2, n))
    for i in range(impacts):
        pulse = (t >= 0.05) & (t < 0.052)
        force[i, pulse] = (90 + 5 * i) * np.sin(np.pi * (t[pulse] - 0.05) / 0.002)
        x = np.convolve(force[i], g)[:n] / fs
        acc = np.gradient(np.gradient(x, 1 / fs), 1 / fs)
        response[i, 0] = acc + 1e-4 * rng.standard_normal(n)
        response[i, 1] = -0.5 * acc + 1e-4 * rng.standard_normal(n)
    dofs = [(101, "+Z"), (102, "+Z")]
    arrays = ema.estimate_frfs(force=force, response=response, fs=fs, dofs=dofs, reference=(101, "+Z"))
    lines = ["impact,time,force:101:+Z[N],acc:101:+Z[m/s^2],acc:102:+Z[m/s^2]"]
    for i in range(impacts):
        for k in range(n):
            lines.append(f"{i + 1},{t[k]!r},{force[i, k]!r},{response[i, 0, k]!r},{response[i, 1, k]!r}")
    (tmp_path / "hits.csv").write_text("\n".join(lines) + "\n")
    from_file = ema.estimate_frfs(tmp_path / "hits.csv")
    np.testing.assert_array_equal(arrays["frequency_hz"], from_file["frequency_hz"])
    np.testing.assert_array_equal(arrays["h"], from_file["h"])
    np.testing.assert_array_equal(arrays["averages"], from_file["averages"])
    # And it is the oscillator: the driving point's peak at 40 Hz, the transfer at -0.5 of it.
    f = arrays["frequency_hz"]
    peak = f[np.argmax(np.abs(arrays["h"][0, :, 0]))]
    assert abs(peak - 40.0) <= f[1] - f[0]
    k = np.argmin(np.abs(f - 40.0))
    assert abs(arrays["h"][0, k, 1] / arrays["h"][0, k, 0] + 0.5) < 0.01
    with pytest.raises(ValueError, match="response: expected shape"):
        ema.estimate_frfs(force=force, response=response[:, :, :100], fs=fs, dofs=dofs, reference=(101, "+Z"))
    with pytest.raises(ValueError, match="dofs"):
        ema.estimate_frfs(force=force, response=response, fs=fs, dofs=dofs[:1], reference=(101, "+Z"))
    with pytest.raises(TypeError, match="all needed"):
        ema.estimate_frfs(force=force, response=response, fs=fs, dofs=dofs)
    with pytest.raises(TypeError, match="not both"):
        ema.estimate_frfs(tmp_path / "hits.csv", force=force, response=response, fs=fs, dofs=dofs, reference=(101, "+Z"))


def test_read_uff_gives_every_dataset_as_ema_info_counts_them(tmp_path):
    # issue 41: every dataset the library reads, as dicts. The counts per dataset type equal
    # `ema info --json`'s; the 58 records' values equal read_frfs's FRFs; a file's geometry
    # equals read_modes's; the 58b records read as the ASCII ones do.
    real = pathlib.Path(os.environ.get("EMA_REAL_DATA_DIR", pathlib.Path(SOURCE) / "tests" / "data" / "real")) / "uff" / "pyuff"
    for name in ("TestLab 161 164 18 15 82.uff", "Sample_UFF58_ascii.uff", "Sample_UFF58b_bin.uff"):
        path = real / name
        datasets = ema.read_uff(path)
        run_ema("info", path, "--json", tmp_path / "info.json")
        counts = {}
        for d in datasets:
            counts[str(d["number"])] = counts.get(str(d["number"]), 0) + 1
        assert counts == load_json(tmp_path / "info.json")["datasets"], name
    ascii_, binary = (ema.read_uff(real / n) for n in ("Sample_UFF58_ascii.uff", "Sample_UFF58b_bin.uff"))
    f58a = [d for d in ascii_ if d["number"] == 58]
    f58b = [d for d in binary if d["number"] == 58]
    assert f58b and all(d["binary"] for d in f58b) and not any(d["binary"] for d in f58a)
    for a, b in zip(f58a, f58b):
        assert (a["response_node"], a["response_direction"]) == (b["response_node"], b["response_direction"])
        # The ASCII file holds 6 significant digits (5e-7 of these values), the binary one all of them.
        np.testing.assert_allclose(b["y"], a["y"], rtol=1e-5, atol=1e-6 * np.abs(a["y"]).max())
    geometry = ema.read_uff(real / "TestLab 161 164 18 15 82.uff")
    nodes = [d for d in geometry if d["number"] == 15][0]["nodes"]
    assert nodes["xyz"].shape == (len(nodes["label"]), 3)
    traces = [d for d in geometry if d["number"] == 82]
    assert len(traces) == 3 and all(len(t["nodes"]) > 1 for t in traces)
    with pytest.raises(TypeError, match="path"):
        ema.read_uff(42)
    with pytest.raises(ValueError, match="missing.uff"):
        ema.read_uff(tmp_path / "missing.uff")
