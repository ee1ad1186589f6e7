"""Native vector environments: N pushing worlds stepped together from one process.

``gymnasium.make_vec("pushlearn/PushBlock-v0", num_envs=8)`` makes one (the
ids' vector entry point; ``vectorization_mode="async"`` still gives
Gymnasium's ``AsyncVectorEnv``). Each sub-environment is a
:class:`~pushlearn.envs.push.PushBlockEnv` (or ``PushTwoBlocksEnv``) with a
lock-step world of its own. In-process worlds (the default) are stepped
all together by one call into Rust (:class:`pushlearn._native.Worlds`),
with the GIL released; with daemons (``sim="daemon"``) a step sends every
world its Move and Advance first and only then reads the states, so the
daemons step in parallel while this process waits. Autoreset follows
Gymnasium's default, ``NEXT_STEP``: the step after an episode ended resets
that sub-environment (its action is ignored, its reward is 0).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .. import native
from .push import (
    ACTUATOR_SPEED,
    MAX_STEPS,
    REACHED,
    PushBlockEnv,
    PushTwoBlocksEnv,
    _PushEnv,
)

# What a vector environment's step returns: observations, rewards,
# terminations, truncations and infos, each batched.
_StepResult = tuple[
    dict[str, Any],
    npt.NDArray[np.float64],
    npt.NDArray[np.bool_],
    npt.NDArray[np.bool_],
    dict[str, Any],
]


__all__ = ["PushBlockVectorEnv", "PushTwoBlocksVectorEnv"]


class _PushVectorEnv(
    VectorEnv[dict[str, Any], npt.NDArray[np.float32], npt.NDArray[Any]]
):
    """``num_envs`` sub-environments of :attr:`env_class`; keywords go to each."""

    env_class: type[_PushEnv]

    def __init__(
        self,
        num_envs: int,
        *,
        max_episode_steps: int | None = MAX_STEPS,
        render_mode: str | None = None,
        **kwargs: Any,
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be a whole number ≥ 1, got {num_envs!r}")
        if max_episode_steps is not None and max_episode_steps < 1:
            raise ValueError(
                f"max_episode_steps must be ≥ 1 or None, got {max_episode_steps}"
            )
        self.num_envs = num_envs
        self.max_episode_steps = max_episode_steps
        """Steps before a sub-environment's episode is truncated (``None``: never)."""
        self.render_mode = render_mode
        self.metadata = {
            **self.env_class.metadata,
            "autoreset_mode": AutoresetMode.NEXT_STEP,
        }
        self.envs: list[_PushEnv] = []
        try:
            for _ in range(num_envs):
                self.envs.append(self.env_class(render_mode=render_mode, **kwargs))
        except BaseException:
            self.close_extras()
            raise
        first = self.envs[0]
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._elapsed = np.zeros(num_envs, dtype=np.int64)
        self._autoreset = np.zeros(num_envs, dtype=np.bool_)
        self._worlds: Any = None
        self._native = native()
        if all(env.in_process for env in self.envs):
            self._worlds = self._native.Worlds([env._native for env in self.envs])
        # The blocks' rows in a state: a slice where they follow each other
        # (every built-in scene), which numpy takes faster than a list.
        rows = first._block_rows
        consecutive = rows == list(range(rows[0], rows[0] + len(rows)))
        self._block_slice: slice | list[int] = (
            slice(rows[0], rows[0] + len(rows)) if consecutive else rows
        )
        self._every = np.ones(num_envs, dtype=np.bool_)
        self._started = False
        # Every sub-environment's target, as its reset drew it.
        self._desired = np.zeros((num_envs, 3 * len(first.blocks)))

    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Resets every sub-environment; an int ``seed`` seeds them ``seed``, ``seed + 1``, …"""
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, int):
            seeds = [seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        infos: dict[str, Any] = {}
        observations = []
        for i, (env, env_seed) in enumerate(zip(self.envs, seeds, strict=True)):
            observation, info = env.reset(seed=env_seed, options=options)
            observations.append(observation)
            infos = self._add_info(infos, info, i)
            self._desired[i] = observation["desired_goal"]
        self._elapsed[:] = 0
        self._autoreset[:] = False
        self._started = True
        return _stacked(observations), infos

    def step(self, actions: npt.ArrayLike) -> _StepResult:
        """Steps every sub-environment: in-process worlds in one call, daemons
        all sent their Moves first, then all states read."""
        batch = np.asarray(actions)
        if batch.shape != (self.num_envs, 2):
            raise ValueError(
                f"actions must have shape ({self.num_envs}, 2), got {batch.shape}"
            )
        # Checked whole before anything is sent, so a bad row sends nothing.
        # Reductions by their ufuncs: ndarray.all and .sum go through Python
        # wrappers that cost more than these small arrays' arithmetic.
        finite = np.logical_and.reduce(np.isfinite(batch), axis=1)
        if not np.logical_and.reduce(finite):
            bad = np.flatnonzero(~finite).tolist()
            raise ValueError(f"the actions of environments {bad} are not finite")
        if self._worlds is not None:
            return self._step_in_process(batch)
        moves = [
            None if reset else env._start_step(batch[i])
            for i, (env, reset) in enumerate(
                zip(self.envs, self._autoreset.tolist(), strict=True)
            )
        ]
        rewards = np.zeros(self.num_envs, dtype=np.float64)
        terminations = np.zeros(self.num_envs, dtype=np.bool_)
        truncations = np.zeros(self.num_envs, dtype=np.bool_)
        infos: list[dict[str, Any]] = []
        observations = []
        for i, env in enumerate(self.envs):
            if self._autoreset[i]:
                observation, info = env.reset()
                self._elapsed[i] = 0
            else:
                move = moves[i]
                assert move is not None
                observation, rewards[i], terminations[i], _, info = env._finish_step(
                    move
                )
                self._elapsed[i] += 1
                truncations[i] = (
                    self.max_episode_steps is not None
                    and self._elapsed[i] >= self.max_episode_steps
                    and not terminations[i]
                )
            observations.append(observation)
            infos.append(info)
        self._autoreset = terminations | truncations
        return (
            _stacked(observations),
            rewards,
            terminations,
            truncations,
            _batched(infos),
        )

    def _step_in_process(self, batch: npt.NDArray[Any]) -> _StepResult:
        """:meth:`step` of in-process worlds: one call steps them all, and the
        observations, rewards and infos are computed for all at once, with
        the sub-environments' arithmetic (so the same bits as theirs)."""
        envs = self.envs
        if not self._started:
            raise RuntimeError("call reset() before step()")
        n = self.num_envs
        resetting = self._autoreset
        any_reset = bool(np.logical_or.reduce(resetting))
        # The ufuncs themselves: np.clip's dispatch costs more than the clipping.
        velocities = np.minimum(np.maximum(batch, -1.0, dtype=np.float64), 1.0)
        velocities *= ACTUATOR_SPEED
        states = self._worlds.move_and_advance(
            velocities,
            planar=True,
            stepped=(~resetting).tolist() if any_reset else None,
        )
        first = envs[0]
        blocks = states[:, self._block_slice]
        actuator = states[:, first._actuator_row]
        observation = np.empty((n, 4 + blocks.shape[1] * 6))
        observation[:, 0:2] = actuator[:, 0:2]
        observation[:, 2:4] = actuator[:, 3:5]
        observation[:, 4:] = blocks.reshape(n, -1)
        achieved = blocks[:, :, :3].reshape(n, -1)
        desired = self._desired.copy()
        distances = self._native.goal_distances(achieved, desired)
        success = np.logical_and.reduce(distances < REACHED, axis=1)
        distance = np.add.reduce(distances, axis=1)
        if first.reward_type == "sparse":
            rewards = success - 1.0
        else:
            rewards = -distance
        terminations = success & first.terminate_on_success
        for env, rows in zip(envs, states, strict=True):
            env._rows = rows
            env._state = None
        self._elapsed += 1
        if self.max_episode_steps is not None:
            truncations = (self._elapsed >= self.max_episode_steps) & ~terminations
        else:
            truncations = np.zeros(n, dtype=np.bool_)
        if any_reset:
            for i in np.flatnonzero(resetting).tolist():
                reset, info = envs[i].reset()
                observation[i] = reset["observation"]
                achieved[i] = reset["achieved_goal"]
                desired[i] = self._desired[i] = reset["desired_goal"]
                success[i], distance[i] = info["is_success"], info["distance"]
                rewards[i], terminations[i], truncations[i] = 0.0, False, False
                self._elapsed[i] = 0
        self._autoreset = terminations | truncations
        infos = {
            "is_success": success,
            "_is_success": self._every.copy(),
            "distance": distance,
            "_distance": self._every.copy(),
        }
        observations = {
            "observation": observation,
            "achieved_goal": achieved,
            "desired_goal": desired,
        }
        return observations, rewards, terminations, truncations, infos

    def render(self) -> tuple[Any, ...] | None:
        """Each sub-environment's picture (``rgb_array``), or ``None`` without a render mode."""
        if self.render_mode is None:
            return None
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs: Any) -> None:
        """Closes every sub-environment and stops its world."""
        self._worlds = None
        for env in self.envs:
            env.close()

    @property
    def world_pids(self) -> list[int | None]:
        """The process ids of the sub-environments' worlds (``None`` for in-process ones)."""
        return [env.world_pid for env in self.envs]


def _batched(infos: list[dict[str, Any]]) -> dict[str, Any]:
    """The sub-environments' infos in Gymnasium's vector form (``VectorEnv._add_info``'s):
    an array per key and a ``_key`` mask; every info here has the same keys."""
    batch: dict[str, Any] = {}
    for key in infos[0]:
        batch[key] = np.array([info[key] for info in infos])
        batch[f"_{key}"] = np.ones(len(infos), dtype=np.bool_)
    return batch


def _stacked(observations: list[dict[str, Any]]) -> dict[str, Any]:
    """The sub-environments' observations as one batch: fresh arrays, each
    ``(num_envs, …)``, as ``gymnasium.vector.utils.concatenate`` builds them
    for these spaces, without its dispatch or a copy out of a reused buffer."""
    return {key: np.stack([o[key] for o in observations]) for key in observations[0]}


class PushBlockVectorEnv(_PushVectorEnv):
    """``num_envs`` × ``pushlearn/PushBlock-v0``, stepped together."""

    env_class = PushBlockEnv


class PushTwoBlocksVectorEnv(_PushVectorEnv):
    """``num_envs`` × ``pushlearn/PushTwoBlocks-v0``, stepped together."""

    env_class = PushTwoBlocksEnv
