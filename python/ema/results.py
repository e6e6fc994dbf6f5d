"""Results as JSON and as tables (docs/python.md, "Results: JSON, tables, notebooks").

The bindings return plain dicts of numpy arrays, lists and numbers. ``to_jsonable``/``to_json`` turn any
of them into JSON; ``to_dataframe`` gives a pandas DataFrame of a result's rows (modes, pairs,
candidates, FRF checks); ``Result`` is the dict the package's functions return, with the three as
methods and an HTML view for notebooks.

JSON convention (the CLI's JSON files use the same): a complex number is an ``[re, im]`` pair (a
complex array: nested lists whose innermost items are those pairs); a number that is not finite
(NaN, ±inf) is ``null``, in a pair too; tuples are lists (a DOF ``(101, '+Z')`` is ``[101, "+Z"]``);
numpy scalars are plain numbers. Mode numbers and ranks stay as the result holds them: 1-based.
"""
from __future__ import annotations

import functools
import html
import json
import math
import os
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Optional, Tuple, TypeVar, cast

import numpy as np

if TYPE_CHECKING:
    import pandas

__all__ = ["Result", "to_json", "to_jsonable", "to_dataframe", "tables"]

# The per-mode arrays of a mode set, in the order a table shows them (those present are taken).
MODE_COLUMNS = ("frequency_hz", "damping_ratio", "frequency_std_hz", "damping_ratio_std", "mpc", "mpd_deg", "mcf",
                "order", "cluster_orders", "pole")


# --- JSON ------------------------------------------------------------------------------------------


def to_jsonable(result: Any) -> Any:
    """Any ema result (nested dicts and lists of numpy arrays, complex numbers, numpy scalars) as data
    json.dumps writes as strict JSON: a complex number as an ``[re, im]`` pair, a NaN or ±inf as None
    (null), a tuple or an array as a list. Raises TypeError naming the key path of a value that has no
    JSON form."""
    return _jsonable(result, "result")


def to_json(result: Any, **json_kwargs: Any) -> str:
    """Any ema result as a JSON string, in to_jsonable's convention (``json_kwargs`` go to json.dumps,
    e.g. ``indent=1``). The string is strict JSON: no NaN or Infinity tokens."""
    json_kwargs.setdefault("allow_nan", False)
    return json.dumps(to_jsonable(result), **json_kwargs)


def _finite_or_none(value: float) -> Optional[float]:
    return value if math.isfinite(value) else None


