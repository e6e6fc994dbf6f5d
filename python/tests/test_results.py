"""ema.Result, ema.to_json/to_jsonable and ema.to_dataframe (issue 41, "A Python user's day"): the
wrapped results are the bindings' dicts unchanged, JSON keeps every number (complex as [re, im],
NaN as null), the tables hold the results' own values."""
import html
import json
import math
import pickle
import subprocess
import sys
import warnings

import numpy as np
import pytest

import ema
from conftest import SOURCE

BEAM = str(SOURCE / "samples" / "meas-point")
GUIDEWAY = SOURCE / "samples" / "guideway"
BEAM_FIT = {"band": (30.0, 300.0), "order_max": 40}


def quiet(function, *args, **kwargs):
    """A fit without its RuntimeWarnings (the beam's negative modal mass): they are in 'warnings'."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return function(*args, **kwargs)


@pytest.fixture(scope="module")
def beam():
    """The measured beam fitted with its stabilisation diagram, and a second fit to correlate with."""
    fit = quiet(ema.fit, BEAM, stabilisation=True, **BEAM_FIT)
    other = quiet(ema.fit, BEAM, band=(20.0, 400.0), order_max=30)
    return fit, other


@pytest.fixture(scope="module")
def guideway_diagnosis():
    """The guideway's stud-5um setup fitted and diagnosed (as examples/guideway_story.py, one setup)."""
    frfs = ema.estimate_frfs([str(GUIDEWAY / "data" / "stud-5um.unv")])
    fit = quiet(ema.fit, frfs, band=(100.0, 450.0))
    return ema.diagnose(str(GUIDEWAY / "model.toml"), {"stud-5um": fit}, sensor_mass=0.0112)


def assert_same_values(wrapped, plain, where="result"):
    """wrapped == plain, key by key and item by item, numpy arrays by value and dtype."""
    assert type(wrapped) is type(plain) or (isinstance(wrapped, dict) and isinstance(plain, dict)), where
    if isinstance(plain, dict):
        assert list(wrapped) == list(plain), where
        for key in plain:
            assert_same_values(wrapped[key], plain[key], f"{where}[{key!r}]")
    elif isinstance(plain, np.ndarray):
        assert wrapped.dtype == plain.dtype and wrapped.shape == plain.shape, where
        np.testing.assert_array_equal(wrapped, plain, err_msg=where)
    elif isinstance(plain, float) and math.isnan(plain):
        assert math.isnan(wrapped), where
    else:
        assert wrapped == plain, where


def test_wrapped_results_are_the_bindings_dicts(beam):
    fit, other = beam
    modes_file = str(SOURCE / "samples" / "guideway" / "model.toml")
    calls = [
        (ema.fit, ema._ema.fit, (BEAM,), dict(stabilisation=True, **BEAM_FIT)),
        (ema.correlate, ema._ema.correlate, (fit, other), {}),
        (ema.quality, ema._ema.quality, (BEAM,), {"modes": fit}),
        (ema.model_modes, ema._ema.model_modes, (modes_file, "stud-5um"), {}),
    ]
    for wrapped_function, binding, args, kwargs in calls:
        wrapped = quiet(wrapped_function, *args, **kwargs)
        plain = quiet(binding, *args, **kwargs)
        assert type(plain) is dict and isinstance(wrapped, dict) and isinstance(wrapped, ema.Result)
        assert_same_values(wrapped, plain, binding.__name__)
        # Still what the bindings take back, and a plain dict where one is asked for.
        assert type(dict(wrapped)) is dict
    # The name and docstring of the binding: help(ema.fit) and the stubs' signature check read them.
    assert ema.fit.__name__ == "fit" and ema.fit.__doc__ == ema._ema.fit.__doc__


def test_a_wrapped_result_goes_back_into_the_bindings(beam):
    fit, other = beam
    f = np.asarray(fit["frequency_hz"])
    np.testing.assert_array_equal(ema.synthesize(fit, f)["h"], ema.synthesize(dict(fit), f)["h"])
    assert ema.correlate(fit, other)["pairs"] == ema.correlate(dict(fit), dict(other))["pairs"]
    back = pickle.loads(pickle.dumps(fit))
    assert type(back) is ema.Result and list(back) == list(fit)
    np.testing.assert_array_equal(back["shapes"], fit["shapes"])


