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


def test_train_says_its_runs_and_decisions_before_it_starts():
    from stsf_gym.cli.train import plan

    job = {"algo": "ppo", "estimator": "truth", "timesteps": 2048, "seed": 0}
    job |= {"world": "irl_corridor", "config": None, "overrides": {}, "n_envs": 1}
    job |= {"suite": None, "out": "x"}
    text = plan([job, {**job, "seed": 1, "out": "y"}], 1)
    assert text.startswith("train: 2 run(s) of ppo: 2048 decisions learning from reward each")
    assert "train: 2 run(s) to run on 1 process(es)" in text
