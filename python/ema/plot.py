"""Plots of ema's results on matplotlib (docs/python.md, "Plots"): the stabilisation diagram, FRFs with
the fitted model's synthesis, a MAC matrix. matplotlib is imported when a plot is made, not by
``import ema``. Each function draws on ``ax`` when given (its figure is returned), otherwise on a new
pyplot figure, and returns the Figure; headless with the Agg backend (``matplotlib.use("Agg")``).

The artists carry gids, so that scripts and tests can find what was drawn: ``poles:stable``,
``poles:partly stable``, ``poles:unstable``, ``poles:non-physical``, ``mode`` (a fitted mode's line),
``sum_frf``; ``frf:RESPONSE/REFERENCE`` and ``synthesis:RESPONSE/REFERENCE``; ``mac`` (the image),
``pair`` (a paired cell's frame).
"""
from __future__ import annotations

import math
import os
import re
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _ema
from .results import stabilisation_poles

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["plot_stabilisation", "plot_frf", "plot_mac"]

# The report's stabilisation diagram (app/report/report.js): the same groups, markers and colours.
POLE_GROUPS: Dict[str, Dict[str, Any]] = {
    "stable": {"label": "stable (frequency, damping, vector)", "marker": "o", "color": "#1b7837", "filled": True},
    "partly stable": {"label": "stable in frequency (and damping or vector)", "marker": "D", "color": "#4393c3",
                      "filled": False},
    "unstable": {"label": "new or unstable", "marker": "o", "color": "#d6604d", "filled": False},
    "non-physical": {"label": "non-physical", "marker": "x", "color": "#999999", "filled": True},
}
MODE_COLOR = "#2166ac"
SUM_FRF_COLOR = "#888888"
QUANTITY_FRF = {"acceleration": "accelerance", "velocity": "mobility", "displacement": "receptance"}
ANNOTATE_MAX_MODES = 20  # beyond that, MAC values in the cells are unreadable


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as pyplot
    except ImportError as error:
        raise ImportError("ema's plots need matplotlib: apt-get install python3-matplotlib (Debian), "
                          "or pip install matplotlib") from error
    return pyplot


def _new_axes(rows: int = 1, **subplots: Any) -> Tuple[Figure, Any]:
    # Constrained layout: labels, colour bar and legend inside the saved image, whatever its size.
    figure, axes = _pyplot().subplots(rows, 1, constrained_layout=True, **subplots)
    return figure, axes


def pole_group(label: str, physical: bool) -> str:
    """Which of POLE_GROUPS a pole of the diagram belongs to (label 's', 'd', 'v', 'f' or 'o')."""
    if not physical:
        return "non-physical"
    return {"s": "stable", "d": "partly stable", "v": "partly stable", "f": "partly stable"}.get(label, "unstable")


def plot_stabilisation(fit_result: Mapping[str, Any], ax: Optional[Axes] = None, *, sum_frf: bool = True) -> Figure:
    """The stabilisation diagram of ``ema.fit(..., stabilisation=True)``: every pole of every model
    order (frequency on x, order on y) marked by its stability, as the HTML report draws it; the fitted
    modes as dashed vertical lines; with ``sum_frf`` the sum of the FRF magnitudes on a second, log
    axis. Returns the Figure."""
    poles = stabilisation_poles(fit_result)  # ValueError without the diagram
    stabilisation = fit_result["stabilisation"]
    figure, ax = _new_axes(figsize=(9, 6)) if ax is None else (ax.figure, ax)
    for group, style in POLE_GROUPS.items():
        members = [p for p in poles if pole_group(p["label"], p["physical"]) == group]
        if not members:
            continue
        ax.plot([p["frequency_hz"] for p in members], [p["order"] for p in members], linestyle="none",
                marker=style["marker"], markersize=5, color=style["color"],
                markerfacecolor=style["color"] if style["filled"] else "none", label=style["label"],
                gid=f"poles:{group}")
    for i, frequency in enumerate(np.asarray(fit_result["frequency_hz"], dtype=float)):
        ax.axvline(frequency, color=MODE_COLOR, linestyle="--", linewidth=1, gid="mode",
                   label="fitted modes" if i == 0 else None)
    lo, hi = stabilisation["band_hz"]
    if hi > lo:
        ax.set_xlim(lo, hi)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("model order")
    handles, labels = ax.get_legend_handles_labels()
    if sum_frf and stabilisation.get("sum_frf"):
        curve = np.asarray(stabilisation["sum_frf"], dtype=float)
        twin = ax.twinx()
        twin.semilogy(curve[:, 0], curve[:, 1], color=SUM_FRF_COLOR, linewidth=1, label="sum of |FRF|", gid="sum_frf")
        twin.set_ylabel("sum of |FRF|")
        # The poles above the curve: the first axes drawn last, with a see-through background.
        ax.set_zorder(twin.get_zorder() + 1)
        ax.patch.set_visible(False)
        more_handles, more_labels = twin.get_legend_handles_labels()
        handles, labels = handles + more_handles, labels + more_labels
    # Below the diagram: inside it, the legend would hide the poles of the highest orders.
    ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3, fontsize="small")
    ax.set_title(f"Stabilisation diagram: {len(fit_result['frequency_hz'])} modes")
    return figure


