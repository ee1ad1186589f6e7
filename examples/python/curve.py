#!/usr/bin/env python3
"""Run a learner through the push task and plot its learning curve beside the thesis's.

The benchmark from Python alone (``pushlearn.bench``): the k-nearest-neighbour
baseline (``pushlearn.baselines.KnnLearner``; any ``pushlearn.Learner`` of
your own goes in its place) or a built-in model is trained on N pushes and
predicts the 21 test pushes, on the same worlds, seeds and driver as
``pushlearn experiment push-task``; its error after 150 chained predictions
is drawn against N beside the thesis's gate model.

    python3 examples/python/curve.py --out figures                 # the page's protocol, 20 folds
    python3 examples/python/curve.py --train-runs 1,3 --folds 2 --out /tmp/curve
    python3 examples/python/curve.py --model gate+ --out figures   # a built-in model instead

Needs the ``pushlearn`` package with matplotlib (and scikit-learn for the
kNN baseline).
"""

# %% The imports: the benchmark, a learner, and matplotlib without a display.
from __future__ import annotations

import argparse
import sys
from pathlib import Path

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pushlearn.bench import LearnerLike, Report, push_task
except ImportError as missing:
    sys.exit(f"error: {missing}")

PANELS = [
    ("block position", "m", "block position error [m]"),
    ("block orientation", "rad", "block orientation error [rad]"),
]
"""The learning-curve table's columns drawn, and their axes."""


# %% Run the learner through the push task.
def run(learner: LearnerLike, train_runs: list[int], folds: int, seed: int) -> Report:
    """The push task's report for ``learner`` (a progress bar on stderr)."""
    return push_task(learner, train_runs=train_runs, folds=folds, seed=seed)


# %% Draw ours against the thesis's, one panel per error.
def plot(report: Report, out: Path) -> Path:
    """Draws the learning curve of ``report`` beside the thesis's into ``out``."""
    rows = report.table("learning-curve").rows
    n = [row["N_train"] for row in rows]
    figure, axes = plt.subplots(
        1, len(PANELS), figsize=(10, 4), constrained_layout=True
    )
    for axis, (column, unit, label) in zip(axes, PANELS, strict=True):
        ours = [row[f"{column} mean [{unit}]"] for row in rows]
        spread = [row[f"{column} std [{unit}]"] or 0.0 for row in rows]
        axis.errorbar(
            n, ours, yerr=spread, marker="o", capsize=3, label=report.document["model"]
        )
        thesis = [
            (x, row[f"{column} thesis mean [{unit}]"])
            for x, row in zip(n, rows, strict=True)
        ]
        known = [(x, y) for x, y in thesis if y is not None]
        if known:
            axis.plot(
                *zip(*known, strict=True),
                "s--",
                color="grey",
                label="gate, thesis (2015)",
            )
        axis.set_xscale("log")
        axis.set_xticks(n, [str(x) for x in n])
        axis.minorticks_off()
        axis.set_xlabel("training runs N")
        axis.set_ylabel(label)
        axis.legend()
    figure.suptitle(
        f"Push task, {report.document['folds']} folds, seed {report.document['seed']}"
    )
    out.mkdir(parents=True, exist_ok=True)
    path = out / "learning-curve.png"
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


# %% The command line.
def main(argv: list[str] | None = None) -> int:
    """Runs the push task, prints its table and writes the figure; returns the exit status."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "--out", type=Path, required=True, help="folder for learning-curve.png"
    )
    parser.add_argument(
        "--train-runs",
        default="1,2,3,5,10",
        help="numbers of training runs, comma-separated (default 1,2,3,5,10)",
    )
    parser.add_argument(
        "--folds", type=int, default=20, help="folds per N (default 20)"
    )
    parser.add_argument(
        "--seed", type=int, default=1, help="seed of every random choice"
    )
    parser.add_argument(
        "--model",
        help="a built-in model (gate, …: pushlearn.model_names()) instead of "
        "the kNN baseline",
    )
    args = parser.parse_args(argv)
    try:
        train_runs = [int(n) for n in args.train_runs.split(",")]
    except ValueError:
        parser.error(f"--train-runs takes numbers like 1,3,10, not {args.train_runs!r}")
    learner: LearnerLike
    if args.model is not None:
        learner = args.model
    else:
        try:
            from pushlearn.baselines import KnnLearner
        except ImportError as missing:
            sys.exit(f"error: the kNN baseline needs scikit-learn ({missing})")
        learner = KnnLearner
    try:
        report = run(learner, train_runs, args.folds, args.seed)
    except (ValueError, RuntimeError) as err:
        sys.exit(f"error: {err}")
    print(report.text(), end="")
    print(f"wrote {plot(report, args.out)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