def test_to_jsonable_convention():
    # Complex as [re, im], every non-finite number as None (inside a pair too), numpy scalars as
    # Python's, tuples as lists, int keys as strings (as json.dumps writes them).
    given = {
        "shape": np.array([1.5 - 2.0j, complex(np.nan, 3.0)]),
        "matrix": np.array([[1.0, np.inf], [-np.inf, np.nan]]),
        "scalars": [np.float32(0.25), np.int64(7), np.bool_(True), np.complex128(1j), float("nan")],
        "dof": (101, "+Z"),
        "integers": np.array([[1, 2]], dtype=np.int32),
        7: None,
    }
    assert ema.to_jsonable(given) == {
        "shape": [[1.5, -2.0], [None, 3.0]],
        "matrix": [[1.0, None], [None, None]],
        "scalars": [0.25, 7, True, [0.0, 1.0], None],
        "dof": [101, "+Z"],
        "integers": [[1, 2]],
        "7": None,
    }
    out = ema.to_jsonable(given)
    assert type(out["scalars"][1]) is int and type(out["scalars"][2]) is bool
    with pytest.raises(TypeError, match=r"result\['nested'\]\[0\]: a object has no JSON form"):
        ema.to_jsonable({"nested": [object()]})
    with pytest.raises(TypeError, match="not a str"):
        ema.to_jsonable({(1, "+Z"): 1.0})


def strict_json(text):
    """json.loads that refuses NaN and Infinity tokens (not JSON, though Python's json writes them)."""
    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")
    return json.loads(text, parse_constant=refuse)


def test_fit_survives_a_json_round_trip(beam):
    fit, _ = beam
    back = strict_json(ema.to_json(fit))
    assert set(back) == set(fit)
    assert back["frequency_hz"] == fit["frequency_hz"].tolist()
    assert back["frequency_std_hz"] == fit["frequency_std_hz"].tolist()
    shapes = np.array(back["shapes"])  # (n_dofs, n_modes, 2)
    np.testing.assert_array_equal(shapes[..., 0] + 1j * shapes[..., 1], fit["shapes"])
    assert [tuple(d) for d in back["dofs"]] == fit["dofs"]
    assert back["stabilisation"] == fit["stabilisation"]  # already JSON: unchanged
    assert fit.to_json(indent=1) == ema.to_json(fit, indent=1)


def test_json_writes_nan_as_null(beam):
    # Real NaNs: a model's modes have no measured sigma; a synthesis is NaN outside the fitted band.
    modes = ema.model_modes(str(GUIDEWAY / "model.toml"), "stud-5um")
    back = strict_json(ema.to_json(modes))
    assert back["frequency_hz"] == modes["frequency_hz"].tolist()
    assert [v is None for v in back["frequency_std_hz"]] == np.isnan(modes["frequency_std_hz"]).tolist()
    fit, _ = beam
    lines = np.linspace(10.0, 400.0, 40)
    synthesis = ema.synthesize(fit, lines)
    h = strict_json(ema.to_json(synthesis))["h"]
    nulls = np.array([[[pair == [None, None] for pair in row] for row in ref] for ref in h])
    assert nulls.any() and (nulls == np.isnan(synthesis["h"])).all()


def test_mode_table_holds_the_fit(beam):
    fit, _ = beam
    table = ema.to_dataframe(fit)
    assert table.index.name == "mode" and table.index.tolist() == list(range(1, len(fit["frequency_hz"]) + 1))
    for column in ["frequency_hz", "damping_ratio", "frequency_std_hz", "damping_ratio_std", "mpc", "mpd_deg", "mcf",
                   "pole"]:
        assert table[column].tolist() == fit[column].tolist(), column
    assert table["order"].tolist() == fit["order"] and table["cluster_orders"].tolist() == fit["cluster_orders"]
    assert fit.to_dataframe().equals(table)


def test_pole_table_holds_the_stabilisation_diagram(beam):
    fit, _ = beam
    poles = ema.to_dataframe(fit, "poles")
    expected = [(entry["order"], pole["frequency_hz"], pole["label"], pole["physical"], complex(*pole["pole"]))
                for entry in fit["stabilisation"]["orders"] for pole in entry["poles"]]
    assert len(expected) > 0
    assert list(zip(poles["order"], poles["frequency_hz"], poles["label"], poles["physical"], poles["pole"])) == expected
    with pytest.raises(ValueError, match="no table 'poles'"):
        ema.to_dataframe(ema.fit(BEAM, **BEAM_FIT), "poles")


