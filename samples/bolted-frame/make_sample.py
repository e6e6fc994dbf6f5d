#!/usr/bin/env python3
"""Builds the bolted-frame sample: FE part matrices of a bolted steel frame from CalculiX (ccx).

    python3 samples/bolted-frame/make_sample.py --out DIR [--ccx PATH] [--ema PATH] [--loose J3] [--factor 0.3]

The structure (SI units: m, kg, Pa) is a portal frame clamped at its base, meshed with 20-node
bricks (C3D20), one element across each member:

  * two columns, 40 x 40 mm, 0.645 m tall, standing on bolted base joints J1 and J2;
  * a crossbeam, 40 mm (y) x 50 mm (z), 1.04 m long, bolted to the front faces of the column tops by
    the lap joints J3 (left) and J4 (right), overhanging the right column by 0.24 m;
  * a 40 x 40 mm bracket hanging 0.305 m from the beam's overhanging end, bolted by the lap joint J5.

Each joint is a 5 mm layer of elements (its own *ELSET J1..J5 and its own material, the equivalent
modulus of the clamped interface). Members and joints share nodes only through the joint layers.

ccx is run with *FREQUENCY, SOLVER=MATRIXSTORAGE on the nominal deck and once per joint with that
joint's modulus halved; K is linear in each set's modulus, so the joint's own stiffness is
K_Jk = (K_nominal - K_k) / (1 - 0.5) and the members' stiffness is K_rest = K_nominal - sum K_Jk.
`ema fe-import` makes them, sparse, from ccx's files, and checks them (the same DOF map in every
run, symmetry, each part positive semi-definite and on its own elements' DOFs, the parts not
overlapping); the mass matrix is the nominal one. The script then checks them against ccx's own
eigenvalues: the eigenvalues of (K_rest + sum K_Jk, M) equal ccx's own
eigenvalues of the nominal deck, and those of (K_rest + sum K_Jk with the loosened joint scaled, M)
equal ccx's eigenvalues of a deck whose joint modulus is scaled (1e-6 relative).

Writes into DIR only: M.mtx, K_rest.mtx, K_J1.mtx..K_J5.mtx, dofs.csv, fe.toml (by ema fe-import), nodes.csv, model.toml,
truth-model.toml, plan.toml, project.toml and ccx/ (the ccx input decks and their .dat output).
Needs Python 3 and numpy, ccx from the Debian package calculix-ccx, and ema (on PATH or --ema).
"""
import argparse
import math
import os
import shutil
import subprocess
import sys
import time

# One BLAS thread: the dense eigen-solves are small, and the machine is shared with builds.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

try:
    import numpy as np
except ImportError:  # pragma: no cover
    sys.exit("make_sample.py: numpy is needed (Debian: apt-get install python3-numpy, then run it with /usr/bin/python3)")

# --- materials (SI) ---------------------------------------------------------------------------
E_STEEL = 210.0e9      # Pa
NU = 0.3
RHO = 7850.0           # kg/m^3
E_JOINT = 7.0e9        # Pa: equivalent modulus of a 5 mm bolted-interface layer (nominal)
SPLIT_SCALE = 0.5      # modulus factor of the per-joint ccx runs (a power of two: exact scaling)
DAMPING = 0.01
UNCERTAINTY = 0.5      # prior 1-sigma of ln(joint stiffness)
N_EIG = 12             # eigenvalues asked of ccx (and compared)

# --- geometry (m) -----------------------------------------------------------------------------
T_J = 0.005            # joint layer thickness
A = 0.04               # column / bracket section side
XB = 0.76              # left face of the right column
X_END = 1.04           # free end of the beam's overhang
Z_BEAM = 0.60          # underside of the beam (= bottom of the corner joints)
Z_TOP = 0.65           # top of beam and columns
Z_BRACKET = 0.345      # lower end of the bracket
Y_COL = (0.0, A)                       # columns
Y_J34 = (A, A + T_J)                   # corner lap-joint layers
Y_BEAM = (A + T_J, 2 * A + T_J)        # beam
Y_J5 = (2 * A + T_J, 2 * A + 2 * T_J)  # bracket lap-joint layer
Y_BRK = (2 * A + 2 * T_J, 3 * A + 2 * T_J)


