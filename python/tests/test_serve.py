"""serve(), serve_tcp() and python -m pushlearn.serve, driven like the experiment driver does."""

from __future__ import annotations

import io
import math
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from conftest import LIMIT, TESTS_DIR, listening_port, python_env, start_background
from driver import (
    LAST_OBSERVED,
    LAST_PREDICTION,
    Script,
    action,
    decode_replies,
    observed,
    recent,
    run,
    world,
)
from pushlearn import Prediction, State
from pushlearn._pb import learner_pb2
from pushlearn.framing import encode_frame, read_frame
from pushlearn.learner import LearnerServer, StateLike
from pushlearn.serve import main as serve_main
from sample_learners import Broken, Recorder


def test_start_is_answered_by_hello() -> None:
    learner = Recorder()
    script = Script()
    script.start(task="move-to-target", rate=10)
    status, replies = run(learner, script)
    assert status == 0
    assert len(replies) == 1
    assert replies[0].seq == 1
    hello = replies[0].hello
    assert hello.protocol_version == learner_pb2.PROTOCOL_VERSION
    assert (hello.name, hello.version) == ("recorder", "1.2")
    assert list(hello.capabilities) == [learner_pb2.FORWARD, learner_pb2.INVERSE]
    assert (
        not hello.ignores_actuator_yaw
    )  # the default: the driver uses the reported yaw
    assert learner.calls == [("start", "move-to-target", 10)]
    assert learner.publish_rate_hz == 10


def test_one_way_calls_get_no_reply() -> None:
    learner = Recorder()
    script = Script()
    script.start()
    script.add(new_fold=learner_pb2.NewFold(seed=42))
    script.add(reset=learner_pb2.Reset(state=observed(world((0.0, 0.0)))))
    script.add(
        update=learner_pb2.Update(
            state=observed(world((0.0, 0.005))), action=action(0, 0.5)
        )
    )
    script.add(set_training=learner_pb2.SetTraining(on=False))
    script.add(bye=learner_pb2.Bye())
    status, replies = run(learner, script)
    assert status == 0
    assert [r.WhichOneof("answer") for r in replies] == ["hello"]
    names = [call[0] for call in learner.calls]
    assert names == ["start", "new_fold", "reset", "update", "set_training"]
    assert learner.calls[1] == ("new_fold", 42)
    assert learner.calls[3][2] == (0.0, 0.5)
    assert learner.calls[3][1].actuator.y == pytest.approx(0.005)
    assert learner.calls[4] == ("set_training", False)


def test_answered_calls_get_a_reply_with_their_seq() -> None:
    learner = Recorder()
    script = Script()
    script.start()
    predict = script.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.1, 0.0))), "action": action(0, 0.5)}
        )
    )
    accepted = script.add(
        set_target=learner_pb2.SetTarget(id=15, x=0.4, y=0.6, theta=0.5)
    )
    refused = script.add(
        set_target=learner_pb2.SetTarget(id=27, x=0.4, y=0.6, theta=0.5)
    )
    act = script.add(act=learner_pb2.Act())
    cleared = script.add(set_target=learner_pb2.SetTarget(clear=True))
    stats = script.add(get_stats=learner_pb2.GetStats())
    status, replies = run(learner, script)
    assert status == 0
    by_seq = {r.seq: r for r in replies}
    assert sorted(by_seq) == [1, predict, accepted, refused, act, cleared, stats]

    prediction = by_seq[predict].prediction
    assert [(b.id, b.x, b.y, b.theta) for b in prediction.bodies] == [
        (8, 0.1, pytest.approx(0.005), 0.0),
        (15, pytest.approx(0.0), pytest.approx(0.25), pytest.approx(0.0)),
    ]
    assert by_seq[accepted].target.accepted
    assert not by_seq[refused].target.accepted
    assert by_seq[refused].target.refusal == "cannot plan for body 27"
    assert learner.target is None  # cleared at the end
    assert (by_seq[act].action.action.vx, by_seq[act].action.action.vy) == (0.1, -0.2)
    assert by_seq[act].action.has_target
    assert ("set_target", None) in learner.calls
    s = by_seq[stats].stats
    assert (s.maps["memory"].update_calls, s.maps["memory"].nodes) == (0, 1)
    assert s.labels["task"] == "push-task"


