"""ema: experimental modal analysis — impact-hammer tests to FRFs, PolyMAX modes, correlation with a
model, which physics the model misses, and data quality. The same C++ library as the `ema` command
line, on numpy arrays (the compiled core is ``ema._ema``; this package re-exports it).

Install (docs/python.md)::

    /usr/bin/python3 -m venv --system-site-packages v
    v/bin/pip install --no-build-isolation .

Every function has a docstring (``help(ema.diagnose)``) and a type stub (``ema/_ema.pyi``).
"""
from . import _ema
from ._ema import (
    InputError,
    UsageError,
    __version__,
    correlate,
    diagnose,
    estimate_frfs,
    fit,
    mac,
    mode_indicators,
    model_modes,
    quality,
    read_frfs,
    read_modes,
    synthesize,
)

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
    "quality",
    "read_frfs",
    "read_modes",
    "synthesize",
]
