"""The pushing world as Gymnasium goal environments (``docs/gym.md``).

``PushBlockEnv`` is the thesis's Move to Target task: push the blue block
``blockA`` from its start (0, 0.25, 0 rad), the actuator starting at (0, 0),
to a target pose. ``PushTwoBlocksEnv`` adds the red block ``blockB`` and a
target for each block. Both follow the goal-environment conventions of
gymnasium-robotics: a dict observation (``observation``, ``achieved_goal``,
``desired_goal``), :meth:`compute_reward` on batches of goals and
``info["is_success"]``.

One step is one world message: the action is sent as a Move and the
environment waits for the first state with it in force, 10 physics steps of
1 ms later at the built-in scenes' 100 Hz. Underneath runs the world of
``pushlearn-sim`` in lock-step mode, in this process by default
(:class:`pushlearn.World`, the daemon's own code), or a ``pushlearn-sim``
daemon (``sim=``); either way the same seed and the same actions give the
same observations bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar, SupportsFloat

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from .. import native
from .._pb import pushlearn_pb2
from ..learner import ACTUATOR_NAME, MAX_POSITION, Shape, State
from ..local_world import LocalWorld
from ..sim import SimClient, WorldHello
from .render import Canvas, Drawn

__all__ = [
    "ACTUATOR_SPEED",
    "MAX_STEPS",
    "REACHED",
    "THESIS_TARGETS",
    "PushBlockEnv",
    "PushTwoBlocksEnv",
    "TargetRegion",
]

ACTUATOR_SPEED = 0.5
"""m/s per unit of action: the thesis's actuator speed (every training push is
0.5 m/s; the world scales longer commands down to 0.5 m/s)."""

MAX_STEPS = 3000
"""Messages before an episode is truncated: the thesis's longest test run."""

REACHED = 0.01
"""The reached criterion: the norm of a block's (Δx, Δy, wrap(Δθ)) to its target,
metres and radians together, below this; the harness's ``GOAL_TOLERANCE``
(``docs/spec/experiments.md`` §4.4)."""

THESIS_TARGETS: tuple[tuple[float, float, float], ...] = (
    (0.6, 0.7, -2.1),
    (-0.6, 0.7, 0.75),
    (-0.6, -0.7, 0.0),
    (0.6, -0.7, math.pi),
)
"""The blue block's four target poses of the thesis's Move to Target (x, y, θ)."""

Observation = dict[str, Any]
"""``observation``, ``achieved_goal`` and ``desired_goal``, each a float64 array."""

Rows = Sequence[Sequence[float]] | npt.NDArray[np.float64]
"""A state's planar rows, one per body: x, y, yaw, vx, vy and the spin about z."""


