"""The kNN and GP baselines on synthetic pushes: they learn, chain, and stay honest."""

from __future__ import annotations

import itertools
import math
import subprocess
import sys

import numpy as np
import pytest
from conftest import LIMIT, TESTS_DIR, python_env
from driver import (
    LAST_OBSERVED,
    LAST_PREDICTION,
    Script,
    action,
    decode_replies,
    observed,
    recent,
)
from pushlearn import Prediction, State
from pushlearn._pb import learner_pb2
from pushlearn.baselines import (
    _GP_THETA0,
    FEATURES,
    GP_STRETCHES,
    BaselineLearner,
    ContactGate,
    GpLearner,
    KnnLearner,
    MlpLearner,
    _gp_neg_log_likelihood,
    _GpPredictor,
    _KnnPredictor,
    _squared_differences,
    apply_change,
    block_change,
    block_features,
    wrap_angle,
)
from pushlearn.learner import Pose, _stats_to_proto
from synthetic import MESSAGES, PUSH, STEP, synthetic_run, synthetic_state


def train(learner: BaselineLearner, starts: list[float], seed: int = 7) -> None:
    """A fold's training as the driver runs it: reset, then update + predict per message."""
    learner.start("push-task", 100)
    learner.new_fold(seed)
    for x0 in starts:
        run = synthetic_run(x0)
        learner.reset(run[0])
        learner.predict(run[0], PUSH)  # the display-only prediction of train_step
        for state in run[1:]:
            learner.update(state, PUSH)
            learner.predict(state, PUSH)
    learner.set_training(False)


def chained_test_run(learner: BaselineLearner, x0: float) -> tuple[Prediction, State]:
    """A push-task test run: 150 chained predictions from the run's first state."""
    run = synthetic_run(x0)
    learner.reset(run[0])
    learner.update(run[0], PUSH)
    p = learner.predict(run[0], PUSH)
    for _ in range(MESSAGES - 1):
        learner.update(p, PUSH)
        p = learner.predict(p, PUSH)
    return p, run[MESSAGES]


