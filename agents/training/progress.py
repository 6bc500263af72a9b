"""What a training run shows while it runs: a progress bar with an ETA over each stage and
TensorBoard scalars for each (SB3 writes the reward stage's; :func:`log_round` the rounds of
the demonstration stage, in the same ``tb/`` folder)."""

from __future__ import annotations

import sys
from pathlib import Path

from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import configure
from tqdm import tqdm

TB_DEMONSTRATIONS = "demonstrations"  # tb/<this>: the demonstration stage's scalars


def stage_bar(
    stage: str, total: int, unit: str, enabled: bool, position: int = 0, initial: int = 0
) -> tqdm:
    """A bar on stderr over ``total`` ``unit`` of ``stage``, drawn at once (count, rate and
    ETA), ``initial`` of them done before (not counted in its rate); ``enabled`` False: a bar
    that draws nothing."""
    return tqdm(
        total=total,
        initial=initial,
        position=position,
        desc=stage,
        unit=unit,
        disable=not enabled,
        file=sys.stderr,
        dynamic_ncols=True,
        mininterval=1.0,
    )


def stage_bars(
    demonstration_episodes: int, reward_steps: int, algo: str, enabled: bool, resumed: int = 0
):
    """The bars of a run's stages, drawn before anything else starts (None: no such stage);
    the reward stage's from the ``resumed`` decisions of its checkpoint."""
    stages = [("demonstrations (episodes)", demonstration_episodes, "ep", 0)]
    stages.append((f"learning from reward ({algo}, decisions)", reward_steps, "decision", resumed))
    made = [None, None]
    position = 0
    for index, (stage, total, unit, initial) in enumerate(stages):
        if total:
            made[index] = stage_bar(stage, total, unit, enabled, position, initial)
            position += 1
    return tuple(made)


def start_at(bar: tqdm, done: int) -> None:
    """Start ``bar`` (not updated yet) now with ``done`` units counted already (tqdm's
    ``initial``): its rate and ETA count only the units run from here, not those of an earlier
    session nor the seconds before (``tqdm.reset`` would draw a negative rate first)."""
    bar.initial = bar.n = done
    if bar.disable:  # a bar that draws nothing keeps no clock
        return
    bar.last_print_n = done
    bar.start_t = bar.last_print_t = bar._time()  # tqdm's clock
    bar.refresh()


class RewardProgress(BaseCallback):
    """The reward stage's bar, in env steps (decisions summed over the envs); a resumed stage
    starts it at its checkpoint, its rate from there (:func:`start_at`)."""

    def __init__(self, bar: tqdm) -> None:
        super().__init__()
        self.bar = bar

    def _on_training_start(self) -> None:
        start_at(self.bar, self.num_timesteps)

    def _on_step(self) -> bool:
        self.bar.update(self.num_timesteps - self.bar.n)
        return True

    def _on_training_end(self) -> None:
        self.bar.close()


def log_round(out: Path, round_: dict) -> None:
    """A demonstration round's scalars at its control steps: val success and return, the
    cloning loss, the data set's size, the wall time."""
    logger = configure(str(Path(out) / "tb" / TB_DEMONSTRATIONS), ["tensorboard"])
    for key in ("val_success", "val_return", "loss", "samples", "wall_time_s"):
        logger.record(f"demonstrations/{key}", round_[key])
    logger.dump(step=round_["control_steps"])
    logger.close()
