"""Which bolted joint of a frame has loosened? An FE model built from parts in numpy/scipy, diagnosed.

A planar steel portal frame (x to the right, z up; rotations about y), clamped at its base:

          J1                         J2
   301 o--o--o--o--o--o--o--o--o--o--o--o--o--o 314    beam 40 x 50 mm, 1.3 m (0.3 m overhang)
   106 o                             o 206
       |                             |
       |  column A                   |  column B        columns 40 x 40 mm, 0.8 m
       |                             |
   ////////////////////////////////////////////

The beam is bolted to the column tops: joints J1 and J2 tie node 106 to 301 and node 206 to 311
(stiff in translation, semi-rigid in rotation). Each column, the beam and each joint is a *part*
(its own stiffness matrix, model-format.md "FE models built from parts"): the parts `columns/A`,
`columns/B`, `beam`, `joints/J1`, `joints/J2`.

The "test" is made on a truth model in which joint J2 has lost 70 % of its stiffness: its modes
(ema.model_modes) at biaxial sensors on the frame, with a 0.1 % measurement σ, in `ema fit --json`'s
layout — what another lab would hand over. ema.diagnose then ranks what the nominal model misses.

Run: v/bin/python examples/fe_parts_diagnosis.py [--factor 0.3] [--joint J2]
"""
import argparse
from typing import Any, Dict, List, Sequence, Tuple

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

import ema
from ema.types import ModelDict, ModesDict, ModesJson, PartDict

Matrix = npt.NDArray[np.float64]

E, RHO = 210e9, 7850.0  # steel, Pa and kg/m^3
COLUMN = (0.04 * 0.04, 0.04 * 0.04**3 / 12)  # area m^2, second moment about y m^4
BEAM = (0.04 * 0.05, 0.04 * 0.05**3 / 12)
JOINT_TRANSLATION, JOINT_ROTATION = 1e10, 2e5  # N/m, N m/rad
DOF_NAMES = ("ux", "uz", "ry")


def frame_element(xa: Matrix, xb: Matrix, area: float, inertia: float) -> Tuple[Matrix, float]:
    """6 x 6 stiffness of a 2D Euler-Bernoulli beam element in the x-z plane, global (ux, uz, ry) per end."""
    d = np.subtract(xb, xa)
    length = float(np.hypot(*d))
    c, s = d / length
    ea, ei = E * area / length, E * inertia
    k1, k2, k3, k4 = 12 * ei / length**3, 6 * ei / length**2, 4 * ei / length, 2 * ei / length
    # Local (u, w, theta) with theta about y: dw/dx = -theta, hence the signs of the k2 terms.
    k = np.array([[ea, 0, 0, -ea, 0, 0],
                  [0, k1, -k2, 0, -k1, -k2],
                  [0, -k2, k3, 0, k2, k4],
                  [-ea, 0, 0, ea, 0, 0],
                  [0, -k1, k2, 0, k1, k2],
                  [0, -k2, k4, 0, k2, k3]])
    r = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    t = np.kron(np.eye(2), r)
    return t.T @ k @ t, length


