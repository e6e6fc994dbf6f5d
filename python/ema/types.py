"""The layouts of ema's results and inputs as TypedDicts, for type checkers and for annotating scripts::

    from ema.types import FitDict
    def report(fit: FitDict) -> None: ...

The bindings (ema._ema) return plain dicts and the package's functions wrap them in ema.Result, a dict
subclass; these classes name their keys and value types (docs/python.md). Nested parts that come from
the CLI's JSON codecs keep the JSON's layout: a complex number there is an [re, im] pair, a number the
codec writes as null (not finite, or unknown) is None. Keys a result holds only sometimes are in a
``total=False`` class (the classes are split in two so that they also work on Python 3.9, which lacks
typing.NotRequired).
"""
from __future__ import annotations

import os
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, bytes, os.PathLike[str]]
Dof = Tuple[int, str]
"""(node, direction): (101, '+Z')."""
RealArray = npt.NDArray[np.float64]
ComplexArray = npt.NDArray[np.complex128]
ComplexPair = List[float]
"""[re, im]: a complex number in the JSON-layout parts of a result."""
Verdict = Literal["pass", "warn"]


class DofJson(TypedDict):
    node: int
    dir: str  # '+X' ... '-RZ'


# --- FRFs: read_frfs, estimate_frfs, synthesize --------------------------------------------------


class _FrfRequired(TypedDict):
    frequency_hz: RealArray  # (n_lines,)
    outputs: List[Dof]
    references: List[Dof]
    h: ComplexArray  # (n_references, n_lines, n_outputs)


class FrfDict(_FrfRequired, total=False):
    """FRFs as read_frfs and estimate_frfs return them (synthesize: the first five keys)."""

    coherence: Optional[RealArray]  # same shape as h
    averages: Optional[npt.NDArray[np.int32]]  # (n_references, n_outputs)
    quantity: Literal["acceleration", "velocity", "displacement"]
    roving_hammer: bool
    window_decay_rate: float
    output_sets: List[int]  # per output, its roving set (empty when unknown)
    summary: Dict[str, Any]  # estimate_frfs: what `ema frf --json` writes (per FRF its rejected impacts)


class ModeIndicatorsDict(TypedDict):
    frequency_hz: RealArray  # (n_lines,)
    cmif: RealArray  # (n_lines, min(outputs, references)), largest first
    mmif: RealArray  # (n_lines, references), smallest first


# --- Mode sets: read_modes, model_modes, fit -------------------------------------------------------


class ModesDict(TypedDict):
    """A mode set as read_modes and model_modes return it (fit adds FitDict's keys)."""

    frequency_hz: RealArray  # (n_modes,)
    damping_ratio: RealArray
    frequency_std_hz: RealArray  # 1 sigma (NaN when unknown)
    damping_ratio_std: RealArray
    pole: ComplexArray  # rad/s
    mpc: RealArray
    mpd_deg: RealArray
    mcf: RealArray
    dofs: List[Dof]
    shapes: ComplexArray  # (n_dofs, n_modes)
    geometry: List[Tuple[int, float, float, float]]  # (node, x, y, z)


class StabilityCriteriaDict(TypedDict):
    frequency_tol: float
    damping_tol: float
    mac_min: float


class StabilisationPoleDict(TypedDict):
    frequency_hz: float
    damping_ratio: float
    pole: ComplexPair  # rad/s
    label: Literal["s", "d", "v", "f", "o"]  # StabilisationDict['labels'] words them
    physical: bool
    participation: List[ComplexPair]


class StabilisationOrderDict(TypedDict):
    order: int
    poles: List[StabilisationPoleDict]


class SelectedPoleDict(TypedDict):
    order: int
    frequency_hz: float
    damping_ratio: float
    frequency_spread_hz: Optional[float]
    damping_spread: Optional[float]
    cluster_orders: int