def _grid(*pieces):
    out = []
    for lo, hi, n in pieces:
        for i in range(n + 1):
            v = round(lo + (hi - lo) * i / n, 9)
            if not out or v > out[-1] + 1e-12:
                out.append(v)
    return out


XS = _grid((0.0, A, 1), (A, XB, 9), (XB, XB + A, 1), (XB + A, X_END - A, 3), (X_END - A, X_END, 1))
YS = [round(v, 9) for v in (0.0, A, A + T_J, 2 * A + T_J, 2 * A + 2 * T_J, 3 * A + 2 * T_J)]
ZS = _grid((0.0, T_J, 1), (T_J, Z_BEAM, 7), (Z_BEAM, Z_TOP, 1))

# (elset, x-range, y-range, z-range); members first, then the joints J1..J5.
BOXES = [
    ("COLUMNS", (0.0, A), Y_COL, (T_J, Z_TOP)),
    ("COLUMNS", (XB, XB + A), Y_COL, (T_J, Z_TOP)),
    ("BEAM", (0.0, X_END), Y_BEAM, (Z_BEAM, Z_TOP)),
    ("BRACKET", (X_END - A, X_END), Y_BRK, (Z_BRACKET, Z_TOP)),
    ("J1", (0.0, A), Y_COL, (0.0, T_J)),
    ("J2", (XB, XB + A), Y_COL, (0.0, T_J)),
    ("J3", (0.0, A), Y_J34, (Z_BEAM, Z_TOP)),
    ("J4", (XB, XB + A), Y_J34, (Z_BEAM, Z_TOP)),
    ("J5", (X_END - A, X_END), Y_J5, (Z_BEAM, Z_TOP)),
]
MEMBERS = ["COLUMNS", "BEAM", "BRACKET"]
JOINTS = ["J1", "J2", "J3", "J4", "J5"]

# C3D20 node order (Abaqus/ccx): corners 1-8, mid-edges 9-20, as offsets on the half-grid.
C3D20 = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2),
         (1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2), (1, 2, 2), (0, 1, 2),
         (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1)]


class Mesh:
    def __init__(self):
        half = []
        for g in (XS, YS, ZS):
            h = []
            for i, v in enumerate(g):
                h.append(v)
                if i + 1 < len(g):
                    h.append(round(0.5 * (v + g[i + 1]), 12))
            half.append(h)
        cells = []  # (elset, (i, j, k))
        for i in range(len(XS) - 1):
            for j in range(len(YS) - 1):
                for k in range(len(ZS) - 1):
                    c = (0.5 * (XS[i] + XS[i + 1]), 0.5 * (YS[j] + YS[j + 1]), 0.5 * (ZS[k] + ZS[k + 1]))
                    owners = [b[0] for b in BOXES if all(b[1 + a][0] < c[a] < b[1 + a][1] for a in range(3))]
                    if len(owners) > 1:
                        raise RuntimeError("mesh: overlapping boxes %s" % owners)
                    if owners:
                        cells.append((owners[0], (i, j, k)))
        keys = set()
        for _, (i, j, k) in cells:
            for o in C3D20:
                keys.add((2 * i + o[0], 2 * j + o[1], 2 * k + o[2]))
        order = sorted(keys, key=lambda q: (q[2], q[1], q[0]))
        self.node_id = {q: n + 1 for n, q in enumerate(order)}
        self.coords = {n + 1: (half[0][q[0]], half[1][q[1]], half[2][q[2]]) for n, q in enumerate(order)}
        self.elements = []  # (element id, elset, [20 node ids])
        for e, (elset, (i, j, k)) in enumerate(sorted(cells, key=lambda c: (order_of(c[0]), c[1][2], c[1][1], c[1][0]))):
            nodes = [self.node_id[(2 * i + o[0], 2 * j + o[1], 2 * k + o[2])] for o in C3D20]
            self.elements.append((e + 1, elset, nodes))
        self.base = sorted(n for n, xyz in self.coords.items() if xyz[2] == 0.0)

    def elset_nodes(self, name):
        return sorted({n for _, s, nodes in self.elements if s == name for n in nodes})


def order_of(elset):
    return (MEMBERS + JOINTS).index(elset)


