"""The guideway story: hammer data of two setups -> FRFs -> modes -> the nominal model's agreement ->
which physics the model misses (samples/guideway/README.md tells the article and the truth).

An air-bearing carriage modelled with its air films alone; the test says the pads are ~8x softer.
ema.diagnose finds why: a compliance (the ball-joint mounts) in series with the bearings.

Run: v/bin/python examples/guideway_story.py [SAMPLE_DIR]   (default: samples/guideway of this repository)
"""
import argparse
import pathlib
import sys
from typing import Dict

import ema
from ema.types import FitDict

SETUPS = ["stud-5um", "stud-9um"]  # the two stud settings of the test (model.toml's [[setup]]s)
BAND = (100.0, 450.0)  # Hz


def main() -> int:
    default = pathlib.Path(__file__).resolve().parents[1] / "samples" / "guideway"
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sample", nargs="?", type=pathlib.Path, default=default,
                        help="the guideway sample folder (model.toml, data/<setup>.unv)")
    args = parser.parse_args()
    model = args.sample / "model.toml"
    if not model.exists():
        sys.exit(f"guideway_story.py: {model} not found; give the samples/guideway folder of the ema repository")

    tests: Dict[str, FitDict] = {}
    for setup in SETUPS:
        frfs = ema.estimate_frfs([str(args.sample / "data" / f"{setup}.unv")])  # hammer time data -> H1 FRFs
        quality = ema.quality(frfs, band=BAND)
        tests[setup] = ema.fit(frfs, band=BAND)  # PolyMAX + ML refinement, with each mode's 1 sigma
        corr = ema.correlate(tests[setup], ema.model_modes(model, setup))
        print(f"{setup}: data quality {quality['verdict']}, {len(tests[setup]['frequency_hz'])} modes "
              f"({', '.join(f'{f:.0f}' for f in tests[setup]['frequency_hz'])} Hz), "
              f"nominal model agrees to {corr['mean_agreement_pct']:.1f} %")

    # Which effect is the model missing, where, how sure? The test's own 11.2 g accelerometers
    # (samples/guideway/project.toml) load each roving set: ema.fit gave each set its poles, and
    # sensor_mass lets the diagnosis model them instead of taking them for a missing mass.
    diagnosis = ema.diagnose(model, tests, sensor_mass=0.0112)
    best = diagnosis["candidates"][0]
    probability = best["probability"]  # None when the diagnosis could not weigh it (the JSON's null)
    share = f"{100 * probability:.0f} %" if probability is not None else "probability unknown"
    print(f"rank 1 ({share}): {best['description']}")
    print(f"  mean frequency error {diagnosis['baseline']['mean_abs_frequency_error_pct']:.2f} % -> "
          f"{best['mean_abs_frequency_error_pct']:.2f} %, mean MAC {diagnosis['baseline']['mean_mac']:.3f} -> "
          f"{best['mean_mac']:.3f}")
    for row in diagnosis["modes"]:
        print(f"  {row['setup']:9s} mode {row['test_mode']}: test {row['test_frequency_hz']:6.1f} Hz, "
              f"model {row['model_frequency_hz_before']:6.1f} -> {row['model_frequency_hz_after']:6.1f} Hz")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