class StabilisationDict(TypedDict):
    """The stabilisation diagram as `ema fit --stabilisation` writes it (without CMIF/MMIF)."""

    band_hz: List[float]  # [lo, hi]
    references: int
    order_min: int
    order_max: int
    criteria: StabilityCriteriaDict
    labels: dict[str, str]  # {'s': 'stable (frequency, damping, vector)', ...}
    orders: List[StabilisationOrderDict]
    selected: List[SelectedPoleDict]
    sum_frf: List[List[float]]  # [[frequency_hz, sum of |H|], ...]


class ModalModelFrfDict(TypedDict):
    response_node: int
    response_dir: str
    reference_node: int
    reference_dir: str
    residues: List[ComplexPair]  # one per pole
    lower_residual: float
    upper_residual: float


class ModalModelDict(TypedDict):
    """The modal model behind the shapes, as `ema fit --json` writes it (synthesize takes it)."""

    frf_type: Literal["accelerance", "mobility", "receptance"]
    band_hz: List[float]
    poles: List[ComplexPair]  # rad/s
    frfs: List[ModalModelFrfDict]


class DroppedPoleDict(TypedDict):
    frequency_hz: float
    damping_ratio: float
    merged_into_hz: Optional[float]
    reason: str


class _FitRequired(ModesDict):
    synthesis_error: float
    reciprocity_transposed: bool
    warnings: List[str]
    order: List[int]  # per mode, the PolyMAX order it was taken from
    cluster_orders: List[int]  # per mode, how many orders held it


class FitDict(_FitRequired, total=False):
    """What fit returns: a mode set plus the fit's own keys."""

    roving_sets: List[List[int]]  # when the FRFs know them
    reference: Dof  # when the FRFs have one reference
    # stabilisation=True only (stabilisation and modal_model are None for method='peak'):
    stabilisation: Optional[StabilisationDict]
    modal_model: Optional[ModalModelDict]
    dropped: List[DroppedPoleDict]


# --- Mode sets in `ema fit --json`'s layout (inputs) ----------------------------------------------


class ShapeValueJson(TypedDict):
    node: int
    dir: str  # '+X' ... '-Z'
    value: Union[float, Sequence[float]]  # re, or [re, im]


class _ModeJsonRequired(TypedDict):
    frequency_hz: float
    shape: List[ShapeValueJson]  # the measured DOFs only, the same in every mode


class ModeJson(_ModeJsonRequired, total=False):
    frequency_std_hz: Optional[float]  # the measured 1 sigma
    damping_ratio: Optional[float]
    damping_ratio_std: Optional[float]


class _ModesJsonRequired(TypedDict):
    modes: List[ModeJson]


class ModesJson(_ModesJsonRequired, total=False):
    """`ema fit --json`'s layout (MODES.json, model-format.md)."""

    roving_sets: List[List[int]]
    reference: Mapping[str, Any]  # {"node": 1, "dir": "+Z"}


Modes = Union[PathLike, ModesDict, ModesJson, Mapping[str, Any]]
"""Wherever a function takes modes: a path, a modes dict (fit's, read_modes', model_modes'), or MODES.json's layout."""


# --- FE models built from parts (inputs) -----------------------------------------------------------


class _PartRequired(TypedDict):
    name: str  # unique; no '/' or '+'


class PartDict(_PartRequired, total=False):
    group: str  # the parts of one group are its members: group/name
    stiffness: Any  # n x n scipy.sparse matrix/array or numpy array: the part's own contribution
    mass: Any  # n x n, optional
    uncertainty: float  # relative 1 sigma (prior of its stiffness factor)


class _ModelRequired(TypedDict):
    dofs: Sequence[Tuple[int, Union[int, str]]]  # (node, 1..6 or 'ux'..'rz') per matrix row


