#!/usr/bin/env python3
# Usage: scripts/mutation-check.py SCRATCH_WORKTREE MUTANTS.json RESULTS.json (docs/testing.md).
# Run it in a scratch worktree with a configured build/ folder, never in your own checkout.
"""Mutation check: apply each hand-made mutation to a scratch worktree, rebuild the test target,
run the module's tests, record whether at least one test fails (the mutant is 'caught')."""
import json, subprocess, sys, pathlib
tree = pathlib.Path(sys.argv[1]); spec = json.load(open(sys.argv[2])); out = sys.argv[3]
results = []
for m in spec:
    f = tree / m["file"]
    src = f.read_text()
    if src.count(m["old"]) != 1:
        results.append({**m, "result": "NOT APPLIED (pattern count %d)" % src.count(m["old"])}); continue
    f.write_text(src.replace(m["old"], m["new"]))
    try:
        b = subprocess.run(["nice", "cmake", "--build", str(tree / "build"), "-j2", "--target", *m["targets"]], capture_output=True, text=True)
        if b.returncode != 0:
            res = "does not compile"
        else:
            t = subprocess.run(["nice", "ctest", "--test-dir", str(tree / "build"), "-R", m["tests"], "-j2", "--timeout", "300"], capture_output=True, text=True)
            failed = [l.split(" - ")[1].split(" (")[0].strip() for l in t.stdout.splitlines() if " - " in l and ("Failed" in l or "Timeout" in l or "Exception" in l)]
            res = ("caught by %d test(s): %s" % (len(failed), ", ".join(failed[:4]) + (" ..." if len(failed) > 4 else ""))) if t.returncode != 0 else "NOT CAUGHT"
    finally:
        f.write_text(src)
    results.append({**m, "result": res})
    print(m["id"], res, flush=True)
json.dump(results, open(out, "w"), indent=1)