class TargetRegion:
    """Where sampled targets lie: block centres in a rectangle, any yaw.

    The actuator can reach every side of a block whose centre lies in it:
    the farthest position it pushes from is within 1.1 m of the origin, and
    the world lets it move within 2.3 m (``docs/world.md``). A target is at
    least ``min_travel`` m from its block's start, so no episode begins
    solved, and two blocks' targets are at least ``min_apart`` m apart, so
    they do not overlap.
    """

    MAX_TRIES = 10_000
    """Draws :meth:`sample` makes for one target before it gives up: a region
    that leaves no room (every point too near the start) would otherwise loop
    forever. The default region needs about 1.1 draws a target."""

    def __init__(
        self,
        x: tuple[float, float] = (-0.7, 0.7),
        y: tuple[float, float] = (-0.8, 0.8),
        min_travel: float = 0.3,
        min_apart: float = 0.5,
    ) -> None:
        for name, (low, high) in (("x", x), ("y", y)):
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ValueError(
                    f"TargetRegion {name} must be finite (low, high) with low <= high, "
                    f"got {(low, high)}"
                )
            if max(abs(low), abs(high)) > MAX_POSITION:
                raise ValueError(
                    f"TargetRegion {name} = {(low, high)} reaches beyond the world "
                    f"(at most {MAX_POSITION} m from the origin)"
                )
        for name, value in (("min_travel", min_travel), ("min_apart", min_apart)):
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(
                    f"TargetRegion {name} must be a finite distance >= 0, got {value}"
                )
        self.x = x
        self.y = y
        self.min_travel = min_travel
        self.min_apart = min_apart

    def sample(
        self, rng: np.random.Generator, starts: Sequence[tuple[float, float]]
    ) -> list[tuple[float, float, float]]:
        """One target per start, drawn from ``rng`` by rejection (uniform over the allowed set)."""
        targets: list[tuple[float, float, float]] = []
        for sx, sy in starts:
            for _ in range(self.MAX_TRIES):
                x = float(rng.uniform(*self.x))
                y = float(rng.uniform(*self.y))
                theta = float(rng.uniform(-math.pi, math.pi))
                if math.hypot(x - sx, y - sy) < self.min_travel:
                    continue
                if any(
                    math.hypot(x - t[0], y - t[1]) < self.min_apart for t in targets
                ):
                    continue
                targets.append((x, y, theta))
                break
            else:
                raise ValueError(
                    f"{self!r} has no room for a target of the block starting at "
                    f"({sx}, {sy}): no point in {self.MAX_TRIES} draws was at least "
                    f"min_travel from it and min_apart from the other targets"
                )
        return targets

    def __repr__(self) -> str:
        return (
            f"TargetRegion(x={self.x}, y={self.y}, min_travel={self.min_travel}, "
            f"min_apart={self.min_apart})"
        )


