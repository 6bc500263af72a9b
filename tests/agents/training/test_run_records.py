"""A training run's records: an episodes file with its header only reads as no rows, and a
changed fine-tuning setting trains the reward stage again but keeps the demonstrations."""

from __future__ import annotations

from stsf_gym.config import parse_overrides


def test_an_episodes_file_with_its_header_only_reads_as_no_rows(tmp_path):
    from stsf_gym.agents.training.training_log import plot_learning_curve, read_rows

    (tmp_path / "episodes.csv").write_text("timesteps,reward,length,success,control_steps\n")
    assert read_rows(tmp_path / "episodes.csv").shape == (0, 5)
    assert plot_learning_curve(tmp_path, "dagger+ppo on truth").is_file()  # set aside: plotted


def test_a_fine_tuning_setting_changed_keeps_the_demonstrations():
    from stsf_gym.agents.training.settings import resolve_run

    def meta(*overrides: str) -> dict:
        run = resolve_run(
            "dagger+ppo", "truth", 16384, 0, "generated", None, parse_overrides(list(overrides)),
            1, "corridor",
        )  # fmt: skip
        return run.meta

    base, tuned = meta(), meta("finetune.learning_rate=1e-5")
    assert tuned["made_by"] != base["made_by"]  # the reward stage is trained again
    assert tuned["demonstrations_made_by"] == base["demonstrations_made_by"]
    rounds = meta("demonstrations.rounds=1")
    assert rounds["demonstrations_made_by"] != base["demonstrations_made_by"]