def write_deck(path, mesh, joint_modulus, eigen):
    """The ccx input deck; eigen=False: store K and M (MATRIXSTORAGE), True: solve N_EIG modes."""
    out = ["** Bolted portal frame (samples/bolted-frame/make_sample.py). SI units: m, kg, Pa.",
           "*HEADING", "bolted frame: columns, beam, bracket, joints J1-J5",
           "*NODE, NSET=NALL"]
    for n in sorted(mesh.coords):
        x, y, z = mesh.coords[n]
        out.append("%d, %r, %r, %r" % (n, x, y, z))
    for elset in MEMBERS + JOINTS:
        out.append("*ELEMENT, TYPE=C3D20, ELSET=%s" % elset)
        for e, s, nodes in mesh.elements:
            if s == elset:
                out.append(", ".join(str(v) for v in [e] + nodes[:15]) + ",")
                out.append(", ".join(str(v) for v in nodes[15:]))
    out.append("*NSET, NSET=NBASE")
    for i in range(0, len(mesh.base), 12):
        out.append(", ".join(str(n) for n in mesh.base[i:i + 12]))
    out += ["*BOUNDARY", "NBASE, 1, 3"]
    mats = [("STEEL", E_STEEL, MEMBERS)] + [("M_" + j, joint_modulus[j], [j]) for j in JOINTS]
    for name, e_mod, sets in mats:
        out += ["*MATERIAL, NAME=%s" % name, "*ELASTIC", "%r, %r" % (e_mod, NU), "*DENSITY", "%r" % RHO]
        for s in sets:
            out.append("*SOLID SECTION, ELSET=%s, MATERIAL=%s" % (s, name))
    out.append("*STEP")
    if eigen:
        out += ["*FREQUENCY", "%d" % N_EIG]
    else:
        out += ["*FREQUENCY, SOLVER=MATRIXSTORAGE", "%d" % N_EIG]
    out.append("*END STEP")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


class Ccx:
    def __init__(self, exe, work):
        self.exe, self.work, self.seconds, self.runs = exe, work, 0.0, 0
        env = dict(os.environ)
        env["OMP_NUM_THREADS"] = "1"
        env["CCX_NPROC_STIFFNESS"] = "1"
        env["CCX_NPROC_EQUATION_SOLVER"] = "1"
        self.env = env

    def version(self):
        try:
            r = subprocess.run([self.exe, "-v"], capture_output=True, text=True, timeout=30)
        except OSError as e:
            fail("cannot run ccx '%s': %s" % (self.exe, e))
        for line in (r.stdout + r.stderr).splitlines():
            if "Version" in line:
                return line.strip().split("Version")[-1].strip()
        return "unknown"

    def run(self, job, expect):
        t0 = time.perf_counter()
        try:
            r = subprocess.run([self.exe, "-i", job], cwd=self.work, capture_output=True, text=True,
                               timeout=600, env=self.env)
        except (OSError, subprocess.TimeoutExpired) as e:
            fail("ccx failed on %s.inp: %s" % (job, e))
        self.seconds += time.perf_counter() - t0
        self.runs += 1
        log = r.stdout + r.stderr
        with open(os.path.join(self.work, job + ".log"), "w") as f:
            f.write(log)
        # ccx exits 0 after an *ERROR too: judge by its output and by the files it must write.
        missing = [x for x in expect if not os.path.isfile(os.path.join(self.work, job + x))]
        if r.returncode != 0 or "*ERROR" in log or "Job finished" not in log or missing:
            tail = "\n".join(log.strip().splitlines()[-15:])
            fail("ccx failed on %s/%s.inp (exit %d%s); last lines of its output:\n%s" % (
                self.work, job, r.returncode, ", missing " + " ".join(job + x for x in missing) if missing else "",
                tail))


def fail(msg):
    sys.stderr.write("make_sample.py: error: %s\n" % msg)
    sys.exit(1)


def read_dofs_csv(path):
    """dofs.csv as ema fe-import writes it: a header, then 'node,dof' per matrix row."""
    with open(path) as f:
        rows = [line.strip().split(",") for line in f.readlines()[1:] if line.strip()]
    return [(int(a), int(b)) for a, b in rows]


def read_mtx(path):
    """A Matrix Market 'coordinate real symmetric' file as 0-based (rows, cols, values) of its lower triangle."""
    with open(path) as f:
        lines = [line for line in f if not line.startswith("%")]
    data = np.array(" ".join(lines[1:]).split(), dtype=float).reshape(-1, 3)
    return data[:, 0].astype(int) - 1, data[:, 1].astype(int) - 1, data[:, 2]


