#!/usr/bin/env python3
"""Times `ema fe-import` on a large CalculiX model: a clamped bar of C3D8 bricks cut into PARTS
segments along x, each its own *ELSET and material (docs/performance.md, "ema fe-import").

    python3 bench/fe-import/bench.py --work DIR [--ema PATH] [--ccx PATH] [--n 20 20 167] [--parts 10]

Writes the decks into DIR, runs ccx (*FREQUENCY, SOLVER=MATRIXSTORAGE) on the nominal deck and on
one deck per part with that part's modulus halved (--jobs ccx runs at a time, default 2), then runs
`/usr/bin/time -v ema fe-import --nominal nominal --part P1=split_P1 ... --deck nominal.inp -o DIR/out/fe.toml` and
prints the DOFs, the parts, the wall time and the peak resident memory. The ccx runs are skipped
when their files are already there (--rerun-ccx to force). Standard library only.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

E, NU, RHO = 210.0e9, 0.3, 7850.0


def write_deck(path, n, parts, moduli, size=(0.02, 0.02, 0.0025)):
    nx, ny, nz = n  # elements along y, z (section) and x (length): nz is the bar's axis
    sx, sy, sz = size
    node = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    out = ["** bench/fe-import/bench.py: a clamped C3D8 bar, %d parts" % parts, "*NODE, NSET=NALL"]
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                out.append("%d, %.9g, %.9g, %.9g" % (node(i, j, k), i * sx, j * sy, k * sz))
    per = [nz * p // parts for p in range(parts + 1)]
    e = 0
    for p in range(parts):
        out.append("*ELEMENT, TYPE=C3D8, ELSET=P%d" % (p + 1))
        for k in range(per[p], per[p + 1]):
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
    for p in range(parts):
        out += ["*MATERIAL, NAME=M%d" % (p + 1), "*ELASTIC", "%r, %r" % (moduli[p], NU), "*DENSITY", "%r" % RHO,
                "*SOLID SECTION, ELSET=P%d, MATERIAL=M%d" % (p + 1, p + 1)]
    out += ["*STEP", "*FREQUENCY, SOLVER=MATRIXSTORAGE", "10", "*END STEP"]
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


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
    args = ap.parse_args()
    ccx, ema = shutil.which(args.ccx), shutil.which(args.ema)
    if not ccx or not ema:
        sys.exit("bench.py: needs ccx and ema (--ccx, --ema)")
    work = os.path.abspath(args.work)
    os.makedirs(os.path.join(work, "out"), exist_ok=True)
    jobs = [("nominal", [E] * args.parts)]
    jobs += [("split_P%d" % (p + 1), [E * (0.5 if q == p else 1.0) for q in range(args.parts)]) for p in range(args.parts)]
    for job, moduli in jobs:
        write_deck(os.path.join(work, job + ".inp"), args.n, args.parts, moduli)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(args.jobs) as pool:
        list(pool.map(lambda j: run_ccx(ccx, work, j[0], args.rerun_ccx), jobs))
    print("ccx: %d runs, %.0f s" % (len(jobs), time.perf_counter() - t0))
    size = sum(os.path.getsize(os.path.join(work, j + x)) for j, _ in jobs for x in (".sti", ".dof")) + \
        os.path.getsize(os.path.join(work, "nominal.mas"))
    cmd = ["/usr/bin/time", "-v", ema, "fe-import", "--nominal", os.path.join(work, "nominal")]
    for p in range(args.parts):
        cmd += ["--part", "P%d=%s" % (p + 1, os.path.join(work, "split_P%d" % (p + 1)))]
    cmd += ["--deck", os.path.join(work, "nominal.inp"), "-o", os.path.join(work, "out", "fe.toml")]
    r = subprocess.run(cmd, capture_output=True, text=True)
    sys.stdout.write(r.stdout)
    if r.returncode != 0:
        sys.exit("bench.py: ema fe-import failed:\n" + r.stderr)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", r.stderr).group(1)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr).group(1))
    print("ema fe-import: %s wall, %.2f GB peak RSS, %.2f GB of ccx files read" % (wall, rss / 1048576.0, size / 1e9))


if __name__ == "__main__":
    main()