def test_features_are_in_the_block_frame() -> None:
    block = Pose(1.0, 2.0, math.pi / 2)  # turned a quarter: its x axis is the world's y
    # A run's first message: no velocity, no motion yet.
    f = block_features(Pose(1.0, 2.5, 0.0), block)
    assert f == pytest.approx([0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    # The actuator came 5 mm along the world's y (the block's x) in 1/100 s;
    # the block came 2 mm along the world's −x (its y) and turned 0.01 rad.
    f = block_features(
        Pose(1.0, 2.5, 0.0),
        block,
        Pose(1.0, 2.495, 0.0),
        Pose(1.002, 2.0, math.pi / 2 - 0.01),
        100.0,
    )
    assert f == pytest.approx([0.5, 0.0, 0.5, 0.0, 0.0, 0.002, 0.01])
    assert len(f) == len(FEATURES)
    after = apply_change(block, [0.1, 0.0, 0.2])
    assert after == pytest.approx((1.0, 2.1, math.pi / 2 + 0.2))
    assert block_change(block, after) == pytest.approx([0.1, 0.0, 0.2])
    assert wrap_angle(math.pi + 0.5) == pytest.approx(-math.pi + 0.5)
    assert wrap_angle(-math.pi) == math.pi


@pytest.mark.parametrize("make", [KnnLearner, lambda: GpLearner(max_samples=100)])
def test_before_any_sample_only_the_actuator_moves(make: type[BaselineLearner]) -> None:
    learner = make()
    learner.start("push-task", 10)
    learner.new_fold(1)
    state = synthetic_state((0.0, 0.1), (0.0, 0.25, 0.3))
    p = learner.predict(state, (0.2, 0.5))
    assert p.actuator == pytest.approx((0.02, 0.15, 0.0))
    assert p.blocks == {15: pytest.approx((0.0, 0.25, 0.3))}


def test_knn_learns_the_push_and_chains_predictions() -> None:
    learner = KnnLearner()
    train(learner, [-0.2, -0.04, 0.0, 0.04, 0.2])
    p, truth = chained_test_run(learner, 0.02)
    assert truth.blocks[15].y > 0.8  # the synthetic world pushed the block 0.55 m
    assert p.blocks[15].y == pytest.approx(truth.blocks[15].y, abs=0.02)
    assert p.blocks[15].x == pytest.approx(0.0, abs=0.01)
    assert tuple(p.actuator) == pytest.approx(
        tuple(truth.actuator), abs=1e-9
    )  # gain 1: exactly a / rate
    # A push that misses the block leaves it where it is.
    p, truth = chained_test_run(learner, 0.21)
    assert tuple(p.blocks[15]) == pytest.approx(tuple(truth.blocks[15]), abs=1e-6)


def one_step_errors(learner: BaselineLearner, x0: float) -> list[float]:
    """|predicted − true| block y of each message of a run, from the true state."""
    run = synthetic_run(x0)
    learner.reset(run[0])
    errors = []
    for state, after in itertools.pairwise(run):
        learner.update(state, PUSH)
        errors.append(
            abs(learner.predict(state, PUSH).blocks[15].y - after.blocks[15].y)
        )
    return errors


def test_gp_learns_the_push_and_chains_predictions() -> None:
    learner = GpLearner(max_samples=200)
    train(learner, [-0.04, 0.0, 0.04])
    # Each message's prediction from the true state is off by less than the
    # push moves the block in one message.
    assert max(one_step_errors(learner, 0.02)) < STEP
    p, truth = chained_test_run(learner, 0.02)
    # Chained, a smooth regressor rides the contact edge (the block exactly
    # 0.05 ahead of the actuator): whether the chain stays in contact for the
    # last 70 messages turns on the BLAS kernel's last bits (0.800 with
    # OpenBLAS's SkylakeX kernels, 0.700 with its Haswell and Zen ones, for
    # the same fitted kernel). Either way it pushed the block most of the
    # 0.55 m, straight.
    assert truth.blocks[15].y > 0.8
    assert p.blocks[15].y == pytest.approx(truth.blocks[15].y, abs=0.12)
    assert abs(p.blocks[15].x) < 0.01
    assert abs(p.blocks[15].theta) < 0.05
    assert len(learner.subsamples[15]) == 200
    assert "RBF" in learner.kernels[15] and "WhiteKernel" in learner.kernels[15]


def chained_ys(learner: BaselineLearner) -> list[float]:
    p, _ = chained_test_run(learner, 0.01)
    return [p.blocks[15].y, p.blocks[15].x, p.blocks[15].theta]


def test_gp_is_deterministic_given_the_fold_seed() -> None:
    a, b, c = (
        GpLearner(max_samples=150),
        GpLearner(max_samples=150),
        GpLearner(max_samples=150),
    )
    train(a, [-0.03, 0.03], seed=11)
    train(b, [-0.03, 0.03], seed=11)
    train(c, [-0.03, 0.03], seed=12)
    assert chained_ys(a) == chained_ys(b)
    chained_ys(c)
    assert a.subsamples == b.subsamples
    assert a.subsamples[15] != c.subsamples[15]  # another fold, another subsample


def test_knn_is_deterministic() -> None:
    a, b = KnnLearner(), KnnLearner()
    train(a, [-0.03, 0.0, 0.03])
    train(b, [-0.03, 0.0, 0.03])
    assert chained_ys(a) == chained_ys(b)


def test_knn_cross_validates_over_the_training_runs_only() -> None:
    learner = KnnLearner()
    train(learner, [-0.04, 0.0, 0.04])
    samples_after_training = learner.stats()["maps"]["block/15"]["inserts"]
    assert learner.training_runs == 3
    assert samples_after_training == 3 * MESSAGES
    chained_test_run(
        learner, 0.3
    )  # the test run's updates, with training off, add nothing
    assert learner.stats()["maps"]["block/15"]["inserts"] == samples_after_training
    choice = learner.choices[15]
    assert choice.method == "GroupKFold"
    assert sorted(set(choice.groups)) == [0, 1, 2]  # the three runs between resets
    assert len(choice.splits) == 3
    groups = np.asarray(choice.groups)
    for train_idx, val_idx in choice.splits:
        # No run is both trained on and validated on.
        assert not set(groups[train_idx]) & set(groups[val_idx])
        assert len(set(groups[val_idx])) == 1
    assert 1 <= choice.k <= 50 and choice.weights in ("uniform", "distance")
    assert (choice.k, choice.weights) == min(
        choice.scores, key=lambda key: choice.scores[key]
    )
    # The regressor learns only inside the contact gate: the messages of the
    # approach, far from the block, are not its samples.
    inside = learner.gates[15].inside_all(
        np.asarray(learner._samples[15].inputs, dtype=np.float64)
    )
    assert 0 < inside.sum() < samples_after_training
    assert len(choice.groups) == inside.sum()


def test_knn_with_one_run_validates_on_contiguous_segments() -> None:
    learner = KnnLearner()
    train(learner, [0.0])
    p, _ = chained_test_run(learner, 0.0)
    choice = learner.choices[15]
    assert choice.method == "KFold" and len(choice.splits) == 5
    for _, val_idx in choice.splits:
        assert val_idx == list(
            range(val_idx[0], val_idx[-1] + 1)
        )  # one segment of the run
    assert p.blocks[15].y > 0.7  # and it still learned the push


def test_the_fit_is_renewed_when_new_samples_arrived() -> None:
    learner = KnnLearner()
    train(learner, [0.2])  # only a miss: it learns that the block stays
    p, _ = chained_test_run(learner, 0.0)
    assert p.blocks[15].y == pytest.approx(0.25, abs=1e-6)
    learner.set_training(True)
    for x0 in (-0.03, 0.0, 0.03):
        run = synthetic_run(x0)
        learner.reset(run[0])
        for state in run[1:]:
            learner.update(state, PUSH)
    learner.set_training(False)
    p, truth = chained_test_run(learner, 0.0)
    assert p.blocks[15].y == pytest.approx(truth.blocks[15].y, abs=0.02)


def test_new_fold_forgets_everything() -> None:
    learner = KnnLearner()
    train(learner, [0.0])
    chained_test_run(learner, 0.0)
    learner.new_fold(3)
    assert learner.training
    assert learner.stats()["maps"]["actuator_steps"]["inserts"] == 0
    p, _ = chained_test_run(learner, 0.0)
    assert p.blocks[15].y == pytest.approx(0.25)  # the prior again


@pytest.mark.parametrize(
    "make", [KnnLearner, lambda: GpLearner(max_samples=100), MlpLearner]
)
def test_stats_are_in_the_reports_form(make: type[BaselineLearner]) -> None:
    learner = make()
    train(learner, [-0.02, 0.02])
    chained_test_run(learner, 0.0)
    message = _stats_to_proto(learner.stats())  # raises if malformed
    assert message.maps["block/15"].inserts == 2 * MESSAGES
    assert sorted(message.maps) == ["actuator_steps", "block/15"]
    assert (
        not message.extra and not message.labels
    )  # the driver takes those only from its models
    assert learner.actuator_gain == pytest.approx(1.0)
    assert learner.training_runs == 2  # the test run's reset is not one
    assert learner.describe_fit()[0].startswith("block 15: ")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: KnnLearner(max_k=0), "max_k"),
        (lambda: GpLearner(max_samples=0), "max_samples"),
        (lambda: MlpLearner(members=0), "members"),
        (lambda: MlpLearner(hidden=(8, 0)), "hidden"),
        (lambda: MlpLearner(epochs=-1), "epochs"),
        (lambda: KnnLearner(inputs="position,colour"), "inputs"),
    ],
)
def test_bad_parameters_are_refused(make: type[BaselineLearner], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()


def test_the_baselines_are_served_by_their_command_line() -> None:
    script = Script()
    script.start()
    script.add(new_fold=learner_pb2.NewFold(seed=5))
    for x0 in (-0.03, 0.03):
        run = synthetic_run(x0, 40)
        script.add(reset=learner_pb2.Reset(state=observed(run[0].to_proto())))
        for state in run[1:]:
            script.add(
                update=learner_pb2.Update(
                    state=observed(state.to_proto()), action=action(*PUSH)
                )
            )
    script.add(set_training=learner_pb2.SetTraining(on=False))
    first = synthetic_run(0.0, 1)[0]
    script.add(reset=learner_pb2.Reset(state=observed(first.to_proto())))
    script.add(
        update=learner_pb2.Update(state=recent(LAST_OBSERVED), action=action(*PUSH))
    )
    script.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_OBSERVED), "action": action(*PUSH)}
        )
    )
    script.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_PREDICTION), "action": action(*PUSH)}
        )
    )
    script.add(get_stats=learner_pb2.GetStats())
    for name in ("knn", "gp", "mlp"):
        done = subprocess.run(
            [sys.executable, "-m", "pushlearn.baselines", name],
            input=script.bytes(),
            capture_output=True,
            env=python_env(),
            cwd=TESTS_DIR,
            timeout=LIMIT,
            check=False,
        )
        assert done.returncode == 0, done.stderr.decode()
        replies = decode_replies(done.stdout)
        assert [r.WhichOneof("answer") for r in replies] == [
            "hello",
            "prediction",
            "prediction",
            "stats",
        ]
        assert replies[0].hello.name == name
        assert list(replies[0].hello.capabilities) == [learner_pb2.FORWARD]
        second = {b.id: b for b in replies[2].prediction.bodies}
        assert second[8].y == pytest.approx(0.010)
        assert replies[3].stats.maps["block/15"].inserts == 80


