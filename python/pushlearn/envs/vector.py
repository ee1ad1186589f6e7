"""Native vector environments: N pushing worlds stepped together from one process.

``gymnasium.make_vec("pushlearn/PushBlock-v0", num_envs=8)`` makes one (the
ids' vector entry point; ``vectorization_mode="async"`` still gives
Gymnasium's ``AsyncVectorEnv``). Each sub-environment is a
:class:`~pushlearn.envs.push.PushBlockEnv` (or ``PushTwoBlocksEnv``) with a
lock-step world of its own. In-process worlds (the default) are stepped
all together by one call into Rust (:class:`pushlearn._native.GoalTask`,
which also computes the observations, rewards, flags and infos), with the
GIL released; with daemons (``sim="daemon"``) a step sends every
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
        # In-process worlds: the whole step in one call into Rust, the
        # sub-environments' own arithmetic (`pushlearn._native.GoalTask`).
        self._task: Any = None
        if all(env.in_process for env in self.envs):
            self._task = native().GoalTask(
                [env._native for env in self.envs],
                first._actuator_row,
                first._block_rows,
                speed=ACTUATOR_SPEED,
                dense=first.reward_type == "dense",
                terminate_on_success=first.terminate_on_success,
                max_episode_steps=max_episode_steps,
            )

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
            if self._task is not None:
                self._task.restart(i, observation["desired_goal"])
        self._elapsed[:] = 0
        self._autoreset[:] = False
        return _stacked(observations), infos

    def step(self, actions: npt.ArrayLike) -> _StepResult:
        """Steps every sub-environment: in-process worlds in one call, daemons
        all sent their Moves first, then all states read."""
        if self._task is not None:
            result: _StepResult
            result, restarts = self._task.step_all(actions)
            if restarts:
                self._restart(result, restarts)
            return result
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

    def _restart(self, result: _StepResult, restarts: list[int]) -> None:
        """Resets the sub-environments in ``restarts``, whose episodes ended at
        the last step, into ``result`` (their rewards and flags are 0 and
        false already): the NEXT_STEP autoreset of in-process worlds."""
        observations, _, _, _, infos = result
        for i in restarts:
            reset, info = self.envs[i].reset()
            for key, value in reset.items():
                observations[key][i] = value
            infos["is_success"][i] = info["is_success"]
            infos["distance"][i] = info["distance"]
            self._task.restart(i, reset["desired_goal"])

    def render(self) -> tuple[Any, ...] | None:
        """Each sub-environment's picture (``rgb_array``), or ``None`` without a render mode."""
        if self.render_mode is None:
            return None
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs: Any) -> None:
        """Closes every sub-environment and stops its world."""
        self._task = None
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
