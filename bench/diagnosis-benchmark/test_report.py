"""Unit test of report.py's model-form scores (ctest diagnosis-benchmark/form-report): four
hand-made score rows whose scores are counted by hand below."""

import os
import sys
import unittest

sys.dont_write_bytecode = True  # no __pycache__ left in the source tree by the test
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report  # noqa: E402


def row(index, noise, truth, shifts, rank1, p, right, rms=0.5, exceeds=True, inadequate=True):
    kinds = "+".join(k for k, _ in rank1) or "none"
    targets = "+".join(t for _, t in rank1)
    return {"index": index, "seed": 2026, "family": "form", "noise": noise,
            "truth": [{"kind": k, "target": t} for k, t in truth], "effect_shift_pct": shifts,
            "rank1": {"kind": kinds, "target": targets, "probability": p}, "p_rank1": p, "right": right,
            "form_error_rms_pct": rms, "effects_clear": bool(truth) and all(x >= 3 * rms for x in shifts),
            "invented": not truth and bool(rank1), "form_exceeds_noise": exceeds, "said_inadequate": inadequate}


def table_rows(text):
    """The table rows of form_tables' text by their first cell."""
    return {ln.split(" | ")[0].lstrip("| "): ln for ln in text.splitlines() if ln.startswith("| ")}


SUPPORTS = ("series_compliance", "supports")
MASS = ("added_mass", "points:102")
ROWS = [
    # clear effect (40 % ≥ 1.5 %) found: right either way
    row(0, 0.005, [SUPPORTS], [40.0], [SUPPORTS], 0.9, True),
    # a mass below 3 × the model error (1.0 % < 1.5 %) left out: wrong, but right against what is visible
    row(1, 0.02, [SUPPORTS, MASS], [30.0, 1.0], [SUPPORTS], 0.8, False),
    # nothing hidden, a mass invented, the model called adequate where its error exceeds the noise
    row(2, 0.005, [], [], [MASS], 0.6, False, inadequate=False),
    # 5 % noise: outside the 0.5–2 % columns
    row(3, 0.05, [], [], [], 0.7, True),
]


class FormReport(unittest.TestCase):
    def test_visible_right(self):
        self.assertTrue(report.visible_right(ROWS[0]))
        self.assertTrue(report.visible_right(ROWS[1]))  # the hidden mass is below the model error
        self.assertFalse(report.visible_right(ROWS[2]))  # invented
        self.assertTrue(report.visible_right(ROWS[3]))
        extra = row(4, 0.005, [SUPPORTS], [40.0], [SUPPORTS, MASS], 0.5, False)
        self.assertFalse(report.visible_right(extra))  # holds an effect not hidden

    def test_table(self):
        text = report.form_tables(ROWS)
        lines = table_rows(text)
        self.assertIn("| 1/1 = 100.0 % | 1/1 = 100.0 % |", lines["rank 1 right, hidden effects clearly beyond the model error"])
        self.assertIn("| 1/2 = 50.0 % | 1/1 = 100.0 % |", lines["discrete effect invented, none hidden"])
        self.assertIn("| 3/4 = 75.0 % | 2/3 = 66.7 % |",
                      lines['"not adequate" said where the model error exceeds the noise'])
        # Brier, 0.5–2 % (rows 0-2): ((0.9-1)² + 0.8² + 0.6²)/3 = (0.01 + 0.64 + 0.36)/3 = 0.337;
        # against the visible truth ((0.01 + 0.04 + 0.36)/3) = 0.137
        self.assertIn("| 0.337 |", lines["Brier score of rank 1's probability"])
        self.assertIn("| 0.137 |", lines["Brier score, right = every clearly visible hidden effect and nothing not hidden"])
        self.assertIn("| 2 | 0.5 % |", text)  # case 2 listed among the misses


    def test_spread_named(self):
        # Nothing hidden; rank 1 names the form truth's spread mass at its size: no invention, right.
        spread = row(5, 0.005, [], [], [("added_mass", "all_points")], 0.7, False, exceeds=True, inadequate=False)
        spread.update({"spread_named": True, "right_spread": True, "invented_spread": False,
                       "form_left_exceeds_noise": False})
        # The same rank 1 but its mass far from the spread's: invented, and the model error it leaves
        # exceeds the noise while it says adequate.
        wrong = dict(spread, index=6, spread_named=False, right_spread=False, invented_spread=True,
                     form_left_exceeds_noise=True)
        self.assertTrue(report.visible_right(spread, True))
        self.assertFalse(report.visible_right(spread))
        self.assertFalse(report.visible_right(wrong, True))
        text = report.form_tables([spread, wrong])
        lines = table_rows(text)
        self.assertIn("| 2/2 = 100.0 % | 2/2 = 100.0 % |", lines["discrete effect invented, none hidden"])
        self.assertIn("| 1/2 = 50.0 % | 1/2 = 50.0 % |", lines["discrete effect invented, none hidden ‡"])
        # Adequate said by both; the error left exceeds the noise in one: 0/2 strict, 0/1 with the spread.
        self.assertIn("| 0/1 = 0.0 % | 0/1 = 0.0 % |",
                      lines['"not adequate" said where the model error rank 1 leaves exceeds the noise ‡'])
        # Brier with the spread: ((0.7 - 1)² + 0.7²)/2 = (0.09 + 0.49)/2 = 0.29; strict (0.49 + 0.49)/2 = 0.49
        self.assertIn("| 0.290 |", lines["Brier score of rank 1's probability ‡"])
        self.assertIn("| 0.490 |", lines["Brier score of rank 1's probability"])
        self.assertIn("| 6 | 0.5 % |", text)      # the wrong one among the misses
        self.assertNotIn("| 5 | 0.5 % |", text)   # the named spread is not


    def test_closed_loop(self):
        # Rows 0-2 at 0.5–2 %: row 0 not replanned (right at 0.9); row 1 replanned and right after
        # (its mass found, p 0.95); row 2 replanned, "none" after at 0.7 (right: nothing hidden).
        rows = [dict(r) for r in ROWS]
        rows[1]["replan"] = {"right_after": True, "p_rank1_after": 0.95,
                             "rank1_after": {"kind": "series_compliance+added_mass", "target": "supports+points:102"}}
        rows[2]["replan"] = {"right_after": True, "p_rank1_after": 0.7, "rank1_after": {"kind": "none", "target": ""}}
        lines = table_rows(report.closed_loop_table(rows))
        self.assertIn("| 0/2 = 0.0 % | 2/2 = 100.0 % |", lines["replanned cases right"])
        self.assertIn("| 1/3 = 33.3 % | 3/3 = 100.0 % |", lines["every case right"])
        self.assertIn("| 1/1 = 100.0 % | 1/1 = 100.0 % |", lines["clearly visible hidden effects right"])
        self.assertIn("| 1/1 = 100.0 % | 0/1 = 0.0 % |", lines['nothing hidden, rank 1 not "none"'])
        # Brier first (0.01 + 0.64 + 0.36)/3 = 0.337; after (0.01 + 0.0025 + 0.09)/3 = 0.034
        self.assertIn("| 0.337 | 0.034 |", lines["Brier score of rank 1's probability"])
        self.assertEqual(report.closed_loop_table(ROWS), "")  # no --replan: no table


if __name__ == "__main__":
    unittest.main()