def test_an_unknown_baseline_is_a_usage_error() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pushlearn.baselines", "svm"],
        capture_output=True,
        env=python_env(),
        timeout=LIMIT,
        check=False,
    )
    assert done.returncode == 2
    assert b"unknown baseline 'svm'" in done.stderr


def test_verbose_fits_log_their_choices(capsys: pytest.CaptureFixture[str]) -> None:
    learner = KnnLearner.from_args(["--verbose", "--max-k", "5"])
    assert learner.max_k == 5
    train(learner, [-0.02, 0.02])
    chained_test_run(learner, 0.0)
    err = capsys.readouterr().err
    assert "knn (seed 7): actuator gains 1.000000 (action), 0.000000 (last" in err
    assert "knn (seed 7): block 15: contact |x| ≤ 0.0" in err
    assert "knn (seed 7): block 15: k=" in err and "GroupKFold, 2 folds, 2 runs" in err


def regression_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Noisy smooth 4 → 3 samples on inputs of different scales, the last constant
    (as the action along the push is in a push task)."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 4)) * [0.05, 0.1, 0.3, 0.0] + [0.0, -0.06, 0.0, 0.5]
    y = np.stack(
        [
            np.tanh(20 * x[:, 0]) * x[:, 2],
            0.005 * np.exp(-((x[:, 1] + 0.06) ** 2) / 0.002),
            0.1 * np.sin(10 * x[:, 0] * x[:, 1]),
        ],
        axis=1,
    )
    return x, y + 0.001 * rng.normal(size=y.shape)