def dense(triplets, n):
    """The symmetric matrix of a lower triangle's triplets (for the sample's own eigen-checks: n ~ 1500)."""
    i, j, v = triplets
    a = np.zeros((n, n))
    a[i, j] = v
    a[j, i] = v
    return a


def read_eigenvalues(path):
    """Eigenvalues (rad^2/s^2) of the E I G E N V A L U E   O U T P U T table of a ccx .dat file."""
    vals, on = [], False
    with open(path) as f:
        for line in f:
            if "E I G E N V A L U E   O U T P U T" in line:
                on, vals = True, []
                continue
            if on:
                p = line.split()
                if len(p) == 5 and p[0].isdigit():
                    vals.append(float(p[1]))
                elif vals and (not p or "P A R T" in line):
                    on = False
    if not vals:
        fail("%s: no eigenvalue table" % path)
    return np.array(vals)


class Eigen:
    """Dense generalised eigen-solves K x = lambda M x through the Cholesky factor of M."""

    def __init__(self, m):
        ell = np.linalg.cholesky(m)
        self.li = np.linalg.inv(ell)  # small (n ~ 1500): an explicit inverse is fine

    def project(self, k):
        """L^-1 K L^-T, using only the rows and columns where K has entries."""
        idx = np.flatnonzero(np.abs(k).sum(axis=0))
        li = self.li[:, idx]
        return li @ k[np.ix_(idx, idx)] @ li.T

    def values(self, a):
        return np.linalg.eigvalsh(0.5 * (a + a.T))

    def vectors(self, a):
        w, y = np.linalg.eigh(0.5 * (a + a.T))
        return w, self.li.T @ y


class Ritz:
    """A reduced model for quick what-ifs on the joints: the first nominal modes plus the static
    responses of the nominal structure to unit loads on every joint DOF (exact for low-rank changes
    up to the modes' truncation)."""

    def __init__(self, m, k_rest, parts, phi, k_nominal):
        idx = np.flatnonzero(sum(np.abs(p).sum(axis=0) for p in parts.values()))
        unit = np.zeros((m.shape[0], len(idx)))
        unit[idx, np.arange(len(idx))] = 1.0
        b = np.linalg.qr(np.hstack([phi, np.linalg.solve(k_nominal, unit)]))[0]
        li = np.linalg.inv(np.linalg.cholesky(b.T @ m @ b))
        self.rest = li @ (b.T @ k_rest @ b) @ li.T
        self.parts = {j: li @ (b.T @ p @ b) @ li.T for j, p in parts.items()}

    def hz(self, factors, count):
        a = self.rest + sum(factors.get(j, 1.0) * p for j, p in self.parts.items())
        return hz(np.linalg.eigvalsh(0.5 * (a + a.T))[:count])


def fit_factor(ritz, names, f_target, count):
    """The single factor on the joints `names` that best explains f_target (rms relative error)."""
    def cost(u):
        f = ritz.hz({j: math.exp(u) for j in names}, count)
        return float(np.sqrt(np.mean((f / f_target[:count] - 1.0) ** 2)))
    lo, hi, g = math.log(0.01), math.log(10.0), (math.sqrt(5.0) - 1.0) / 2.0
    c, d = hi - g * (hi - lo), lo + g * (hi - lo)
    fc, fd = cost(c), cost(d)
    for _ in range(50):
        if fc < fd:
            hi, d, fd = d, c, fc
            c = hi - g * (hi - lo)
            fc = cost(c)
        else:
            lo, c, fc = c, d, fd
            d = lo + g * (hi - lo)
            fd = cost(d)
    u = 0.5 * (lo + hi)
    return math.exp(u), cost(u)


def hz(lam):
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)


