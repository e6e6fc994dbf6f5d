"""A vendor's UFF file of measured FRFs to modes: read, check, fit, write MODES.json.

Reads the FRFs (UFF 58, function type 4; or an FRF table) another tool exported, prints what it holds,
the data-quality verdict, the mode indicator's peaks and the modes PolyMAX + the maximum-likelihood
refinement find, each with its 1σ. With -o it writes them in `ema fit --json`'s layout (MODES.json),
which `ema diagnose --test` and ema.diagnose read back.

Run: v/bin/python examples/uff_to_modes.py [FRF_FILE] [--band LO HI] [-o MODES.json]
     (default: samples/uff/dataset58_FRF.unv of this repository, a copy of UFFFiles.jl's test file)
"""
import argparse
import json
import pathlib
import sys
from typing import List, Optional, Tuple

import numpy as np

import ema
from ema.types import ModeJson, ModesDict, ModesJson


def modes_json(modes: ModesDict) -> ModesJson:
    """A modes dict (ema.fit's) in `ema fit --json`'s layout: what other tools and ema diagnose read."""
    out: List[ModeJson] = []
    for i, f in enumerate(modes["frequency_hz"]):
        sigma = modes["frequency_std_hz"][i]
        out.append({
            "frequency_hz": float(f),
            "frequency_std_hz": float(sigma) if np.isfinite(sigma) else None,
            "damping_ratio": float(modes["damping_ratio"][i]),
            "shape": [{"node": node, "dir": direction, "value": [v.real, v.imag]}
                      for (node, direction), v in zip(modes["dofs"], modes["shapes"][:, i])],
        })
    return {"modes": out}


def main() -> int:
    default = pathlib.Path(__file__).resolve().parents[1] / "samples" / "uff" / "dataset58_FRF.unv"
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("frfs", nargs="?", type=pathlib.Path, default=default, help="UFF 58 FRF file (or FRF table)")
    parser.add_argument("--band", nargs=2, type=float, metavar=("LO", "HI"), help="fit band in Hz (default: all lines)")
    parser.add_argument("--order-max", type=int, default=0, help="highest PolyMAX order (0: automatic)")
    parser.add_argument("-o", "--output", type=pathlib.Path, help="write the modes as MODES.json")
    args = parser.parse_args()
    if not args.frfs.exists():
        sys.exit(f"uff_to_modes.py: {args.frfs} not found")

    frfs = ema.read_frfs(args.frfs)
    f = frfs["frequency_hz"]
    print(f"{args.frfs.name}: {len(frfs['outputs'])} responses x {len(frfs['references'])} references, "
          f"{len(f)} lines {f[0]:g}..{f[-1]:g} Hz, {frfs['quantity']}; "
          f"responses {frfs['outputs']}, references {frfs['references']}")
    band: Optional[Tuple[float, float]] = (args.band[0], args.band[1]) if args.band else None
    print(f"data quality: {ema.quality(frfs, band=band)['verdict']}")

    cmif = ema.mode_indicators(frfs, band=band)
    first = cmif["cmif"][:, 0]
    peaks = [i for i in range(1, len(first) - 1) if first[i] > first[i - 1] and first[i] >= first[i + 1]]
    strongest = sorted(sorted(peaks, key=lambda i: -float(first[i]))[:5])
    print("CMIF peaks (the strongest five):", ", ".join(f"{cmif['frequency_hz'][i]:.1f} Hz" for i in strongest))

    modes = ema.fit(frfs, band=band, order_max=args.order_max)
    print(f"{len(modes['frequency_hz'])} modes (synthesis error {modes['synthesis_error']:.3g}):")
    print("   #   f [Hz]     ±1σ     ζ [%]    ±1σ    MPC")
    for i, fn in enumerate(modes["frequency_hz"]):
        print(f"  {i + 1:2d} {fn:8.2f} {modes['frequency_std_hz'][i]:7.2f} {100 * modes['damping_ratio'][i]:8.3f} "
              f"{100 * modes['damping_ratio_std'][i]:6.2f} {modes['mpc'][i]:6.3f}")
    if args.output:
        args.output.write_text(json.dumps(modes_json(modes), indent=1) + "\n")
        back = ema.read_modes(args.output)
        assert np.array_equal(back["frequency_hz"], modes["frequency_hz"])
        print(f"wrote {args.output} ({len(back['frequency_hz'])} modes, read back identical)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