class ModelDict(_ModelRequired, total=False):
    """An FE model built from parts (model-format.md, "FE models built from parts")."""

    mass: Any  # n x n scipy.sparse or numpy; optional when parts carry the mass
    stiffness: Any  # n x n, whatever is in no part; optional
    parts: Sequence[PartDict]
    nodes: Union[Mapping[int, Sequence[float]], Sequence[Sequence[float]]]  # {node: (x, y, z)} or [(node, x, y, z)]
    points: Sequence[Union[int, Mapping[str, int]]]  # [{"id": 101, "node": 1003}, ...] or [node, ...]
    damping: Union[float, Sequence[float], Mapping[str, Any]]
    priors: Mapping[str, float]  # {effect kind: relative 1 sigma}
    name: str


Model = Union[PathLike, ModelDict, Mapping[str, Any], Any]
"""A model file path, a ModelDict, or any object with ModelDict's keys as attributes."""


# --- correlate -------------------------------------------------------------------------------------


class PairDict(TypedDict):
    test_mode: int  # 1-based
    model_mode: int  # 1-based
    test_frequency_hz: float
    model_frequency_hz: float
    agreement_pct: float
    frequency_error_pct: float
    mac: float
    remark: str


class CorrelationDict(TypedDict):
    """What correlate returns (`ema correlate --json`'s numbers)."""

    pairs: List[PairDict]
    mac: RealArray  # (n_test, n_model): mac[test_mode - 1, model_mode - 1]
    unpaired_test: List[int]  # 1-based mode numbers
    unpaired_model: List[int]
    mean_agreement_pct: float
    min_agreement_pct: float
    mean_mac: float
    shared_dofs: int
    table: str  # the validation table (Markdown)


# --- diagnose --------------------------------------------------------------------------------------


class BaselineDict(TypedDict):
    mean_abs_frequency_error_pct: Optional[float]
    mean_mac: Optional[float]
    mean_agreement_pct: Optional[float]
    score: Optional[float]
    cost: Optional[float]
    paired_modes: int


class _EffectRequired(TypedDict):
    kind: str
    target: str
    parameters: dict[str, float]


class EffectDict(_EffectRequired, total=False):
    law: str  # the spring law in model-file TOML


class ModelErrorDict(TypedDict):
    frequency_rel: Optional[float]
    shape: Optional[float]
    frequency_common_rel: Optional[float]
    dominates: bool


class OutsideStatedDict(TypedDict):
    target: str
    sigmas: Optional[float]


class CandidateModeDict(TypedDict):
    setup: str
    test_mode: int  # 1-based
    test_frequency_hz: float
    sigma_hz: Optional[float]
    model_frequency_hz: Optional[float]
    frequency_misfit_sigma: Optional[float]
    mac: Optional[float]
    shape_misfit_sigma: Optional[float]


class _CandidateRequired(TypedDict):
    rank: int  # 1 = best
    kind: str
    target: str
    parameters: dict[str, float]
    uncertainty: dict[str, Optional[float]]  # 1 sigma per parameter
    prior_sigma: dict[str, Optional[float]]
    probability: Optional[float]
    mean_abs_frequency_error_pct: Optional[float]
    mean_mac: Optional[float]
    mean_agreement_pct: Optional[float]
    score: Optional[float]
    log_evidence: Optional[float]
    log_prior: Optional[float]
    cost: Optional[float]
    explained_pct: Optional[float]
    paired_modes: int
    plausible: bool
    reduced_chi2: Optional[float]
    noise_consistent: bool
    flags: List[str]
    prior_z: dict[str, Optional[float]]
    tied_with: List[str]
    description: str
    effects: List[EffectDict]
    model_error: ModelErrorDict
    outside_stated: List[OutsideStatedDict]
    modes: List[CandidateModeDict]


class CandidateDict(_CandidateRequired, total=False):
    at_bound: List[str]
    outside_prior: List[str]
    reduced_model: bool
    error: str


class DiagnoseOptionsDict(TypedDict):
    frequency_floor: float
    shape_sigma: float
    max_effects: int
    members: bool
    model_error: bool
    effect_prior_odds: float
    mac_min: float


class EffectProbabilityDict(TypedDict):
    kind: str
    target: str
    probability: float


class CandidateGroupDict(TypedDict):
    kind: str
    target: str
    ranks: List[int]
    probability: float


