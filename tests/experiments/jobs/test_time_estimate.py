"""Time before work: the count and an estimate from a measured rate, before any job runs."""

import json

import pytest

from stsf_gym.experiments.jobs import estimate
from stsf_gym.experiments.jobs.cache import run_cached
from stsf_gym.experiments.jobs.estimate import Stopwatch, duration, plan_line, work_key
from stsf_gym.experiments.jobs.spec import Finished


@pytest.fixture(autouse=True)
def rates(tmp_path, monkeypatch):
    path = tmp_path / "rates.json"
    monkeypatch.setenv(estimate.RATES_ENV, str(path))
    return path


def _jobs(n: int, world: str = "a") -> list[dict]:
    return [{"world": world, "seed": s} for s in range(n)]


def test_durations_read_as_a_person_says_them():
    assert [duration(s) for s in (0.2, 40, 200, 7200)] == ["1 s", "40 s", "3 min", "2.0 h"]


def test_no_rate_yet_says_so_and_still_counts():
    line = plan_line("evaluate w", "episode", 10, _jobs(10), 2)
    assert line.startswith("evaluate w: 10 episode(s) to run on 2 process(es)")
    assert "no rate measured here yet" in line


def test_a_measured_rate_gives_the_estimate(rates):
    rates.write_text(json.dumps({"evaluate w": {work_key(_jobs(1)): {"seconds": 30, "jobs": 4}}}))
    line = plan_line("evaluate w", "episode", 12, _jobs(8), 2)  # 4 done already
    assert "8 episode(s) to run (4 already done) on 2 process(es): about 2 min" in line
    assert "30.0 s per episode per process, measured here over 4 on this work" in line


def test_work_key_ignores_the_seeds_only():
    assert work_key(_jobs(3)) == work_key(_jobs(7))
    assert work_key(_jobs(3)) != work_key(_jobs(3, world="b"))


def test_a_run_records_its_rate_and_another_setting_falls_back_on_it(rates):
    clock = Stopwatch("sweep s", _jobs(2), 2)
    clock.tick()
    clock.tick()
    clock.save()
    saved = json.loads(rates.read_text())["sweep s"]
    assert saved[work_key(_jobs(2))]["jobs"] == 2 and saved["last"] == saved[work_key(_jobs(2))]
    assert "on other settings" in plan_line("sweep s", "cell", 3, _jobs(3, world="b"), 1)


def test_run_cached_says_its_plan_on_stderr_before_the_first_job(tmp_path, capsys):
    said = []

    def runner(fn, jobs):
        said.append(capsys.readouterr().err)  # what was printed before any job ran
        for job in jobs:
            yield job, Finished(fn(job), ["stsf_gym/metrics.py"])

    store = tmp_path / "seeds.sqlite"
    run_cached(lambda job: job["seed"], _jobs(3), store, lambda j: str(j["seed"]), runner,
               "table1", unit="seed")  # fmt: skip
    assert "table1: 3 seed(s) to run on 1 process(es)" in said[0]
    run_cached(lambda job: job["seed"], _jobs(3), store, lambda j: str(j["seed"]), runner,
               "table1", unit="seed")  # fmt: skip
    assert "table1: all 3 seed(s) already done" in said[1]


def _train_job(out, timesteps: int = 2048, seed: int = 0) -> dict:
    job = {"algo": "ppo", "estimator": "truth", "timesteps": timesteps, "seed": seed}
    job |= {"world": "irl_corridor", "config": None, "overrides": {}, "n_envs": 1}
    return job | {"suite": None, "out": str(out)}


def test_train_says_its_runs_and_decisions_before_it_starts(tmp_path):
    from stsf_gym.experiments.jobs.train_estimate import plan

    text, lefts = plan([_train_job(tmp_path / "x"), _train_job(tmp_path / "y", seed=1)], 1)
    assert text.startswith("train: 2 run(s) of ppo: 2048 decisions learning from reward each")
    assert "train: 2 run(s) to run on 1 process(es): 4,096 decisions" in text
    assert "no speed measured here yet" in text and [x.decisions for x in lefts] == [2048] * 2


def test_a_speed_and_the_units_left_give_the_estimate():
    estimate.record_speed("train x", "k", 1_000, 20.0)  # 50 decisions/s: a short run...
    estimate.record_speed("train x", "k", 9_000, 80.0)  # ...and a long one, summed
    seconds, said = estimate.speed_estimate("train x", "k", 1_550_336, "decision")
    assert seconds == pytest.approx(1_550_336 / 100)
    assert said == "100.0 decisions/s, measured here over 10,000 on this work"
    assert "on other settings" in estimate.speed_estimate("train x", "k2", 10, "decision")[1]
    assert estimate.speed_estimate("train y", "k", 10, "decision") is None


def test_train_estimates_the_decisions_left_after_a_checkpoint(tmp_path, monkeypatch):
    from stsf_gym.experiments.jobs import train_estimate

    job = _train_job(tmp_path / "run", timesteps=204_800)
    monkeypatch.setattr(train_estimate, "resumable_steps", lambda out, made_by: 88_064)
    left = train_estimate.run_left(job)
    assert (left.done, left.decisions) == (88_064, 204_800 - 88_064)
    estimate.record_speed(train_estimate.speed_desc(left.run, "decision"), "other", 100, 1.0)
    text = train_estimate.time_line([job], [left], 1)
    assert "116,736 decisions (88,064 already done, resumed)" in text
    assert "about 19 min (100.0 decisions/s, measured here over 100 on other settings)" in text
    ran = {"timesteps": 204_800, "resumed_from": 88_064, "session_wall_time_s": 2_000.0}
    train_estimate.record_run(job, left, ran)
    assert "measured here over 116,736 on this work" in train_estimate.time_line([job], [left], 1)


def test_a_speed_is_kept_per_resolved_settings_not_per_command(tmp_path):
    from stsf_gym.experiments.jobs import train_estimate

    job = _train_job(tmp_path / "run")
    changed = job | {"overrides": {**(job["overrides"] or {}), "n_steps": 64}}
    key = train_estimate.speed_key(job, train_estimate.run_left(job).run)
    longer = job | {"timesteps": 4096}
    assert train_estimate.speed_key(longer, train_estimate.run_left(longer).run) == key
    # the same command over a changed config file: the resolved settings tell them apart
    run = train_estimate.run_left(changed).run
    assert train_estimate.speed_key(job, run) != key