# --- test points: (node coordinates, label) spread over the outer surfaces -----------------------
def test_point_coords():
    pts = []
    zc = [ZS[3], ZS[5], ZS[7]]  # 0.175, 0.345, 0.515 m up the columns
    for z in zc + [Z_BEAM]:
        pts.append(((0.0, 0.0, z), "left column"))
    for z in zc + [Z_BEAM]:
        pts.append(((XB + A, 0.0, z), "right column"))
    for x in (0.0, XS[3], XS[6], XS[9], XB + A, X_END):
        pts.append(((x, Y_BEAM[1], Z_TOP), "beam top, front edge"))
    for x in (XS[5], X_END):
        pts.append(((x, Y_BEAM[0], Z_TOP), "beam top, back edge"))
    for z in (ZS[6], Z_BRACKET):
        pts.append(((X_END, Y_BRK[1], z), "bracket, front"))
    return pts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="folder to write the sample into (created)")
    ap.add_argument("--ccx", default=None, help="the CalculiX solver (default: ccx on PATH)")
    ap.add_argument("--ema", default=None, help="the ema executable, for `ema fe-import` (default: ema on PATH)")
    ap.add_argument("--loose", default="J3", choices=JOINTS, help="joint loosened in the truth model")
    ap.add_argument("--factor", type=float, default=0.3, help="its stiffness factor in the truth model")
    ap.add_argument("--keep-ccx-files", action="store_true",
                    help="keep ccx's .sti/.mas/.dof/.frd files in OUT/ccx (default: only decks, .dat, logs)")
    args = ap.parse_args()
    if not (0.0 < args.factor) or args.factor == 1.0:
        ap.error("--factor must be positive and not 1")
    t_start = time.perf_counter()
    exe = args.ccx or shutil.which("ccx")
    if not exe or not (os.path.isfile(exe) and os.access(exe, os.X_OK)) and not shutil.which(exe):
        fail("CalculiX ccx not found%s; install it (Debian: apt-get install calculix-ccx) or pass --ccx PATH"
             % (" at '%s'" % args.ccx if args.ccx else " on PATH"))
    exe = os.path.abspath(shutil.which(exe) or exe)  # absolute: ccx runs in OUT/ccx
    ema = shutil.which(args.ema or "ema")
    if not ema:
        fail("ema not found%s; build it (cmake --build build --target ema) and put it on PATH or pass --ema PATH"
             % (" at '%s'" % args.ema if args.ema else " on PATH"))
    ema = os.path.abspath(ema)
    out = os.path.abspath(args.out)
    here = os.path.dirname(os.path.abspath(__file__))
    if os.path.commonpath([out, here]) == here:
        fail("--out must not be inside the sample's source folder (%s)" % here)
    work = os.path.join(out, "ccx")
    os.makedirs(work, exist_ok=True)
    ccx = Ccx(exe, work)
    version = ccx.version()

    mesh = Mesh()
    nominal = {j: E_JOINT for j in JOINTS}

    # 1. Matrices: nominal deck, then one deck per joint with its modulus scaled.
    jobs = [("nominal", nominal)] + [("split_" + j, dict(nominal, **{j: SPLIT_SCALE * E_JOINT})) for j in JOINTS]
    for job, moduli in jobs:
        write_deck(os.path.join(work, job + ".inp"), mesh, moduli, eigen=False)
        ccx.run(job, (".sti", ".mas", ".dof"))

    # 2. Parts by difference, sparse, by ema: K_Jk = (K_nominal - K_k) / (1 - 0.5), K_rest =
    # K_nominal - sum K_Jk, and the checks (the same DOF map in every run, symmetry, each part
    # positive semi-definite, the parts not overlapping, each K_Jk on its own element's DOFs and
    # K_rest on the members' -- the deck's *ELSETs). It writes M.mtx, K_rest.mtx,
    # K_J1.mtx..K_J5.mtx, dofs.csv and fe.toml ([fe] + [[fe.part]]) into OUT.
    import_cmd = [ema, "fe-import", "--nominal", os.path.join(work, "nominal")]
    for j in JOINTS:
        import_cmd += ["--part", "%s=%s:%r" % (j, os.path.join(work, "split_" + j), SPLIT_SCALE)]
    import_cmd += ["--deck", os.path.join(work, "nominal.inp"), "-o", os.path.join(out, "fe.toml"),
                   "--group", "joints", "--uncertainty", repr(UNCERTAINTY), "--nodes", "nodes.csv"]
    r = subprocess.run(import_cmd, capture_output=True, text=True)
    if r.returncode != 0:
        fail("ema fe-import failed (exit %d):\n%s" % (r.returncode, (r.stdout + r.stderr).strip()))
    for line in r.stdout.strip().splitlines():
        print("ema fe-import: " + line)
    dofs = read_dofs_csv(os.path.join(out, "dofs.csv"))
    n = len(dofs)
    index = {dof: r for r, dof in enumerate(dofs)}
    if any(d not in (1, 2, 3) for _, d in dofs):
        fail("unexpected ccx DOF map (directions other than 1..3)")
    if any(nd in mesh.base for nd, _ in dofs) or len(dofs) != 3 * (len(mesh.coords) - len(mesh.base)):
        fail("ccx DOF map: expected every node but the clamped base, three directions each")
    M = read_mtx(os.path.join(out, "M.mtx"))
    k_rest = read_mtx(os.path.join(out, "K_rest.mtx"))
    parts = {j: read_mtx(os.path.join(out, "K_%s.mtx" % j)) for j in JOINTS}
    joint_dofs = len(set(parts[JOINTS[0]][0]) | set(parts[JOINTS[0]][1]))
    M, k_rest = dense(M, n), dense(k_rest, n)
    parts = {j: dense(parts[j], n) for j in JOINTS}

    # 3. Eigenvalues against ccx's own: nominal deck and the deck with the loosened joint.
    truth_moduli = dict(nominal, **{args.loose: args.factor * E_JOINT})
    for job, moduli in (("eig_nominal", nominal), ("eig_truth", truth_moduli)):
        write_deck(os.path.join(work, job + ".inp"), mesh, moduli, eigen=True)
        ccx.run(job, (".dat",))
    lam_ccx = read_eigenvalues(os.path.join(work, "eig_nominal.dat"))
    lam_ccx_truth = read_eigenvalues(os.path.join(work, "eig_truth.dat"))
    eig = Eigen(M)
    a_rest = eig.project(k_rest)
    a_part = {j: eig.project(parts[j]) for j in JOINTS}
    a_nom = a_rest + sum(a_part.values())
    lam_nom, phi_nom = eig.vectors(a_nom)
    lam_truth, phi_truth = eig.vectors(a_nom + (args.factor - 1.0) * a_part[args.loose])
    for what, mine, theirs in (("nominal", lam_nom, lam_ccx), ("truth", lam_truth, lam_ccx_truth)):
        rel = np.abs(mine[:len(theirs)] - theirs) / theirs
        if rel.max() > 1e-6:
            fail("%s eigenvalues differ from ccx's by %.3g (relative); ccx %s, parts %s" % (
                what, rel.max(), theirs[:6], mine[:6]))
        print("check: %s eigenvalues of the parts = ccx's (%d modes, max relative difference %.1e)"
              % (what, len(theirs), rel.max()))
    f_nom, f_truth = hz(lam_nom), hz(lam_truth)

    # 4. The test: band over the modes, points, reference and roving sets.
    n_modes = 8
    f_in = max(f_nom[n_modes - 1], f_truth[n_modes - 1])     # highest mode in the band, nominal or truth
    f_out = min(f_nom[n_modes], f_truth[n_modes])             # lowest mode above it
    band = (math.floor(0.8 * min(f_nom[0], f_truth[0]) / 5.0) * 5.0,
            math.ceil((f_in + 0.35 * (f_out - f_in)) / 5.0) * 5.0)
    if not f_in < band[1] < f_out:
        fail("no band upper limit separates mode %d (%.1f Hz) from mode %d (%.1f Hz)"
             % (n_modes, f_in, n_modes + 1, f_out))
    gaps = np.diff(f_truth[:n_modes + 1]) / f_truth[:n_modes]
    if gaps.min() < 0.03:
        fail("modes closer than 3 %% (%s)" % np.round(f_truth[:n_modes + 1], 1))
    coord_node = {v: k for k, v in mesh.coords.items()}
    points = []
    for i, (xyz, label) in enumerate(test_point_coords()):
        key = tuple(round(c, 9) for c in xyz)
        node = next((nd for c, nd in coord_node.items() if all(abs(a - b) < 1e-9 for a, b in zip(c, key))), None)
        if node is None or (node, 1) not in index:
            fail("no free FE node at test point %s" % (xyz,))
        points.append((101 + i, node, label))
    # Reference: the test DOF where the weakest of the band's modes is strongest (truth model, as tested).
    best = None
    for pid, node, _ in points:
        for d, name in ((1, "X"), (2, "Y"), (3, "Z")):
            amp = np.abs(phi_truth[index[(node, d)], :n_modes]) / np.abs(phi_truth[:, :n_modes]).max(axis=0)
            if best is None or amp.min() > best[0]:
                best = (amp.min(), "%d+%s" % (pid, name))
    reference = best[1]
    fs = 2.56 * band[1]
    fs = float(2 ** math.ceil(math.log2(fs))) if fs > 1024 else float(math.ceil(fs / 256.0) * 256)
    t_decay = 5.0 / (DAMPING * 2 * math.pi * min(f_truth[0], f_nom[0]))  # 5 time constants of mode 1
    samples = int(2 ** math.ceil(math.log2(t_decay * fs)))

    # 5. Files.
    with open(os.path.join(out, "nodes.csv"), "w") as f:
        f.write("node,x,y,z\n" + "".join("%d,%r,%r,%r\n" % ((nd,) + mesh.coords[nd]) for nd in sorted(mesh.coords)))
    model = model_toml(version, n, points, mesh, os.path.join(out, "fe.toml"))
    with open(os.path.join(out, "model.toml"), "w") as f:
        f.write(model)
    with open(os.path.join(out, "truth-model.toml"), "w") as f:
        f.write(model.replace('name = "Bolted frame (nominal joints)"',
                              'name = "Bolted frame (truth: %s loosened)"' % args.loose, 1))
        f.write("\n# The truth: joint %s has lost stiffness (ccx: its modulus x %g gives the same modes).\n"
                "[[effect]]\nkind = \"stiffness_scale\"\ntarget = \"joints/%s\"\nfactor = %r\n"
                % (args.loose, args.factor, args.loose, args.factor))
    with open(os.path.join(out, "plan.toml"), "w") as f:
        f.write(plan_toml(points, reference, fs, samples))
    with open(os.path.join(out, "project.toml"), "w") as f:
        f.write(project_toml(points, band))
    if not args.keep_ccx_files:
        for name in os.listdir(work):
            if not name.endswith((".inp", ".dat", ".log")):
                os.remove(os.path.join(work, name))

    # 6. Summary.
    counts = {s: sum(1 for _, es, _ in mesh.elements if es == s) for s in MEMBERS + JOINTS}
    print("bolted frame: %d nodes, %d C3D20 elements (%s), %d DOFs after clamping %d base nodes"
          % (len(mesh.coords), len(mesh.elements), ", ".join("%s %d" % kv for kv in counts.items()), n,
             len(mesh.base)))
    print("parts: K_rest (members) + %d joints in group 'joints' (%s), %d DOFs (J1); joint modulus %.3g GPa"
          % (len(JOINTS), ", ".join(JOINTS), joint_dofs, E_JOINT / 1e9))
    print("ccx %s: %d runs, %.2f s" % (version, ccx.runs, ccx.seconds))
    print("%-5s %10s %10s %8s" % ("mode", "nominal", "truth", "change"))
    for i in range(n_modes + 1):
        print("%-5d %9.2f  %9.2f  %+7.2f %%%s" % (i + 1, f_nom[i], f_truth[i], 100 * (f_truth[i] / f_nom[i] - 1),
                                                  "" if i < n_modes else "   (above the band)"))
    print("truth: %s x %g; band %g-%g Hz (%d modes); reference %s; %g Hz x %d samples (%.2f s)"
          % (args.loose, args.factor, band[0], band[1], n_modes, reference, fs, samples, samples / fs))
    ritz = Ritz(M, k_rest, parts, phi_nom[:, :40], k_rest + sum(parts.values()))
    err = np.abs(ritz.hz({args.loose: args.factor}, n_modes) / f_truth[:n_modes] - 1).max()
    print("sensitivity (each joint alone x %g, %% change of modes 1-%d; reduced model, %.0e of the full one):"
          % (args.factor, n_modes, err))
    for j in JOINTS:
        f = ritz.hz({j: args.factor}, n_modes)
        print("  %-6s %s" % (j, " ".join("%+6.2f" % v for v in 100 * (f / f_nom[:n_modes] - 1))))
    fits = sorted(((fit_factor(ritz, names, f_truth, n_modes), label) for label, names in
                   [(j, [j]) for j in JOINTS] + [("joints", JOINTS)]), key=lambda t: t[0][1])
    print("truth frequencies explained by one factor on (best first): " + "; ".join(
        "%s x %.3f (rms %.2f %%)" % (label, fac, 100 * rms) for (fac, rms), label in fits))
    if fits[0][1] != args.loose:
        print("note: the frequencies alone point to %s, not to the loosened %s" % (fits[0][1], args.loose))
    print("wrote %s (%.1f s)" % (out, time.perf_counter() - t_start))


