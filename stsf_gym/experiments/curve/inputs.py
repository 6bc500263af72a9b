"""What :func:`~stsf_gym.experiments.curve.run.accuracy_curve` checks before any cell runs,
and the worlds and env of a suite's curve: every refusal a :class:`ConfigError` naming the
value, the same from Python as from ``stsf-gym accuracy-curve``."""

from __future__ import annotations

from stsf_gym.agents.registry import check_agents
from stsf_gym.config_files import deep_merge
from stsf_gym.envs.generated_env import check_distinct_worlds, generated_label
from stsf_gym.envs.suite import load_suite
from stsf_gym.estimators import make_estimator
from stsf_gym.validation import ConfigError, Range, check_number

DIAL = "degraded-truth"  # the pose source the dial's levels scale
DEFAULT_WORLD = "irl_corridor"  # the curve's world without a suite
SUITE_WORLDS = "test"  # the split a suite's curve drives on


def check_request(agents: list[str], levels: list[float], dial: dict) -> None:
    """Every level a positive scale of the dial's errors, the dial's options those of
    :data:`DIAL` without its scale (each level sets it), and every agent made once."""
    for level in levels:
        check_number(level, "--levels", Range(ge=0))
    if not levels or any(not level > 0 for level in levels):
        raise ConfigError(f"levels must be positive numbers, got {levels!r}")
    if "scale" in dial:  # each level sets it: a scale in the dial would change nothing
        raise ConfigError(
            f"--dial scale={dial['scale']}: the dial's scale is what --levels lists "
            f"(--levels {dial['scale']}); --dial sets the dial's other options"
        )
    make_estimator(DIAL, **dial)  # a bad dial option fails before any work
    check_agents(agents)


def check_dial_timing(dial: dict, episode_seconds: float) -> None:
    """A dial whose measurements could never reach an episode of ``episode_seconds`` is
    refused: a latency as long as the episode (every measurement would report the start pose)
    or a measurement period as long (one measurement at the start, none after)."""
    latency, rate = dial.get("latency_s", 0.0), dial.get("rate_hz")
    if latency >= episode_seconds:
        raise ConfigError(
            f"--dial latency_s={latency:g}: no measurement that old arrives in an episode of "
            f"{episode_seconds:g} s (sim.max_episode_seconds); give a latency below it"
        )
    if rate is not None and 1.0 / rate >= episode_seconds:
        raise ConfigError(
            f"--dial rate_hz={rate:g}: one measurement every {1.0 / rate:g} s is none after the "
            f"start of an episode of {episode_seconds:g} s (sim.max_episode_seconds)"
        )


def curve_world(
    world: str | None, env: dict, suite: str | None, seed: int, seeds: int
) -> tuple[str, dict]:
    """The world and env of the curve's episodes: ``world`` (default :data:`DEFAULT_WORLD`)
    and ``env``, or for ``suite`` its test worlds and its episode env under ``env``, with the
    episode seeds within the split (none driven twice)."""
    if suite is None:
        return world or DEFAULT_WORLD, env
    if world is not None:
        raise ConfigError(
            f"suite {suite!r} picks the worlds (its {SUITE_WORLDS} split): give no world "
            f"(got {world!r})"
        )
    loaded = load_suite(suite)
    test_worlds = loaded.generator_config().split_range(SUITE_WORLDS)
    check_distinct_worlds(test_worlds, range(seed, seed + seeds), f"--seed {seed} --seeds {seeds}")
    return generated_label(SUITE_WORLDS), deep_merge(loaded.episode_env, env)