def sklearn_gp(theta: np.ndarray | None = None) -> object:
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF(
        length_scale=np.ones(4), length_scale_bounds=(1e-2, 1e3)
    ) + WhiteKernel(noise_level=1e-2, noise_level_bounds=(1e-10, 1e1))
    if theta is None:
        return GaussianProcessRegressor(kernel=kernel, normalize_y=True)
    return GaussianProcessRegressor(
        kernel=kernel.clone_with_theta(theta), normalize_y=True, optimizer=None
    )


def test_the_gp_likelihood_and_gradient_are_sklearns() -> None:
    from sklearn.preprocessing import StandardScaler

    x, y = regression_data(90, 1)
    xs = StandardScaler().fit_transform(x)
    gp = sklearn_gp(_GP_THETA0).fit(xs, y)  # type: ignore[attr-defined]
    yn = (y - y.mean(axis=0)) / y.std(axis=0)
    for theta in (_GP_THETA0, np.log([2.0, 0.5, 3.0, 1.2, 7.0, 0.05])):
        lml, gradient = gp.log_marginal_likelihood(theta, eval_gradient=True)
        ours, our_gradient = _gp_neg_log_likelihood(theta, _squared_differences(xs), yn)
        assert -ours == pytest.approx(lml, rel=1e-9)
        scale = float(np.max(np.abs(gradient)))
        assert -our_gradient == pytest.approx(gradient, rel=1e-7, abs=1e-9 * scale)