def model_toml(version, n, points, mesh, fe_toml):
    """model.toml: the [fe] + [[fe.part]] tables ema fe-import wrote (fe_toml), the damping and the points."""
    with open(fe_toml) as f:
        fe = "".join(line for line in f if not line.startswith("#"))
    lines = [
        "# Bolted steel portal frame: FE matrices from CalculiX ccx %s (C3D20 bricks, SI units)," % version,
        "# made by samples/bolted-frame/make_sample.py. %d DOFs; the joints J1..J5 are parts of group" % n,
        "# 'joints', each the difference of two ccx assemblies, imported by `ema fe-import`",
        "# (see samples/bolted-frame/README.md). [fe].stiffness: the members (columns, beam, bracket).",
        "[model]",
        'name = "Bolted frame (nominal joints)"',
        "",
        fe.strip(),
    ]
    lines += ["", "[damping]", "ratio = %r" % DAMPING, ""]
    for pid, node, label in points:
        x, y, z = mesh.coords[node]
        lines += ["[[point]]                  # %s (%.3f, %.3f, %.3f) m" % (label, x, y, z),
                  "id = %d" % pid, "node = %d" % node]
    return "\n".join(lines) + "\n"


def plan_toml(points, reference, fs, samples):
    ids = [p[0] for p in points]
    per = 5
    sets = [ids[i:i + per] for i in range(0, len(ids), per)]
    lines = [
        "# Simulated roving-accelerometer hammer test of the bolted frame (docs/plan-format.md):",
        "# %d test points x 3 directions in %d roving sets of triaxial accelerometers, the hammer at"
        % (len(ids), len(sets)),
        "# %s, 5 impacts per set, 1 %% noise on every channel. Made by make_sample.py." % reference,
        "[plan]",
        'references = ["%s"]' % reference,
        "sample_rate_hz = %r" % fs,
        "samples = %d" % samples,
        "pre_trigger = 0.05",
        "impacts = 5",
        "force_peak_n = 200.0",
        "force_spread = 0.15",
        "pulse_duration_s = 1.0e-3",
        "force_noise = 0.01",
        "response_noise = 0.01",
        'response = "acceleration"',
        "sensor_mass = 0.0",
        "seed = 7",
    ]
    for i, s in enumerate(sets):
        lines += ["", "[[set]]", 'name = "set %d"' % (i + 1),
                  "sensors = [%s]" % ", ".join('"%d+%s"' % (p, d) for p in s for d in "XYZ")]
    return "\n".join(lines) + "\n"