class DiagnosisStepDict(TypedDict):
    added: str
    mean_abs_frequency_error_pct: Optional[float]
    mean_mac: Optional[float]
    mean_agreement_pct: Optional[float]


class DiagnosisModeRowDict(TypedDict):
    setup: str
    test_mode: int  # 1-based
    test_frequency_hz: float
    model_frequency_hz_before: Optional[float]
    agreement_pct_before: Optional[float]
    mac_before: Optional[float]
    model_frequency_hz_after: Optional[float]
    agreement_pct_after: Optional[float]
    mac_after: Optional[float]
    sigma_hz: Optional[float]
    frequency_misfit_sigma_before: Optional[float]
    frequency_misfit_sigma_after: Optional[float]
    shape_misfit_sigma_before: Optional[float]
    shape_misfit_sigma_after: Optional[float]


class _DiagnosisRequired(TypedDict):
    baseline: BaselineDict
    candidates: List[CandidateDict]  # ranked, rank 1 first
    criterion: str
    options: DiagnoseOptionsDict
    residual_count: int
    test_modes: int
    model_solves: int
    candidates_screened: int
    explanation: str
    effect_probabilities: List[EffectProbabilityDict]
    groups: List[CandidateGroupDict]
    steps: List[DiagnosisStepDict]


class FindingParameterDict(TypedDict):
    name: str  # 'k', 'factor', 'mass', 'modulus', 'value'
    value: Optional[float]  # SI units
    sigma: Optional[float]


class FindingSpringsDict(TypedDict):
    setup: str
    per_spring_n_per_m: Optional[float]  # mean linearised stiffness of the target's springs with rank 1's effects
    element_n_per_m: Optional[float]  # series_compliance: the element in series alone


class FindingWildcardDict(TypedDict):
    target: str  # 'joints/*', 'points:*'
    probability: float


class _FindingRequired(TypedDict):
    kind: str
    target: str
    description: str
    probability: float  # summed over every candidate that holds the effect
    parameters: List[FindingParameterDict]
    springs: List[FindingSpringsDict]


class FindingDict(_FindingRequired, total=False):
    """One effect of rank 1 as numbers (DIAG.json findings[])."""

    any: FindingWildcardDict


class DiagnosisDict(_DiagnosisRequired, total=False):
    """What diagnose returns: DIAG.json's layout, as `ema diagnose --json` writes it."""

    model_error: ModelErrorDict  # rank 1's, when there is a candidate
    modes: List[DiagnosisModeRowDict]  # every test mode before and after rank 1, when there is a candidate
    findings: List[FindingDict]  # rank 1's effects as numbers
    nonlinearity: Dict[str, Any]  # with force levels (ema diagnose --force-level)


# --- run -------------------------------------------------------------------------------------------


class RunTestDict(TypedDict):
    name: str
    setup: str
    frf: Optional[Dict[str, Any]]  # `ema frf --json`; None when the project gives FRFs or the step failed
    modes: Optional[Dict[str, Any]]  # `ema fit --json`
    select_hz: List[float]  # the selection the fit used; [] = automatic
    picked_by_hand: bool
    correlation_before: Optional[CorrelationDict]
    correlation_after: Optional[CorrelationDict]


class RunStepDict(TypedDict):
    step: str  # 'frf', 'fit', 'model (nominal)', 'correlate (nominal)', 'diagnose', ...
    test: Optional[str]  # None for the diagnosis
    status: Literal["done", "failed", "skipped", "given"]
    error: str


class RunProblemDict(TypedDict):
    test: Optional[str]
    what: str
    error: str


class RunDict(TypedDict):
    """What run returns: a project's whole story, as `ema run` computes it."""

    project: str
    model: str
    tests: List[RunTestDict]
    diagnosis: Optional[DiagnosisDict]
    steps: List[RunStepDict]
    problems: List[RunProblemDict]
    mean_agreement_pct_before: Optional[float]
    mean_mac_before: Optional[float]
    mean_agreement_pct_after: Optional[float]
    mean_mac_after: Optional[float]


