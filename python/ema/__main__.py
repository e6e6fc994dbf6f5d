"""``python -m ema``: the installed package's version (``--version``, as ``ema --version`` prints it),
where it is installed and its functions."""
import argparse
import os
import sys
from typing import Optional, Sequence

import ema


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m ema",
        description="The ema Python package: experimental modal analysis on numpy arrays. "
        "help(ema) and help(ema.<function>) in Python tell the rest (docs/python.md).")
    parser.add_argument("--version", action="version", version=f"ema {ema.__version__}")
    parser.parse_args(argv)
    print(f"ema {ema.__version__} ({os.path.dirname(ema.__file__)}, Python {sys.version.split()[0]})")
    print("functions:")
    for name in ema.__all__:
        obj = getattr(ema, name)
        if callable(obj) and not isinstance(obj, type):
            doc = (obj.__doc__ or "").strip().splitlines()
            # pybind11 puts the signature first: show the first sentence after it.
            summary = next((line for line in doc[1:] if line.strip()), "") if doc and doc[0].startswith(name + "(") else (doc[0] if doc else "")
            print(f"  {name:16s} {summary.strip()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
