"""One flag for agents on every command that runs them, and unknown options named with the
option meant."""

import pytest

from stsf_gym import cli

AGENT_COMMANDS = {
    "evaluate": [],
    "accuracy-curve": [],
    "benchmark": ["--suite", "sparse"],
}


@pytest.mark.parametrize("command", AGENT_COMMANDS)
@pytest.mark.parametrize("flag", ["--agents", "--agent"])
def test_agents_flag_and_its_alias(command, flag):
    argv = [command, *AGENT_COMMANDS[command], flag, "follower,cautious-follower"]
    args = cli.build_parser(command).parse_args(argv)
    assert args.agents == "follower,cautious-follower"


@pytest.mark.parametrize("command", cli.COMMANDS)
def test_an_unknown_option_names_the_close_match(command, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main([command, "--jsno"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2
    assert f"stsf-gym {command}: error: unknown option --jsno (did you mean --json?)" in err


def test_a_typo_of_the_agents_flag(capsys):
    with pytest.raises(SystemExit):
        cli.main(["evaluate", "--agnets", "follower"])
    assert "unknown option --agnets (did you mean --agents?)" in capsys.readouterr().err


def test_a_mistyped_command_names_the_command_meant(capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["evalute", "--agents", "follower"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2
    assert "stsf-gym: error: unknown command 'evalute' (did you mean evaluate?)" in err


@pytest.mark.parametrize(("typed", "number"), [("1e6", 1_000_000), ("2048.0", 2048), ("40", 40)])
def test_a_count_typed_with_an_exponent_is_a_number(typed, number):
    args = cli.build_parser("train").parse_args(["train", "--timesteps", typed])
    assert args.timesteps == number


@pytest.mark.parametrize("typed", ["1.5", "ten", "inf", "nan"])
def test_a_count_that_is_no_whole_number_is_refused(typed, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["benchmark", "--suite", "sparse", "--worlds", typed])
    err = capsys.readouterr().err
    assert exit_.value.code == 2
    assert f"error: argument --worlds: must be a whole number, got '{typed}'" in err


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--estimators", "stfs"], "unknown estimator 'stfs' (did you mean 'stsf'?)"),
        (["--agents", "cautious_follower"], "(did you mean 'cautious-follower'?)"),
        (["--world", "irl_coridor"], "unknown world 'irl_coridor' (did you mean 'irl_corridor'?)"),
        (
            ["--agents", "pretrained:sparse/dagger-stfs"],
            "(did you mean 'pretrained:sparse/dagger-stsf'?)",
        ),
    ],
)
def test_a_mistyped_name_is_refused_with_the_name_meant(run_cli, tmp_path, argv, said):
    code, err = run_cli("evaluate", *argv, "--out", str(tmp_path / "o"))
    assert code == 2 and said in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