def test_the_gp_fits_and_predicts_as_sklearn_does() -> None:
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    x, y = regression_data(120, 2)
    ours = _GpPredictor(x, y)
    theirs = make_pipeline(StandardScaler(), sklearn_gp())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        theirs.fit(x, y)
    gp = theirs[-1]
    # The same optimiser from the same start reaches the same optimum (its
    # path may part from scikit-learn's in the last bits of a gradient).
    assert gp.log_marginal_likelihood(ours.theta) == pytest.approx(
        gp.log_marginal_likelihood_value_, rel=1e-6
    )
    # With these hyper-parameters, scikit-learn predicts what ours does.
    fixed = make_pipeline(StandardScaler(), sklearn_gp(ours.theta)).fit(x, y)
    queries, _ = regression_data(20, 3)
    for q in [*queries, *x[:5]]:
        expected = fixed.predict(q[None, :])[0]
        assert ours.predict_one(list(q)) == pytest.approx(expected, rel=1e-9, abs=1e-15)


@pytest.mark.parametrize(
    ("k", "weights"),
    [(1, "uniform"), (9, "uniform"), (1, "distance"), (12, "distance")],
)
def test_knn_predicts_as_sklearn_does(k: int, weights: str) -> None:
    from sklearn.neighbors import KNeighborsRegressor
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    x, y = regression_data(200, 4)
    ours = _KnnPredictor(x, y, k, weights)
    theirs = make_pipeline(
        StandardScaler(), KNeighborsRegressor(n_neighbors=k, weights=weights)
    ).fit(x, y)
    queries, _ = regression_data(30, 5)
    # Training samples themselves: an exact match takes all the weight.
    for q in [*queries, *x[:5]]:
        expected = theirs.predict(q[None, :])[0]
        assert ours.predict_one(list(q)) == pytest.approx(
            expected, rel=1e-12, abs=1e-15
        )


def pushed_samples() -> tuple[np.ndarray, np.ndarray]:
    """Samples of a block pushed along its y at 5 mm per message from behind its
    face (y = −0.075), at offsets |x| ≤ 0.2, then sliding free (the actuator
    gone, each change 0.7 of the last), and the actuator far off."""
    x, y = [], []
    for rx in np.linspace(-0.2, 0.2, 9):
        for _ in range(5):
            x.append([rx, -0.075, 0.0, 0.5, 0.0, 0.005, 0.0])
            y.append([0.0, 0.005, 0.0])
    change = 0.005
    for _ in range(6):  # the slide after release, the actuator beside the block
        x.append([0.3, -0.05, 0.0, 0.5, 0.0, change, 0.0])
        change *= 0.7
        y.append([0.0, change, 0.0])
    x.append([0.0, -0.3, 0.0, 0.5, 0.0, 0.0, 0.0])  # approaching: nothing moves
    y.append([0.0, 0.0, 0.0])
    return np.asarray(x), np.asarray(y)


