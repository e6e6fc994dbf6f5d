#!/usr/bin/env python3
"""Side by side: reading an ASCII UFF 58 file with pyuff and with ema (issue #18).

Times, on the same file and machine, one after the other:
  * pyuff      pyuff.UFF(path).read_sets()             (the peer; import it from --pyuff-path)
  * ema read   ema.read_frfs(path)                     (the Python module: UFF read on two
               threads, the FRF set assembled, copied into a numpy array)
  * ema fit    `ema fit path -o OUT --method peak`     (the CLI: read + peak picking + UFF 55 write)
and checks that both readers give the same numbers: every record pyuff returns is looked up by
its (response, reference) DOFs in ema's FRF set and compared value by value (they must be
bit-identical: both parse the same decimal text to the nearest double).

Usage (docs/performance.md):
  python3 bench/peers/uff_read_vs_pyuff.py FILE.unv --ema build/app/ema \
      --ema-module build/python --pyuff-path DIR_WITH_PYUFF [--repeat 3] [--json out.json]

The figures are wall times; run it on an otherwise idle machine. pyuff needs numpy.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

AXES = ["X", "Y", "Z", "RX", "RY", "RZ"]


def dof_code(name):
    """ema's direction name ("+Z", "-RX", "S") as a UFF direction code (3, -4, 0)."""
    if name == "S":
        return 0
    sign = -1 if name.startswith("-") else 1
    return sign * (AXES.index(name.lstrip("+-")) + 1)


def timed(fn, repeat):
    times, result = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
        if _ + 1 < repeat:
            result = None  # free it before the next run
    return times, result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("uff")
    ap.add_argument("--ema", required=True, help="the ema executable")
    ap.add_argument("--ema-module", required=True, help="folder holding the ema Python module (build/python)")
    ap.add_argument("--pyuff-path", default=None, help="folder to put first on sys.path to import pyuff")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default=None, help="write the figures here too")
    args = ap.parse_args()
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")
    if not os.path.isfile(args.uff):
        ap.error(f"{args.uff}: no such file")
    if args.pyuff_path:
        sys.path.insert(0, args.pyuff_path)
    sys.path.insert(0, args.ema_module)
    try:
        import numpy as np
        import pyuff
    except ImportError as e:
        sys.exit(f"uff_read_vs_pyuff: cannot import the peer ({e}); pass --pyuff-path")
    import ema

    size_mb = os.path.getsize(args.uff) / 1e6
    out = {"file": os.path.abspath(args.uff), "size_mb": round(size_mb, 1),
           "pyuff_version": getattr(pyuff, "__version__", "?"), "numpy_version": np.__version__,
           "python": sys.version.split()[0]}

    pyuff_times, sets = timed(lambda: pyuff.UFF(args.uff).read_sets(), args.repeat)
    if isinstance(sets, dict):
        sets = [sets]
    ema_times, frfs = timed(lambda: ema.read_frfs(args.uff), args.repeat)

    with tempfile.TemporaryDirectory() as tmp:
        def fit():
            subprocess.run([args.ema, "fit", args.uff, "-o", os.path.join(tmp, "modes.unv"), "--method", "peak"],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        fit_times, _ = timed(fit, args.repeat)

    # Exactness: every pyuff record against ema's FRF set.
    outputs = {(n, dof_code(d)): i for i, (n, d) in enumerate(frfs["outputs"])}
    references = {(n, dof_code(d)): i for i, (n, d) in enumerate(frfs["references"])}
    h = frfs["h"]
    compared = mismatched = 0
    for s in sets:
        if s.get("type") != 58:
            continue
        o = outputs.get((int(s["rsp_node"]), int(s["rsp_dir"])))
        r = references.get((int(s["ref_node"]), int(s["ref_dir"])))
        if o is None or r is None:
            mismatched += 1
            continue
        data = np.asarray(s["data"])
        ours = h[r, :, o]
        if data.shape != ours.shape or not np.array_equal(data, ours.astype(data.dtype)):
            mismatched += 1
        compared += 1
    out.update({
        "records_pyuff": len(sets), "records_compared": compared, "records_mismatched": mismatched,
        "pyuff_read_s": [round(t, 3) for t in pyuff_times],
        "ema_read_frfs_s": [round(t, 3) for t in ema_times],
        "ema_fit_peak_s": [round(t, 3) for t in fit_times],
    })
    p, r, f = (statistics.median(x) for x in (pyuff_times, ema_times, fit_times))
    out["speedup_read"] = round(p / r, 1)
    out["speedup_fit_peak"] = round(p / f, 1)
    print(f"{args.uff}: {size_mb:.0f} MB, pyuff {out['pyuff_version']} (numpy {np.__version__}, Python {out['python']})")
    print(f"  pyuff read_sets        median {p:7.2f} s  {out['pyuff_read_s']}")
    print(f"  ema.read_frfs          median {r:7.2f} s  {out['ema_read_frfs_s']}   {p / r:5.1f}x")
    print(f"  ema fit --method peak  median {f:7.2f} s  {out['ema_fit_peak_s']}   {p / f:5.1f}x")
    print(f"  values: {compared} records compared, {mismatched} differ")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 1 if mismatched or compared == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
