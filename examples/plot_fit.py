"""Measured FRFs to modes, and the three plots that say whether to trust them, saved as PNG files.

Fits the FRFs with the stabilisation diagram kept (ema.fit(..., stabilisation=True)), prints the modes
as a table (ema.to_dataframe) and saves:

  stabilisation.png  every pole per model order, stable or not, the fitted modes, the sum of |FRF|
  frf.png            the measured FRFs (magnitude and phase) with the fitted model's synthesis
  mac.png            the MAC of the modes: against the model's modes with --model (ema.correlate,
                     the pairs framed), else against themselves (auto-MAC: distinct modes have
                     small off-diagonal values)

and the fit as JSON (fit.json: complex numbers as [re, im], NaN as null).

Run: v/bin/python examples/plot_fit.py [FRFS] [--band LO HI] [--order-max N] [--model MODEL [--setup S]] [-o DIR]
     (default: samples/meas-point of this repository, a measured beam, in 30..300 Hz at orders up to 40)
"""
import argparse
import pathlib
import sys
import warnings
from typing import Optional, Tuple, Union

import matplotlib
import numpy as np
import numpy.typing as npt

matplotlib.use("Agg")  # files only: no display needed

import ema  # noqa: E402  (after the backend is chosen)
from ema.types import CorrelationDict, FitDict  # noqa: E402


def main() -> int:
    repository = pathlib.Path(__file__).resolve().parents[1]
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("frfs", nargs="?", type=pathlib.Path, default=repository / "samples" / "meas-point",
                        help="FRFs: UFF 58 file, FRF table or folder (default: samples/meas-point)")
    parser.add_argument("--band", nargs=2, type=float, metavar=("LO", "HI"), help="fit band in Hz (default: 30 300 "
                        "for the default FRFs, else all lines)")
    parser.add_argument("--order-max", type=int, help="highest PolyMAX order (default: 40 for the default FRFs, else "
                        "automatic)")
    parser.add_argument("--model", help="a model file (TOML) or modes file to correlate the modes with")
    parser.add_argument("--setup", default="", help="the model's setup (with a TOML model)")
    parser.add_argument("-o", "--output", type=pathlib.Path, default=pathlib.Path("."), help="folder for the files")
    args = parser.parse_args()
    if not args.frfs.exists():
        sys.exit(f"plot_fit.py: {args.frfs} not found")
    sample = args.frfs == parser.get_default("frfs")
    band: Optional[Tuple[float, float]] = (args.band[0], args.band[1]) if args.band else (30.0, 300.0) if sample else None
    order_max: int = args.order_max if args.order_max is not None else 40 if sample else 0

    frfs = ema.read_frfs(str(args.frfs))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # fit["warnings"] lists them: printed below
        fit: FitDict = ema.fit(frfs, band=band, order_max=order_max, stabilisation=True)
    print(f"{len(fit['frequency_hz'])} modes (synthesis error {fit['synthesis_error']:.3g}):")
    modes = ema.to_dataframe(fit)
    print(modes[["frequency_hz", "frequency_std_hz", "damping_ratio", "mpc"]].to_string(float_format="{:.4g}".format))
    for warning in fit["warnings"]:
        print(f"warning: {warning}")

    args.output.mkdir(parents=True, exist_ok=True)
    mac: Union[CorrelationDict, npt.NDArray[np.float64]]
    if args.model:
        model = ema.read_modes(args.model) if not args.model.endswith(".toml") else ema.model_modes(args.model, args.setup)
        mac = ema.correlate(fit, model)
        print(f"against {args.model}: mean MAC {mac['mean_mac']:.3f}, mean agreement {mac['mean_agreement_pct']:.1f} %")
    else:
        mac = ema.mac(fit["shapes"], fit["shapes"])
    frf_figure = ema.plot_frf(frfs, fit)
    if band:
        frf_figure.axes[0].set_xlim(*band)  # the fitted band: the synthesis is NaN outside it
    figures = {
        "stabilisation.png": ema.plot_stabilisation(fit),
        "frf.png": frf_figure,
        "mac.png": ema.plot_mac(mac) if args.model else ema.plot_mac(mac, labels=("mode", "mode")),
    }
    for name, figure in figures.items():
        figure.savefig(args.output / name, dpi=100)
        print(f"wrote {args.output / name}")
    (args.output / "fit.json").write_text(ema.to_json(fit, indent=1) + "\n")
    print(f"wrote {args.output / 'fit.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