def test_the_contact_gate_is_where_the_block_was_pushed() -> None:
    gate = ContactGate.fit(*pushed_samples())
    # The slide after release did not widen the region (its changes shrank).
    assert (gate.half_x, gate.half_y) == pytest.approx((0.2, 0.075))
    assert gate.radius == pytest.approx(math.hypot(0.2, 0.075))
    assert gate.pushed == 45
    assert gate.inside([0.1, -0.07, 0, 0, 0, 0, 0])
    assert not gate.inside([0.1, -0.08, 0, 0, 0, 0, 0])
    assert not gate.inside([0.25, -0.07, 0, 0, 0, 0, 0])
    # Outside, the block slides on: the last change times the learned decay.
    assert gate.decay[1] == pytest.approx(0.7)
    assert gate.slide([0.3, -0.3, 0, 0, 0, 0.002, 0]) == pytest.approx(
        [0.0, 0.0014, 0.0]
    )
    # A pusher inside the region is put back on the nearest contact surface.
    assert gate.snap([0.1, -0.06, 0.0, 0.5, 0, 0, 0])[:2] == pytest.approx(
        [0.1, -0.075]
    )
    assert gate.snap([0.19, 0.0, 0, 0, 0, 0, 0])[:2] == pytest.approx([0.2, 0.0])
    # Moving, it goes back along its path: near the region's end the nearest
    # boundary is the end (x = 0.2), but it came through the face.
    assert gate.snap([0.19, -0.06, 0.0, 0.5, 0, 0, 0])[:2] == pytest.approx(
        [0.19, -0.075]
    )
    assert gate.snap([0.19, -0.06, 0.3, 0.4, 0, 0, 0])[:2] == pytest.approx(
        [0.19 - 0.015 * 0.75, -0.075]
    )


def test_a_round_block_gates_by_its_rim() -> None:
    angles = np.linspace(0, 2 * math.pi, 16, endpoint=False)
    x = [[0.1 * math.cos(a), 0.1 * math.sin(a), 0, 0.5, 0, 0.0, 0] for a in angles]
    y = [[0.0, 0.005, 0.0]] * len(x)
    gate = ContactGate.fit(np.asarray(x), np.asarray(y))
    assert gate.radius == pytest.approx(0.1)
    assert gate.inside([0.05, 0.05, 0, 0, 0, 0, 0])
    # In the box the rim spans but beyond the rim: no contact.
    assert not gate.inside([0.09, 0.09, 0, 0, 0, 0, 0])
    assert gate.snap([0.03, 0.04, 0, 0, 0, 0, 0])[:2] == pytest.approx([0.06, 0.08])


def test_a_block_beyond_the_contact_region_does_not_move() -> None:
    learner = KnnLearner()
    train(learner, [-0.03, 0.0, 0.03])
    state = synthetic_state((0.5, 0.1), (0.0, 0.25, 0.3))
    learner.reset(state)
    p = learner.predict(state, PUSH)
    assert tuple(p.blocks[15]) == pytest.approx((0.0, 0.25, 0.3), abs=1e-12)
    # Without the gate, the nearest pushing samples would have moved it.
    assert learner.gates[15].half_x < 0.1


def test_a_test_runs_restated_first_state_starts_no_history() -> None:
    learner = KnnLearner()
    train(learner, [0.0])
    run = synthetic_run(0.0)
    learner.reset(run[0])
    learner.update(run[0], PUSH)  # the driver's first update of a test run
    assert learner._previous is None and learner._last_action == (0.0, 0.0)
    learner.update(run[1], PUSH)
    assert learner._previous is run[0] and learner._last_action == PUSH


def test_the_actuator_is_fitted_on_the_action_and_the_last_one() -> None:
    # A world whose actuator moves by the mean of this and the last action:
    # one message of latency, half the time.
    learner = KnnLearner()
    learner.start("push-task", 100)
    learner.new_fold(1)
    rng = np.random.default_rng(3)
    x, last = 0.0, (0.0, 0.0)
    state = synthetic_state((x, 0.0), (0.0, 0.25, 0.0))
    learner.reset(state)
    for _ in range(60):
        a = (float(rng.uniform(-0.5, 0.5)), 0.0)
        x += 0.5 * (a[0] + last[0]) / 100
        state = synthetic_state((x, 0.0), (0.0, 0.25, 0.0))
        learner.update(state, a)
        last = a
    learner.set_training(False)
    learner.predict(state, (0.1, 0.0))  # fits
    assert learner.actuator_gains == pytest.approx((0.5, 0.5))
    p = learner.predict(state, (0.1, 0.0))
    assert p.actuator.x == pytest.approx(x + 0.5 * (0.1 + last[0]) / 100)