def _wrap(angle: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    # The harness's single wrap (learner::eval::wrapped_angle_error): the
    # same operations, so the same bits as the Rust criterion.
    return np.asarray(
        np.where(
            angle > math.pi,
            angle - 2.0 * math.pi,
            np.where(angle < -math.pi, angle + 2.0 * math.pi, angle),
        )
    )


def goal_distances(
    achieved_goal: npt.ArrayLike, desired_goal: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """Each block's distance to its target, ``‖(Δx, Δy, wrap(Δθ))‖``, over batches.

    Goals have shape ``(..., 3k)`` for k blocks; the result ``(..., k)``.
    The angle difference is wrapped once (by 2π when beyond ±π), so a yaw of
    π and one of −π are the same pose: the criterion the benchmark judges
    every task with a goal by, bit for bit the harness's
    (``pushlearn._native.goal_distance``, ``docs/spec/experiments.md`` §4.4).
    """
    achieved = np.asarray(achieved_goal, dtype=np.float64)
    desired = np.asarray(desired_goal, dtype=np.float64)
    if achieved.shape != desired.shape or achieved.shape[-1] % 3:
        raise ValueError(
            f"goals must have one shape (..., 3k); got {achieved.shape} and {desired.shape}"
        )
    a = achieved.reshape(*achieved.shape[:-1], -1, 3)
    d = desired.reshape(*desired.shape[:-1], -1, 3)
    delta = a - d
    delta[..., 2] = _wrap(delta[..., 2])
    return np.asarray(np.sqrt(np.sum(delta * delta, axis=-1)))


def _goal_distances_one(
    achieved: Sequence[float], desired: Sequence[float]
) -> list[float]:
    """:func:`goal_distances` of one goal in plain floats, the same operations in
    the same order (so the same bits): a step's path, where numpy's cost per
    call on 3-vectors exceeds the arithmetic many times."""
    distances = []
    for i in range(0, len(achieved), 3):
        dx = achieved[i] - desired[i]
        dy = achieved[i + 1] - desired[i + 1]
        dtheta = achieved[i + 2] - desired[i + 2]
        if dtheta > math.pi:
            dtheta -= 2.0 * math.pi
        elif dtheta < -math.pi:
            dtheta += 2.0 * math.pi
        distances.append(math.sqrt(dx * dx + dy * dy + dtheta * dtheta))
    return distances


class _PushEnv(gym.Env[Observation, npt.NDArray[np.float32]]):
    """What both environments share; the subclasses name the scene and the blocks.

    Options (keywords of ``gymnasium.make``):

    * ``targets``: where the episodes' targets come from (see the subclass);
      ``region`` a :class:`TargetRegion` for ``targets="region"``;
    * ``reward_type``: ``"sparse"`` (−1 per step until success, then 0) or
      ``"dense"`` (minus the distance, :func:`goal_distances`);
    * ``terminate_on_success`` (default true): end the episode when the
      target is reached, as the thesis's runs end; false keeps going, as
      gymnasium-robotics' goal environments do;
    * ``latency_max`` (default 2, the experiments' default): the lock-step
      latency emulation's largest delay of a Move in physics steps, ``None``
      for none;
    * ``sim``: where the world runs. ``None`` (default): in this process
      (:class:`pushlearn.World`, no daemon, no socket); ``"daemon"``: a
      ``pushlearn-sim`` of its own, started as a child process (``sim_bin``
      the binary, :func:`pushlearn.local_world.find_sim_binary`; giving
      ``sim_bin`` implies it); ``"HOST:PORT"``: a running world (its scene
      and latency must match);
    * ``show_target``: also publish the targets as the world's target ghosts,
      which ``pushlearn view --sim ADDRESS`` draws as outlines (with a daemon);
    * ``image_size``: the side of ``rgb_array`` pictures in pixels (480);
      ``timeout``: seconds to wait for the world before an error (30).

    The episode length is ``gymnasium.make``'s ``max_episode_steps``
    (default :data:`MAX_STEPS`, the thesis's 3000 messages).
    """

    # Not a ClassVar: gymnasium.Env declares it an instance variable.
    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 100}  # noqa: RUF012

    scene: ClassVar[str]
    """The world's scene."""
    blocks: ClassVar[tuple[str, ...]]
    """The blocks with a target, in the order of the goals."""
    default_targets: ClassVar[str]

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        targets: str | Sequence[Sequence[float]] | None = None,
        region: TargetRegion | None = None,
        reward_type: str = "sparse",
        terminate_on_success: bool = True,
        latency_max: int | None = 2,
        sim: str | None = None,
        sim_bin: str | None = None,
        show_target: bool = False,
        image_size: int = 480,
        timeout: float = 30.0,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        if reward_type not in ("sparse", "dense"):
            raise ValueError(
                f"reward_type must be 'sparse' or 'dense', got {reward_type!r}"
            )
        if latency_max is not None and (
            isinstance(latency_max, bool)
            or not isinstance(latency_max, int)
            or latency_max < 0
        ):
            raise ValueError(
                f"latency_max must be a number of steps ≥ 0 or None, got {latency_max!r}"
            )
        self.render_mode = render_mode
        self.reward_type = reward_type
        self.terminate_on_success = terminate_on_success
        self.region = region if region is not None else TargetRegion()
        self.targets = self._check_targets(
            self.default_targets if targets is None else targets
        )
        """``"thesis"``, ``"region"`` or the fixed target list episodes draw from."""
        self.show_target = show_target
        self._world: LocalWorld | None = None
        self._client: SimClient | None = None
        self._native: Any = None
        # The step in Rust, over the in-process world (`None` with a daemon).
        self._task: Any = None
        # A daemon's last state; an in-process world's is built when asked for.
        self._state: State | None = None
        # A daemon's last state's planar rows (x, y, yaw, vx, vy, spin) in
        # the scene's body order.
        self._rows: Rows | None = None
        self._started = False
        self._target_values: tuple[float, ...] = (0.0,) * (3 * len(self.blocks))
        self._closed = False

        if sim is None and sim_bin is None:
            self._native = native().World(self.scene, latency_max=latency_max)
            hello = WorldHello.from_proto(
                pushlearn_pb2.Hello.FromString(self._native.hello_bytes())
            )
        elif sim is None or sim == "daemon":
            self._world = LocalWorld(
                scene=self.scene, latency_max=latency_max, sim_bin=sim_bin
            )
            self._client = self._world.connect(timeout)
            hello = self._client.hello
        else:
            host, _, port = sim.rpartition(":")
            if not host or not port.isdigit():
                raise ValueError(
                    f"sim must be None, 'daemon' or HOST:PORT, got {sim!r}"
                )
            self._client = SimClient.connect(host.strip("[]"), int(port), timeout)
            self._check_world(sim, latency_max)
            hello = self._client.hello
        self.latency_max = hello.latency_max_steps
        """The world's latency emulation (largest delay of a Move in steps; ``None``: none)."""
        self._shapes = hello.shapes
        self.shapes: dict[str, Shape] = {
            name: hello.shapes[name]
            for name in (ACTUATOR_NAME, *self.blocks)
            if name in hello.shapes
        }
        """The shapes of the actuator and of every block, by body name, as the
        world's Hello gives them (what the learner protocol shows a learner):
        the observation's vectors carry poses only."""
        self._starts = {body.name: body for body in hello.bodies}
        self._names = [body.name for body in hello.bodies]
        self._actuator_row = self._names.index(ACTUATOR_NAME)
        self._block_rows = [self._names.index(name) for name in self.blocks]
        if self._native is not None:
            self._task = native().GoalTask(
                [self._native],
                self._actuator_row,
                self._block_rows,
                speed=ACTUATOR_SPEED,
                dense=reward_type == "dense",
                terminate_on_success=terminate_on_success,
            )

        # Positions and velocities are unbounded (the world has no walls);
        # yaws lie in [−π, π].
        n = len(self.blocks)
        inf = np.inf
        low = np.array([-inf] * 4 + [-inf, -inf, -math.pi, -inf, -inf, -inf] * n)
        goal_low = np.array([-inf, -inf, -math.pi] * n)
        self.observation_space = spaces.Dict(
            {
                "observation": spaces.Box(low, -low, dtype=np.float64),
                "achieved_goal": spaces.Box(goal_low, -goal_low, dtype=np.float64),
                "desired_goal": spaces.Box(goal_low, -goal_low, dtype=np.float64),
            }
        )
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._canvas = Canvas(image_size) if render_mode == "rgb_array" else None

    # -- checks ------------------------------------------------------------------

    def _check_targets(
        self, targets: str | Sequence[Sequence[float]]
    ) -> str | tuple[tuple[float, ...], ...]:
        if isinstance(targets, str):
            allowed = ("thesis", "region") if len(self.blocks) == 1 else ("region",)
            if targets not in allowed:
                raise ValueError(
                    f"targets must be one of {allowed} or a list of goals, got {targets!r}"
                )
            return targets
        checked = tuple(self._check_goal(goal, "a target") for goal in targets)
        if not checked:
            raise ValueError("targets is empty: give at least one goal")
        return checked

    def _check_goal(self, goal: Any, what: str) -> tuple[float, ...]:
        values = np.asarray(goal, dtype=np.float64).reshape(-1)
        if values.shape != (3 * len(self.blocks),):
            raise ValueError(
                f"{what} must have {3 * len(self.blocks)} numbers (x, y, θ for "
                f"{', '.join(self.blocks)}), got {np.asarray(goal).shape}"
            )
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{what} must be finite numbers, got {values.tolist()}")
        if np.any(np.abs(values) > MAX_POSITION):
            raise ValueError(
                f"{what} must lie in the world (x, y at most {MAX_POSITION} m from the "
                f"origin, θ at most {MAX_POSITION} rad), got {values.tolist()}"
            )
        return tuple(float(v) for v in values)

    def _check_world(self, sim: str, latency_max: int | None) -> None:
        assert self._client is not None
        hello = self._client.hello
        problems = []
        if hello.scene != self.scene:
            problems.append(
                f"its scene is {hello.scene!r}, this environment needs {self.scene!r}"
            )
        if hello.latency_max_steps != latency_max:

            def say(value: int | None) -> str:
                return (
                    "no latency emulation" if value is None else f"latency_max {value}"
                )

            problems.append(
                f"it has {say(hello.latency_max_steps)}, this environment was asked for "
                f"{say(latency_max)} (pass latency_max={hello.latency_max_steps!r}, or start the "
                "world with the matching --latency-max)"
            )
        names = {body.name for body in hello.bodies}
        missing = [name for name in (ACTUATOR_NAME, *self.blocks) if name not in names]
        if missing:
            problems.append(f"it has no {', '.join(missing)}")
        if problems:
            self._client.close()
            raise ValueError(f"the world at {sim} does not fit: " + "; ".join(problems))

    # -- the Gymnasium API -------------------------------------------------------

    @property
    def state(self) -> State:
        """The last world state, with every body as the world sent it (for models
        that parse the world themselves, such as :class:`pushlearn.GateModel`)."""
        if not self._started:
            raise RuntimeError("no world state yet: call reset() first")
        if self._state is not None:
            return self._state
        # In-process: built when asked for, not at every step.
        return State.from_world_state(
            pushlearn_pb2.WorldState.FromString(self._live_native().state_bytes()),
            self._shapes,
        )

    @property
    def address(self) -> str:
        """The world's ``HOST:PORT`` (``pushlearn view --sim ADDRESS`` watches it)."""
        if self._native is not None:
            raise RuntimeError(
                "this environment's world runs in this process and has no address: "
                "make it with sim='daemon' for one that pushlearn view can watch"
            )
        return self._live_client().address

    @property
    def world_pid(self) -> int | None:
        """The process id of the world this environment started (``None`` when it connected to one)."""
        return None if self._world is None else self._world.pid

    def _live_client(self) -> SimClient:
        if self._client is None:
            raise RuntimeError("the environment is closed")
        return self._client

    def _live_native(self) -> Any:
        if self._native is None:
            raise RuntimeError("the environment is closed")
        return self._native

    @property
    def in_process(self) -> bool:
        """Whether the world runs in this process (:class:`pushlearn.World`)."""
        return self._native is not None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Puts the world back to its start and draws a target.

        ``seed`` seeds the environment's generator, which draws the target (unless
        ``options`` gives one) and then the world's latency seed, so the same
        seed and actions give the same episode bit for bit. ``options``:
        ``"target"``, this episode's goal (x, y, θ per block); ``"actuator"``,
        the actuator's start (x, y) instead of (0, 0), e.g. for training pushes.
        """
        super().reset(seed=seed)
        if self._native is None:
            self._live_client()
        options = dict(options or {})
        unknown = sorted(set(options) - {"target", "actuator"})
        if unknown:
            raise ValueError(
                f"unknown reset options {unknown}: the options are 'target' and 'actuator'"
            )
        if "target" in options:
            target = self._check_goal(options["target"], "options['target']")
        else:
            target = self._draw_target()
        actuator = options.get("actuator")
        if actuator is not None:
            ax, ay = (
                float(v) for v in np.asarray(actuator, dtype=np.float64).reshape(2)
            )
            if not (math.isfinite(ax) and math.isfinite(ay)):
                raise ValueError(f"options['actuator'] must be finite, got {(ax, ay)}")
        latency_seed = int(self.np_random.integers(0, 2**63))
        self._target_values = target
        poses = []
        if actuator is not None:
            poses.append((ACTUATOR_NAME, ax, ay, 0.03, 0.0))
        if self.show_target:
            for i, name in enumerate(self.blocks):
                x, y, theta = self._target_values[3 * i : 3 * i + 3]
                poses.append((f"{name}ShadowTarget", x, y, 0.05, theta))

        if self._native is not None:
            world = self._native
            world.move(0.0, 0.0)
            world.reset()
            if self.latency_max is not None:
                world.latency_seed(latency_seed)
            for name, x, y, z, yaw in poses:
                half = yaw / 2.0
                world.set_pose(
                    name, (x, y, z), (0.0, 0.0, math.sin(half), math.cos(half))
                )
            observation = self._observe_rows(world.advance(planar=True).tolist())
            self._task.restart(0, observation[0]["desired_goal"])
            self._started = True
            return observation
        client = self._live_client()
        client.move(0.0, 0.0)
        last = client.reset()
        if self.latency_max is not None:
            last = client.latency_seed(latency_seed)
        for name, x, y, z, yaw in poses:
            last = client.set_pose(name, x, y, z, yaw)
        observation = self._observe(client.next_state(after=last))
        self._started = True
        return observation

    def step(
        self, action: npt.ArrayLike
    ) -> tuple[Observation, SupportsFloat, bool, bool, dict[str, Any]]:
        """Sends the action as a Move of ``ACTUATOR_SPEED · action`` m/s (clipped to
        [−1, 1] first) and returns the first state with it in force."""
        task = self._task
        if task is not None:
            # Everything in one call into Rust (`pushlearn._native.GoalTask`):
            # Python's arithmetic on a step's few numbers cost more than
            # the physics.
            step: tuple[Observation, float, bool, bool, dict[str, Any]] = task.step(
                action
            )
            return step
        return self._finish_step(self._start_step(action))

    def _velocity(self, action: npt.ArrayLike) -> tuple[float, float]:
        """The checked action as the Move's velocity (m/s)."""
        self._live_client()
        if not self._started:
            raise RuntimeError("call reset() before step()")
        values = np.asarray(action, dtype=np.float64)
        if values.shape != (2,):
            raise ValueError(f"an action has shape (2,), got {values.shape}")
        # Plain floats from here: numpy's per-call cost on two numbers is
        # most of a step's Python time.
        ax, ay = values.tolist()
        if not (math.isfinite(ax) and math.isfinite(ay)):
            raise ValueError(f"an action must be finite, got {[ax, ay]}")
        vx = min(max(ax, -1.0), 1.0) * ACTUATOR_SPEED
        vy = min(max(ay, -1.0), 1.0) * ACTUATOR_SPEED
        return vx, vy

    def _start_step(self, action: npt.ArrayLike) -> int:
        """With a daemon: checks and sends the action (with its Advance, in
        lock-step); the Move's seq.

        :meth:`step` in two halves, so that a vector environment can start
        all its daemons stepping before it waits for any.
        """
        vx, vy = self._velocity(action)
        client = self._live_client()
        if client.lockstep:
            return client.move_and_advance(vx, vy)
        return client.move(vx, vy)

    def _finish_step(
        self, move: int
    ) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """The step's result once the state with the Move ``move`` in force arrives."""
        return self._result(*self._observe(self._live_client().next_state(after=move)))

    def _result(
        self, observation: Observation, info: dict[str, Any]
    ) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """A step's result from its observation and info."""
        if self.reward_type == "sparse":
            reward = 0.0 if info["is_success"] else -1.0
        else:
            reward = -info["distance"]
        terminated = info["is_success"] and self.terminate_on_success
        return observation, reward, terminated, False, info

    def compute_reward(
        self, achieved_goal: npt.ArrayLike, desired_goal: npt.ArrayLike, info: Any
    ) -> npt.NDArray[np.float64]:
        """The reward of goals, for one or a batch (shape ``(..., 3k)``).

        Sparse: −1 until every block meets the reached criterion, then 0.
        Dense: minus the sum of the blocks' distances (:func:`goal_distances`).
        """
        distances = goal_distances(achieved_goal, desired_goal)
        if self.reward_type == "sparse":
            return np.asarray(
                -(~np.all(distances < REACHED, axis=-1)).astype(np.float64)
            )
        return np.asarray(-np.sum(distances, axis=-1))

    def render(self) -> npt.NDArray[np.uint8] | None:
        """An ``rgb_array`` picture of the world from above (``None`` without a render mode)."""
        if self._canvas is None:
            return None
        if not self._started:
            raise RuntimeError("call reset() before render()")
        rows = (
            self._live_native().state(planar=True).tolist()
            if self._native is not None
            else self._rows
        )
        assert rows is not None  # a daemon's, kept by every reset and step
        goal = self._target_values
        things = [
            Drawn(
                name,
                self._shapes[name],
                goal[3 * i],
                goal[3 * i + 1],
                goal[3 * i + 2],
                True,
            )
            for i, name in enumerate(self.blocks)
            if name in self._shapes
        ]
        for name, (x, y, yaw, *_) in zip(self._names, rows, strict=True):
            if name in self._shapes:
                things.append(Drawn(name, self._shapes[name], x, y, yaw))
        return self._canvas.draw(things)

    def close(self) -> None:
        """Disconnects and stops the world this environment started; safe to call again."""
        self._native = None
        self._task = None
        if self._client is not None:
            self._client.close()
            self._client = None
        if self._world is not None:
            self._world.close()
            self._world = None

    # -- observations ------------------------------------------------------------

    def _draw_target(self) -> tuple[float, ...]:
        if self.targets == "thesis":
            return THESIS_TARGETS[int(self.np_random.integers(len(THESIS_TARGETS)))]
        if self.targets == "region":
            starts = [self._starts[name].position[:2] for name in self.blocks]
            return tuple(
                v
                for target in self.region.sample(self.np_random, starts)
                for v in target
            )
        assert not isinstance(self.targets, str)
        return self.targets[int(self.np_random.integers(len(self.targets)))]

    def _observe(self, state: State) -> tuple[Observation, dict[str, Any]]:
        """:meth:`_observe_rows` of a daemon's ``state``, kept as :attr:`state`."""
        by_name = {body.name: body for body in state.bodies}
        rows = []
        for name in self._names:
            body = by_name[name]
            vx, vy = _planar_velocity(body)
            spin = 0.0 if body.ang_vel is None else body.ang_vel[2]
            rows.append([body.position[0], body.position[1], body.yaw, vx, vy, spin])
        observation = self._observe_rows(rows)
        self._state = state
        return observation

    def _observe_rows(
        self, rows: Sequence[Sequence[float]]
    ) -> tuple[Observation, dict[str, Any]]:
        """The observation of a state's planar rows (``World.state(planar=True)``,
        the scene's body order) and its ``info``: whether every block meets
        the reached criterion, and the sum of their distances to their targets."""
        self._rows = rows
        self._state = None
        actuator = rows[self._actuator_row]
        row = [actuator[0], actuator[1], actuator[3], actuator[4]]
        goal: list[float] = []
        for i in self._block_rows:
            block = rows[i]
            goal += block[:3]
            row += block
        distances = _goal_distances_one(goal, self._target_values)
        observation = {
            "observation": np.array(row, dtype=np.float64),
            "achieved_goal": np.array(goal, dtype=np.float64),
            "desired_goal": np.array(self._target_values, dtype=np.float64),
        }
        info = {
            "is_success": all(d < REACHED for d in distances),
            "distance": sum(distances),
        }
        return observation, info