def test_state_references_give_back_the_very_same_objects() -> None:
    learner = Recorder()
    script = Script()
    script.start()
    script.add(reset=learner_pb2.Reset(state=observed(world((0.0, 0.0)))))
    script.add(
        update=learner_pb2.Update(state=recent(LAST_OBSERVED), action=action(0, 0.5))
    )
    script.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_OBSERVED), "action": action(0, 0.5)}
        )
    )
    script.add(
        update=learner_pb2.Update(state=recent(LAST_PREDICTION), action=action(0, 0.5))
    )
    script.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_PREDICTION), "action": action(0, 0.5)}
        )
    )
    script.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_PREDICTION), "action": action(0, 0.5)}
        )
    )
    status, replies = run(learner, script)
    assert status == 0
    calls = learner.calls[1:]
    observed_state = calls[0][1]
    assert isinstance(observed_state, State)
    assert calls[1][1] is observed_state
    assert calls[2][1] is observed_state
    first_prediction = calls[3][1]
    assert isinstance(first_prediction, Prediction)
    assert calls[4][1] is first_prediction
    second_prediction = calls[5][1]
    assert second_prediction is not first_prediction
    # The chain moved the actuator 5 mm per prediction: 0 → 0.005 → 0.010 → 0.015.
    assert [r.prediction.bodies[0].y for r in replies[1:]] == pytest.approx(
        [0.005, 0.010, 0.015]
    )


class Keeper(Recorder):
    """Keeps a handle in its predictions and states, as the native learners do."""

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        prediction = super().predict(state, action)
        prediction.handle = ("made by", id(self), len(self.calls))
        if isinstance(state, State):
            state.handle = "parsed once"
        return prediction


def test_handles_survive_the_round_trip() -> None:
    learner = Keeper()
    script = Script()
    script.start()
    script.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
    )
    script.add(
        update=learner_pb2.Update(state=recent(LAST_PREDICTION), action=action(0, 0.5))
    )
    script.add(
        update=learner_pb2.Update(state=recent(LAST_OBSERVED), action=action(0, 0.5))
    )
    status, _ = run(learner, script)
    assert status == 0
    assert learner.calls[2][1].handle == ("made by", id(learner), 2)
    assert learner.calls[3][1].handle == "parsed once"


def error_of(replies: list[Any]) -> tuple[int, str]:
    assert replies, "no reply at all"
    last = replies[-1]
    assert last.WhichOneof("answer") == "error", last
    return last.seq, last.error.message


def test_an_exception_in_learner_code_is_an_error_reply_and_ends_serving(
    capsys: pytest.CaptureFixture[str],
) -> None:
    script = Script()
    script.start()
    script.add(reset=learner_pb2.Reset(state=observed(world((0.0, 0.0)))))
    failing = script.add(
        update=learner_pb2.Update(
            state=observed(world((0.0, 0.005))), action=action(0, 0.5)
        )
    )
    script.add(
        predict=learner_pb2.Predict(
            **{"from": recent(LAST_OBSERVED), "action": action(0, 0.5)}
        )
    )
    status, replies = run(Broken(), script)
    assert status == 1
    assert (
        len(replies) == 2
    )  # the Hello and the Error: the Predict after it was not served
    assert error_of(replies) == (
        failing,
        "ZeroDivisionError: the model divided by zero",
    )
    log = capsys.readouterr().err
    assert (
        "Traceback" in log
        and "ZeroDivisionError" in log
        and "Update (seq 3) raised" in log
    )


def test_a_failing_constructor_is_reported_for_start() -> None:
    def factory() -> Recorder:
        raise RuntimeError("no model file")

    script = Script()
    script.start()
    status, replies = run(factory, script)
    assert status == 1
    assert error_of(replies) == (1, "RuntimeError: no model file")