def project_toml(points, band):
    by = {}
    for pid, _, label in points:
        by.setdefault(label, []).append(pid)
    lines = []
    for ids in by.values():
        lines += [[a, b] for a, b in zip(ids, ids[1:])]
    lc, rc = by["left column"], by["right column"]
    front, back, brk = by["beam top, front edge"], by["beam top, back edge"], by["bracket, front"]
    lines += [[lc[-1], front[0]], [rc[-1], front[4]], [front[-1], brk[0]], [back[-1], front[-1]]]
    return "\n".join([
        "# `ema run project.toml -o REPORT/` on the simulated test of the bolted frame (docs/project-file.md).",
        "# time.unv: ema simulate truth-model.toml --plan plan.toml -o time.unv",
        "[project]",
        'name = "Bolted frame"',
        'model = "model.toml"           # nominal joints; the truth has one joint loosened',
        "",
        "[[test]]",
        'name = "hammer"',
        'time = ["time.unv"]',
        "",
        "[frf]",
        'estimator = "H1"',
        "",
        "[fit]",
        "band = [%r, %r]            # Hz: the frame's first eight modes" % band,
        'select = "auto"',
        "",
        "[report]",
        'title = "Bolted frame: which joint has loosened?"',
        "lines = [%s]" % ", ".join("[%d, %d]" % tuple(l) for l in lines),
    ]) + "\n"


if __name__ == "__main__":
    main()