def test_the_mlp_learns_the_push_online_and_at_the_end() -> None:
    learner = MlpLearner(members=3, hidden=(16, 16), epochs=20)
    learner.start("push-task", 100)
    learner.new_fold(7)
    run = synthetic_run(0.0)
    learner.reset(run[0])
    for state in run[1:]:
        learner.update(state, PUSH)
    # Trained online: after 150 messages (two batches of 64) it predicts
    # before training ends.
    assert learner.ensembles[15].calls == 2
    second = synthetic_run(0.02)
    learner.reset(second[0])
    for state in second[1:]:
        learner.update(state, PUSH)
    learner.set_training(False)
    p, truth = chained_test_run(learner, 0.01)
    assert learner.ensembles[15].calls == 2 + 2 + 20  # the final epochs
    assert p.blocks[15].y == pytest.approx(truth.blocks[15].y, abs=0.05)
    assert p.blocks[15].theta == 0.0  # an output that never varied stays exact
    # Far from anything it saw, the ensemble's change stays within those seen.
    ensemble = learner.ensembles[15]
    wild = ensemble.predict_one([5.0, -3.0, 40.0, -20.0])
    outputs = np.asarray(learner._samples[15].outputs)
    assert np.all(wild >= outputs.min(axis=0)) and np.all(wild <= outputs.max(axis=0))


def test_the_mlp_is_deterministic_given_the_fold_seed() -> None:
    def trained(seed: int) -> tuple[list[float], list[np.ndarray]]:
        learner = MlpLearner(members=2, hidden=(8,), epochs=3)
        train(learner, [-0.03, 0.03], seed=seed)
        weights = [w for m in learner.ensembles[15].members for w in m.coefs_]
        return chained_ys(learner), weights

    (ys, weights), (ys_again, weights_again) = trained(11), trained(11)
    assert ys == ys_again
    assert all(
        np.array_equal(a, b) for a, b in zip(weights, weights_again, strict=True)
    )
    _, other = trained(12)  # another fold, other initial weights and order
    assert not any(np.array_equal(a, b) for a, b in zip(weights, other, strict=True))
    # The members of one ensemble differ too.
    assert not np.array_equal(weights[0], weights[2])


def test_the_mlp_explains_itself() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pushlearn.baselines", "mlp", "--help"],
        capture_output=True,
        env=python_env(),
        cwd=TESTS_DIR,
        timeout=LIMIT,
        check=False,
    )
    assert done.returncode == 0, done.stderr.decode()
    text = done.stdout.decode()
    assert "ensemble" in text and "partial_fit" in text
    for option in ("--members", "--hidden", "--batch", "--epochs", "--inputs"):
        assert option in text
    top = subprocess.run(
        [sys.executable, "-m", "pushlearn.baselines", "--help"],
        capture_output=True,
        env=python_env(),
        cwd=TESTS_DIR,
        timeout=LIMIT,
        check=False,
    )
    assert b"knn|gp|mlp" in top.stdout


def test_the_gp_stretches_its_length_scales_by_cross_validation_over_runs() -> None:
    learner = GpLearner(max_samples=200)
    train(learner, [-0.04, 0.0, 0.04])
    chained_test_run(learner, 0.02)
    model = learner._models[15]
    assert set(model.stretch_scores) == set(GP_STRETCHES)
    assert model.stretch == min(
        model.stretch_scores, key=lambda f: (model.stretch_scores[f], f)
    )
    assert "stretched" in learner.kernels[15]
    # One run: nothing between runs to validate on, the likelihood's scales.
    single = GpLearner(max_samples=200)
    train(single, [0.0])
    chained_test_run(single, 0.0)
    assert single._models[15].stretch == 1.0 and not single._models[15].stretch_scores
