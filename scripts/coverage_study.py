"""Coverage study of the hull coefficients' 95 % intervals under the generator's conditions.

    python scripts/coverage_study.py --conditions 200hz 50hz --days 100 --out coverage.csv

Each day's rows are appended to ``--out`` as they come (a rerun skips the days already
there); at the end the summary (coverage with its Clopper-Pearson interval) is printed and
written next to it as ``*_summary.csv``. See towtank.testing.coverage and docs/method.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import pandas as pd

from towtank.testing.coverage import CONDITIONS, day_result, summarise


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--conditions", nargs="+", default=list(CONDITIONS))
    ap.add_argument("--days", type=int, default=100)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--out", type=Path, default=Path("coverage.csv"))
    args = ap.parse_args()
    done = set()
    if args.out.exists():
        old = pd.read_csv(args.out)
        done = set(zip(old["condition"], old["seed"], strict=True))
    for cond in args.conditions:
        for seed in range(args.first_seed, args.first_seed + args.days):
            if (cond, seed) in done:
                continue
            t0 = time.time()
            rows = day_result(cond, seed)
            pd.DataFrame(rows).to_csv(args.out, mode="a", header=not args.out.exists(),
                                      index=False)
            print(f"{cond} seed {seed}: {time.time() - t0:.1f} s", flush=True)
    summary = summarise(pd.read_csv(args.out).to_dict("records"))
    summary.to_csv(args.out.with_name(args.out.stem + "_summary.csv"), index=False)
    with pd.option_context("display.width", 200, "display.max_rows", 200):
        print(summary.to_string(index=False))


if __name__ == "__main__":
    main()
