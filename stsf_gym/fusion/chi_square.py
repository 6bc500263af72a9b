"""Quantiles of the chi-square distribution with a whole number of degrees of freedom.

The gates of the estimators (squared Mahalanobis distances, ``dof`` 2 or 3) need the value
``x`` below which a chi-square variable with ``k`` degrees of freedom falls with probability
``p``. Its distribution function is the regularised lower incomplete gamma function
``P(k/2, x/2)``; its upper tail ``Q = 1 - P`` has a closed form for a whole ``k``
(Abramowitz & Stegun 26.4.4-26.4.5):

    k even:  Q = exp(-x/2) * sum_{j < k/2} (x/2)^j / j!
    k odd:   Q = erfc(sqrt(x/2)) + exp(-x/2) * sum_{j < (k-1)/2} (x/2)^(j+1/2) / Gamma(j+3/2)

The tail, not ``1 - Q``, is compared with ``1 - p``, so no precision is lost for the ``p``
near 1 the gates use; it is inverted by bisection to the last bit (``Q`` falls strictly in
``x``). Agrees with ``2 * scipy.special.gammaincinv(k / 2, p)`` to a few units in the last
place. Computed
here with the standard library so that an env process need not load SciPy (about 27 MB of
memory) for two numbers.
"""

from __future__ import annotations

import functools
import math


def chi_square_tail(x: float, dof: int) -> float:
    """``P(chi2_dof > x)`` for a whole number of degrees of freedom ``dof >= 1``."""
    if x <= 0:
        return 1.0
    half = x / 2
    if dof % 2 == 0:
        terms = [half**j / math.factorial(j) for j in range(dof // 2)]
        return math.exp(-half) * math.fsum(terms)
    terms = [half ** (j + 0.5) / math.gamma(j + 1.5) for j in range((dof - 1) // 2)]
    return math.erfc(math.sqrt(half)) + math.exp(-half) * math.fsum(terms)


@functools.cache
def chi_square_quantile(probability: float, dof: int) -> float:
    """The ``x`` with ``P(chi2_dof <= x) = probability`` (0 < probability < 1); kept per
    argument pair, as gates ask for the same few."""
    if not 0 < probability < 1:
        raise ValueError(f"probability must be in (0, 1), got {probability}")
    if dof < 1 or dof != int(dof):
        raise ValueError(f"degrees of freedom must be a whole number >= 1, got {dof}")
    tail = 1.0 - probability
    low, high = 0.0, float(dof)
    while chi_square_tail(high, dof) > tail:
        low, high = high, 2 * high
    while True:
        middle = (low + high) / 2
        if middle in (low, high):  # the interval is one floating-point step wide
            return middle
        if chi_square_tail(middle, dof) > tail:
            low = middle
        else:
            high = middle