def test_pair_table_holds_the_correlation(beam):
    fit, other = beam
    corr = ema.correlate(fit, other)
    table = ema.to_dataframe(corr)
    assert len(table) == len(corr["pairs"]) > 0
    for key in corr["pairs"][0]:
        assert table[key].tolist() == [p[key] for p in corr["pairs"]], key
    # Mode numbers are 1-based: the MAC matrix at (test_mode - 1, model_mode - 1) is the pair's MAC.
    assert table["mac"].tolist() == [corr["mac"][t - 1, m - 1] for t, m in zip(table["test_mode"], table["model_mode"])]


def test_candidate_table_holds_the_diagnosis(guideway_diagnosis):
    d = guideway_diagnosis
    table = ema.to_dataframe(d)
    candidates = d["candidates"]
    assert table.index.name == "rank" and table.index.tolist() == [c["rank"] for c in candidates]
    assert table.index[0] == 1
    for key in ["kind", "target", "description", "probability", "mean_abs_frequency_error_pct", "mean_mac", "score"]:
        assert table[key].tolist() == [c[key] for c in candidates], key
    # Nested dicts as dotted columns: rank 1's stiffness of the series compliance and its 1 sigma.
    for name, value in candidates[0]["parameters"].items():
        assert table.loc[1, f"parameters.{name}"] == value
        assert table.loc[1, f"uncertainty.{name}"] == candidates[0]["uncertainty"][name]
    modes = ema.to_dataframe(d, "modes")
    assert modes["test_frequency_hz"].tolist() == [m["test_frequency_hz"] for m in d["modes"]]
    assert modes["test_mode"].tolist() == list(range(1, len(d["modes"]) + 1))


def test_quality_tables(beam):
    fit, _ = beam
    q = ema.quality(BEAM, modes=fit)
    frfs = ema.to_dataframe(q)
    assert len(frfs) == len(q["frfs"]) > 0
    assert frfs["response.node"].tolist() == [c["response"]["node"] for c in q["frfs"]]
    assert frfs["reference.dir"].tolist() == [c["reference"]["dir"] for c in q["frfs"]]
    modes = ema.to_dataframe(q, "modes")
    assert modes.index.tolist() == [m["mode"] for m in q["modes"]] == [1, 2, 3]
    assert modes["frequency_hz"].tolist() == fit["frequency_hz"].tolist()


def test_to_dataframe_refuses_what_has_no_table():
    frfs = ema.read_frfs(BEAM)
    with pytest.raises(ValueError, match="no table"):
        ema.to_dataframe(frfs)
    with pytest.raises(TypeError, match="expected an ema result"):
        ema.to_dataframe([1, 2])


def test_html_view_shows_the_rows(beam, guideway_diagnosis):
    fit, other = beam
    view = fit._repr_html_()
    assert f"{len(fit['frequency_hz'])} modes" in view
    for f in fit["frequency_hz"]:
        assert f"<td>{f:.6g}</td>" in view
    assert "poles" in view  # the other tables are named
    assert isinstance(guideway_diagnosis, ema.Result)
    view = guideway_diagnosis._repr_html_()
    best = guideway_diagnosis["candidates"][0]
    assert html.escape(best["description"]) in view and f"{100 * best['probability']:.1f} %" in view
    corr = ema.correlate(fit, other)
    assert f"mean MAC {corr['mean_mac']:.3f}" in corr._repr_html_()


def test_import_needs_neither_pandas_nor_matplotlib():
    # Lazy imports: `import ema` loads neither; without them, the functions that need one say which
    # package to install (the others work).
    code = ("import sys\n"
            "import ema\n"
            "print('matplotlib' in sys.modules, 'pandas' in sys.modules)\n"
            "sys.modules['pandas'] = None; sys.modules['matplotlib.pyplot'] = None\n"
            "for call in (lambda: ema.to_dataframe({'pairs': []}), lambda: ema.plot_mac([[1.0]])):\n"
            "    try:\n"
            "        call()\n"
            "    except ImportError as e:\n"
            "        print(e)\n"
            "print(ema.to_json({'mac': ema.mac([[1.0]], [[1.0]])}))\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == "False False"
    assert "python3-pandas" in lines[1] and "pip install pandas" in lines[1]
    assert "python3-matplotlib" in lines[2] and "pip install matplotlib" in lines[2]
    assert json.loads(lines[3]) == {"mac": [[1.0]]}