def _planar_velocity(body: Any) -> tuple[float, float]:
    return (0.0, 0.0) if body.lin_vel is None else (body.lin_vel[0], body.lin_vel[1])


class PushBlockEnv(_PushEnv):
    """``pushlearn/PushBlock-v0``: the blue block to a target pose (the thesis's Move to Target).

    Observation ``observation`` (10 floats): the actuator's x, y, vx, vy, then
    the block's x, y, θ, vx, vy, ω (m, rad, m/s, rad/s, world frame);
    ``achieved_goal`` the block's (x, y, θ), ``desired_goal`` the target.
    Targets (``targets=``): ``"thesis"`` (default) draws one of the thesis's
    four per episode, ``"region"`` samples :class:`TargetRegion`, a list of
    (x, y, θ) draws from it. See :class:`_PushEnv` for the other options.
    """

    scene = "one_block"
    blocks = ("blockA",)
    default_targets = "thesis"


class PushTwoBlocksEnv(_PushEnv):
    """``pushlearn/PushTwoBlocks-v0``: the blue and the red block, each to its own target.

    Observation ``observation`` (16 floats): the actuator's x, y, vx, vy, then
    for ``blockA`` and then ``blockB`` x, y, θ, vx, vy, ω; the goals are
    (x, y, θ) of both blocks in that order, and success needs both.
    Targets are sampled from :class:`TargetRegion` (default) or drawn from
    a list of 6-number goals.
    """

    scene = "two_blocks"
    blocks = ("blockA", "blockB")
    default_targets = "region"