def build_frame() -> ModelDict:
    """Nodes, DOF map, lumped mass and the parts' stiffness matrices (scipy.sparse, full storage)."""
    nodes: Dict[int, Tuple[float, float, float]] = {}
    for i in range(1, 7):  # columns: 6 elements each over 0.8 m; the base nodes 100, 200 are clamped
        nodes[100 + i] = (0.0, 0.0, 0.8 * i / 6)
        nodes[200 + i] = (1.0, 0.0, 0.8 * i / 6)
    for i in range(14):  # beam: 13 elements of 0.1 m
        nodes[301 + i] = (0.1 * i, 0.0, 0.8)
    nodes_free = sorted(nodes)
    nodes[100], nodes[200] = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)
    index = {(node, d): 3 * i + j for i, node in enumerate(nodes_free) for j, d in enumerate(DOF_NAMES)}
    n = len(index)
    dofs = [(node, d) for node in nodes_free for d in DOF_NAMES]
    mass = np.zeros(n)

    def assemble(elements: Sequence[Tuple[int, int]], section: Tuple[float, float]) -> Any:
        rows: List[int] = []
        cols: List[int] = []
        vals: List[float] = []
        for a, b in elements:
            k, length = frame_element(np.take(nodes[a], (0, 2)), np.take(nodes[b], (0, 2)), *section)
            ids = [index.get((node, d), -1) for node in (a, b) for d in DOF_NAMES]  # -1: clamped
            for p, ip in enumerate(ids):
                for q, iq in enumerate(ids):
                    if ip >= 0 and iq >= 0:
                        rows.append(ip)
                        cols.append(iq)
                        vals.append(k[p, q])
            m_half = RHO * section[0] * length / 2  # lumped: translations only, rotations massless
            for node in (a, b):
                for d in ("ux", "uz"):
                    if (node, d) in index:
                        mass[index[node, d]] += m_half
        return sp.csc_matrix((vals, (rows, cols)), shape=(n, n))

    def joint(a: int, b: int) -> Any:
        """Two coincident nodes tied: stiff in ux and uz, semi-rigid in ry (a bolted joint)."""
        rows: List[int] = []
        cols: List[int] = []
        vals: List[float] = []
        for d, k in (("ux", JOINT_TRANSLATION), ("uz", JOINT_TRANSLATION), ("ry", JOINT_ROTATION)):
            i, j = index[a, d], index[b, d]
            rows += [i, j, i, j]
            cols += [i, j, j, i]
            vals += [k, k, -k, -k]
        return sp.csc_matrix((vals, (rows, cols)), shape=(n, n))

    column_a = [(100 + i, 101 + i) for i in range(6)]
    column_b = [(200 + i, 201 + i) for i in range(6)]
    beam = [(301 + i, 302 + i) for i in range(13)]
    parts: List[PartDict] = [
        {"name": "A", "group": "columns", "stiffness": assemble(column_a, COLUMN), "uncertainty": 0.1},
        {"name": "B", "group": "columns", "stiffness": assemble(column_b, COLUMN), "uncertainty": 0.1},
        {"name": "beam", "stiffness": assemble(beam, BEAM), "uncertainty": 0.1},
        {"name": "J1", "group": "joints", "stiffness": joint(106, 301), "uncertainty": 0.5},
        {"name": "J2", "group": "joints", "stiffness": joint(206, 311), "uncertainty": 0.5},
    ]
    return {
        "name": "bolted portal frame",
        "dofs": dofs,
        "mass": sp.diags(mass).tocsc(),
        "parts": parts,
        "nodes": {node: nodes[node] for node in nodes_free},
        "points": [103, 106, 203, 206, 301, 304, 307, 311, 314],  # biaxial sensors (+X, +Z)
        "damping": 0.01,
    }


def measured(modes: ModesDict, sigma: float = 0.001, seed: int = 1) -> ModesJson:
    """A mode set in `ema fit --json`'s layout: +X and +Z at the sensors, frequencies with a 1σ noise."""
    rng = np.random.default_rng(seed)
    keep = [r for r, (_, direction) in enumerate(modes["dofs"]) if direction in ("+X", "+Z")]
    out: List[Any] = []
    for i, f in enumerate(modes["frequency_hz"]):
        f_measured = f * (1 + sigma * rng.standard_normal())
        shape = [{"node": modes["dofs"][r][0], "dir": modes["dofs"][r][1], "value": modes["shapes"][r, i].real}
                 for r in keep]
        out.append({"frequency_hz": f_measured, "frequency_std_hz": sigma * f_measured,
                    "damping_ratio": modes["damping_ratio"][i], "shape": shape})
    return {"modes": out}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--joint", default="J2", choices=["J1", "J2"], help="the joint loosened in the truth")
    parser.add_argument("--factor", type=float, default=0.3, help="its stiffness factor in the truth")
    parser.add_argument("--modes", type=int, default=6, help="test modes measured")
    args = parser.parse_args()

    nominal = build_frame()
    truth = dict(nominal, parts=[dict(p, stiffness=args.factor * p["stiffness"]) if p["name"] == args.joint else p
                                 for p in nominal["parts"]])
    test = measured(ema.model_modes(truth, max_modes=args.modes))
    print(f"{len(nominal['dofs'])} DOFs, parts: " +
          ", ".join(p.get("group", "") + "/" * ("group" in p) + p["name"] for p in nominal["parts"]))
    print(f"truth: joint {args.joint} at {args.factor:g} x its stiffness; test modes (Hz): " +
          " ".join(f"{m['frequency_hz']:.1f}" for m in test["modes"]))

    corr = ema.correlate(test, ema.model_modes(nominal))
    print(f"nominal model: agreement {corr['mean_agreement_pct']:.1f} %, mean MAC {corr['mean_mac']:.3f}")

    diagnosis = ema.diagnose(nominal, {"": test})
    best = diagnosis["candidates"][0]
    probability = best["probability"]  # None when the diagnosis could not weigh it (the JSON's null)
    share = f"{100 * probability:.0f} %" if probability is not None else "unknown"
    print(f"rank 1: {best['description']} (probability {share})")
    for key, value in best["parameters"].items():
        print(f"  {key} = {value:.3g} ± {best['uncertainty'][key]:.2g}")
    print(f"  mean frequency error {diagnosis['baseline']['mean_abs_frequency_error_pct']:.2f} % -> "
          f"{best['mean_abs_frequency_error_pct']:.3f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
