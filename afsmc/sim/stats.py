"""Confidence intervals used by `sim-check` and `simulate` (see docs/monte-carlo.md)."""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal
from typing import Any

import numpy as np
import numpy.typing as npt


class _Stats:
    """scipy.stats, imported on first use: it costs ~0.4 s at every CLI start otherwise."""

    def __getattr__(self, name: str) -> object:
        from scipy import stats as real

        return getattr(real, name)


stats: Any = _Stats()


CLOPPER_PEARSON = "Clopper-Pearson"


def outward_decimals(low: float, high: float) -> tuple[str, str]:
    """A probability interval [low, high] rounded outwards (within [0, 1]) to the fewest
    decimals that widen it by at most 5% (or 1e-12): short numbers for a file that
    still cover the interval."""
    width = max(high - low, 0.0)
    for digits in range(1, 16):
        q = Decimal(1).scaleb(-digits)
        a = Decimal(repr(low)).quantize(q, rounding=ROUND_FLOOR)
        b = Decimal(repr(high)).quantize(q, rounding=ROUND_CEILING)
        if float(b - a) <= width * 1.05 + 1e-12 or digits == 15:
            break
    a, b = max(a, Decimal(0)), min(b, Decimal(1))
    return _plain(a), _plain(b)


def _plain(d: Decimal) -> str:
    return format(d.normalize(), "f")


def clopper_pearson(k: int, n: int, confidence: float) -> tuple[float, float]:
    """The exact (conservative) binomial interval for k successes out of n."""
    if n <= 0:
        return 0.0, 1.0
    a = 1.0 - confidence
    low = 0.0 if k <= 0 else float(stats.beta.ppf(a / 2, k, n - k + 1))
    high = 1.0 if k >= n else float(stats.beta.ppf(1 - a / 2, k + 1, n - k))
    return low, high


def mean_interval(x: npt.NDArray[np.float64], confidence: float) -> tuple[float, float]:
    """Normal-approximation interval of the mean (the samples are many and independent)."""
    n = len(x)
    m = float(np.mean(x))
    if n < 2:
        return m, m
    half = float(stats.norm.ppf(0.5 + confidence / 2)) * float(np.std(x, ddof=1)) / math.sqrt(n)
    return m - half, m + half


def quantile_interval(sorted_x: npt.NDArray[np.float64], q: float,
                      confidence: float) -> tuple[float, float]:
    """Distribution-free interval of the q-quantile from order statistics.

    The number of samples below the true quantile is Binomial(n, q), so
    [x_(l), x_(u+1)] with l, u its (1-conf)/2 and (1+conf)/2 quantiles covers the
    quantile with probability >= confidence, whatever the distribution. A rank outside
    the sample gives an unbounded end: too few samples cannot bound the quantile there
    (clamping it to the sample's extremes made `sim-check --runs 10` report drifts that
    the rule cannot support)."""
    n = len(sorted_x)
    a = 1.0 - confidence
    lo_rank = int(stats.binom.ppf(a / 2, n, q))  # 1-based order statistic x_(l)
    hi_rank = int(stats.binom.ppf(1 - a / 2, n, q)) + 1  # x_(u+1)
    return (float(sorted_x[lo_rank - 1]) if lo_rank >= 1 else -math.inf,
            float(sorted_x[hi_rank - 1]) if hi_rank <= n else math.inf)


def shortest_decimal(target: float, low: float, high: float) -> str:
    """The decimal with the fewest digits in [low, high], nearest `target` at that precision."""
    for digits in range(1, 12):
        v = round(target, digits)
        if low <= v <= high:
            return f"{v:.{digits}f}"
    return repr(target)


def normal_quantile(p: float) -> float:
    return float(stats.norm.ppf(p))


def merge_moments(count: list[int], total: list[float], m2: list[float], k: int,
                  vals: npt.NDArray[np.float64] | tuple[int, float, float]) -> None:
    """Add values (or another group's (count, total, m2)) to group k's count, sum and sum
    of squared deviations from the mean, exactly as one pass over all of them would (Chan
    et al.'s pairwise update: stable, and independent of the mean's magnitude)."""
    if isinstance(vals, tuple):
        n_b, s_b, m2_b = vals
    else:
        n_b = len(vals)
        s_b = float(np.sum(vals))
        m2_b = float(np.sum((vals - s_b / n_b) ** 2)) if n_b else 0.0
    if n_b == 0:
        return
    n_a = count[k]
    if n_a:
        delta = s_b / n_b - total[k] / n_a
        m2[k] += m2_b + delta * delta * n_a * n_b / (n_a + n_b)
    else:
        m2[k] = m2_b
    count[k] += n_b
    total[k] += s_b
