#!/usr/bin/env python3
"""Times `ema fe-import` on a large CalculiX model: a clamped bar of C3D8 bricks cut into PARTS
segments along x, each its own *ELSET and material (docs/performance.md, "ema fe-import").

    python3 bench/fe-import/bench.py --work DIR [--ema PATH] [--ccx PATH] [--n 20 20 167] [--parts 10]

Writes the decks into DIR, runs ccx (*FREQUENCY, SOLVER=MATRIXSTORAGE) on the nominal deck and on
one deck per part with that part's modulus halved (--jobs ccx runs at a time, default 2), then runs
`/usr/bin/time -v ema fe-import --nominal nominal --part P1=split_P1 ... --deck nominal.inp -o DIR/out/fe.toml` and
prints the DOFs, the parts, the wall time and the peak resident memory. The ccx runs are skipped
when their files are already there (--rerun-ccx to force). Standard library only.

--joints: the parts are bolted joints instead of segments — one layer of elements each (J1..JN,
equally spaced along the bar, the rest of the bar the model's own stiffness). --diagnose (with
--joints): the loosened-joint case of issue 39 — a model file around the imported parts with test
points along one edge of the bar, a truth with joint --loose at --factor of its stiffness, its
lowest --modes modes at the points (`ema model`) as the test, and `/usr/bin/time -v ema diagnose`;
exits 1 unless rank 1 is that joint.

    python3 bench/fe-import/bench.py --work DIR --ema build/app/ema --n 3 3 40 --parts 5 --joints --diagnose
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

E, NU, RHO = 210.0e9, 0.3, 7850.0


def joint_layers(nz, parts):
    """The element layer (along the bar) of each joint: equally spaced, none at the clamped end."""
    return [(p + 1) * nz // (parts + 1) for p in range(parts)]


def write_deck(path, n, parts, moduli, size=(0.02, 0.02, 0.0025), joints=False):
    """The clamped bar's deck: PARTS segments P1..PN along it (moduli[p]), or with `joints` PARTS
    one-layer joints J1..JN (moduli[p]) in a bar of steel (ELSET BAR, the rest of the layers)."""
    nx, ny, nz = n  # elements along y, z (section) and x (length): nz is the bar's axis
    if joints:
        layers = joint_layers(nz, parts)
        title = "a clamped C3D8 bar with %d one-layer joints" % parts
        sets = [("BAR", [k for k in range(nz) if k not in layers], E, "M_BAR")] + \
               [("J%d" % (p + 1), [layers[p]], moduli[p], "M_J%d" % (p + 1)) for p in range(parts)]
    else:
        per = [nz * p // parts for p in range(parts + 1)]
        title = "a clamped C3D8 bar, %d parts" % parts
        sets = [("P%d" % (p + 1), range(per[p], per[p + 1]), moduli[p], "M%d" % (p + 1)) for p in range(parts)]
    sx, sy, sz = size
    node = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    out = ["** bench/fe-import/bench.py: " + title, "*NODE, NSET=NALL"]
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                out.append("%d, %.9g, %.9g, %.9g" % (node(i, j, k), i * sx, j * sy, k * sz))
    e = 0
    for name, ks, _, _ in sets:  # each element set: its layers of elements along the bar
        out.append("*ELEMENT, TYPE=C3D8, ELSET=%s" % name)
        for k in ks:
            for j in range(ny):
                for i in range(nx):
                    e += 1
                    c = [node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k)]
                    t = [node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)]
                    out.append(", ".join(str(v) for v in [e] + c + t))
    out.append("*NSET, NSET=NBASE")
    base = [node(i, j, 0) for j in range(ny + 1) for i in range(nx + 1)]
    for i in range(0, len(base), 12):
        out.append(", ".join(str(v) for v in base[i:i + 12]))
    out += ["*BOUNDARY", "NBASE, 1, 3"]
    for name, _, modulus, material in sets:
        out += ["*MATERIAL, NAME=%s" % material, "*ELASTIC", "%r, %r" % (modulus, NU), "*DENSITY", "%r" % RHO,
                "*SOLID SECTION, ELSET=%s, MATERIAL=%s" % (name, material)]
    out += ["*STEP", "*FREQUENCY, SOLVER=MATRIXSTORAGE", "10", "*END STEP"]
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def timed(cmd):
    """Runs cmd under /usr/bin/time -v: (CompletedProcess, wall text, peak RSS in GB). Without
    /usr/bin/time (Debian's `time` package: not on every machine) the wall time is measured here
    and the peak memory is not known."""
    if not os.path.isfile("/usr/bin/time"):
        t0 = time.perf_counter()
        r = subprocess.run(cmd, capture_output=True, text=True)
        return r, "%.2f s" % (time.perf_counter() - t0), float("nan")
    r = subprocess.run(["/usr/bin/time", "-v"] + cmd, capture_output=True, text=True)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", r.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr)
    return r, wall.group(1) if wall else "?", int(rss.group(1)) / 1048576.0 if rss else float("nan")


def diagnose(ema, work, n, parts, loose, factor, modes):
    """The loosened-joint case: model.toml around out/fe.toml, the truth's modes as the test,
    ema diagnose; returns True when rank 1 is the loosened joint alone."""
    out = os.path.join(work, "out")
    with open(os.path.join(out, "fe.toml")) as f:
        fe = "".join(line for line in f if not line.startswith("#"))
    nx, ny, nz = n
    node = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    # Test points: the corner edge x = y = 0 and the opposite one, at 8 stations along the bar.
    stations = sorted({max(1, round(nz * (s + 1) / 8)) for s in range(8)})
    points = [(100 + q, node(0, 0, k)) for q, k in enumerate(stations)] + \
             [(200 + q, node(nx, ny, k)) for q, k in enumerate(stations)]
    model = ["[model]", 'name = "clamped bar with %d bolted joints (bench/fe-import)"' % parts, "", fe.strip(), "",
             "[damping]", "ratio = 0.01", ""]
    for pid, nd in points:
        model += ["[[point]]", "id = %d" % pid, "node = %d" % nd, ""]
    with open(os.path.join(out, "model.toml"), "w") as f:
        f.write("\n".join(model))
    with open(os.path.join(out, "truth.toml"), "w") as f:
        f.write("\n".join(model) + '\n[[effect]]\nkind = "stiffness_scale"\ntarget = "joints/%s"\nfactor = %r\n'
                % (loose, factor))
    r, wall, rss = timed([ema, "model", os.path.join(out, "truth.toml"), "-o", os.path.join(out, "truth.unv"),
                          "--max-modes", str(modes)])
    if r.returncode != 0:
        sys.exit("bench.py: ema model failed:\n" + r.stderr[-2000:])
    print("ema model (the truth, %d modes): %s wall, %.2f GB peak RSS" % (modes, wall, rss))
    r, wall, rss = timed([ema, "diagnose", os.path.join(out, "model.toml"), "--test", os.path.join(out, "truth.unv"),
                          "--json", os.path.join(out, "diag.json")])
    if r.returncode != 0:
        sys.exit("bench.py: ema diagnose failed:\n" + r.stderr[-2000:])
    with open(os.path.join(out, "diag.json")) as f:
        first = json.load(f)["candidates"][0]
    right = first["kind"] == "stiffness_scale" and first["target"] == "joints/" + loose
    factor_found = next(iter(first.get("parameters", {}).values()), float("nan")) if right else float("nan")
    print("ema diagnose: %s wall, %.2f GB peak RSS; rank 1: %s %s (probability %s)%s"
          % (wall, rss, first["kind"], first["target"], first.get("probability"),
             ", factor %.3f for %.3f" % (factor_found, factor) if right else " — NOT the loosened joint"))
    return right


def run_ccx(ccx, work, job, rerun):
    if not rerun and all(os.path.isfile(os.path.join(work, job + x)) for x in (".sti", ".mas", ".dof")):
        return 0.0
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1")
    t0 = time.perf_counter()
    r = subprocess.run([ccx, "-i", job], cwd=work, capture_output=True, text=True, env=env)
    log = r.stdout + r.stderr
    with open(os.path.join(work, job + ".log"), "w") as f:
        f.write(log)
    if "*ERROR" in log or not os.path.isfile(os.path.join(work, job + ".sti")):
        sys.exit("bench.py: ccx failed on %s (see %s.log)" % (job, job))
    for x in (".frd", ".12d", ".cvg", ".sta"):
        if os.path.isfile(os.path.join(work, job + x)):
            os.remove(os.path.join(work, job + x))
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", required=True)
    ap.add_argument("--ema", default="ema")
    ap.add_argument("--ccx", default="ccx")
    ap.add_argument("--n", type=int, nargs=3, default=[20, 20, 167], help="elements: x y (section), z (length)")
    ap.add_argument("--parts", type=int, default=10)
    ap.add_argument("--rerun-ccx", action="store_true")
    ap.add_argument("--jobs", type=int, default=2, help="ccx runs at a time")
    ap.add_argument("--joints", action="store_true", help="the parts are one-layer joints J1..JN in a steel bar")
    ap.add_argument("--diagnose", action="store_true", help="(with --joints) diagnose a loosened joint")
    ap.add_argument("--loose", default=None, help="the loosened joint (default: the middle one)")
    ap.add_argument("--factor", type=float, default=0.3, help="its stiffness factor in the truth")
    ap.add_argument("--modes", type=int, default=8, help="test modes (the truth's lowest)")
    args = ap.parse_args()
    if args.diagnose and not args.joints:
        sys.exit("bench.py: --diagnose needs --joints")
    ccx, ema = shutil.which(args.ccx), shutil.which(args.ema)
    if not ccx or not ema:
        sys.exit("bench.py: needs ccx and ema (--ccx, --ema)")
    work = os.path.abspath(args.work)
    os.makedirs(os.path.join(work, "out"), exist_ok=True)
    prefix = "J" if args.joints else "P"
    jobs = [("nominal", [E] * args.parts)]
    jobs += [("split_%s%d" % (prefix, p + 1), [E * (0.5 if q == p else 1.0) for q in range(args.parts)])
             for p in range(args.parts)]
    for job, moduli in jobs:
        write_deck(os.path.join(work, job + ".inp"), args.n, args.parts, moduli, joints=args.joints)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(args.jobs) as pool:
        list(pool.map(lambda j: run_ccx(ccx, work, j[0], args.rerun_ccx), jobs))
    print("ccx: %d runs, %.0f s" % (len(jobs), time.perf_counter() - t0))
    size = sum(os.path.getsize(os.path.join(work, j + x)) for j, _ in jobs for x in (".sti", ".dof")) + \
        os.path.getsize(os.path.join(work, "nominal.mas"))
    cmd = [ema, "fe-import", "--nominal", os.path.join(work, "nominal")]
    for p in range(args.parts):
        cmd += ["--part", "%s%d=%s" % (prefix, p + 1, os.path.join(work, "split_%s%d" % (prefix, p + 1)))]
    cmd += ["--deck", os.path.join(work, "nominal.inp"), "-o", os.path.join(work, "out", "fe.toml")]
    if args.joints:
        cmd += ["--group", "joints", "--uncertainty", "0.5"]
    r, wall, rss = timed(cmd)
    sys.stdout.write(r.stdout)
    if r.returncode != 0:
        sys.exit("bench.py: ema fe-import failed:\n" + r.stderr)
    print("ema fe-import: %s wall, %.2f GB peak RSS, %.2f GB of ccx files read" % (wall, rss, size / 1e9))
    if args.diagnose:
        loose = args.loose or "J%d" % ((args.parts + 1) // 2)
        if not diagnose(ema, work, args.n, args.parts, loose, args.factor, args.modes):
            sys.exit(1)


if __name__ == "__main__":
    main()
