"""What printed precision does to an overlap recomputed from positions.

A value printed with P significant digits (``%g``: P = 6) is known to within
half its last digit, h/2 with h = 10^(floor(log10|x|) - P + 1). The overlap
delta = r1 + r2 - |x2 - x1| of two such centres is then off by at most
sqrt(3) h (the rounding of the three components, projected on the normal), a
relative bound sqrt(3) h / delta that grows as the overlap shrinks. Every
reader that recomputes overlaps uses these functions (``docs/physics.md``).
"""

from __future__ import annotations

import numpy as np

FULL_PRECISION_DIGITS = 15
"""Values printed with at least this many significant digits count as exact doubles."""


def printed_step(x: np.ndarray, digits: int | None) -> np.ndarray:
    """Step h of the last printed digit of values ``x`` printed with ``digits``
    significant digits: h = 10^(floor(log10|x|) - digits + 1) (units of x);
    0 at full precision (``digits`` None or >= 15) and for x = 0."""
    if digits is None or digits >= FULL_PRECISION_DIGITS:
        return np.zeros(np.shape(x))
    with np.errstate(divide="ignore"):
        exponent = np.floor(np.log10(np.abs(np.asarray(x, dtype=np.float64))))
    return np.where(np.isfinite(exponent), 10.0 ** (exponent - digits + 1), 0.0)


def position_error(h: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Relative error bound sqrt(3) h / delta of an overlap recomputed from
    positions printed with step h (inf where delta <= 0 and h > 0: the printed
    positions do not even show the contact)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(delta > 0, np.sqrt(3.0) * h / delta, np.where(h > 0, np.inf, 0.0))


def relative_rounding(digits: int | None) -> float:
    """Largest relative rounding error of a value printed with ``digits`` significant digits."""
    return 0.0 if digits is None or digits >= FULL_PRECISION_DIGITS else 0.5 * 10.0 ** (1 - digits)