Dof = Tuple[int, str]
DofLike = Union[Tuple[int, str], str]


def _dof(value: DofLike) -> Dof:
    """(101, '+Z') from (101, '+Z') or '101+Z'."""
    if isinstance(value, str):
        match = re.fullmatch(r"\s*(\d+)\s*([+-]R?[XYZ])\s*", value.upper())
        if not match:
            raise ValueError(f"'{value}': expected a DOF like '101+Z'")
        return int(match.group(1)), match.group(2)
    node, direction = value  # a (node, direction) pair, or a list of the two
    return int(node), str(direction)


def _dof_name(dof: Dof) -> str:
    return f"{dof[0]}{dof[1]}"


def _mode_frequencies(modes: Mapping[str, Any]) -> List[float]:
    if "frequency_hz" in modes:
        return [float(f) for f in np.atleast_1d(modes["frequency_hz"])]
    return [float(m["frequency_hz"]) for m in modes.get("modes", [])]  # MODES.json's layout


def plot_frf(frfs: Union[str, "os.PathLike[str]", Mapping[str, Any]], modes_or_fit: Optional[Mapping[str, Any]] = None,
             ax: Union[Axes, Sequence[Axes], None] = None, *, responses: Optional[Sequence[DofLike]] = None,
             references: Optional[Sequence[DofLike]] = None) -> Figure:
    """Measured FRFs: magnitude (log) over phase (degrees), one curve per response/reference pair
    (``responses``/``references`` as (101, '+Z') or '101+Z' select some; default all). With
    ``modes_or_fit``: its modes as dotted vertical lines, and for a fit made with stabilisation=True
    the synthesis of its modal model (ema.synthesize at the measured lines) dashed over each FRF it
    holds. ``frfs``: an FRF dict or a path ema.read_frfs reads. ``ax``: two Axes (magnitude, phase), or
    one (magnitude only). Returns the Figure."""
    data = _ema.read_frfs(frfs) if isinstance(frfs, (str, os.PathLike)) else frfs
    frequency = np.asarray(data["frequency_hz"], dtype=float)
    h = np.asarray(data["h"])
    outputs = [_dof(d) for d in data["outputs"]]
    inputs = [_dof(d) for d in data["references"]]
    if h.shape != (len(inputs), len(frequency), len(outputs)):
        raise ValueError(f"frfs['h']: shape {h.shape}, expected (references, lines, outputs) = "
                         f"({len(inputs)}, {len(frequency)}, {len(outputs)})")
    wanted_outputs = None if responses is None else {_dof(d) for d in responses}
    wanted_inputs = None if references is None else {_dof(d) for d in references}
    curves = [(i, o) for i, ref in enumerate(inputs) for o, out in enumerate(outputs)
              if (wanted_inputs is None or ref in wanted_inputs) and (wanted_outputs is None or out in wanted_outputs)]
    if not curves:
        raise ValueError("plot_frf: no FRF of these responses and references")

    if ax is None:
        figure, (magnitude_ax, phase_ax) = _new_axes(2, sharex=True, figsize=(9, 6),
                                                     gridspec_kw={"height_ratios": [2, 1]})
    elif isinstance(ax, (Sequence, np.ndarray)):  # (magnitude, phase), as plt.subplots(2) gives them
        magnitude_ax, phase_ax = ax
        figure = magnitude_ax.figure
    else:
        magnitude_ax, phase_ax, figure = ax, None, ax.figure

    synthesis: Dict[Tuple[Dof, Dof], npt.NDArray[np.complex128]] = {}
    if modes_or_fit is not None and modes_or_fit.get("modal_model"):
        synthesised = _ema.synthesize(modes_or_fit, frequency)
        syn_h = np.asarray(synthesised["h"])
        for i, ref in enumerate(_dof(d) for d in synthesised["references"]):
            for o, out in enumerate(_dof(d) for d in synthesised["outputs"]):
                synthesis[(out, ref)] = syn_h[i, :, o]

    for i, o in curves:
        name = f"{_dof_name(outputs[o])}/{_dof_name(inputs[i])}"
        values = h[i, :, o]
        line, = magnitude_ax.semilogy(frequency, np.abs(values), linewidth=1, label=name, gid=f"frf:{name}")
        if phase_ax is not None:
            phase_ax.plot(frequency, np.angle(values, deg=True), linewidth=1, color=line.get_color(), gid=f"frf:{name}")
        model = synthesis.get((outputs[o], inputs[i]))
        if model is not None:
            magnitude_ax.semilogy(frequency, np.abs(model), linestyle="--", linewidth=1.2, color=line.get_color(),
                                  label=f"{name} synthesis", gid=f"synthesis:{name}")
            if phase_ax is not None:
                phase_ax.plot(frequency, np.angle(model, deg=True), linestyle="--", linewidth=1.2,
                              color=line.get_color(), gid=f"synthesis:{name}")
    if modes_or_fit is not None:
        for k, frequency_hz in enumerate(_mode_frequencies(modes_or_fit)):
            for target in (magnitude_ax, phase_ax):
                if target is not None:
                    target.axvline(frequency_hz, color=MODE_COLOR, linestyle=":", linewidth=1, gid="mode",
                                   label="modes" if k == 0 and target is magnitude_ax else None)

    kind = QUANTITY_FRF.get(str(data.get("quantity", "")), "FRF")
    magnitude_ax.set_ylabel(f"|H| ({kind})")
    magnitude_ax.set_title("FRFs (response/reference)" + (" and the fit's synthesis (dashed)" if synthesis else ""))
    if len(curves) <= 10:
        magnitude_ax.legend(fontsize="small")
    if phase_ax is not None:
        phase_ax.set_ylabel("phase (deg)")
        phase_ax.set_ylim(-180, 180)
        phase_ax.set_yticks([-180, -90, 0, 90, 180])
        phase_ax.set_xlabel("frequency (Hz)")
    else:
        magnitude_ax.set_xlabel("frequency (Hz)")
    return figure


