"""The rule for intervals from too few worlds, derived from the sign test."""

from math import comb

from stsf_gym.experiments.benchmark.small_samples import (
    MARK,
    MIN_PAIRED_WORLDS,
    few_worlds_note,
    marked,
    min_paired_worlds,
)


def sign_test_p(n: int, k: int) -> float:
    """Two-sided exact sign-test p-value of k of n pairs going one way."""
    tail = sum(comb(n, i) for i in range(k, n + 1)) / 2**n
    return min(1.0, 2 * tail)


def test_six_worlds_are_the_fewest_that_can_show_a_difference():
    assert MIN_PAIRED_WORLDS == 6
    assert sign_test_p(5, 5) > 0.05 > sign_test_p(6, 6)  # every world the same way
    assert min_paired_worlds(0.01) == 8  # 2 / 2^8 = 0.0078


def test_marks_and_notes_only_below_the_rule():
    assert marked("+0.00 (+0.00 to +0.00)", 2) == f"+0.00 (+0.00 to +0.00) {MARK}"
    assert marked("+0.10 (-0.05 to +0.25)", 6) == "+0.10 (-0.05 to +0.25)"
    assert "2 x 0.5^5 = 0.062, above 0.05" in few_worlds_note(5)
    assert few_worlds_note(6) is None
