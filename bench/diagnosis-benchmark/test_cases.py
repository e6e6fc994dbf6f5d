"""Unit test of cases.py's model-form truths (ctest diagnosis-benchmark/form-cases): the form-rich
family is the form family's cases with errors added from their own draw, and its beam elements
are Timoshenko's — checked against the closed-form tip deflection of a cantilever."""

import os
import random
import sys
import tempfile
import unittest

sys.dont_write_bytecode = True  # no __pycache__ left in the source tree by the test
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench  # noqa: E402
import cases  # noqa: E402


def solve(a, b):
    """x with a x = b (Gaussian elimination with partial pivoting; a small dense system)."""
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        for r in range(c + 1, n):
            f = m[r][c] / m[c][c]
            for k in range(c, n + 1):
                m[r][k] -= f * m[c][k]
    x = [0.0] * n
    for r in range(n - 1, -1, -1):
        x[r] = (m[r][n] - sum(m[r][k] * x[k] for k in range(r + 1, n))) / m[r][r]
    return x


def tip_deflection(kk, dofs):
    """The free end's deflection under a unit tip force, node 1 clamped (uz, ry removed)."""
    full = [[0.0] * dofs for _ in range(dofs)]
    for (r, c), v in kk.items():
        full[r][c] += v
        if r != c:
            full[c][r] += v
    keep = list(range(2, dofs))
    a = [[full[r][c] for c in keep] for r in keep]
    b = [0.0] * len(keep)
    b[-2] = 1.0  # uz of the last node
    return solve(a, b)[-2]


class FormCases(unittest.TestCase):
    def test_rich_is_the_form_case_plus_its_errors(self):
        for index in (0, 4, 17):
            form = cases.make_case(index, 2026, 0, cases.FORM_FAMILY)
            rich = cases.make_case(index, 2026, 0, cases.FORM_RICH_FAMILY)
            self.assertEqual(form["truth"], rich["truth"])
            for name in ("nominal.toml", "plan.toml", "fe/K.mtx", "fe/M.mtx"):
                self.assertEqual(form["files"][name], rich["files"][name], name)
            self.assertNotEqual(form["files"]["truth-fe/K.mtx"], rich["files"]["truth-fe/K.mtx"])
            self.assertGreater(rich["form_error"]["shear_ratio"], 0.0)
            self.assertEqual(len(rich["form_error"]["rotational_restraints"]), form["files"]["nominal.toml"].count("[[spring]]"))

    def test_timoshenko_cantilever(self):
        m, _ = cases.build_fe(random.Random(7), {})
        f = m.form
        dofs = 2 * f["nodes"]
        length, ei, h = f["length"], f["ei"], f["height"]
        # Euler: L³/3EI, exact for cubic elements; Timoshenko adds L/(κGA) = L·r·h²/(12 EI), r = E/κG.
        euler, _ = f["assemble"]()
        self.assertAlmostEqual(tip_deflection(euler, dofs) / (length ** 3 / (3 * ei)), 1.0, places=9)
        for ratio in (3.1, 40.0):
            kk, _ = f["assemble"](shear_ratio=ratio)
            exact = length ** 3 / (3 * ei) + length * ratio * h * h / (12 * ei)
            self.assertAlmostEqual(tip_deflection(kk, dofs) / exact, 1.0, places=9)
        # Nothing added: the plain beam, entry by entry.
        self.assertEqual(f["assemble"](shear_ratio=0.0, rotary=False), f["assemble"]())
        # A rotational restraint only on its node's rotation; rotary inertia only adds mass.
        kk, mm = f["assemble"](rotational_restraints={1: 5.0}, rotary=True)
        k0, m0 = f["assemble"]()
        self.assertAlmostEqual(kk[(1, 1)] - k0[(1, 1)], 5.0, places=6)
        self.assertEqual({k: v for k, v in kk.items() if k != (1, 1)}, {k: v for k, v in k0.items() if k != (1, 1)})
        self.assertGreater(mm[(1, 1)], m0[(1, 1)])

    def test_replan_counts_the_dofs_the_model_has(self):
        # The follow-up plan's free DOFs (bench.py replan): an FE beam's points carry uz only (its
        # nodes: uz, ry), a frame's (DOFs 1..6) and a body's point three translations.
        with tempfile.TemporaryDirectory() as folder:
            case = cases.make_case(0, 2026, 0, cases.FORM_FAMILY)
            cases.write_case(case, folder)
            self.assertEqual(bench.test_dof_count(folder), case["files"]["nominal.toml"].count("[[point]]"))
            self.assertGreater(bench.test_dof_count(folder), 0)
            # The look-alike family's frame: six DOFs per node, numbered 1..6, three of them translations.
            frame = cases.make_case(0, 2026, 0, cases.LOOKALIKE_FAMILY)
            with tempfile.TemporaryDirectory() as frame_folder:
                cases.write_case(frame, frame_folder)
                self.assertEqual(bench.test_dof_count(frame_folder), 3 * frame["files"]["nominal.toml"].count("[[point]]"))
            with open(os.path.join(folder, "nominal.toml"), "w") as f:
                f.write('[[point]]\nid = 1\nbody = "b"\nat = [0, 0, 0]\n\n[[point]]\nid = 2\nbody = "b"\nat = [1, 0, 0]\n')
            self.assertEqual(bench.test_dof_count(folder), 6)


if __name__ == "__main__":
    unittest.main()