def plot_mac(mac_matrix_or_correlation: Union[Mapping[str, Any], Any], ax: Optional[Axes] = None, *,
             annotate: Optional[bool] = None, labels: Tuple[str, str] = ("test mode", "model mode")) -> Figure:
    """A MAC matrix as a heat map (0 white .. 1 dark), rows the test modes and columns the model modes,
    both numbered from 1 as everywhere in ema; each cell annotated with its value (``annotate``: None =
    up to 20 modes each way). Takes a matrix (ema.mac) or what ema.correlate returns, whose pairs are
    framed. ``labels``: the rows' and the columns' axis labels (("mode", "mode") for an auto-MAC).
    Returns the Figure."""
    pairs: Sequence[Mapping[str, Any]] = []
    if isinstance(mac_matrix_or_correlation, Mapping):
        if "mac" not in mac_matrix_or_correlation:
            raise ValueError("plot_mac: expected a MAC matrix or what ema.correlate returns (a dict with 'mac')")
        matrix = np.asarray(mac_matrix_or_correlation["mac"], dtype=float)
        pairs = mac_matrix_or_correlation.get("pairs", [])
    else:
        matrix = np.asarray(mac_matrix_or_correlation, dtype=float)
    if matrix.ndim != 2 or 0 in matrix.shape:
        raise ValueError(f"plot_mac: expected a 2-D MAC matrix (test modes x model modes), got shape {matrix.shape}")
    n_test, n_model = matrix.shape
    size = (max(4.0, 1.8 + 0.55 * n_model), max(3.2, 1.4 + 0.5 * n_test))
    figure, ax = _new_axes(figsize=size) if ax is None else (ax.figure, ax)
    image = ax.imshow(matrix, cmap="Blues", vmin=0.0, vmax=1.0, interpolation="nearest", gid="mac")
    figure.colorbar(image, ax=ax, label="MAC")
    if annotate is None:
        annotate = max(n_test, n_model) <= ANNOTATE_MAX_MODES
    if annotate:
        for r in range(n_test):
            for c in range(n_model):
                value = matrix[r, c]
                ax.text(c, r, f"{value:.2f}" if math.isfinite(value) else "–", ha="center", va="center",
                        fontsize="small", color="white" if value > 0.6 else "black")
    for pair in pairs:  # 1-based mode numbers: the matrix's indices plus one
        ax.add_patch(_pair_frame((pair["model_mode"] - 1.5, pair["test_mode"] - 1.5)))
    for axis, n, label in ((ax.yaxis, n_test, labels[0]), (ax.xaxis, n_model, labels[1])):
        step = max(1, math.ceil(n / 30))  # at most ~30 tick labels
        ticks = list(range(0, n, step))
        axis.set_ticks(ticks)
        axis.set_ticklabels([str(t + 1) for t in ticks])
        axis.set_label_text(label)
    ax.set_title("MAC")
    return figure


def _pair_frame(corner: Tuple[float, float]) -> Any:
    """The frame around a paired cell, from its lower-left corner in data coordinates."""
    from matplotlib.patches import Rectangle

    return Rectangle(corner, 1.0, 1.0, fill=False, edgecolor="#d6604d", linewidth=2, gid="pair")
