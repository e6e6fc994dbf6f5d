"""Type stubs of ema._ema, the compiled core of the ema package (python/ema_module.cpp).

Results are plain dicts of numpy arrays, lists and numbers with the names of the CLI's JSON; the
TypedDicts below name their keys. Inputs that take a mode set accept a path, a ModesDict (what
fit, read_modes and model_modes return) or a dict in `ema fit --json`'s layout (ModesJson).
"""
import os
from typing import Any, Literal, Mapping, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

class InputError(ValueError):
    """Bad input data (a malformed file, inconsistent arrays); the message names the file or argument."""

class UsageError(ValueError):
    """A bad option value (an unknown criterion, an option out of range)."""

Path = Union[str, bytes, os.PathLike[str]]
Dof = Tuple[int, str]
"""(node, direction): (101, '+Z')."""

class FrfDict(TypedDict, total=False):
    frequency_hz: npt.NDArray[np.float64]  # (n_lines,)
    outputs: list[Dof]
    references: list[Dof]
    h: npt.NDArray[np.complex128]  # (n_references, n_lines, n_outputs)
    coherence: npt.NDArray[np.float64] | None  # same shape as h
    averages: npt.NDArray[np.int_] | None  # (n_references, n_outputs)
    quantity: Literal["acceleration", "velocity", "displacement"]
    roving_hammer: bool
    window_decay_rate: float
    output_sets: list[int]  # per output, its roving set (empty when unknown)

class ModesDict(TypedDict, total=False):
    frequency_hz: npt.NDArray[np.float64]  # (n_modes,)
    damping_ratio: npt.NDArray[np.float64]
    frequency_std_hz: npt.NDArray[np.float64]  # 1 sigma (NaN when unknown)
    damping_ratio_std: npt.NDArray[np.float64]
    pole: npt.NDArray[np.complex128]  # rad/s
    mpc: npt.NDArray[np.float64]
    mpd_deg: npt.NDArray[np.float64]
    mcf: npt.NDArray[np.float64]
    dofs: list[Dof]
    shapes: npt.NDArray[np.complex128]  # (n_dofs, n_modes)
    geometry: list[Tuple[int, float, float, float]]
    # fit() only:
    synthesis_error: float
    reciprocity_transposed: bool
    warnings: list[str]
    order: list[int]
    cluster_orders: list[int]
    roving_sets: list[list[int]]
    reference: Dof

class ShapeValueJson(TypedDict):
    node: int
    dir: str  # '+X' ... '-Z'
    value: Union[float, Sequence[float]]  # re, or [re, im]

class ModeJson(TypedDict, total=False):
    frequency_hz: float  # required
    frequency_std_hz: float | None  # the measured 1 sigma
    damping_ratio: float | None
    damping_ratio_std: float | None
    shape: list[ShapeValueJson]  # required: the measured DOFs only, the same in every mode

class ModesJson(TypedDict, total=False):
    """`ema fit --json`'s layout (MODES.json, model-format.md)."""

    modes: list[ModeJson]  # required
    roving_sets: list[list[int]]
    reference: Mapping[str, Any]  # {"node": 1, "dir": "+Z"}

Modes = Union[Path, ModesDict, ModesJson, Mapping[str, Any]]

class PartDict(TypedDict, total=False):
    name: str  # required, unique; no '/' or '+'
    group: str  # the parts of one group are its members: group/name
    stiffness: Any  # n x n scipy.sparse matrix/array or numpy array: the part's own contribution
    mass: Any  # n x n, optional
    uncertainty: float  # relative 1 sigma (prior of its stiffness factor)

