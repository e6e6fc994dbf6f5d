"""ema.plot_stabilisation, ema.plot_frf and ema.plot_mac (issue 41) on the Agg backend: what is drawn
is the data given (the poles per order, the FRFs and their synthesis, the MAC values)."""
import collections
import warnings

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib", reason="python3-matplotlib (scripts/install-deps.sh --test)")
matplotlib.use("Agg")  # headless: before pyplot is imported
import matplotlib.pyplot as plt  # noqa: E402

import ema  # noqa: E402
from conftest import SOURCE  # noqa: E402

BEAM = str(SOURCE / "samples" / "meas-point")


@pytest.fixture(scope="module")
def beam():
    """The measured beam fitted with its stabilisation diagram (its FRFs, the fit, a second fit)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the beam's negative modal mass, in 'warnings'
        fit = ema.fit(BEAM, band=(30.0, 300.0), order_max=40, stabilisation=True)
        other = ema.fit(BEAM, band=(20.0, 400.0), order_max=30)
    return ema.read_frfs(BEAM), fit, other


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def lines_by_gid(figure):
    found = collections.defaultdict(list)
    for ax in figure.axes:
        for line in ax.get_lines():
            found[line.get_gid()].append(line)
    return found


def test_stabilisation_diagram_draws_every_pole_of_every_order(beam):
    _, fit, _ = beam
    figure = ema.plot_stabilisation(fit)
    lines = lines_by_gid(figure)
    poles = [(p["frequency_hz"], entry["order"], p["label"], p["physical"])
             for entry in fit["stabilisation"]["orders"] for p in entry["poles"]]
    drawn = [(x, y, gid) for gid, group in lines.items() if gid.startswith("poles:")
             for line in group for x, y in zip(line.get_xdata(), line.get_ydata())]
    # Every pole once, at (frequency, order).
    assert sorted((x, y) for x, y, _ in drawn) == sorted((f, n) for f, n, _, _ in poles)
    # Stable (label 's', physical) filled; the non-physical apart whatever their label.
    stable = lines["poles:stable"][0]
    assert sorted(zip(stable.get_xdata(), stable.get_ydata())) == \
        sorted((f, n) for f, n, label, physical in poles if label == "s" and physical)
    non_physical = lines["poles:non-physical"][0]
    assert sorted(zip(non_physical.get_xdata(), non_physical.get_ydata())) == \
        sorted((f, n) for f, n, _, physical in poles if not physical)
    # The fitted modes as vertical lines, the sum of |FRF| on the second axis, the band as the x range.
    assert sorted(line.get_xdata()[0] for line in lines["mode"]) == sorted(fit["frequency_hz"].tolist())
    sum_frf = np.array(fit["stabilisation"]["sum_frf"])
    (curve,) = lines["sum_frf"]
    np.testing.assert_array_equal(curve.get_xdata(), sum_frf[:, 0])
    np.testing.assert_array_equal(curve.get_ydata(), sum_frf[:, 1])
    assert curve.axes.get_yscale() == "log" and curve.axes is not stable.axes
    assert stable.axes.get_xlim() == tuple(fit["stabilisation"]["band_hz"])
    assert stable.axes.get_ylabel() == "model order"


def test_stabilisation_needs_the_diagram(beam):
    _, _, other = beam
    with pytest.raises(ValueError, match="stabilisation=True"):
        ema.plot_stabilisation(other)


def test_stabilisation_on_given_axes_without_the_sum(beam):
    _, fit, _ = beam
    figure, ax = plt.subplots()
    assert ema.plot_stabilisation(fit, ax=ax, sum_frf=False) is figure
    assert figure.axes == [ax] and "sum_frf" not in lines_by_gid(figure)


def test_frf_plot_draws_the_measured_frfs_and_the_synthesis(beam):
    frfs, fit, _ = beam
    figure = ema.plot_frf(frfs, fit)
    magnitude_ax, phase_ax = figure.axes
    lines = lines_by_gid(figure)
    h, f = frfs["h"], frfs["frequency_hz"]
    synthesis = ema.synthesize(fit, f)
    names = [(i, o, f"{out[0]}{out[1]}/{ref[0]}{ref[1]}")
             for i, ref in enumerate(frfs["references"]) for o, out in enumerate(frfs["outputs"])]
    assert len([g for g in lines if g.startswith("frf:")]) == len(names) == h.shape[0] * h.shape[2]
    for i, o, name in names:
        magnitude, phase = lines[f"frf:{name}"]
        assert magnitude.axes is magnitude_ax and phase.axes is phase_ax
        np.testing.assert_array_equal(magnitude.get_xdata(), f)
        np.testing.assert_array_equal(magnitude.get_ydata(), np.abs(h[i, :, o]))
        np.testing.assert_array_equal(phase.get_ydata(), np.angle(h[i, :, o], deg=True))
        # The synthesis of the same FRF (matched by its DOFs), NaN outside the fitted band.
        si = synthesis["references"].index(frfs["references"][i])
        so = synthesis["outputs"].index(frfs["outputs"][o])
        model_magnitude, _ = lines[f"synthesis:{name}"]
        np.testing.assert_array_equal(model_magnitude.get_ydata(), np.abs(synthesis["h"][si, :, so]))
        assert model_magnitude.get_color() == magnitude.get_color() and model_magnitude.get_linestyle() == "--"
    assert magnitude_ax.get_yscale() == "log"
    assert sorted({line.get_xdata()[0] for line in lines["mode"]}) == sorted(fit["frequency_hz"].tolist())


def test_frf_plot_selects_dofs_and_takes_given_axes(beam):
    frfs, fit, _ = beam
    figure, ax = plt.subplots()
    # A path and a mode set without a modal model (its first mode): the mode's line, no synthesis;
    # one Axes: the magnitude only.
    first_mode = {"frequency_hz": fit["frequency_hz"][:1]}
    assert ema.plot_frf(BEAM, first_mode, ax=ax, responses=["1+X"], references=[(2, "+X")]) is figure
    assert figure.axes == [ax]
    lines = lines_by_gid(figure)
    assert sorted(g for g in lines if g.startswith(("frf:", "synthesis:"))) == ["frf:1+X/2+X"]
    i, o = frfs["references"].index((2, "+X")), frfs["outputs"].index((1, "+X"))
    np.testing.assert_array_equal(lines["frf:1+X/2+X"][0].get_ydata(), np.abs(frfs["h"][i, :, o]))
    assert [line.get_xdata()[0] for line in lines["mode"]] == first_mode["frequency_hz"].tolist()
    with pytest.raises(ValueError, match="no FRF"):
        ema.plot_frf(frfs, responses=["99+Z"])


def test_mac_heat_map_shows_the_correlation(beam):
    _, fit, other = beam
    corr = ema.correlate(fit, other)
    figure = ema.plot_mac(corr)
    ax = figure.axes[0]
    (image,) = ax.get_images()
    np.testing.assert_array_equal(image.get_array(), corr["mac"])
    n_test, n_model = corr["mac"].shape
    # Each cell annotated with its value; mode numbers from 1 on both axes.
    assert [t.get_text() for t in ax.texts] == [f"{v:.2f}" for v in corr["mac"].ravel()]
    assert [t.get_text() for t in ax.get_yticklabels()] == [str(k) for k in range(1, n_test + 1)]
    assert [t.get_text() for t in ax.get_xticklabels()] == [str(k) for k in range(1, n_model + 1)]
    assert (ax.get_ylabel(), ax.get_xlabel()) == ("test mode", "model mode")
    # The pairs framed on their cells (1-based numbers: the cell of index number - 1).
    frames = sorted((p.get_x() + 0.5, p.get_y() + 0.5) for p in ax.patches if p.get_gid() == "pair")
    assert frames == sorted((p["model_mode"] - 1, p["test_mode"] - 1) for p in corr["pairs"])


def test_mac_heat_map_of_a_matrix(beam, tmp_path):
    _, fit, other = beam
    matrix = ema.mac(fit["shapes"], other["shapes"][:, :2])  # 3 test modes x 2 model modes
    figure, ax = plt.subplots()
    assert ema.plot_mac(matrix, ax=ax, labels=("mode", "mode")) is figure
    (image,) = ax.get_images()
    assert image.get_array().shape == (3, 2)
    np.testing.assert_array_equal(image.get_array(), matrix)
    assert [t.get_text() for t in ax.get_yticklabels()] == ["1", "2", "3"]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["1", "2"]
    # Text position (column, row) = (model, test): the value of that cell.
    for text in ax.texts:
        column, row = text.get_position()
        assert text.get_text() == f"{matrix[row, column]:.2f}"
    assert not [p for p in ax.patches if p.get_gid() == "pair"]
    figure.savefig(tmp_path / "mac.png")
    assert (tmp_path / "mac.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="2-D"):
        ema.plot_mac(np.ones(3))