def _jsonable(value: Any, where: str) -> Any:
    # bool before int: bool is an int subclass, and numpy's bool_ is neither.
    if value is None or isinstance(value, (str, bool)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return _finite_or_none(float(value))
    if isinstance(value, (complex, np.complexfloating)):
        c = complex(value)
        return [_finite_or_none(c.real), _finite_or_none(c.imag)]
    if isinstance(value, np.ndarray):
        return _array_jsonable(value, where)
    if isinstance(value, Mapping):
        return {_json_key(k, where): _jsonable(v, f"{where}[{k!r}]") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{where}: a {type(value).__name__} has no JSON form")


def _array_jsonable(array: np.ndarray[Any, Any], where: str) -> Any:
    # Whole arrays at once: an FRF set holds millions of numbers.
    if np.iscomplexobj(array):
        array = np.stack([array.real, array.imag], axis=-1)  # the innermost axis: [re, im]
    if array.dtype.kind == "f":
        cells = array.astype(object)
        cells[~np.isfinite(array)] = None
        return cells.tolist()
    if array.dtype.kind in "biu":
        return array.tolist()
    return _jsonable(array.tolist(), where)  # object arrays: item by item


def _json_key(key: Any, where: str) -> str:
    if isinstance(key, str):
        return key
    if isinstance(key, (int, np.integer)) and not isinstance(key, (bool, np.bool_)):
        return str(int(key))
    raise TypeError(f"{where}: the key {key!r} is not a str (JSON object keys are strings)")


# --- Tables ----------------------------------------------------------------------------------------

Row = Dict[str, Any]


def _is_mode_set(result: Mapping[str, Any]) -> bool:
    """A modes dict of arrays (fit, read_modes, model_modes): not MODES.json's layout, not FRFs."""
    return isinstance(result.get("frequency_hz"), np.ndarray) and ("damping_ratio" in result or "shapes" in result)


def _row_tables(result: Mapping[str, Any]) -> List[str]:
    """The keys of ``result`` holding a list of dicts: each is a table of one row per item."""
    return [k for k, v in result.items() if isinstance(v, list) and v and all(isinstance(x, Mapping) for x in v)]


def tables(result: Mapping[str, Any]) -> List[str]:
    """The names ``to_dataframe(result, table=...)`` takes, the default first: 'modes' (a mode set's
    per-mode arrays), 'poles' (the stabilisation diagram's poles of a fit with stabilisation=True), and
    every key holding a list of dicts ('pairs', 'candidates', 'frfs', ...)."""
    names = []
    default = _default_table(result)
    if default:
        names.append(default)
    if _is_mode_set(result):
        names.append("modes")
        if result.get("stabilisation"):
            names.append("poles")
    names += _row_tables(result)
    return list(dict.fromkeys(names))  # first occurrence kept, in order


def _default_table(result: Mapping[str, Any]) -> Optional[str]:
    for key in ("candidates", "pairs"):  # diagnose, correlate
        if key in result:
            return key
    if "driving_points" in result:  # quality: the checks per FRF
        return "frfs"
    if _is_mode_set(result) or isinstance(result.get("modes"), list):  # a mode set, or MODES.json's layout
        return "modes"
    row_tables = _row_tables(result)
    return row_tables[0] if row_tables else None


def stabilisation_poles(fit_result: Mapping[str, Any]) -> List[Row]:
    """The poles of ``fit(..., stabilisation=True)``'s diagram, one row per pole and order:
    order, frequency_hz, damping_ratio, label ('s' stable ... 'o' new or unstable), physical, pole
    (complex, rad/s). Raises ValueError for a fit without the diagram."""
    stabilisation = fit_result.get("stabilisation")
    if not stabilisation:
        raise ValueError("the fit has no stabilisation diagram: fit with ema.fit(..., stabilisation=True) "
                         "(method='polymax')")
    return [{"order": entry["order"], "frequency_hz": pole["frequency_hz"], "damping_ratio": pole["damping_ratio"],
             "label": pole["label"], "physical": pole["physical"], "pole": complex(*pole["pole"])}
            for entry in stabilisation["orders"] for pole in entry["poles"]]


def _mode_rows(result: Mapping[str, Any]) -> List[Row]:
    frequencies = result["frequency_hz"]
    n = len(frequencies)
    # Only what has one value per mode (a result may carry other lists of that length by chance: dofs).
    columns = [c for c in MODE_COLUMNS if c in result and _has_length(result[c], n)]
    return [{"mode": i + 1, **{c: _scalar(result[c][i]) for c in columns}} for i in range(n)]


def _has_length(value: Any, n: int) -> bool:
    return isinstance(value, (list, np.ndarray)) and np.ndim(value) == 1 and len(value) == n


def _scalar(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value


def _flatten(item: Mapping[str, Any], prefix: str = "") -> Row:
    """A row of a list-of-dicts table: nested dicts as dotted columns (response.node, parameters.k)."""
    row: Row = {}
    for key, value in item.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            row.update(_flatten(value, name + "."))
        else:
            row[name] = value
    return row


# The columns that say which row it is come first (the bindings' JSON parts hold their keys sorted).
LEADING_COLUMNS = ("mode", "rank", "setup", "test_mode", "model_mode", "order", "kind", "target", "description",
                   "probability", "response.node", "response.dir", "reference.node", "reference.dir", "dof.node",
                   "dof.dir", "i.node", "i.dir", "j.node", "j.dir", "verdict", "frequency_hz")


def _leading_first(row: Row) -> Row:
    first = {c: row[c] for c in LEADING_COLUMNS if c in row}
    return {**first, **{c: v for c, v in row.items() if c not in first}}


def table_rows(result: Mapping[str, Any], table: Optional[str] = None) -> Tuple[str, List[Row]]:
    """The rows of one table of ``result`` as dicts (``tables(result)`` names them; None: the default)."""
    if not isinstance(result, Mapping):
        raise TypeError(f"expected an ema result (a dict), got {type(result).__name__}")
    available = tables(result)
    name = table if table is not None else (available[0] if available else None)
    if name is None or name not in available:
        what = f"no table '{name}'" if name is not None else "no table"
        raise ValueError(f"this result has {what}; it has: {', '.join(available) or 'none'} "
                         "(to_dataframe takes mode sets, fits, correlate, diagnose and quality results)")
    if name == "modes" and _is_mode_set(result):
        return name, _mode_rows(result)
    if name == "poles":
        return name, stabilisation_poles(result)
    return name, [_leading_first(_flatten(item)) for item in result[name]]


def _pandas() -> Any:
    try:
        import pandas
    except ImportError as error:
        raise ImportError("ema.to_dataframe needs pandas: apt-get install python3-pandas (Debian), "
                          "or pip install pandas") from error
    return pandas


# The column that numbers a table's rows from 1, made its index (mode sets, quality's modes; candidates).
INDEX_COLUMNS = ("mode", "rank")


def to_dataframe(result: Mapping[str, Any], table: Optional[str] = None) -> pandas.DataFrame:
    """A pandas DataFrame of one table of a result, one row per item:

    - a mode set (fit, read_modes, model_modes): one row per mode, indexed by the 1-based mode number,
      columns frequency_hz, damping_ratio, the 1-sigma columns, mpc, mpd_deg, mcf (fit: order,
      cluster_orders), pole (complex); ``table='poles'``: the stabilisation diagram's poles
      (fit(..., stabilisation=True)); ``table='dropped'``: the poles the fit dropped;
    - correlate: one row per pair (test_mode, model_mode 1-based, frequencies, agreement_pct, mac, ...);
    - diagnose: one row per candidate, indexed by rank (nested dicts as dotted columns:
      parameters.k, uncertainty.k, model_error.shape); ``table='modes'``: every test mode before and
      after rank 1; also 'groups', 'steps', 'effect_probabilities';
    - quality: one row per FRF (response.node, response.dir, ...); also 'driving_points',
      'reciprocity', 'modes'.

    Lists inside a row (a candidate's effects) stay lists. Needs pandas (imported here, not by
    ``import ema``)."""
    pd = _pandas()
    _, rows = table_rows(result, table)
    frame = pd.DataFrame(rows)
    for column in INDEX_COLUMNS:
        if column in frame.columns and frame[column].is_unique:
            return frame.set_index(column)
    return frame


# --- HTML (notebooks) ------------------------------------------------------------------------------

HTML_MAX_ROWS = 30


def _cell(value: Any) -> str:
    if value is None:
        return "–"
    if isinstance(value, (float, np.floating)):
        return f"{value:.6g}"
    if isinstance(value, (complex, np.complexfloating)):
        return f"{value.real:.6g}{value.imag:+.6g}j"
    if isinstance(value, (list, tuple)) and len(value) > 4:
        return f"[{len(value)} items]"
    return str(value)


def _summary(result: Mapping[str, Any]) -> str:
    """One line: what the result is and its headline numbers."""
    if "candidates" in result:
        candidates = result["candidates"]
        if not candidates:
            return "ema.diagnose: no candidate"
        best = candidates[0]
        probability = best.get("probability")
        share = f" ({100 * probability:.1f} %)" if probability is not None else ""
        return f"ema.diagnose: {len(candidates)} candidates; rank 1{share}: {best.get('description', '')}"
    if "pairs" in result:
        return (f"ema.correlate: {len(result['pairs'])} pairs, mean MAC {result.get('mean_mac', math.nan):.3f}, "
                f"mean agreement {result.get('mean_agreement_pct', math.nan):.2f} %")
    if "driving_points" in result:
        return f"ema.quality: verdict {result.get('verdict')}, {result.get('warnings')} warnings"
    if _is_mode_set(result):
        text = f"{len(result['frequency_hz'])} modes"
        if "synthesis_error" in result:
            text = f"ema.fit: {text}, synthesis error {result['synthesis_error']:.3g}"
            if result.get("warnings"):
                text += f", {len(result['warnings'])} warnings"
        return text
    return f"ema result: {', '.join(map(str, result))}"


def to_html(result: Mapping[str, Any], max_rows: int = HTML_MAX_ROWS) -> str:
    """The notebook view: the summary line, then the default table (its first ``max_rows`` rows);
    without pandas."""
    parts = [f"<div class=\"ema-result\"><p><b>{html.escape(_summary(result))}</b></p>"]
    try:
        name, rows = table_rows(result)
    except ValueError:
        name, rows = "", []
    if rows:
        columns = list(dict.fromkeys(c for row in rows for c in row))
        head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
        body = "".join("<tr>" + "".join(f"<td>{html.escape(_cell(row.get(c)))}</td>" for c in columns) + "</tr>"
                       for row in rows[:max_rows])
        parts.append(f"<table><caption>{html.escape(name)}</caption><thead><tr>{head}</tr></thead>"
                     f"<tbody>{body}</tbody></table>")
        if len(rows) > max_rows:
            parts.append(f"<p>… {len(rows) - max_rows} more rows: to_dataframe(table='{html.escape(name)}')</p>")
    others = [t for t in tables(result) if t != name]
    if others:
        parts.append(f"<p>other tables: {html.escape(', '.join(others))}</p>")
    parts.append("</div>")
    return "".join(parts)


# --- The result dict -------------------------------------------------------------------------------


class Result(Dict[str, Any]):
    """An ema result: the dict the binding returned (every key and value unchanged, ``isinstance(r,
    dict)``), plus ``to_dataframe()``, ``to_json()``, ``to_jsonable()`` and an HTML view in notebooks.
    Type checkers see the TypedDict of each function (ema.types); in typed code call the module's
    functions (``ema.to_dataframe(r)``), which take any result, wrapped or plain."""

    __slots__ = ()

    def to_dataframe(self, table: Optional[str] = None) -> pandas.DataFrame:
        return to_dataframe(self, table)

    def to_json(self, **json_kwargs: Any) -> str:
        return to_json(self, **json_kwargs)

    def to_jsonable(self) -> Any:
        return to_jsonable(self)

    def _repr_html_(self) -> str:
        return to_html(self)


Function = TypeVar("Function", bound=Callable[..., Any])


def returning_result(function: Function) -> Function:
    """``function`` (a binding returning a dict) returning a Result instead; its name, docstring and,
    for type checkers, its signature unchanged."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        return Result(function(*args, **kwargs))

    return cast(Function, wrapper)
