"""Type stubs of ema._ema, the compiled core of the ema package (python/ema_module.cpp).

Results are dicts of numpy arrays, lists and numbers with the names of the CLI's JSON; the TypedDicts
of ema.types name their keys (the package's fit, read_modes, model_modes, correlate, diagnose, plan
and quality return them wrapped in ema.Result, a dict subclass). Inputs that take a mode set accept a path,
a ModesDict (what fit, read_modes and model_modes return) or a dict in `ema fit --json`'s layout
(ModesJson).
"""
from typing import Any, Dict, List, Literal, Mapping, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from .types import CorrelationDict as CorrelationDict
from .types import DiagnosisDict as DiagnosisDict
from .types import RunDict as RunDict
from .types import Dof as Dof
from .types import FitDict as FitDict
from .types import FrfDict as FrfDict
from .types import Model as Model
from .types import ModelDict as ModelDict
from .types import ModeIndicatorsDict as ModeIndicatorsDict
from .types import ModeJson as ModeJson
from .types import Modes as Modes
from .types import ModesDict as ModesDict
from .types import ModesJson as ModesJson
from .types import PartDict as PartDict
from .types import PathLike as PathLike
from .types import PlanDict as PlanDict
from .types import QualityDict as QualityDict
from .types import ShapeValueJson as ShapeValueJson

Path = PathLike

__version__: str

class InputError(ValueError):
    """Bad input data (a malformed file, inconsistent arrays); the message names the file or argument."""

class UsageError(ValueError):
    """A bad option value (an unknown criterion, an option out of range)."""

def read_frfs(path: Path) -> FrfDict:
    """Reads FRFs (UFF 58 function type 4 with coherence type 6, or an FRF table/folder) as an FRF dict."""

def read_modes(path: Path) -> ModesDict:
    """Reads mode shapes (UFF 55, FE modes as UFF 2414, or MODES.json) with their geometry as a modes dict."""

def read_uff(path: Path) -> List[Dict[str, Any]]:
    """Every dataset of a UFF file as a dict: 'number', 'line' and its fields (see the docstring)."""

def write_modes(modes: Union[Path, Mapping[str, Any]], path: Path, *, binary: bool = False) -> None:
    """Modes as UFF 55 (or JSON when path ends in .json), read back by read_modes."""

def write_frfs(frfs: Union[Path, Mapping[str, Any]], path: Path, *, binary: bool = False) -> None:
    """FRFs as UFF 58 (58b with binary=True), read back by read_frfs."""

def estimate_frfs(
    paths: Union[Path, Sequence[Path], None] = None,
    estimator: str = "H1",
    *,
    band: Tuple[float, float] | None = None,
    exp_window: Union[str, float] = "auto",
    exp_end_level: float = ...,
    quantity: str = "",
    trigger_level: float = ...,
    force_window: float = ...,
    double_hit_ratio: float = ...,
    double_hit_autocorrelation: float = ...,
    accept_double_hits: bool = False,
    overload_fraction: float = ...,
    level_tolerance: float = ...,
    force: npt.ArrayLike | None = None,
    response: npt.ArrayLike | None = None,
    fs: float | None = None,
    dofs: Sequence[Union[str, Tuple[int, str]]] | None = None,
    reference: Union[str, Tuple[int, str], None] = None,
    response_quantity: Literal["acceleration", "velocity", "displacement"] = "acceleration",
) -> FrfDict:
    """Hammer time data (UFF 58 type 1, CSV or MATLAB .mat; one file per roving set) to FRFs, as `ema frf`."""

def fit(
    frfs: Union[Path, FrfDict],
    band: Tuple[float, float] | None = None,
    order_max: int = 0,
    select: Sequence[float] = ...,
    method: Literal["polymax", "peak"] = "polymax",
    refine: Literal["ml", "none"] = "ml",
    stabilisation: bool = False,
) -> FitDict:
    """Fits modes to FRFs as `ema fit` (PolyMAX, stabilisation, selection, LSFD, ML refinement with 1 sigma)."""

def synthesize(fit_result: Mapping[str, Any], frequency_hz: npt.ArrayLike) -> FrfDict:
    """FRFs of a fitted modal model (ema.fit(..., stabilisation=True)) at frequency_hz: the synthesis a
    fit is judged by; NaN outside the fitted band and for FRFs the model does not hold."""

def mode_indicators(frfs: Union[Path, FrfDict], band: Tuple[float, float] | None = None) -> ModeIndicatorsDict:
    """CMIF and MMIF of the FRFs in the band: {'frequency_hz', 'cmif', 'mmif'}."""

def model_modes(model: Model, setup: str = "", max_modes: int = 0) -> ModesDict:
    """The model's own modes as `ema model` (a model file or an FE model built from parts in Python),
    with the shapes at its test points (+X, +Y, +Z each)."""

def mac(a: npt.ArrayLike, b: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """MAC between every column of a and every column of b (rows/DOFs aligned)."""

def correlate(test: Modes, model: Modes, mac_min: float = ...) -> CorrelationDict:
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
    shape_residual: Literal["per-dof", "mac"] = "per-dof",
    shape_dof_sigma: float = 0.1,
) -> DiagnosisDict:
    """Which physical effect is the model missing, where, and how sure? As `ema diagnose`; returns
    DIAG.json's layout ('candidates' ranked, rank 1 first)."""

def run(project: Path, output: Path = "ema-run") -> RunDict:
    """A project file's whole story as `ema run` computes it (frf, fit, correlate, diagnose, correlate
    with the updated model), writing no file; output only names the results' sources."""

def plan(
    model: Model,
    *,
    setup: str = "",
    band: Tuple[float, float] | None = None,
    sensors: int = 4,
    sets: int = 1,
    triaxial: bool = False,
    references: int = 1,
    sensor_mass: float = 0.0,
    impacts: int = 5,
    candidates: Union[Path, DiagnosisDict, Mapping[str, Any], None] = None,
    keep: Path | None = None,
    output: Path | None = None,
) -> PlanDict:
    """The test to run next, as `ema plan`: sensors, references and acquisition settings for the band's
    modes, and with candidates (a DIAG.json path or what diagnose returns) the sensors that tell its
    look-alike readings apart; returns PLAN.json's layout plus 'plan_toml', the plan file's text."""

def quality(
    frfs: Union[Path, FrfDict, Sequence[Union[Path, FrfDict]]],
    modes: Modes | None = None,
    band: Tuple[float, float] | None = None,
) -> QualityDict:
    """Data-quality checks as `ema quality --json`."""