# --- plan ------------------------------------------------------------------------------------------


class PlanSetDict(TypedDict):
    name: str  # 'set 1', 'set 2', ... as the plan file names them
    sensors: List[str]  # DOFs '101+X', ...


class PlannedModeDict(TypedDict):
    frequency_hz: Optional[float]
    observability: Optional[float]  # RMS at the sensors over RMS at every candidate DOF: 1 = as an average sensor
    damping_ratio: Optional[float]
    reference_participation: Optional[float]  # the best reference's squared amplitude over the mode's largest (0..1)
    excited: bool


class PlanAcquisitionDict(TypedDict):
    sample_rate_hz: Optional[float]
    samples: int
    record_length_s: Optional[float]
    pulse_duration_s: Optional[float]  # half-sine contact time of the hammer tip
    impacts: int
    sensor_mass_kg: Optional[float]


class SeparationDict(TypedDict):
    a: str  # 'kind on target' of a reading
    b: str
    sigma_before: Optional[float]  # in units of the expected noise: the kept plan's sensors, else the plan for the modes
    sigma_after: Optional[float]  # with the plan made


class _PlanRequired(TypedDict):
    sensors: List[str]  # every set's DOFs, in order: '101+X', ...
    references: List[str]  # hammer DOFs
    sets: List[PlanSetDict]
    modes: List[PlannedModeDict]  # the target modes, by frequency
    automac_max_offdiagonal: Optional[float]
    automac: List[List[Optional[float]]]  # (modes, modes) over every planned sensor DOF
    band_hz: List[Optional[float]]  # [lo, hi]
    acquisition: PlanAcquisitionDict
    notes: List[str]  # what the plan could not satisfy
    plan_toml: str  # the plan file's text (what ema.plan(..., output=...) writes)


class PlanDict(_PlanRequired, total=False):
    """What plan returns: PLAN.json (`ema plan --json`) plus the plan file's text."""

    separations: List[SeparationDict]  # with candidates only: per pair of look-alike readings


# --- quality ---------------------------------------------------------------------------------------


class QualityThresholdsDict(TypedDict):
    reciprocity_tolerance: float
    resonance_level: float
    coherence_min: float
    coherence_max_low_fraction: float
    scatter_max: float


class ReciprocityCheckDict(TypedDict):
    i: DofJson
    j: DofJson
    relative_difference: Optional[float]
    amplitude_ratio: Optional[float]
    tolerance: float
    verdict: Verdict
    reason: str


class DrivingPointCheckDict(TypedDict):
    dof: DofJson
    resonances: int
    flipped: int
    flipped_frequencies_hz: List[float]
    sign_consistency: Optional[float]
    verdict: Verdict
    reason: str


class FrfCheckDict(TypedDict):
    response: DofJson
    reference: DofJson
    mean_coherence: Optional[float]
    low_coherence_fraction: Optional[float]
    averages: int
    median_random_error: Optional[float]
    max_random_error: Optional[float]
    coherence_verdict: Verdict
    scatter_verdict: Verdict
    reason: str


class CoherenceMapDict(TypedDict):
    frequency_hz: List[float]
    labels: List[str]  # one per FRF
    coherence: List[List[Optional[float]]]  # (FRFs, lines)


class ModeCheckDict(TypedDict):
    mode: int  # 1-based
    frequency_hz: Optional[float]
    mpc: Optional[float]
    mpd_deg: Optional[float]
    mcf: Optional[float]
    verdict: Verdict
    reason: str


class QualityDict(TypedDict):
    """What quality returns: `ema quality --json`."""

    verdict: Verdict
    warnings: int
    thresholds: QualityThresholdsDict
    reciprocity: List[ReciprocityCheckDict]
    driving_points: List[DrivingPointCheckDict]
    frfs: List[FrfCheckDict]
    coherence_map: Optional[CoherenceMapDict]  # None without coherence
    modes: List[ModeCheckDict]  # with modes=... only
    notes: List[str]
