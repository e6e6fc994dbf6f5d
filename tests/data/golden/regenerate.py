#!/usr/bin/env python3
"""Rewrites the "diagnosis" numbers of the golden files from the DIAG.json files the golden tests
just wrote (run them first: ctest -R 'BenchGolden|SampleBoltedFrame') and from an `ema run` of the
guideway sample (`ema run samples/guideway/project.toml -o DIR`: what the pipeline's golden test
runs in memory). Only for a change that moves the diagnosis' numbers on purpose; say which in
`--why`, it goes into "about".

  python3 tests/data/golden/regenerate.py --build build --guideway DIR --why "shapes per DOF (2026-11-27)"
(--bolted-frame-modes: the bolted frame's fitted modes as well, for a change of the model's own solve)
"""
import argparse
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def pruned(value, template):
    """`value` cut to the keys `template` holds (a list's items to the union of its items' keys):
    the golden files keep the numbers they were written with, not every key DIAG.json has."""
    if isinstance(template, dict) and isinstance(value, dict):
        return {k: pruned(value[k], template[k]) for k in template if k in value}
    if isinstance(template, list) and isinstance(value, list) and template:
        if all(isinstance(t, dict) for t in template):
            union = {}
            for t in template:
                for k, v in t.items():
                    union.setdefault(k, v)
            return [pruned(v, union) for v in value]
        return [pruned(v, template[0]) for v in value]
    return value


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", required=True, help="the build folder the tests ran in")
    p.add_argument("--guideway", required=True, help="the output folder of `ema run samples/guideway/project.toml`")
    p.add_argument("--why", required=True, help="the change that moved the numbers")
    p.add_argument("--bolted-frame-modes", action="store_true",
                   help="also rewrite the bolted frame's fitted modes (out/hammer/modes.json): for a change of the "
                        "model's own solve, which moves the simulated test of its truth")
    args = p.parse_args()
    tmp = os.path.join(args.build, "tests", "tmp")
    sources = {f"bench-case-000{i}.json": os.path.join(tmp, "bench-golden", "cases", f"000{i}", "diag.json")
               for i in range(3)}
    sources["guideway-run.json"] = os.path.join(args.guideway, "diagnosis.json")
    sources["bolted-frame-run.json"] = os.path.join(tmp, "bolted-frame", "out", "diagnosis.json")
    for name, source in sources.items():
        if not os.path.isfile(source):
            raise SystemExit(f"regenerate.py: {source} not found; run the golden tests first")
        path = os.path.join(HERE, name)
        with open(path) as f:
            golden = json.load(f)
        with open(source) as f:
            diag = json.load(f)
        missing = [k for k in golden["diagnosis"] if k not in diag]
        if missing:
            raise SystemExit(f"regenerate.py: {source} lacks {', '.join(missing)}")
        golden["diagnosis"] = pruned(diag, golden["diagnosis"])
        golden["about"] = golden["about"].split(" Diagnosis numbers rewritten")[0] + \
            f" Diagnosis numbers rewritten for: {args.why}."
        if name == "bolted-frame-run.json" and args.bolted_frame_modes:
            with open(os.path.join(tmp, "bolted-frame", "out", "hammer", "modes.json")) as f:
                golden["modes"]["hammer"] = pruned(json.load(f), golden["modes"]["hammer"])
            golden["about"] = golden["about"][:-1] + "; the fitted modes too (the truth's simulated test moved)."
        with open(path + ".tmp", "w") as f:
            json.dump(golden, f, indent=1, ensure_ascii=False)
            f.write("\n")
        os.replace(path + ".tmp", path)
        print(f"{name}: from {source}")


if __name__ == "__main__":
    main()
