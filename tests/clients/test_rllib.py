"""RLlib: the ``register_env`` entry seeds each env of each runner apart, and RLlib's PPO
trains on a registered id (optional extra ``stsf-gym[rllib]``)."""

import numpy as np
import pytest

from stsf_gym.agents.rllib import env_creator


class Context(dict):
    """What RLlib hands a creator: the env config with the runner's indices."""

    def __init__(self, config: dict, worker_index: int = 0, vector_index: int = 0) -> None:
        super().__init__(config)
        self.worker_index, self.vector_index = worker_index, vector_index


CONFIG = {"env_id": "stsf_gym/Straight10m-Odometry-v0", "camera__enabled": False}


def _first_steps(env) -> np.ndarray:
    obs = [env.step(np.float32([0.8, 0.1]))[0] for _ in range(5)]
    env.close()
    return np.array(obs)


def test_env_creator_gives_each_worker_and_vector_slot_its_own_stream():
    a, b = env_creator(Context(CONFIG, 1, 0)), env_creator(Context(CONFIG, 2, 0))
    c = env_creator(Context(CONFIG, 1, 1))
    assert a.observation_space.shape == b.observation_space.shape  # the flat policy input
    runs = [_first_steps(env) for env in (a, b, c)]
    assert not np.array_equal(runs[0], runs[1]) and not np.array_equal(runs[0], runs[2])


def test_env_creator_repeats_in_a_new_process_and_keeps_the_dict_on_request():
    from stsf_gym.agents import rllib

    rllib._made.clear()  # as in a fresh worker process
    first = _first_steps(env_creator(Context(CONFIG, 3, 0)))
    rllib._made.clear()
    np.testing.assert_array_equal(first, _first_steps(env_creator(Context(CONFIG, 3, 0))))
    env = env_creator({**CONFIG, "policy_observation": False, "num_envs": 1})
    assert "pose" in env.observation_space.spaces
    env.close()
    with pytest.raises(ValueError, match="PolicyObservation needs obs"):
        env_creator({"env_id": "stsf_gym/Straight10m-v0", "camera__enabled": False})


def test_rllib_ppo_trains_one_iteration_on_a_registered_id():
    pytest.importorskip("ray.rllib", reason="optional extra: pip install 'stsf-gym[rllib]'")
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    register_env("stsf_gym", env_creator)
    config = (
        PPOConfig()
        .environment(
            "stsf_gym",
            env_config={
                "env_id": "stsf_gym/Straight10m-Truth-v0",
                "camera__mode": "fast",
                "sim__max_episode_seconds": 5.0,
            },
        )
        .env_runners(num_env_runners=0, num_envs_per_env_runner=2, rollout_fragment_length=64)
        .training(train_batch_size_per_learner=128, minibatch_size=64, num_epochs=1)
        .rl_module(model_config={"fcnet_hiddens": [16, 16]})
    )
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        algo = config.build_algo()
        result = algo.train()
        algo.stop()
    finally:
        ray.shutdown()
    assert result["env_runners"]["num_env_steps_sampled_lifetime"] >= 128
    learner = result["learners"]["default_policy"]
    assert np.isfinite(learner["total_loss"])
