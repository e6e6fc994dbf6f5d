"""ema: experimental modal analysis — impact-hammer tests to FRFs, PolyMAX modes, correlation with a
model, which physics the model misses, and data quality. The same C++ library as the `ema` command
line, on numpy arrays (the compiled core is ``ema._ema``; this package re-exports it).

Install (docs/python.md)::

    /usr/bin/python3 -m venv --system-site-packages v
    v/bin/pip install --no-build-isolation .

Every function has a docstring (``help(ema.diagnose)``) and a type stub (``ema/_ema.pyi``; the result
layouts as TypedDicts in ``ema.types``). fit, read_modes, model_modes, correlate, diagnose, plan,
run and quality return an ``ema.Result``: the binding's dict, unchanged, with ``to_dataframe()``, ``to_json()``
and an HTML view in notebooks. ``ema.to_json``/``ema.to_jsonable``/``ema.to_dataframe`` take any result;
``ema.plot_stabilisation``, ``ema.plot_frf`` and ``ema.plot_mac`` draw them (matplotlib, imported
when a plot is made).
"""
from . import _ema
from ._ema import (
    InputError,
    UsageError,
    __version__,
    estimate_frfs,
    mac,
    mode_indicators,
    read_frfs,
    read_uff,
    synthesize,
    write_frfs,
    write_modes,
)
from .plot import plot_frf, plot_mac, plot_stabilisation
from .results import Result, returning_result, to_dataframe, to_json, to_jsonable

# The functions whose results have rows (modes, pairs, candidates, checks) return a Result: the same
# dict with table and JSON methods. FRF dicts and mode indicators stay plain dicts (to_json takes them).
fit = returning_result(_ema.fit)
read_modes = returning_result(_ema.read_modes)
model_modes = returning_result(_ema.model_modes)
correlate = returning_result(_ema.correlate)
diagnose = returning_result(_ema.diagnose)
plan = returning_result(_ema.plan)
run = returning_result(_ema.run)
quality = returning_result(_ema.quality)

__doc__ = (_ema.__doc__ or "") + "\n\n" + __doc__.split("\n\n", 1)[1]

__all__ = [
    "InputError",
    "UsageError",
    "__version__",
    "correlate",
    "diagnose",
    "estimate_frfs",
    "fit",
    "mac",
    "mode_indicators",
    "model_modes",
    "plan",
    "quality",
    "read_frfs",
    "read_modes",
    "read_uff",
    "run",
    "synthesize",
    "write_frfs",
    "write_modes",
    # pure Python (results.py, plot.py)
    "Result",
    "to_dataframe",
    "to_json",
    "to_jsonable",
    "plot_stabilisation",
    "plot_frf",
    "plot_mac",
]
