"""Gymnasium environments of the pushing world (``docs/gym.md``).

Importing :mod:`pushlearn` registers them when Gymnasium is installed
(``pip install '.[gym]'``)::

    import gymnasium as gym
    import pushlearn

    gym.register_envs(pushlearn)              # keeps linters from calling the import unused
    env = gym.make("pushlearn/PushBlock-v0")  # the world of pushlearn-sim, in this process

``pushlearn/PushBlock-v0`` is the thesis's Move to Target with one block,
``pushlearn/PushTwoBlocks-v0`` the two-block scene with a target per block;
both are truncated after the thesis's 3000 messages.
``gymnasium.make_vec(ID, num_envs=N)`` gives a native vector environment
(:mod:`pushlearn.envs.vector`): N worlds stepped together from one process,
in one call into Rust.
"""

from __future__ import annotations

__all__ = ["ENV_IDS", "register_envs"]

ENV_IDS = ("pushlearn/PushBlock-v0", "pushlearn/PushTwoBlocks-v0")
"""The registered environment ids."""

_ENTRY_POINTS = {
    "pushlearn/PushBlock-v0": ("push:PushBlockEnv", "vector:PushBlockVectorEnv"),
    "pushlearn/PushTwoBlocks-v0": (
        "push:PushTwoBlocksEnv",
        "vector:PushTwoBlocksVectorEnv",
    ),
}


def register_envs() -> None:
    """Registers :data:`ENV_IDS` with Gymnasium (once; later calls do nothing)."""
    import gymnasium

    from .push import MAX_STEPS

    for env_id, (single, vector) in _ENTRY_POINTS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point=f"{__name__}.{single}",
                vector_entry_point=f"{__name__}.{vector}",
                max_episode_steps=MAX_STEPS,
            )