def test_a_factory_function_makes_the_learner() -> None:
    made: list[Recorder] = []

    def factory() -> Recorder:
        made.append(Recorder())
        return made[-1]

    script = Script()
    script.start()
    status, replies = run(factory, script)
    assert status == 0 and replies[0].hello.name == "recorder"
    assert len(made) == 1 and made[0].calls == [("start", "push-task", 100)]


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (
            lambda s: s.add(new_fold=learner_pb2.NewFold(seed=1)),
            "first request must be Start, not NewFold",
        ),
        (
            lambda s: s.add(
                start=learner_pb2.Start(protocol_version=0, task="push-task")
            ),
            "driver speaks learner protocol version 0",
        ),
        (lambda s: (s.start(), s.start()), "Start was sent twice"),
        (lambda s: (s.start(), s.add()), "carries no call"),
        (
            lambda s: (
                s.start(),
                s.add(update=learner_pb2.Update(state=recent(LAST_OBSERVED))),
            ),
            "Update refers to LAST_OBSERVED, but no state was sent yet",
        ),
        (
            lambda s: (
                s.start(),
                s.add(predict=learner_pb2.Predict(**{"from": recent(LAST_PREDICTION)})),
            ),
            "Predict refers to LAST_PREDICTION, but the learner has made no prediction yet",
        ),
        (
            lambda s: (s.start(), s.add(reset=learner_pb2.Reset())),
            "Reset carries no state",
        ),
    ],
)
def test_protocol_violations_are_error_replies(build: Any, message: str) -> None:
    script = Script()
    build(script)
    status, replies = run(Recorder(), script)
    assert status == 1
    seq, text = error_of(replies)
    assert seq == len(script.requests)
    assert text.startswith("ProtocolError: ")
    assert message in text


def test_a_seq_that_does_not_increase_is_refused() -> None:
    data = encode_frame(
        learner_pb2.Request(
            seq=5,
            start=learner_pb2.Start(
                protocol_version=learner_pb2.PROTOCOL_VERSION, task="x"
            ),
        )
    ) + encode_frame(learner_pb2.Request(seq=5, act=learner_pb2.Act()))
    out = io.BytesIO()
    assert serve_recorder(data, out) == 1
    assert (
        "seq 5 is not greater than the previous one (5)"
        in error_of(decode_replies(out.getvalue()))[1]
    )


def serve_recorder(data: bytes, out: io.BytesIO) -> int:
    from pushlearn import serve

    return serve(Recorder(), stdin=io.BytesIO(data), stdout=out)


def test_garbage_is_an_error_with_seq_zero() -> None:
    script = Script()
    script.start()
    data = script.bytes() + struct.pack(">I", 3) + b"\xff\xff\xff"
    out = io.BytesIO()
    assert serve_recorder(data, out) == 1
    seq, text = error_of(decode_replies(out.getvalue()))
    assert seq == 0 and "does not decode as Request" in text


def test_a_truncated_request_is_an_error() -> None:
    script = Script()
    script.start()
    script.add(act=learner_pb2.Act())
    out = io.BytesIO()
    assert serve_recorder(script.bytes()[:-1], out) == 1
    assert "ended inside a frame" in error_of(decode_replies(out.getvalue()))[1]


def test_end_of_input_without_bye_ends_normally() -> None:
    script = Script()
    script.start()
    script.add(new_fold=learner_pb2.NewFold(seed=3))
    status, replies = run(Recorder(), script)
    assert status == 0 and len(replies) == 1


class BadPredictions(Recorder):
    def __init__(self, make: Any) -> None:
        super().__init__()
        self.make = make

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        return self.make(state)  # type: ignore[no-any-return]


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda s: Prediction({8: (0, 0, 0), 15: (math.nan, 0, 0)}),
            "non-finite x (nan) for body 15 (blockA)",
        ),
        (lambda s: Prediction({8: (0, 0, 0)}), "no pose for body 15 (blockA)"),
        (
            lambda s: Prediction({8: (0, 0, 0), 15: (0, 0, 0), 27: (0, 0, 0)}),
            "body 27, which is not in the state",
        ),
        (
            lambda s: s.poses(),
            "predict() returned dict, expected a pushlearn.Prediction",
        ),
    ],
)
def test_invalid_predictions_are_not_sent(make: Any, message: str) -> None:
    script = Script()
    script.start()
    script.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
    )
    status, replies = run(BadPredictions(make), script)
    assert status == 1
    seq, text = error_of(replies)
    assert seq == 2 and text.startswith("InvalidPrediction: ") and message in text


