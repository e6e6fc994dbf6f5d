"""Every binding driven with wrong shapes, types and values (issue 41): a Python exception every
time, never a crash. Runs in a child interpreter so that a crash (a segfault, an abort) is this
test's failure with the call that caused it, not the end of the pytest run.

The arguments: each function with 0-2 positional arguments from a battery of wrong values (every
combination), 3 arguments on a fixed-seed sample, and every keyword of its stub given each wrong
value beside a valid first argument where one exists (so the keyword's own check is reached).
"""

import os
import subprocess
import sys
import textwrap

_CHILD = textwrap.dedent(
    r'''
    import ast, inspect, itertools, json, os, random, sys, warnings
    import numpy as np
    import ema

    bad = [None, 0, -1, 1e300, float("nan"), "", "no/such/file.unv", b"\xff", [], {}, (), [1, 2], {"a": 1},
           (1.0,), (5.0, 1.0), np.zeros(0), np.zeros((2, 2, 2)), np.array([1 + 2j]), np.array(["x"]), object()]
    sys.path.insert(0, os.environ["EMA_PYTHON_TESTS"])
    from test_ema import _two_mode_frfs  # the analytic two-mode FRFs the other tests fit
    frfs = _two_mode_frfs()
    model = os.path.join(os.environ["EMA_SOURCE_DIR"], "samples", "guideway", "model.toml")
    fitted = ema.fit(frfs, band=(10.0, 190.0), stabilisation=True)
    first = {"fit": frfs, "mode_indicators": frfs, "synthesize": fitted, "mac": np.eye(2), "plan": model,
             "model_modes": model, "correlate": fitted, "diagnose": model, "quality": frfs,
             "to_dataframe": fitted, "to_json": fitted, "to_jsonable": fitted, "plot_mac": np.eye(2),
             "plot_frf": frfs, "plot_stabilisation": fitted}
    # Keyword names from the stubs (the compiled functions) and the signatures (the Python ones).
    stub = ast.parse(open(os.path.join(os.path.dirname(ema.__file__), "_ema.pyi")).read())
    keywords = {d.name: [a.arg for a in d.args.args[1:] + d.args.kwonlyargs]
                for d in stub.body if isinstance(d, ast.FunctionDef)}
    rng = random.Random(41)
    names = [n for n in ema.__all__ if callable(getattr(ema, n)) and not inspect.isclass(getattr(ema, n))]

    def call(name, *args, **kwargs):
        print(json.dumps({"call": name, "args": [repr(a)[:60] for a in args],
                          "kwargs": {k: repr(v)[:60] for k, v in kwargs.items()}}), file=sys.stderr, flush=True)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                getattr(ema, name)(*args, **kwargs)
        except Exception:
            pass  # what is asked: an exception, never a crash
        except BaseException as e:  # SystemExit, KeyboardInterrupt: not what a binding may raise
            raise AssertionError(f"{name}: {type(e).__name__}") from e

    for name in names:
        for k in (0, 1, 2):
            for args in itertools.product(bad, repeat=k):
                call(name, *args)
        for _ in range(300):
            call(name, *rng.choices(bad, k=3))
        if name in first:
            try:
                params = list(inspect.signature(getattr(ema, name)).parameters)[1:]
            except (TypeError, ValueError):
                params = []
            for kw in dict.fromkeys(keywords.get(name, []) + params):
                if kw in ("args", "kwargs"):
                    continue
                for value in bad:
                    call(name, first[name], **{kw: value})
    print("done", len(names))
    '''
)


def test_every_binding_raises_on_wrong_arguments_and_never_crashes(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", EMA_PYTHON_TESTS=os.path.dirname(os.path.abspath(__file__)))
    env.setdefault("EMA_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
    os.chdir(tmp_path)  # a binding that writes (plan's output) writes here
    done = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True, timeout=600)
    last = [line for line in done.stderr.splitlines() if line.startswith("{")][-1:] or ["(none)"]
    assert done.returncode == 0, (f"exit {done.returncode} at the call {last[0]}\n" + done.stderr[-2000:])
    assert done.stdout.strip().startswith("done"), done.stdout
    assert int(done.stdout.split()[1]) >= 15, done.stdout  # every binding was driven