class ModelDict(TypedDict, total=False):
    """An FE model built from parts (model-format.md, "FE models built from parts")."""

    dofs: Sequence[Tuple[int, Union[int, str]]]  # required: (node, 1..6 or 'ux'..'rz') per matrix row
    mass: Any  # n x n scipy.sparse or numpy; optional when parts carry the mass
    stiffness: Any  # n x n, whatever is in no part; optional
    parts: Sequence[PartDict]
    nodes: Union[Mapping[int, Sequence[float]], Sequence[Sequence[float]]]  # {node: (x, y, z)} or [(node, x, y, z)]
    points: Sequence[Union[int, Mapping[str, int]]]  # [{"id": 101, "node": 1003}, ...] or [node, ...]
    damping: Union[float, Sequence[float], Mapping[str, Any]]
    priors: Mapping[str, float]  # {effect kind: relative 1 sigma}
    name: str

Model = Union[Path, ModelDict, Mapping[str, Any], Any]
"""A model file path, a ModelDict, or any object with ModelDict's keys as attributes."""

def read_frfs(path: Path) -> FrfDict:
    """Reads FRFs (UFF 58 function type 4 with coherence type 6, or an FRF table/folder) as an FRF dict."""

def read_modes(path: Path) -> ModesDict:
    """Reads mode shapes (UFF 55, FE modes as UFF 2414, or MODES.json) with their geometry as a modes dict."""

def estimate_frfs(paths: Sequence[str], estimator: str = "H1") -> FrfDict:
    """Hammer time data (UFF 58 type 1, CSV or MATLAB .mat; one file per roving set) to FRFs, as `ema frf`."""

def fit(
    frfs: Union[Path, FrfDict],
    band: Tuple[float, float] | None = None,
    order_max: int = 0,
    select: Sequence[float] = ...,
    method: Literal["polymax", "peak"] = "polymax",
    refine: Literal["ml", "none"] = "ml",
    stabilisation: bool = False,
) -> ModesDict:
    """Fits modes to FRFs as `ema fit` (PolyMAX, stabilisation, selection, LSFD, ML refinement with 1 sigma)."""

def synthesize(fit_result: Mapping[str, Any], frequency_hz: npt.ArrayLike) -> FrfDict:
    """FRFs of a fitted modal model (ema.fit(..., stabilisation=True)) at frequency_hz: the synthesis a
    fit is judged by; NaN outside the fitted band and for FRFs the model does not hold."""

def mode_indicators(frfs: Union[Path, FrfDict], band: Tuple[float, float] | None = None) -> dict[str, npt.NDArray[np.float64]]:
    """CMIF and MMIF of the FRFs in the band: {'frequency_hz', 'cmif', 'mmif'}."""

def model_modes(model: Model, setup: str = "", max_modes: int = 0) -> ModesDict:
    """The model's own modes as `ema model` (a model file or an FE model built from parts in Python),
    with the shapes at its test points (+X, +Y, +Z each)."""

def mac(a: npt.ArrayLike, b: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """MAC between every column of a and every column of b (rows/DOFs aligned)."""

def correlate(test: Modes, model: Modes, mac_min: float = ...) -> dict[str, Any]:
    """Test modes against model modes as `ema correlate`: MAC, pairing, agreement."""

def diagnose(
    model: Model,
    tests: Union[Modes, Mapping[str, Modes]],
    criterion: Literal["", "evidence", "bic", "aicc"] = "",
    *,
    max_effects: int = 3,
    members: bool = True,
    frequency_floor: float = 1e-3,
    shape_sigma: float = 0.01,
    mac_min: float = 0.5,
    sensor_mass: float = 0.0,
    effect_prior_odds: float = 0.25,
    exact_form: bool = False,
) -> dict[str, Any]:
    """Which physical effect is the model missing, where, and how sure? As `ema diagnose`; returns
    DIAG.json's layout ('candidates' ranked, rank 1 first)."""

def quality(
    frfs: Union[Path, FrfDict, Sequence[Union[Path, FrfDict]]],
    modes: Modes | None = None,
    band: Tuple[float, float] | None = None,
) -> dict[str, Any]:
    """Data-quality checks as `ema quality --json`."""