class BadReplies(Recorder):
    def act(self) -> Any:
        return (math.inf, 0.0), True

    def stats(self) -> Any:
        return {"maps": {"m": {"nodes": -1}}}


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            {"act": learner_pb2.Act()},
            "InvalidAction: act()'s vx is not a finite number (inf)",
        ),
        (
            {"get_stats": learner_pb2.GetStats()},
            "InvalidStats: stats()['maps']['m']['nodes'] is -1",
        ),
    ],
)
def test_invalid_actions_and_stats_are_not_sent(call: Any, message: str) -> None:
    script = Script()
    script.start()
    script.add(**call)
    status, replies = run(BadReplies(), script)
    assert status == 1
    assert message in error_of(replies)[1]


class BorrowsAReservedName(Recorder):
    def stats(self) -> Any:
        return {"maps": {"gate": {"update_calls": 1, "inserts": 1, "nodes": 1}}}


def test_statistics_under_a_built_in_models_name_are_checked_as_the_driver_does() -> (
    None
):
    script = Script()
    script.start()
    script.add(get_stats=learner_pb2.GetStats())
    status, replies = run(BorrowsAReservedName(), script)
    assert status == 1
    text = error_of(replies)[1]
    assert 'map "actuator" is missing' in text, text
    assert "reserved" in text, text


def test_serve_refuses_what_is_not_a_learner() -> None:
    with pytest.raises(TypeError, match="Learner subclass, got the class int"):
        from pushlearn import serve

        serve(int)  # type: ignore[arg-type]


# -- real processes -------------------------------------------------------------


def serve_in_subprocess(
    args: list[str], script: Script
) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(
        [sys.executable, "-m", "pushlearn.serve", *args],
        input=script.bytes(),
        capture_output=True,
        env=python_env(),
        cwd=TESTS_DIR,
        timeout=LIMIT,
        check=False,
    )


def test_stray_prints_do_not_corrupt_the_stream() -> None:
    script = Script()
    script.start()
    script.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
    )
    script.add(bye=learner_pb2.Bye())
    done = serve_in_subprocess(["sample_learners:Printer"], script)
    stderr = done.stderr.decode()
    assert done.returncode == 0, stderr
    replies = decode_replies(done.stdout)  # raises on any stray byte
    assert [r.WhichOneof("answer") for r in replies] == ["hello", "prediction"]
    assert "starting!" in stderr and "more text on stdout" in stderr
    assert "native code writing to fd 1" in stderr
    assert "predicting (0.0, 0.5)" in stderr


def test_learner_arguments_reach_from_args() -> None:
    script = Script()
    script.start()
    script.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
    )
    done = serve_in_subprocess(["sample_learners:Recorder", "--step", "3"], script)
    assert done.returncode == 0, done.stderr.decode()
    replies = decode_replies(done.stdout)
    assert replies[1].prediction.bodies[0].y == pytest.approx(0.015)


def test_a_learner_error_exits_with_status_1() -> None:
    script = Script()
    script.start()
    script.add(
        update=learner_pb2.Update(
            state=observed(world((0.0, 0.0))), action=action(0, 0.5)
        )
    )
    done = serve_in_subprocess(["sample_learners:Broken"], script)
    assert done.returncode == 1
    assert error_of(decode_replies(done.stdout)) == (
        2,
        "ZeroDivisionError: the model divided by zero",
    )
    assert "Traceback" in done.stderr.decode()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "no learner given"),
        (["sample_learners"], "must be given as MODULE:CLASS"),
        (["no_such_module_here:X"], "cannot import 'no_such_module_here'"),
        (["sample_learners:Nope"], "has no attribute 'Nope'"),
        (["sample_learners:Broken", "--flag"], "unrecognized arguments: --flag"),
        (
            ["sample_learners:make_recorder", "x"],
            "is a function, which takes no command-line arguments",
        ),
        (["pushlearn:State"], "not a pushlearn.Learner subclass"),
        (
            ["sample_learners:Recorder", "--listen", "nowhere"],
            "--listen needs HOST:PORT",
        ),
        (["--bogus", "sample_learners:Recorder"], "unknown option '--bogus'"),
        (["missing_file.py:X"], "missing_file.py: no such file"),
    ],
)
def test_command_line_mistakes_exit_2_with_a_message(
    argv: list[str],
    message: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(TESTS_DIR)
    monkeypatch.syspath_prepend(str(TESTS_DIR))
    assert serve_main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "usage:" in err


def test_a_learner_from_a_file(tmp_path: Path) -> None:
    source = tmp_path / "my_learner.py"
    source.write_text(
        "from pushlearn import Learner\n"
        "class Mine(Learner):\n"
        "    name = 'mine'\n"
        "    def new_fold(self, seed): pass\n"
    )
    script = Script()
    script.start()
    done = serve_in_subprocess([f"{source}:Mine"], script)
    assert done.returncode == 0, done.stderr.decode()
    assert decode_replies(done.stdout)[0].hello.name == "mine"


class Connection:
    """A driver's side of one TCP learner session."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=LIMIT)
        self.reader = self.sock.makefile("rb")
        self.writer = self.sock.makefile("wb")
        self.seq = 0

    def call(self, **call: Any) -> Any:
        self.seq += 1
        from pushlearn.framing import write_frame

        write_frame(self.writer, learner_pb2.Request(seq=self.seq, **call))
        return self.seq

    def reply(self) -> Any:
        return read_frame(self.reader, learner_pb2.Reply)

    def close(self) -> None:
        self.reader.close()
        self.writer.close()
        self.sock.close()


def start_call() -> dict[str, Any]:
    return {
        "start": learner_pb2.Start(
            protocol_version=learner_pb2.PROTOCOL_VERSION,
            task="push-task",
            publish_rate_hz=100,
        )
    }


def drive_two_connections(port: int) -> list[Any]:
    a, b = Connection(port), Connection(port)
    try:
        a.call(**start_call())
        b.call(**start_call())
        assert a.reply().hello.name == "recorder"
        assert b.reply().hello.name == "recorder"
        a.call(reset=learner_pb2.Reset(state=observed(world((0.0, 0.0)))))
        b.call(reset=learner_pb2.Reset(state=observed(world((0.0, 0.0)))))
        for _ in range(3):
            a.call(
                update=learner_pb2.Update(
                    state=recent(LAST_OBSERVED), action=action(0, 0.5)
                )
            )
        b.call(
            update=learner_pb2.Update(
                state=recent(LAST_OBSERVED), action=action(0, 0.5)
            )
        )
        b.call(get_stats=learner_pb2.GetStats())
        a.call(get_stats=learner_pb2.GetStats())
        stats_b, stats_a = b.reply().stats, a.reply().stats
        return [stats_a, stats_b]
    finally:
        a.close()
        b.close()


def test_serve_tcp_gives_each_connection_its_own_learner(tmp_path: Path) -> None:
    child = start_background(
        [
            sys.executable,
            "-m",
            "pushlearn.serve",
            "sample_learners:Recorder",
            "--listen",
            "127.0.0.1:0",
        ],
        tmp_path / "daemon.log",
        env=python_env(),
    )
    try:
        port = listening_port(child)
        stats_a, stats_b = drive_two_connections(port)
        assert stats_a.maps["memory"].update_calls == 3
        assert stats_b.maps["memory"].update_calls == 1
        assert stats_a.extra["instance"] != stats_b.extra["instance"]
        assert stats_a.extra["pid"] == stats_b.extra["pid"] == child.pid  # one process
        # A third session after the first two ended still works.
        assert drive_two_connections(port)[0].maps["memory"].update_calls == 3
    finally:
        child.stop()


def test_a_learner_server_runs_sessions_concurrently() -> None:
    server = LearnerServer(Recorder)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        # Both connections are open at once: neither session waits for the other.
        stats_a, stats_b = drive_two_connections(server.address[1])
        assert (
            stats_a.maps["memory"].update_calls,
            stats_b.maps["memory"].update_calls,
        ) == (3, 1)
    finally:
        server.shutdown()
        server.server_close()
    assert server.address_text.startswith("127.0.0.1:")


def test_a_learner_server_at_its_connection_cap_refuses_one_more_and_serves_the_rest() -> (
    None
):
    server = LearnerServer(Recorder, max_connections=1)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    first = Connection(server.address[1])
    try:
        first.call(**start_call())
        assert first.reply().hello.name == "recorder"
        extra = Connection(server.address[1])
        try:
            extra.call(**start_call())
            refusal = extra.reply()
            assert refusal.error.message == (
                "too many connections: this learner daemon serves at most 1 at once"
            )
            assert extra.reply() is None  # and the connection is closed
        finally:
            extra.close()
        # The session already running is served as before.
        first.call(get_stats=learner_pb2.GetStats())
        assert first.reply().HasField("stats")
    finally:
        first.close()
    # Its slot is free again once it ended.
    again = Connection(server.address[1])
    try:
        for _ in range(50):
            again.call(**start_call())
            reply = again.reply()
            if reply.HasField("hello"):
                break
            again.close()
            time.sleep(0.02)
            again = Connection(server.address[1])
        assert reply.hello.name == "recorder"
    finally:
        again.close()
        server.shutdown()
        server.server_close()
    with pytest.raises(ValueError, match="at least 1"):
        LearnerServer(Recorder, max_connections=0)


def test_a_learner_server_needs_a_factory() -> None:
    with pytest.raises(TypeError, match="not a learner instance"):
        LearnerServer(Recorder())  # type: ignore[arg-type]


class NumpyReplies(Recorder):
    """Returns numpy scalars, as learners built on numpy naturally do."""

    def act(self) -> Any:
        import numpy as np

        return (np.float64(0.25), np.float32(-0.5)), np.bool_(True)

    def stats(self) -> Any:
        import numpy as np

        return {"maps": {"m": {"nodes": np.int64(3)}}, "extra": {"x": np.float64(1.5)}}


def test_numpy_scalars_are_accepted_in_replies() -> None:
    script = Script()
    script.start()
    act = script.add(act=learner_pb2.Act())
    stats = script.add(get_stats=learner_pb2.GetStats())
    status, replies = run(NumpyReplies(), script)
    assert status == 0
    by_seq = {r.seq: r for r in replies}
    assert by_seq[act].action.action.vx == 0.25 and by_seq[act].action.action.vy == -0.5
    assert by_seq[act].action.has_target is True
    assert by_seq[stats].stats.maps["m"].nodes == 3
    assert by_seq[stats].stats.extra["x"] == 1.5


def read_reply_within(stream: Any, seconds: float = LIMIT) -> Any:
    """The next Reply, failing the test instead of hanging if none comes."""
    result: list[Any] = []
    reader = threading.Thread(
        target=lambda: result.append(read_frame(stream, learner_pb2.Reply))
    )
    reader.daemon = True
    reader.start()
    reader.join(seconds)
    assert result, f"no reply within {seconds} s (was it flushed?)"
    return result[0]


def test_replies_are_flushed_before_the_next_request_over_pipes() -> None:
    """The driver waits for each answer: serve() must not wait for more input first."""
    import os

    from pushlearn import serve
    from pushlearn.framing import write_frame

    to_learner_r, to_learner_w = os.pipe()
    to_driver_r, to_driver_w = os.pipe()
    with (
        os.fdopen(to_learner_r, "rb") as learner_in,
        os.fdopen(to_driver_w, "wb") as learner_out,
        os.fdopen(to_learner_w, "wb") as driver_out,
        os.fdopen(to_driver_r, "rb") as driver_in,
    ):
        status: list[int] = []
        server = threading.Thread(
            target=lambda: status.append(
                serve(Recorder(), stdin=learner_in, stdout=learner_out)
            )
        )
        server.start()
        write_frame(driver_out, request_of(1, **start_call()))
        assert read_reply_within(driver_in).hello.name == "recorder"
        predict = learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
        write_frame(driver_out, request_of(2, predict=predict))
        assert read_reply_within(driver_in).seq == 2
        write_frame(driver_out, request_of(3, bye=learner_pb2.Bye()))
        server.join(LIMIT)
        assert status == [0]


def request_of(seq: int, **call: Any) -> Any:
    return learner_pb2.Request(seq=seq, **call)


def test_replies_are_flushed_by_the_served_process() -> None:
    from pushlearn.framing import write_frame

    process = subprocess.Popen(
        [sys.executable, "-m", "pushlearn.serve", "sample_learners:Printer"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        env=python_env(),
        cwd=TESTS_DIR,
    )
    assert process.stdin is not None and process.stdout is not None
    try:
        write_frame(process.stdin, request_of(1, **start_call()))
        assert read_reply_within(process.stdout).hello.name == "printer"
        predict = learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(0, 0.5)}
        )
        write_frame(process.stdin, request_of(2, predict=predict))
        assert read_reply_within(process.stdout).prediction.bodies[
            0
        ].y == pytest.approx(0.005)
        process.stdin.close()  # end of input: the learner exits normally
        assert process.wait(LIMIT) == 0
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_a_learner_that_cannot_be_made_is_reported_to_the_driver() -> None:
    script = Script()
    script.start()
    done = serve_in_subprocess(["sample_learners:Unbuildable"], script)
    assert done.returncode == 1
    assert error_of(decode_replies(done.stdout)) == (
        1,
        "RuntimeError: no model file at /nowhere",
    )
    first_line = done.stderr.decode().splitlines()[0]
    assert first_line == (
        "pushlearn.serve: cannot make the learner sample_learners:Unbuildable: "
        "RuntimeError: no model file at /nowhere"
    )


def test_a_learner_that_cannot_be_made_fails_even_without_a_driver() -> None:
    done = serve_in_subprocess(
        ["sample_learners:Unbuildable"], Script()
    )  # no Start at all
    assert done.returncode == 1
    assert b"cannot make the learner" in done.stderr


def test_a_daemon_whose_learner_cannot_be_made_does_not_start() -> None:
    done = serve_in_subprocess(
        ["sample_learners:Unbuildable", "--listen", "127.0.0.1:0"], Script()
    )
    assert done.returncode == 1
    assert b"listening on" not in done.stdout
    assert b"cannot make the learner" in done.stderr


def test_a_module_that_fails_to_import_shows_where(tmp_path: Path) -> None:
    source = tmp_path / "broken_module.py"
    source.write_text("import no_such_dependency_here\n")
    done = serve_in_subprocess([f"{source}:X"], Script())
    stderr = done.stderr.decode()
    assert done.returncode == 1
    assert f"importing {source}:X failed" in stderr
    assert "No module named 'no_such_dependency_here'" in stderr


class SignedZeros(Recorder):
    """Predicts and acts with −0.0, as the built-in models do after rounding."""

    ignores_actuator_yaw = True

    def predict(self, state: StateLike, action: tuple[float, float]) -> Prediction:
        self.calls.append(("predict", state, action))
        return Prediction({id_: (-0.0, 0.0, -0.0) for id_ in state.poses()})

    def act(self) -> Any:
        return (-0.0, 0.0), False


def test_signed_zeros_survive_both_ways() -> None:
    import math

    learner = SignedZeros()
    script = Script()
    script.start()
    predict = script.add(
        predict=learner_pb2.Predict(
            **{"from": observed(world((0.0, 0.0))), "action": action(-0.0, 0.5)}
        )
    )
    act = script.add(act=learner_pb2.Act())
    status, replies = run(learner, script)
    assert status == 0
    by_seq = {r.seq: r for r in replies}
    assert by_seq[1].hello.ignores_actuator_yaw
    # The driver's −0.0 arrives as −0.0 ...
    assert math.copysign(1.0, learner.calls[-1][2][0]) == -1.0
    # ... and the learner's −0.0 leaves as −0.0, every number present on the wire.
    for body in by_seq[predict].prediction.bodies:
        assert body.HasField("x") and body.HasField("y") and body.HasField("theta")
        assert math.copysign(1.0, body.x) == -1.0 and math.copysign(1.0, body.y) == 1.0
    reply = by_seq[act].action.action
    assert reply.HasField("vx") and reply.HasField("vy")
    assert math.copysign(1.0, reply.vx) == -1.0
